// The legend as a way into the map, and the header folded on a phone.
// A module of the page's script (bundled by src/render/page/bundle.rs). Each
// group's entry (the first ones and those of the full list that "and N more
// groups" opens) highlights its group on the map while the pointer or the
// focus is on it, and zooms to it on a click or Enter. The full list scrolls
// and is filtered as the reader types (by name or id, case-insensitive;
// Enter zooms to the first match, Escape closes it). On a narrow screen
// (page.css) the title shows one line and the legend folds behind a button,
// so that the map starts near the top; both unfold on a click.
import { index, part, root } from "./model.js";
import { clear, highlight, hovered } from "./hover.js";
import { zoomStraightTo } from "./zoom.js";

var legend = part("legend");
var tip = part("tooltip");
var lit = -1;

function nodeOfEntry(el) {
  var li = el && el.closest ? el.closest("li[data-id]") : null;
  if (!li || !legend || !legend.contains(li)) { return -1; }
  var i = index.get(li.getAttribute("data-id"));
  return i === undefined ? -1 : i;
}
// The group drawn bright on the map (the tooltip stays hidden: it would
// cover the list).
function light(i) {
  lit = i;
  highlight(i, false);
  tip.hidden = true;
}
function unlight() {
  if (lit >= 0 && hovered() === lit) { clear(); }
  lit = -1;
}
function go(i) {
  var more = legend.querySelector(".np-legend-more details");
  if (more) { more.open = false; }
  unlight();
  zoomStraightTo(i);
}

// The full list: filtered as the reader types.
function filterList() {
  var box = legend.querySelector(".np-legend-filter");
  var list = legend.querySelector(".np-legend-list");
  var none = legend.querySelector(".np-legend-none");
  if (!box || !list) { return; }
  function matches() {
    return Array.prototype.filter.call(list.children, function (li) { return !li.hidden; });
  }
  box.addEventListener("input", function () {
    var q = box.value.trim().toLowerCase();
    var shown = 0;
    Array.prototype.forEach.call(list.children, function (li) {
      var text = (li.textContent + "\u0000" + (li.getAttribute("data-id") || "")).toLowerCase();
      li.hidden = q !== "" && text.indexOf(q) < 0;
      if (!li.hidden) { shown++; }
    });
    if (none) { none.hidden = shown > 0; }
  });
  box.addEventListener("keydown", function (e) {
    var first = matches()[0];
    if (e.key === "Enter" && first) {
      e.preventDefault();
      var i = nodeOfEntry(first);
      if (i >= 0) { go(i); }
    } else if (e.key === "ArrowDown" && first) {
      e.preventDefault();
      first.focus();
    } else if (e.key === "Escape") {
      e.preventDefault();
      var d = box.closest("details");
      d.open = false;
      d.querySelector("summary").focus();
    }
  });
  var details = box.closest("details");
  details.addEventListener("toggle", function () {
    if (details.open) { box.focus({ preventScroll: true }); } else { unlight(); }
  });
}

// Entries: hover and focus highlight, click and Enter zoom, the arrows
// move through the full list.
function entries() {
  Array.prototype.forEach.call(legend.querySelectorAll("li[data-id]"), function (li) {
    li.tabIndex = 0;
    li.setAttribute("role", "button");
    li.setAttribute("aria-label", "Zoom to " + li.textContent);
  });
  legend.addEventListener("pointerover", function (e) {
    var i = nodeOfEntry(e.target);
    if (i >= 0 && i !== lit && e.pointerType !== "touch") { light(i); }
  });
  legend.addEventListener("pointerout", function (e) {
    if (nodeOfEntry(e.relatedTarget) < 0) { unlight(); }
  });
  legend.addEventListener("focusin", function (e) {
    var i = nodeOfEntry(e.target);
    if (i >= 0) { light(i); }
  });
  legend.addEventListener("focusout", function (e) {
    if (nodeOfEntry(e.relatedTarget) < 0) { unlight(); }
  });
  legend.addEventListener("click", function (e) {
    var i = nodeOfEntry(e.target);
    if (i >= 0) { go(i); }
  });
  legend.addEventListener("keydown", function (e) {
    var i = nodeOfEntry(e.target);
    if (i < 0) { return; }
    if (e.key === "Enter" || e.key === " ") {
      e.preventDefault();
      go(i);
    } else if (e.key === "ArrowDown" || e.key === "ArrowUp") {
      var li = e.target.closest("li");
      var step = e.key === "ArrowDown" ? "nextElementSibling" : "previousElementSibling";
      for (var n = li[step]; n; n = n[step]) {
        if (!n.hidden) { e.preventDefault(); n.focus(); return; }
      }
    }
  });
}

// On a narrow screen: a button that unfolds the legend, and the title
// unfolded by a click; `refit` sizes the map again after either.
function folds(refit) {
  var title = part("title");
  if (title) {
    title.title = title.textContent;
    title.addEventListener("click", function () {
      root.classList.toggle("np-title-open");
      refit();
    });
  }
  if (!legend) { return; }
  var groups = legend.querySelectorAll(":scope > li").length;
  var toggle = document.createElement("button");
  toggle.type = "button";
  toggle.className = "np-legend-toggle";
  toggle.textContent = "Legend";
  toggle.setAttribute("aria-expanded", "false");
  toggle.setAttribute("aria-controls", legend.id);
  toggle.title = groups + " entries";
  toggle.addEventListener("click", function () {
    var open = root.classList.toggle("np-legend-shown");
    toggle.setAttribute("aria-expanded", open ? "true" : "false");
    refit();
  });
  legend.parentNode.insertBefore(toggle, legend);
}

export function legendControls(refit) {
  if (legend) {
    entries();
    filterList();
  }
  folds(refit);
}

// The live preview's patch brought a new legend (page/patch.js): it takes
// the old one's place, and its entries and list work as the old ones did.
export function renewLegend(fresh) {
  if (!legend || !fresh) { return; }
  unlight();
  legend.parentNode.replaceChild(fresh, legend);
  legend = fresh;
  entries();
  filterList();
}
