// The page's events and start: the entry module of the page's script.
// Bundled by src/render/page/bundle.rs; what it imports runs before it. Mouse
// and pen hover, keyboard focus, touch (a first tap shows the tooltip, a
// second tap on the same cell zooms), clicks and keys for the zoom (a click
// one level down; shift-, alt- or double click to the deepest group under
// the pointer; Escape or Backspace one level up), the optimisation slider,
// the unrealised-links toggle, the picture's size within the window (and the
// zoom's labels fitted again to it), and the mark `nptreemap-ready` once
// everything answers.
import {
  N, NS, cells, centroid, data, globally, ids, index, isLeaf, leafOf, map, nodeOf, part, partners, pathLabels, retire, root,
  svg, weights
} from "./model.js";
import { clear, highlight, hovered, hushed, place, placeAt } from "./hover.js";
import { forgetStaticLabels, forgetUnitPx } from "./lod.js";
import { patcher } from "./patch.js";
import { isOutside, isZoomed, refitLabels, view, zoomDeepest, zoomInto, zoomOut, zoomToAtOnce } from "./zoom.js";
import { searchBox } from "./search.js";
import { legendControls } from "./legend.js";
import { showLink } from "./link.js";

var pointer = "mouse";
var tapped = -1;

map.addEventListener("pointerdown", function (e) { pointer = e.pointerType || "mouse"; });
// Where the pointer is, for the hover's hush after a zoom (hover.js): every
// pointer event on the page tells it.
["pointerdown", "pointermove"].forEach(function (type) {
  globally(document, type, function (e) { if (!map.contains(e.target)) { hushed(e.clientX, e.clientY); } });
});
// Pointer events, not mouse events: the mouse events a browser sends after
// a tap must not count as hovering (they would turn the first tap into a
// zoom).
map.addEventListener("pointerover", function (e) {
  if (e.pointerType === "touch" || hushed(e.clientX, e.clientY)) { return; }
  pointer = e.pointerType || "mouse";
  var i = leafOf(e.target);
  if (i === hovered()) { return; }
  if (i < 0) { clear(); return; }
  highlight(i, false);
  place(e.clientX, e.clientY);
});
map.addEventListener("pointermove", function (e) {
  if (e.pointerType === "touch" || hushed(e.clientX, e.clientY)) { return; }
  // The first move after a zoom's hush: the cell under the pointer now.
  var i = leafOf(e.target);
  if (i >= 0 && i !== hovered()) { highlight(i, false); }
  if (hovered() >= 0) { place(e.clientX, e.clientY); }
});
map.addEventListener("pointerleave", function (e) {
  if (e.pointerType !== "touch") { clear(); }
});

// Keyboard: Tab moves through the cells, the focused one behaves as
// hovered and wears the focus ring.
map.addEventListener("focusin", function (e) {
  var i = leafOf(e.target);
  if (i < 0) { return; }
  var el = cells[i];
  if (!el.hasAttribute("role")) {
    el.setAttribute("role", "img");
    el.setAttribute("aria-label", pathLabels(i).join(" \u203a ") + ", weight " + weights[i] + (data.unit || ""));
  }
  // The ring for keyboard focus; a click focuses the cell too, quietly.
  var ring = true;
  try { ring = el.matches(":focus-visible"); } catch (err) { ring = true; }
  highlight(i, ring);
  placeAt(i);
});
map.addEventListener("focusout", function (e) {
  if (!map.contains(e.relatedTarget)) { clear(); }
});

map.addEventListener("click", function (e) {
  if (isOutside(e.target)) { zoomOut(); return; }
  var i = nodeOf(e.target);
  if (i < 0) { return; }
  if (pointer === "touch" && isLeaf(i) && tapped !== i) {
    // Touch: the first tap acts as hover.
    tapped = i;
    highlight(i, false);
    placeAt(i);
    return;
  }
  tapped = -1;
  // The second click of a double click goes on to the deepest group (the
  // first went one level down); a third and more do nothing.
  if (e.detail > 2) { return; }
  if (e.detail !== 2 && isLeaf(i)) { showLink(i); }
  if (e.shiftKey || e.altKey || e.detail === 2) { zoomDeepest(i, e.detail === 2); } else { zoomInto(i); }
});
// A tap elsewhere on the page ends the touch hover.
globally(document, "click", function (e) {
  if (pointer === "touch" && !map.contains(e.target) && hovered() >= 0) { tapped = -1; clear(); }
});
map.addEventListener("keydown", function (e) {
  var i = leafOf(e.target);
  if ((e.key === "Enter" || e.key === " ") && i >= 0) { e.preventDefault(); showLink(i); zoomInto(i); }
});
root.addEventListener("keydown", function (e) {
  if (e.key === "Escape" && isZoomed() && !e.defaultPrevented) { zoomOut(); }
});
// Backspace goes up one level, from anywhere in the map's container but a
// text field, or from the page itself when this is its first map (a click
// on the map focuses a cell, so the key usually starts inside).
function typing(el) {
  return !!el && (el.isContentEditable || /^(INPUT|TEXTAREA|SELECT)$/.test(el.tagName));
}
globally(document, "keydown", function (e) {
  if (e.key !== "Backspace" || e.defaultPrevented || e.altKey || e.ctrlKey || e.metaKey || !isZoomed()) { return; }
  var t = e.target;
  var mine = root.contains(t) || ((t === document.body || t === document.documentElement) &&
    document.querySelector(".nptreemap") === root);
  if (!mine || typing(t)) { return; }
  e.preventDefault();
  zoomOut();
});

