// Hover, focus and the found cell, drawn on a layer of their own.
// A module of the page's script (bundled by src/render/page/bundle.rs). The
// picture itself never changes on hover: a second SVG over it (its own
// compositing layer) holds a veil in the background colour, three quarters
// opaque, and on top of it the hovered cell and its neighbours drawn again
// with their labels and the tabs between them, the partners' outlines and the
// focus ring. So a hover repaints that small layer only, whatever the size of
// the map, and tabs, labels and markers of the other cells are dimmed with
// them.
import {
  EMPTY, NS, cells, data, ids, index, isLeaf, labels, map, near, parents, part, partners, pathLabels, root, svg, weights
} from "./model.js";
import { labelFor } from "./lod.js";

export const over = svg.cloneNode(false);
over.removeAttribute("width");
over.removeAttribute("height");
over.setAttribute("class", "np-hover");
over.setAttribute("aria-hidden", "true");
over.setAttribute("focusable", "false");
var veil = document.createElementNS(NS, "rect");
veil.setAttribute("class", "np-veil");
(function () {
  var vb = svg.getAttribute("viewBox").split(/[\s,]+/).map(Number);
  veil.setAttribute("x", vb[0]); veil.setAttribute("y", vb[1]);
  veil.setAttribute("width", vb[2]); veil.setAttribute("height", vb[3]);
})();
var layer = document.createElementNS(NS, "g");
over.appendChild(veil);
over.appendChild(layer);
map.appendChild(over);
var tip = part("tooltip");
var current = -1;
// The leaf (or found group) drawn on the layer, -1 when none.
export function hovered() { return current; }
// After a zoom the cell under a pointer that has not moved is another one,
// and the browser says the pointer is over it: the hover stays off until
// the pointer moves (main.js asks `hushed` before drawing a hover).
var hush = { on: false, x: -1e9, y: -1e9 };
export function hushHover() { hush.on = true; }
// Whether a pointer event at (x, y) is to be passed over: the hover is
// hushed and the pointer is where it was at the zoom. Any other position
// ends the hush; a position is remembered while not hushed.
export function hushed(x, y) {
  if (hush.on && Math.abs(x - hush.x) < 1 && Math.abs(y - hush.y) < 1) { return true; }
  hush.on = false;
  hush.x = x;
  hush.y = y;
  return false;
}

// Tabs by the leaves they join, found on first use (a page that is only
// looked at never pays for them).
var tabsOf = null;
function tabsFor(i) {
  if (!tabsOf) {
    tabsOf = new Map();
    Array.prototype.forEach.call(svg.querySelectorAll("g.np-tab"), function (t) {
      [t.getAttribute("data-a"), t.getAttribute("data-b")].forEach(function (id) {
        var k = index.get(id);
        if (k === undefined) { return; }
        if (!tabsOf.has(k)) { tabsOf.set(k, []); }
        tabsOf.get(k).push(t);
      });
    });
  }
  return tabsOf.get(i) || EMPTY;
}

// A copy of `el` for the layer, wrapped in a copy of its parent group
// (font, fill and halo come from there); never a second data-id.
function copyOf(el, cls) {
  var c = el.cloneNode(true);
  c.removeAttribute("data-id");
  c.removeAttribute("tabindex");
  var t = c.querySelector && c.querySelector("title");
  if (t) { c.removeChild(t); }
  if (cls) { c.setAttribute("class", cls); }
  return c;
}
function inGroupOf(el, child) {
  var g = el.parentNode.cloneNode(false);
  g.removeAttribute("id");
  g.appendChild(child);
  return g;
}
function outline(i, cls) {
  var c = copyOf(cells[i], cls);
  c.setAttribute("data-of", ids[i]);
  c.setAttribute("fill", "none");
  return c;
}

function clearLayer() {
  while (layer.firstChild) { layer.removeChild(layer.firstChild); }
}
export function clear() {
  current = -1;
  clearLayer();
  over.classList.remove("np-on");
  tip.hidden = true;
  root.removeAttribute("data-current");
}

