// The live preview's patch applied to this map in place (issue 32): a
// module of the page's script (bundled by src/render/page/bundle.rs). The
// server sends what changed since the page the browser has
// (src/render/html/patch.rs writes it): cells by position among the
// picture's `path[data-id]`s with their new outline and fill, the picture's
// other changed parts whole (by class), the changed nodes of the data, and
// the legend when it changed (whole; legend.js binds it as it bound the old).
// `check` finds everything a patch names and parses its parts, or says no
// (the live preview then loads the whole page); `apply` puts it in place,
// reads the changed nodes again (model.js `renew`) and says what the
// stability panel needs of the data: leaves whose weight changed, and the
// realised constraints kept. Only the cells the patch names are touched:
// on a map of 20,000 leaves an edit that moved 30 cells costs 30 cells.
import { EMPTY, N, NS, data, isLeaf, leafCells, part, partners, renew, svg } from "./model.js";
import { renewLegend } from "./legend.js";

// A part's markup as an element of this document, or null.
function parsed(markup) {
  var doc = new DOMParser().parseFromString("<svg xmlns=\"" + NS + "\">" + markup + "</svg>", "image/svg+xml");
  if (doc.getElementsByTagName("parsererror").length) { return null; }
  var el = doc.documentElement.firstElementChild;
  return el ? document.importNode(el, true) : null;
}

// The legend's markup (our own HTML, its text escaped) as an element of
// this document, or null; a parsed document runs nothing it holds.
function parsedLegend(markup) {
  var el = new DOMParser().parseFromString(markup, "text/html").body.firstElementChild;
  return el && el.classList.contains("np-legend") ? document.importNode(el, true) : null;
}

// The picture's top-level element of class `cls` (exactly), or null.
function partOf(cls) {
  for (var k = 0; k < svg.children.length; k++) {
    if (svg.children[k].getAttribute("class") === cls) { return svg.children[k]; }
  }
  return null;
}

// Realised constraint pairs, each once.
function realized() {
  var out = new Set();
  for (var i = 0; i < N; i++) {
    (partners[i] || EMPTY).forEach(function (p) { if (p[1] && p[0] > i) { out.add(i * N + p[0]); } });
  }
  return out;
}

// What `patch` names, found: { cells: [[element, d, fill]], parts:
// [[old, new]] }; null when anything is missing or out of place.
function check(patch) {
  var list = svg.querySelectorAll("path[data-id]");
  if (list.length !== patch.count) { return null; }
  var cells = [], parts = [], k;
  for (k = 0; k < patch.cells.length; k++) {
    var c = patch.cells[k], el = list[c[0]];
    if (!el || el.getAttribute("data-id") !== c[1]) { return null; }
    cells.push([el, c[2], c[3]]);
  }
  for (k = 0; k < patch.parts.length; k++) {
    var old = partOf(patch.parts[k][0]), fresh = parsed(patch.parts[k][1]);
    if (!old || !fresh) { return null; }
    parts.push([old, fresh]);
  }
  for (k = 0; k < patch.nodes.length; k++) {
    var n = patch.nodes[k];
    if (!(n[0] < N) || !data.nodes[n[0]] || data.nodes[n[0]].id !== n[1].id) { return null; }
  }
  var legend = null;
  if (typeof patch.legend === "string") {
    legend = parsedLegend(patch.legend);
    if (!legend || !part("legend")) { return null; }
  }
  return { cells: cells, parts: parts, legend: legend };
}

// Puts a checked patch in place; `after` runs once the map is whole again
// (its labels, links and hover found anew: main.js).
function apply(ready, patch, after) {
  ready.cells.forEach(function (c) {
    c[0].setAttribute("d", c[1]);
    c[0].setAttribute("fill", c[2]);
  });
  ready.parts.forEach(function (p) { p[0].parentNode.replaceChild(p[1], p[0]); });
  if (ready.legend) { renewLegend(ready.legend); }
  var changed = 0;
  patch.nodes.forEach(function (n) {
    if (isLeaf(n[0]) && data.nodes[n[0]].weight !== n[1].weight) { changed++; }
  });
  var before = realized();
  if (patch.labels && data.labels) { Object.assign(data.labels, patch.labels); }
  renew(patch.nodes);
  var now = realized(), kept = 0;
  before.forEach(function (key) { if (now.has(key)) { kept++; } });
  // The data block stays the map's truth for whoever reads it later.
  var block = part("data");
  if (block && patch.nodes.length) { block.textContent = JSON.stringify(data).replace(/</g, "\\u003c"); }
  after();
  return { leaves: leafCells.length, changed: changed, realized: before.size, kept: kept };
}

// The map's patch interface for the live preview (main.js hands it over
// as `root.npPatch`).
export function patcher(after) {
  return {
    check: check,
    apply: function (ready, patch) { return apply(ready, patch, after); }
  };
}
