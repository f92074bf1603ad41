// The search box and its list of matches.
// A module of the page's script (bundled by src/render/page/bundle.rs): finds
// nodes by label or by path as the reader types (case-insensitive), lists the
// best matches (at most MATCHES: whole labels, then label starts, then label
// parts, then paths), and on Enter (or a click on a match) zooms to the match
// and highlights it. `/` anywhere outside a text field jumps to the box. A
// combobox with a listbox, for screen readers.
import { N, cells, globally, ids, labels, map, parents, part, pathLabels, root } from "./model.js";
import { highlight, placeAt } from "./hover.js";
import { zoomStraightTo } from "./zoom.js";

export const searchBox = part("search-box");
var list = part("matches");
var MATCHES = 12;
var lowerLabels = null, lowerPaths = null, lowerIds = null;
var matches = [], active = -1, found = -1;

function lowerIndex() {
  if (lowerLabels) { return; }
  lowerLabels = labels.map(function (l) { return l.toLowerCase(); });
  // The ids too: a label may show only the last segment of a path-like id
  // (`render.labels.text`), and a reader types the whole `a.b.c`.
  lowerIds = ids.map(function (d) { return String(d).toLowerCase(); });
  lowerPaths = new Array(N);
  for (var i = 0; i < N; i++) {
    // Breadth-first order: the parent's path is there already.
    var p = parents[i] > 0 ? lowerPaths[parents[i]] + "/" : "";
    lowerPaths[i] = p + lowerLabels[i];
  }
}

// The best matches for `q` (at most MATCHES) and how many there are.
function search(q) {
  lowerIndex();
  var ranks = [[], [], [], []], total = 0;
  for (var i = 1; i < N; i++) {
    var l = lowerLabels[i], r;
    var d = lowerIds[i];
    if (l === q || d === q) { r = 0; } else if (l.lastIndexOf(q, 0) === 0) { r = 1; } else if (l.indexOf(q) >= 0) { r = 2; } else if (lowerPaths[i].indexOf(q) >= 0 || d.indexOf(q) >= 0) { r = 3; } else { continue; }
    total++;
    if (ranks[r].length < MATCHES) { ranks[r].push(i); }
  }
  return { list: [].concat(ranks[0], ranks[1], ranks[2], ranks[3]).slice(0, MATCHES), total: total };
}

function showMatches() {
  var q = searchBox.value.trim().toLowerCase();
  while (list.firstChild) { list.removeChild(list.firstChild); }
  matches = [];
  active = -1;
  searchBox.removeAttribute("aria-activedescendant");
  if (!q) {
    list.hidden = true;
    searchBox.setAttribute("aria-expanded", "false");
    return;
  }
  var r = search(q);
  matches = r.list;
  matches.forEach(function (i, k) {
    var li = document.createElement("li");
    li.id = list.id + "-" + k;
    li.setAttribute("role", "option");
    li.setAttribute("aria-selected", "false");
    li.setAttribute("data-id", ids[i]);
    var name = document.createElement("span");
    name.className = "np-match-label";
    name.textContent = labels[i];
    li.appendChild(name);
    var where = pathLabels(i).slice(0, -1).join(" \u203a ");
    if (where) {
      var p = document.createElement("span");
      p.className = "np-match-path";
      p.textContent = where;
      li.appendChild(p);
    }
    li.addEventListener("mousedown", function (e) { e.preventDefault(); });
    li.addEventListener("click", function () { go(i); });
    list.appendChild(li);
  });
  var note = document.createElement("li");
  note.className = "np-match-none";
  note.setAttribute("aria-disabled", "true");
  note.textContent = r.total === 0 ? "no match" :
    r.total > matches.length ? (r.total - matches.length) + " more; type more to narrow" : "";
  if (note.textContent) { list.appendChild(note); }
  list.hidden = false;
  searchBox.setAttribute("aria-expanded", "true");
  if (matches.length) { select(0); }
}

function select(k) {
  var items = list.querySelectorAll("[role=option]");
  if (!items.length) { return; }
  k = (k + items.length) % items.length;
  if (active >= 0 && items[active]) { items[active].setAttribute("aria-selected", "false"); }
  active = k;
  items[k].setAttribute("aria-selected", "true");
  items[k].scrollIntoView({ block: "nearest" });
  searchBox.setAttribute("aria-activedescendant", items[k].id);
}

function closeList() {
  list.hidden = true;
  searchBox.setAttribute("aria-expanded", "false");
}

// Zooms to match i and highlights it: a leaf with its neighbourhood, a
// group with its cells, either ringed.
function go(i) {
  closeList();
  found = i;
  root.setAttribute("data-found", ids[i]);
  var marks = window.performance && performance.getEntriesByName ? performance.getEntriesByName("nptreemap-zoomed").length : 0;
  zoomStraightTo(i);
  function mark() {
    if (found !== i || !cells[i]) { return; }
    // A leaf with its neighbourhood; a group with all its cells (see
    // highlight); both ringed.
    highlight(i, true);
    placeAt(i);
  }
  // After the zoom has placed its labels (at once on big maps).
  var tries = 0;
  (function wait() {
    var now = window.performance && performance.getEntriesByName ? performance.getEntriesByName("nptreemap-zoomed").length : marks + 1;
    if (now > marks || ++tries > 120) { mark(); } else { requestAnimationFrame(wait); }
  })();
}

searchBox.addEventListener("input", showMatches);
searchBox.addEventListener("keydown", function (e) {
  if (e.key === "ArrowDown" || e.key === "ArrowUp") {
    e.preventDefault();
    if (list.hidden) { showMatches(); }
    select(active + (e.key === "ArrowDown" ? 1 : -1));
  } else if (e.key === "Enter") {
    e.preventDefault();
    if (list.hidden) { showMatches(); }
    if (matches.length) { go(matches[Math.max(0, active)]); }
  } else if (e.key === "Escape") {
    if (!list.hidden) { closeList(); } else if (searchBox.value) { searchBox.value = ""; showMatches(); } else { searchBox.blur(); }
    e.stopPropagation();
  }
});
searchBox.addEventListener("focus", function () { if (searchBox.value.trim()) { showMatches(); } });
searchBox.addEventListener("blur", closeList);

// `/` focuses the box of the map in use: the one holding the focus, else
// the one the pointer was on last, else the first in the document.
globally(document, "keydown", function (e) {
  if (e.key !== "/" || e.ctrlKey || e.metaKey || e.altKey || e.defaultPrevented) { return; }
  var t = e.target;
  if (t && (t.isContentEditable || /^(input|textarea|select)$/i.test(t.tagName || ""))) { return; }
  var maps = document.querySelectorAll(".nptreemap");
  var mine = root.contains(document.activeElement);
  var anyFocus = Array.prototype.some.call(maps, function (m) { return m.contains(document.activeElement); });
  var last = document.documentElement.getAttribute("data-np-last");
  var chosen = mine || (!anyFocus && (last ? last === root.id : maps[0] === root));
  if (!chosen) { return; }
  e.preventDefault();
  searchBox.focus();
  searchBox.select();
});
map.addEventListener("pointerenter", function () {
  document.documentElement.setAttribute("data-np-last", root.id);
});