// The hovered (or focused, or found) leaf i: its neighbourhood over the
// veil, its partners outlined, a ring when `ring`, and the tooltip.
export function highlight(i, ring) {
  current = i;
  clearLayer();
  var keep = new Set(near[i]);
  keep.add(i);
  var frag = document.createDocumentFragment();
  // A group (the search found one) keeps all of its cells: the veil has a
  // hole in the group's shape instead of copies of its many cells.
  var holed = !isLeaf(i) && !!cells[i];
  veil.style.display = holed ? "none" : "";
  if (holed) {
    var x = +veil.getAttribute("x"), y = +veil.getAttribute("y");
    var w = +veil.getAttribute("width"), h = +veil.getAttribute("height");
    var hole = document.createElementNS(NS, "path");
    hole.setAttribute("class", "np-veil np-veil-holed");
    hole.setAttribute("fill-rule", "evenodd");
    hole.setAttribute("d", "M" + x + "," + y + "h" + w + "v" + h + "h" + -w + "Z" + cells[i].getAttribute("d"));
    frag.appendChild(hole);
  }
  keep.forEach(function (k) {
    if (!cells[k]) { return; }
    var c = copyOf(cells[k], "np-near");
    c.setAttribute("data-of", ids[k]);
    frag.appendChild(c);
  });
  keep.forEach(function (k) {
    tabsFor(k).forEach(function (t) {
      var a = index.get(t.getAttribute("data-a")), b = index.get(t.getAttribute("data-b"));
      // Each tab once, from its first end, and only between two kept cells.
      if (k === a && keep.has(b)) {
        var c = copyOf(t, "np-tab");
        frag.appendChild(inGroupOf(t, c));
      }
    });
  });
  keep.forEach(function (k) {
    var l = labelFor(k);
    if (l) {
      var c = copyOf(l);
      c.setAttribute("data-of", ids[k]);
      frag.appendChild(inGroupOf(l, c));
    }
  });
  partners[i].forEach(function (p) {
    if (cells[p[0]]) {
      frag.appendChild(outline(p[0], p[1] ? "np-partner" : "np-partner np-partner-unrealized"));
    }
  });
  if (ring) {
    frag.appendChild(outline(i, "np-ring-outer"));
    frag.appendChild(outline(i, "np-ring-inner"));
  }
  layer.appendChild(frag);
  over.classList.add("np-on");
  root.setAttribute("data-current", ids[i]);
  fillTip(i);
}

// The tooltip: the path below the map's root, the weight as the picture
// writes it, the similar cells, then the node's own fields.
function fillTip(i) {
  while (tip.firstChild) { tip.removeChild(tip.firstChild); }
  function line(cls, text) {
    var d = document.createElement("div");
    d.className = cls;
    d.textContent = text;
    tip.appendChild(d);
  }
  line("np-tip-path", pathLabels(i).join(" \u203a "));
  line("np-tip-line", "weight " + weights[i] + (data.unit || ""));
  var ps = partners[i];
  if (ps.length) {
    var apart = ps.filter(function (p) { return !p[1]; }).length;
    line("np-tip-line", "similar to " + ps.length + " cell" + (ps.length === 1 ? "" : "s") +
      (apart ? ", " + apart + " not adjacent" : ", all adjacent"));
  }
  (data.nodes[i].fields || EMPTY).forEach(function (f) { line("np-tip-line", f[0] + ": " + f[1]); });
  // Items of weight 0 beside the cell (or under it) that have no cell.
  [parents[i], i].forEach(function (k) {
    var e = k >= 0 && data.nodes[k].empty;
    if (!e) { return; }
    line("np-tip-line np-tip-empty", labels[k] + " also holds " + e.items + " item" + (e.items === 1 ? "" : "s") +
      " of weight 0, not drawn: " + e.names.join(", ") + (e.more ? " and " + e.more + " more" : ""));
  });
  tip.hidden = false;
}

// Beside the point, flipped to its other side near the window's edge so
// the tooltip never runs out of view; moved by a transform (no layout).
export function place(cx, cy) {
  // Fractional sizes: a rounded one lets the last fraction of a pixel out.
  var r = tip.getBoundingClientRect(), w = Math.ceil(r.width), h = Math.ceil(r.height);
  var x = cx + 14, y = cy + 14;
  if (x + w > window.innerWidth) { x = Math.max(0, cx - 14 - w); }
  if (y + h > window.innerHeight) { y = Math.max(0, cy - 14 - h); }
  tip.style.transform = "translate(" + Math.round(x) + "px," + Math.round(y) + "px)";
}
// Below the cell's middle (above it near the window's bottom), so the
// tooltip leaves the cell in view.
export function placeAt(i) {
  var r = cells[i].getBoundingClientRect();
  place(r.left + r.width / 2, r.top + Math.max(r.height - 8, r.height / 2));
}
