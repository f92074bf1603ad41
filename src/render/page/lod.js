// Labels: the picture's own by node, and those placed for a zoomed view.
// A module of the page's script (bundled by src/render/page/bundle.rs). When
// the view shows part of the map z times larger, every leaf in view gets the
// label the picture would give it at that scale, by the picture's own fitter
// (fit.js): shown when it reaches the picture's minimum size on screen, never
// above the picture's maximum. Placed again after every zoom and resize. The group names of the two levels below the view are
// drawn large and light. Text widths are measured by the browser in the
// labels' own font. Labels stay SVG text, so the browser's find (Ctrl-F) sees
// them.
import { EMPTY, N, NS, bbox, cells, centroid, data, depths, full, ids, isLeaf, labels, leafCells, poly, root, svg, within } from "./model.js";
import { lineFit, placeLeaf, positive } from "./fit.js";

// How the picture labels cells (src/render/html.rs, `HtmlLabels`); null
// when it has no leaf labels.
export const LS = data.labels || null;
var zoomLabels = null, zoomGroups = null, zoomLabelOf = new Map();
var measure = null, widthCache = new Map();

// The picture's labels by node, found on first use (a page that is only
// looked at never pays for them).
var staticLabels = null;
function staticLabel(i) {
  if (!staticLabels) {
    staticLabels = new Map();
    var group = svg.querySelector("g.np-labels");
    var placed = data.labels ? data.labels.placed : EMPTY;
    if (group && placed.length === group.children.length) {
      for (var k = 0; k < placed.length; k++) { staticLabels.set(placed[k], group.children[k]); }
    }
  }
  return staticLabels.get(i);
}
// The picture's label group was replaced (page/patch.js): found again.
export function forgetStaticLabels() { staticLabels = null; }

function textWidth(s) {
  var w = widthCache.get(s);
  if (w === undefined) {
    if (!measure) {
      measure = document.createElement("canvas").getContext("2d");
      measure.font = "100px " + (LS ? LS.font : "sans-serif");
    }
    w = measure.measureText(s).width / 100;
    widthCache.set(s, w);
  }
  return w;
}

// The largest font size (canvas units) at which a box of `wEm` x `hEm`
// font sizes centred on (cx, cy) lies inside convex cell i.
function fitSize(i, cx, cy, wEm, hEm) {
  var p = poly(i), n = p.length, best = Infinity;
  if (n < 6) { return 0; }
  // The polygon's orientation decides which side of each edge is inside.
  var area = 0;
  for (var k = 0; k < n; k += 2) { area += p[k] * p[(k + 3) % n] - p[(k + 2) % n] * p[k + 1]; }
  var s = area >= 0 ? 1 : -1;
  for (var k = 0; k < n; k += 2) {
    var x0 = p[k], y0 = p[k + 1], x1 = p[(k + 2) % n], y1 = p[(k + 3) % n];
    // Outward normal of the edge, and how far the centre is inside it.
    var nx = s * (y1 - y0), ny = -s * (x1 - x0);
    var room = -(nx * (cx - x0) + ny * (cy - y0));
    var reach = Math.abs(nx) * wEm / 2 + Math.abs(ny) * hEm / 2;
    if (reach > 0) { best = Math.min(best, room / reach); }
  }
  return Math.max(0, best);
}

// Screen pixels per canvas unit when the whole map shows (the picture's
// box does not change with its view box; a resize forgets it).
var unitPxKnown = 0;
export function unitPx() {
  if (!unitPxKnown) {
    var r = svg.getBoundingClientRect();
    unitPxKnown = r.width > 0 ? r.width / full[2] : 1;
  }
  return unitPxKnown;
}
export function forgetUnitPx() { unitPxKnown = 0; }
// Smallest zoom label on screen, pixels: the picture's smallest size, as
// a PNG at scale 1 draws it; the largest is the picture's largest label as
// it shows on this screen, and never less than twice that.
export const MIN_PX = LS ? Math.max(LS.min, 6) : 9;
function sizeRange(z) {
  var px = unitPx() * z;
  return [MIN_PX / px, Math.max(LS.max * unitPx(), 2 * MIN_PX) / px];
}

// The shortest text leaf i may show: the label itself when short, else
// its first four characters and an ellipsis.
function shortestText(i) {
  var chars = Array.from(labels[i]);
  return chars.length <= 5 ? labels[i] : chars.slice(0, 4).join("").replace(/\s+$/, "") + "\u2026";
}

// The largest font size (canvas units) at which leaf i fits the shortest
// text it may show on one line.
export function shortestFit(i) {
  return LS ? lineFit(positive(poly(i)), textWidth(shortestText(i)), LS.line) : 0;
}

// What leaf i shows at zoom z: fit.js's placement ({ lines, size }) or null.
function fitLeaf(i, z, range) {
  if (!LS || !labels[i]) { return null; }
  var r = range || sizeRange(z);
  return placeLeaf(labels[i], positive(poly(i)), r[0], r[1], textWidth, LS.line, LS.ascent);
}

