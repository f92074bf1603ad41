// The page's model of its map: its parts, its data, its cells, its listeners.
// A module of the page's script (bundled by src/render/page/bundle.rs) that
// imports nothing: the map's container and parts, the data block read once
// into arrays by node index (labels, parents, children, depths, subtree
// ranges), relations made symmetric, the cells of the picture by index, the
// polygons and boxes parsed from their path data on first use, and the
// listeners the map keeps on the window and the document. Maps and arrays,
// never plain objects keyed by id: ids such as "constructor" or "__proto__"
// are data.
if (window.performance && performance.mark) { performance.mark("nptreemap-start"); }
export const root = document.currentScript.parentNode;
export function part(name) { return root.querySelector(".np-" + name); }
// Listeners on the window or the document outlive the map: they are added
// through `globally`, so that a map that is replaced (the live preview
// swaps in the rebuilt one) takes them with it (`retire`, which main.js
// hands the live preview as `root.npRetire`) instead of keeping itself
// alive through them.
var life = window.AbortController ? new AbortController() : null;
export function globally(target, type, fn) {
  target.addEventListener(type, fn, life ? { signal: life.signal } : false);
}
export function retire() { if (life) { life.abort(); } }
export const data = JSON.parse(part("data").textContent);
export const map = part("map");
export const svg = map.querySelector("svg");
export const NS = svg.namespaceURI;
// The picture's whole view box (the zoom changes the picture's own).
export const full = svg.getAttribute("viewBox").split(/[\s,]+/).map(Number);
export const N = data.nodes.length;
export const ids = new Array(N), labels = new Array(N), weights = new Array(N);
export const parents = new Int32Array(N), depths = new Int32Array(N);
const kids = new Array(N);
export const near = new Array(N), partners = new Array(N);
export const index = new Map();
export const EMPTY = [];
(function () {
  var i, n;
  for (i = 0; i < N; i++) {
    n = data.nodes[i];
    ids[i] = n.id;
    labels[i] = typeof n.label === "string" ? n.label : n.id;
    weights[i] = n.weight;
    parents[i] = typeof n.parent === "number" ? n.parent : -1;
    depths[i] = parents[i] >= 0 ? depths[parents[i]] + 1 : 0;
    kids[i] = EMPTY;
    near[i] = EMPTY;
    partners[i] = EMPTY;
    index.set(n.id, i);
  }
  for (i = 0; i < N; i++) {
    if (parents[i] >= 0) { add(kids, parents[i], i); }
  }
  relate();
})();
function add(list, k, v) {
  if (list[k] === EMPTY) { list[k] = []; }
  list[k].push(v);
}
// The relations of the data, made symmetric: written once per pair, at the
// lower index (src/render/html.rs).
function relate() {
  var i;
  for (i = 0; i < N; i++) { near[i] = EMPTY; partners[i] = EMPTY; }
  for (i = 0; i < N; i++) {
    var n = data.nodes[i];
    (n.near || EMPTY).forEach(function (j) { add(near, i, j); add(near, j, i); });
    (n.partners || EMPTY).forEach(function (p) { add(partners, i, p); add(partners, p[0], [i, p[1]]); });
  }
}
// A live patch changed these nodes (page/patch.js: [index, node], the
// tree's shape the same): what is read from them is read again.
export function renew(changed) {
  changed.forEach(function (c) {
    var i = c[0], n = c[1];
    data.nodes[i] = n;
    labels[i] = typeof n.label === "string" ? n.label : n.id;
    weights[i] = n.weight;
  });
  if (changed.length) { relate(); }
  forgetOutlines();
}
export function isLeaf(i) { return kids[i].length === 0; }

// Pre-order positions: node k lies in the subtree of g when
// first[g] <= first[k] <= last[g].
const first = new Int32Array(N), last = new Int32Array(N);
(function () {
  if (!N) { return; }
  var stack = [0], seen = new Uint8Array(N), order = 0;
  while (stack.length) {
    var i = stack[stack.length - 1];
    if (!seen[i]) {
      seen[i] = 1;
      first[i] = order++;
      for (var k = kids[i].length - 1; k >= 0; k--) { stack.push(kids[i][k]); }
    } else {
      stack.pop();
      last[i] = order - 1;
    }
  }
})();
export function within(g, k) { return first[g] <= first[k] && first[k] <= last[g]; }

// Root to node, both included.
export function ancestors(i) {
  var out = [];
  for (var k = i; k >= 0; k = parents[k]) { out.unshift(k); }
  return out;
}
// The names from the top-level group down to the node (the root's name
// is the map's, not the node's).
export function pathLabels(i) {
  return ancestors(i).slice(1).map(function (k) { return labels[k]; });
}

export const cells = new Array(N);
export const leafCells = [];
Array.prototype.forEach.call(svg.querySelectorAll("path[data-id]"), function (el) {
  var i = index.get(el.getAttribute("data-id"));
  if (i === undefined) { return; }
  cells[i] = el;
  if (isLeaf(i)) { leafCells.push(i); }
});
export function nodeOf(target) {
  var el = target && target.closest ? target.closest("path[data-id]") : null;
  if (!el || el.ownerSVGElement !== svg) { return -1; }
  var i = index.get(el.getAttribute("data-id"));
  return i === undefined ? -1 : i;
}
export function leafOf(target) {
  var i = nodeOf(target);
  return i >= 0 && isLeaf(i) ? i : -1;
}

// Cell polygons as flat coordinate arrays, from the paths' "Mx,yLx,y...Z".
var polys = new Array(N), boxes = new Array(N);
// The cells' outlines changed (page/past.js drew another layout): parsed
// again on next use.
export function forgetOutlines() {
  polys = new Array(N);
  boxes = new Array(N);
}
export function poly(i) {
  if (polys[i] === undefined) {
    var el = cells[i];
    var nums = el ? (el.getAttribute("d").match(/-?[0-9.]+(?:e-?[0-9]+)?/g) || EMPTY) : EMPTY;
    var p = new Float64Array(nums.length);
    for (var k = 0; k < nums.length; k++) { p[k] = +nums[k]; }
    polys[i] = p;
  }
  return polys[i];
}
// [x0, y0, x1, y1] of a cell.
export function bbox(i) {
  if (boxes[i] === undefined) {
    var p = poly(i), b = [Infinity, Infinity, -Infinity, -Infinity];
    for (var k = 0; k + 1 < p.length; k += 2) {
      b[0] = Math.min(b[0], p[k]); b[1] = Math.min(b[1], p[k + 1]);
      b[2] = Math.max(b[2], p[k]); b[3] = Math.max(b[3], p[k + 1]);
    }
    boxes[i] = b;
  }
  return boxes[i];
}
// Area-weighted centroid of a cell.
export function centroid(i) {
  var p = poly(i), a = 0, cx = 0, cy = 0, n = p.length;
  for (var k = 0; k + 1 < n; k += 2) {
    var x0 = p[k], y0 = p[k + 1], x1 = p[(k + 2) % n], y1 = p[(k + 3) % n];
    var c = x0 * y1 - x1 * y0;
    a += c; cx += (x0 + x1) * c; cy += (y0 + y1) * c;
  }
  if (Math.abs(a) < 1e-12) { var b = bbox(i); return [(b[0] + b[2]) / 2, (b[1] + b[3]) / 2]; }
  return [cx / (3 * a), cy / (3 * a)];
}
