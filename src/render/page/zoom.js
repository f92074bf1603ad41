// The zoom: the view (a group, or a leaf's surroundings) and its breadcrumb.
// A module of the page's script (bundled by src/render/page/bundle.rs): a
// click (Enter on a focused cell, a breadcrumb, a search, a legend entry)
// shows a group, or a leaf's surroundings, as large as the picture allows;
// a click goes one level down, a shift- or alt-click or a double click
// straight to the deepest group under the pointer. The cells outside the
// view's group dim under one veil with a hole in its shape (one element,
// whatever the map's size), the hover veil is cleared, labels are placed
// for the zoomed extent once the zoom ends, the breadcrumb names the way
// back and its "up" button (Escape, Backspace) goes one level up.
import { N, NS, ancestors, cells, centroid, data, full, ids, isLeaf, labels, leafCells, parents, part, root, svg, within } from "./model.js";
import { clear, highlight, hovered, hushHover, over } from "./hover.js";
import {
  LS, MIN_PX, dropZoomLabels, labelShown, placeZoomLabels, shortestFit, unitPx
} from "./lod.js";

var crumbs = part("crumbs");
// The one-level-up control, beside the breadcrumb while zoomed.
var up = document.createElement("button");
up.type = "button";
up.className = "np-up";
up.textContent = "\u2191 Up";
up.title = "Up one level (Backspace)";
up.setAttribute("aria-label", "Up one level");
up.hidden = true;
crumbs.parentNode.insertBefore(up, crumbs);
// The view: a group, and optionally a leaf of it shown larger still. Only
// this file changes it (main.js reads it).
export const view = { node: 0, leaf: -1, box: full };
function setViewTo(node, leaf, box) {
  view.node = node;
  view.leaf = leaf;
  view.box = box;
}
var outsideVeil = null;
var focusable = new Uint8Array(N);
// Zoom steps that would enlarge the view less than this are passed over.
var MIN_GAIN = 1.5;
// Deepest zoom, relative to the whole map.
var MAX_ZOOM = 400;
// Set while the live preview restores a view (no animation then).
var instantZoom = false;
// The running zoom animation's number: a newer zoom ends an older one, so
// that only the last places its labels.
var animation = 0;

leafCells.forEach(function (i) { cells[i].setAttribute("tabindex", "0"); focusable[i] = 1; });

function zoomOf(box) { return full[2] / box[2]; }
function setView(box) {
  var text = box.map(function (v) { return v.toFixed(2); }).join(" ");
  svg.setAttribute("viewBox", text);
  over.setAttribute("viewBox", text);
}
function animate(from, to, done) {
  // Big maps repaint slowly: they (and readers who ask for less motion)
  // go straight to the end.
  var still = instantZoom || leafCells.length > 3000 ||
    (window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)").matches);
  var mine = ++animation;
  if (still) { setView(to); done(); return; }
  var start = null;
  function step(t) {
    if (mine !== animation) { return; }
    if (start === null) { start = t; }
    var k = Math.min(1, (t - start) / 250);
    var e = k < 0.5 ? 2 * k * k : 1 - Math.pow(-2 * k + 2, 2) / 2;
    setView(from.map(function (v, i) { return v + (to[i] - v) * e; }));
    if (k < 1) { requestAnimationFrame(step); } else { setView(to); done(); }
  }
  requestAnimationFrame(step);
}

// The box that shows leaf i of group g large enough for its label: at
// least twice the current zoom, centred on the leaf, inside g's box.
function leafBox(i, g) {
  var outer = data.nodes[g].zoom || full;
  var z = Math.max(2 * zoomOf(view.box), zoomOf(outer));
  var c = centroid(i);
  if (LS) {
    // Large enough for the shortest text the leaf may show, with room.
    var s = shortestFit(i);
    if (s > 0) { z = Math.max(z, 1.25 * MIN_PX / (unitPx() * s)); }
  }
  z = Math.min(z, MAX_ZOOM);
  var w = full[2] / z, h = full[3] / z;
  var x = Math.min(Math.max(c[0] - w / 2, outer[0]), outer[0] + outer[2] - w);
  var y = Math.min(Math.max(c[1] - h / 2, outer[1]), outer[1] + outer[3] - h);
  if (w > outer[2]) { x = c[0] - w / 2; }
  if (h > outer[3]) { y = c[1] - h / 2; }
  return [x, y, w, h];
}

// The element the zoom's own layers go before: the overlay marks and the
// border stay above the labels, as in the picture.
function layersBefore() {
  return svg.querySelector(":scope > .np-unrealized, :scope > .np-unlinked, :scope > .np-border") || null;
}

function setOutside(g) {
  if (outsideVeil && outsideVeil.parentNode) { outsideVeil.parentNode.removeChild(outsideVeil); }
  outsideVeil = null;
  if (g === 0 || !cells[g]) { return; }
  var big = Math.max(full[2], full[3]) * 4;
  outsideVeil = document.createElementNS(NS, "path");
  outsideVeil.setAttribute("class", "np-outside-veil");
  outsideVeil.setAttribute("d", "M" + (full[0] - big) + "," + (full[1] - big) + "h" + 3 * big + "v" + 3 * big +
    "h" + -3 * big + "Z" + cells[g].getAttribute("d"));
  svg.appendChild(outsideVeil);
}

// Whether `el` is the veil over the cells outside the view's group.
export function isOutside(el) { return outsideVeil !== null && el === outsideVeil; }