// The label shown for node i now: the zoomed view's, else the picture's.
export function labelFor(i) {
  return root.classList.contains("np-zoomed") ? zoomLabelOf.get(i) : staticLabel(i);
}
export function labelShown(i, z) {
  if (z > 1.0001) { return !!fitLeaf(i, z); }
  return !!staticLabel(i);
}

// A group name centred on (x, y).
function textAt(x, y, size, text) {
  var t = document.createElementNS(NS, "text");
  t.setAttribute("x", x.toFixed(2));
  t.setAttribute("y", (y + 0.35 * size).toFixed(2));
  t.setAttribute("font-size", size.toFixed(2));
  t.textContent = text;
  return t;
}

// A leaf's label as fit.js placed it: each line at its own baseline.
function placedText(f) {
  var t = document.createElementNS(NS, "text");
  t.setAttribute("font-size", f.size.toFixed(2));
  t.setAttribute("stroke-width", (0.2 * f.size).toFixed(2));
  if (f.lines.length === 1) {
    t.setAttribute("x", f.lines[0].x.toFixed(2));
    t.setAttribute("y", f.lines[0].baseline.toFixed(2));
    t.textContent = f.lines[0].text;
    return t;
  }
  f.lines.forEach(function (line) {
    var s = document.createElementNS(NS, "tspan");
    s.setAttribute("x", line.x.toFixed(2));
    s.setAttribute("y", line.baseline.toFixed(2));
    s.textContent = line.text;
    t.appendChild(s);
  });
  return t;
}

export function dropZoomLabels() {
  [zoomLabels, zoomGroups].forEach(function (g) { if (g && g.parentNode) { g.parentNode.removeChild(g); } });
  zoomLabels = zoomGroups = null;
  zoomLabelOf = new Map();
}

// Places the labels of everything in view box `box` (zoomed z times) and,
// for the two levels below `g`, the group names.
export function placeZoomLabels(box, z, g, before) {
  dropZoomLabels();
  if (!LS || z <= 1.0001) { return; }
  var x0 = box[0], y0 = box[1], x1 = box[0] + box[2], y1 = box[1] + box[3];
  function inView(i) {
    var b = bbox(i);
    return b[2] > x0 && b[0] < x1 && b[3] > y0 && b[1] < y1;
  }
  zoomGroups = document.createElementNS(NS, "g");
  zoomGroups.setAttribute("class", "np-group-labels np-zoom-groups");
  zoomGroups.setAttribute("font-family", LS.font);
  zoomGroups.setAttribute("text-anchor", "middle");
  zoomGroups.setAttribute("fill", LS.fill);
  zoomGroups.setAttribute("fill-opacity", "0.3");
  zoomGroups.setAttribute("pointer-events", "none");
  var taken = [], range = sizeRange(z);
  [1, 2].forEach(function (step) {
    for (var i = 0; i < N; i++) {
      if (depths[i] !== depths[g] + step || isLeaf(i) || !within(g, i) || !cells[i] || !inView(i)) { continue; }
      var c = centroid(i), w = textWidth(labels[i]);
      var size = 0.8 * fitSize(i, c[0], c[1], w + 0.4, 1.4);
      size = Math.min(size, (step === 1 ? 3 : 2) * range[1]);
      if (size < 1.6 * range[0]) { continue; }
      var r = [c[0] - size * w / 2, c[1] - 0.6 * size, c[0] + size * w / 2, c[1] + 0.6 * size];
      if (taken.some(function (q) { return r[0] < q[2] && q[0] < r[2] && r[1] < q[3] && q[1] < r[3]; })) { continue; }
      taken.push(r);
      var t = textAt(c[0], c[1], size, labels[i]);
      t.setAttribute("data-of", ids[i]);
      zoomGroups.appendChild(t);
    }
  });
  zoomLabels = document.createElementNS(NS, "g");
  zoomLabels.setAttribute("class", "np-labels np-zoom-labels");
  zoomLabels.setAttribute("font-family", LS.font);
  zoomLabels.setAttribute("text-anchor", "middle");
  zoomLabels.setAttribute("fill", LS.fill);
  zoomLabels.setAttribute("stroke", LS.halo);
  zoomLabels.setAttribute("stroke-linejoin", "round");
  zoomLabels.setAttribute("paint-order", "stroke");
  zoomLabels.setAttribute("pointer-events", "none");
  leafCells.forEach(function (i) {
    if (!inView(i)) { return; }
    var f = fitLeaf(i, z, range);
    if (!f) { return; }
    var t = placedText(f);
    t.setAttribute("data-of", ids[i]);
    zoomLabels.appendChild(t);
    zoomLabelOf.set(i, t);
  });
  svg.insertBefore(zoomGroups, before);
  svg.insertBefore(zoomLabels, before);
}