// The optimisation slider: frame k drawn over the map, the last position
// the finished picture.
(function () {
  var slider = part("frame");
  if (!slider || !data.frames) { return; }
  var frameLayer = document.createElementNS(NS, "g");
  frameLayer.setAttribute("class", "np-frame-layer");
  frameLayer.setAttribute("pointer-events", "none");
  frameLayer.setAttribute("stroke", "#ffffff");
  frameLayer.setAttribute("stroke-width", "1");
  svg.appendChild(frameLayer);
  var caption = part("frame-label");
  function showFrame() {
    var k = parseInt(slider.value, 10);
    while (frameLayer.firstChild) { frameLayer.removeChild(frameLayer.firstChild); }
    var frame = data.frames[k];
    if (!frame) { caption.textContent = "final layout"; return; }
    frame.cells.forEach(function (c) {
      var p = document.createElementNS(NS, "path");
      p.setAttribute("d", c[1]);
      p.setAttribute("fill", c[2]);
      p.setAttribute("data-frame-id", c[0]);
      frameLayer.appendChild(p);
    });
    caption.textContent = (k + 1) + " / " + data.frames.length + ": " + frame.label;
  }
  slider.addEventListener("input", showFrame);
  showFrame();
})();

// The unrealised links: dashed lines between the centres of similar cells
// that do not touch, drawn from the data into the picture's (empty) group
// the first time the checkbox asks for them; drawn again on demand after a
// live patch (`redraw`).
var unrealized = (function () {
  var toggleBox = part("unrealized-toggle");
  var group = svg.querySelector(".np-unrealized");
  var drawn = false;
  function toggle() {
    if (toggleBox.checked && group && !drawn) {
      drawn = true;
      var frag = document.createDocumentFragment();
      for (var i = 0; i < N; i++) {
        partners[i].forEach(function (p) {
          var j = p[0];
          if (p[1] || j < i || !cells[i] || !cells[j]) { return; }
          var a = centroid(i), b = centroid(j);
          var l = document.createElementNS(NS, "line");
          l.setAttribute("x1", a[0].toFixed(2)); l.setAttribute("y1", a[1].toFixed(2));
          l.setAttribute("x2", b[0].toFixed(2)); l.setAttribute("y2", b[1].toFixed(2));
          frag.appendChild(l);
        });
      }
      group.appendChild(frag);
    }
    root.classList.toggle("np-hide-unrealized", !toggleBox.checked);
  }
  toggleBox.addEventListener("change", toggle);
  toggle();
  return {
    redraw: function () {
      group = svg.querySelector(".np-unrealized");
      while (group && group.firstChild) { group.removeChild(group.firstChild); }
      drawn = false;
      toggle();
    }
  };
})();

// As wide as the container allows, and no wider than keeps the whole
// picture in the window below what stands above it.
(function () {
  var aspect = parseFloat(map.getAttribute("data-aspect")) || 1;
  function fit() {
    var above = map.getBoundingClientRect().top - root.getBoundingClientRect().top;
    var room = Math.max(240, window.innerHeight - above - 16);
    map.style.maxWidth = Math.round(room * aspect) + "px";
    forgetUnitPx();
    refitLabels();
  }
  fit();
  globally(window, "resize", fit);
  // The legend's and the title's toggles change what stands above the map.
  legendControls(fit);
})();

// glue: issue 25. The live preview (src/serve/live.js) replaces this map
// with its rebuilt one and carries the view across: the zoomed group and
// leaf, the search text, the hovered cell.
root.npView = {
  get: function () {
    return { node: ids[view.node], leaf: view.leaf >= 0 ? ids[view.leaf] : null,
      current: hovered() >= 0 ? ids[hovered()] : null, search: searchBox.value };
  },
  set: function (s) {
    var g = index.get(s.node), l = s.leaf === null ? -1 : index.get(s.leaf);
    if (g !== undefined && (g !== 0 || l !== -1)) { zoomToAtOnce(g, l === undefined ? -1 : l); }
    if (s.search) { searchBox.value = s.search; }
    var c = s.current === null ? undefined : index.get(s.current);
    if (c !== undefined && isLeaf(c)) { highlight(c, false); placeAt(c); }
  }
};

// glue: issue 30. The live preview calls this on the map it replaces, so
// that nothing outside the map keeps the old one alive.
root.npRetire = retire;

// glue: issue 32. The live preview patches this map in place (page/patch.js).
// The hovered or focused cell stays so, drawn again with its new outline
// and neighbours.
root.npPatch = patcher(function () {
  var shown = hovered();
  forgetStaticLabels();
  unrealized.redraw();
  refitLabels();
  if (shown >= 0) { highlight(shown, false); }
});

if (window.performance && performance.mark) { performance.mark("nptreemap-ready"); }