export function zoomTo(g, leaf) {
  if (g < 0 || g >= N) { return; }
  var box = leaf >= 0 ? leafBox(leaf, g) : (g === 0 ? full : (data.nodes[g].zoom || full));
  var from = svg.getAttribute("viewBox").split(/[\s,]+/).map(Number);
  // Only a keyboard focus (its ring) is drawn again after the zoom: the
  // pointer's hover is cleared, and comes back when the pointer moves.
  var wasCurrent = hovered(), ring = over.querySelector(".np-ring-outer") !== null;
  setViewTo(g, leaf, box);
  clear();
  hushHover();
  dropZoomLabels();
  setOutside(g);
  leafCells.forEach(function (i) {
    var inside = g === 0 || within(g, i);
    if (inside !== !!focusable[i]) {
      focusable[i] = inside ? 1 : 0;
      cells[i].setAttribute("tabindex", inside ? "0" : "-1");
    }
  });
  var zoomed = g !== 0 || leaf >= 0;
  root.classList.toggle("np-zoomed", zoomed);
  root.setAttribute("data-zoom", ids[g]);
  drawCrumbs();
  animate(from, box, function () {
    if (zoomed) { placeZoomLabels(box, zoomOf(box), g, layersBefore()); }
    if (ring && wasCurrent >= 0 && document.activeElement === cells[wasCurrent]) { highlight(wasCurrent, ring); }
    if (window.performance && performance.mark) { performance.mark("nptreemap-zoomed"); }
  });
}

// zoomTo without the animation (the live preview restoring a view).
export function zoomToAtOnce(g, leaf) {
  instantZoom = true;
  zoomTo(g, leaf);
  instantZoom = false;
}

// The labels placed again for the current view (the picture's size on
// screen changed).
export function refitLabels() {
  if (root.classList.contains("np-zoomed")) { placeZoomLabels(view.box, zoomOf(view.box), view.node, layersBefore()); }
}

// Whether the view is zoomed in (there is a level to go up to).
export function isZoomed() { return view.node !== 0 || view.leaf >= 0; }

// One step back: from a leaf to its group, from a group to the group above
// it that is worth zooming into (or the whole map).
export function zoomOut() {
  if (view.leaf >= 0) { zoomTo(view.node, -1); return; }
  for (var k = parents[view.node]; k >= 0; k = parents[k]) {
    if (k === 0 || data.nodes[k].zoom) { zoomTo(k, -1); return; }
  }
}

function drawCrumbs() {
  while (crumbs.firstChild) { crumbs.removeChild(crumbs.firstChild); }
  up.hidden = !isZoomed();
  var path = ancestors(view.node);
  if (view.leaf >= 0) { path.push(view.leaf); }
  path.forEach(function (k, n) {
    if (n > 0) { crumbs.appendChild(document.createTextNode(" \u203a ")); }
    var b = document.createElement("button");
    b.className = "np-crumb";
    b.type = "button";
    b.textContent = labels[k];
    b.setAttribute("data-id", ids[k]);
    if (n === path.length - 1) { b.setAttribute("aria-current", "location"); }
    b.addEventListener("click", function () {
      if (k === view.leaf) { return; }
      var g = k;
      while (g > 0 && !data.nodes[g].zoom) { g = parents[g]; }
      zoomTo(g, -1);
    });
    crumbs.appendChild(b);
  });
}
up.addEventListener("click", function () { zoomOut(); });

// Whether group g is worth a zoom step from the current view.
function gain(g) {
  var z = data.nodes[g].zoom;
  return z ? view.box[2] / z[2] : 0;
}

// The next zoom towards node i: the first group below the view on its way
// that enlarges the view enough; past the last group, the leaf itself
// while its label does not show yet.
export function zoomInto(i) {
  var path = ancestors(i);
  var at = path.indexOf(view.node);
  if (at < 0) { zoomTo(0, -1); return; }
  for (var k = at + 1; k < path.length; k++) {
    var g = path[k];
    if (isLeaf(g)) { break; }
    if (gain(g) >= MIN_GAIN) { zoomTo(g, -1); return; }
  }
  if (isLeaf(i) && view.leaf !== i && !labelShown(i, zoomOf(view.box))) { zoomTo(view.node, i); }
}

// The deepest group worth zooming into that holds node i (a leaf's own
// group first), or the whole map.
function deepestGroup(i) {
  var g = isLeaf(i) ? parents[i] : i;
  while (g > 0 && !data.nodes[g].zoom) { g = parents[g]; }
  return g < 0 ? 0 : g;
}

// Straight to the deepest group under the pointer (shift-, alt- or
// double click on node i); there already, the next step towards i, unless
// `settled` (the second click of a double click whose first one got there).
export function zoomDeepest(i, settled) {
  var g = deepestGroup(i);
  if (g === view.node || !within(view.node, g)) {
    if (!settled) { zoomInto(i); }
    return;
  }
  zoomTo(g, -1);
}

// Straight to node i (the search): its deepest group worth zooming into,
// then the leaf itself when its label would not show there.
export function zoomStraightTo(i) {
  var g = deepestGroup(i);
  var box = g === 0 ? full : data.nodes[g].zoom;
  if (isLeaf(i) && !labelShown(i, zoomOf(box))) {
    setViewTo(g, -1, box);
    zoomTo(g, i);
  } else {
    zoomTo(g, -1);
  }
}
drawCrumbs();
