// The live preview's browser side: the page follows each rebuild in place.
// src/serve/mod.rs serves it; the page as served loads it, the page on disk
// never does. It listens to the server's event stream; when its dataset is
// rebuilt it asks the server for what changed since the page it shows
// (`?since=KEY`, issue 32: src/serve/pages.rs) and patches the map in place:
// only the changed cells morph, the changed labels and tabs fade across, and
// the map's script reads the changed nodes again (page/patch.js), so the
// view stays as it is at any size. When the server cannot patch (a node
// added or removed, another legend, a page it no longer has) it fetches the
// page again and morphs every cell of the picture from
// its old polygon to its new one (matched by node id; new cells grow from
// their most similar sibling and fade in, removed ones fade out; labels and
// tabs fade across) in under half a second, then puts the new map in place of
// the old one in the same document (no reload) and carries the view over:
// zoom, search text, hovered or focused cell. With prefers-reduced-motion, or
// past BIG cells, it swaps at once. A failed rebuild shows its message over the
// last good picture until the next good one, or until the config reloads. A
// small panel gives the last update's stability figures (as `eval --previous`
// defines them: leaf centroid displacement as a share of the canvas diagonal,
// mean and largest; realised constraints kept), docked beside the map and
// folded by a click. The morph is
// src/render/page/history.js's, imported (both bundled by
// src/render/page/bundle.rs into the one script src/serve/mod.rs serves).
//
// Catching up (issue 30): the page knows the build key it was served with
// (src/serve/events.rs); every stream, the first and each reconnection,
// starts with the current keys, and a page whose key is not the current one
// fetches the page again. So a page that missed rebuilds while its stream was
// down, or outlived the daemon that served it, shows the current map once the
// stream is back.
//
// Memory (issue 30): the page keeps one map. The history of layouts
// (`history:`) is the page's own (page/past.js, its ◀/▶ control, each layout
// once, in the served page's data), not a list of fetched pages; the map that
// is replaced is retired (`npRetire`), so nothing keeps it alive.
import { animate as morphFrames, centroid, draw, fade, points, still, track } from "../render/page/history.js";

var me = document.currentScript;
var NONCE = me.nonce || me.getAttribute("nonce") || "";
var DATASET = me.getAttribute("data-dataset");
// The build key of the map shown (src/serve/events.rs).
var KEY = me.getAttribute("data-key") || "";
var EVENTS = me.getAttribute("data-events") || "/_np/events";
// The morph, then the new labels fading in: 360 + 120 ms, under 500.
var MORPH_MS = 360, FADE_MS = 120;
// Maps with more leaves than this swap at once (as the page's zoom does).
var BIG = 3000;
// Test hooks and counters: `slow` stretches the animation (screenshots
// of the morph midway), `frames` counts this script's animation frames.
// `loads` counts whole pages fetched, `patches` patches applied, `patched`
// the cells the last patch changed; `whole` turns the patch off (a
// benchmark's baseline, benches/live.py).
var live = window.npLive = { updates: 0, frames: 0, slow: 1, figures: null, errors: 0, animating: 0,
  loads: 0, patches: 0, patched: 0, whole: false };

function container() { return document.querySelector(".nptreemap"); }
function pictureOf(c) { return c ? c.querySelector(".np-map > svg:not(.np-hover)") : null; }

// ---- the panel: status, figures ----
// Docked beside the map (under it on a narrow window; live.css), never over
// it or the tooltip; a click on its status line folds the figures away.
var panel = document.createElement("details");
panel.className = "np-live-panel";
panel.open = true;
var statusLine = document.createElement("summary");
statusLine.className = "np-live-status";
statusLine.setAttribute("role", "status");
statusLine.textContent = "live: connecting";
var figuresLine = document.createElement("div");
figuresLine.className = "np-live-figures";
figuresLine.setAttribute("aria-live", "polite");
figuresLine.textContent = "no update yet";
panel.appendChild(statusLine);
panel.appendChild(figuresLine);
document.body.appendChild(panel);
document.body.classList.add("np-live-docked");
document.documentElement.setAttribute("data-np-live", "");
// The map fits itself to the window on a resize (page/main.js): the
// panel's width changes what is left for it.
panel.addEventListener("toggle", function () { window.dispatchEvent(new window.Event("resize")); });

var banner = document.createElement("div");
banner.className = "np-live-error";
banner.setAttribute("role", "alert");
banner.hidden = true;
document.body.appendChild(banner);
var problems = new Map();
function showProblems() {
  while (banner.firstChild) { banner.removeChild(banner.firstChild); }
  problems.forEach(function (e) {
    var p = document.createElement("p");
    var head = document.createElement("strong");
    var where = e.file ? " in " + e.file.split(/[\\/]/).pop() + (e.line ? ", line " + e.line : "") : "";
    head.textContent = e.dataset + ": error" + where + ":";
    p.appendChild(head);
    p.appendChild(document.createTextNode(" " + e.message));
    var note = document.createElement("span");
    note.className = "np-live-consequence";
    note.textContent = " (" + e.consequence + "; the last good picture is shown)";
    p.appendChild(note);
    banner.appendChild(p);
  });
  banner.hidden = problems.size === 0;
  document.documentElement.toggleAttribute("data-np-live-error", problems.size > 0);
}

// ---- the figures of an update ----
function model(c) {
  var block = c && c.querySelector("script.np-data");
  var data = null;
  try { data = block ? JSON.parse(block.textContent) : null; } catch (err) { data = null; }
  var nodes = data ? data.nodes : [];
  var parent = new Set(), cells = new Map(), pairs = new Set(), similar = new Map(), kin = new Map();
  function link(list, k, v) { if (!list.has(k)) { list.set(k, []); } list.get(k).push(v); }
  nodes.forEach(function (n) {
    if (typeof n.parent === "number") { parent.add(n.parent); link(kin, n.parent, n.id); }
  });
  var svg = pictureOf(c);
  if (svg) {
    Array.prototype.forEach.call(svg.querySelectorAll("path[data-id]"), function (el) {
      cells.set(el.getAttribute("data-id"), el);
    });
  }
  nodes.forEach(function (n, i) {
    (n.partners || []).forEach(function (p) {
      var other = nodes[p[0]];
      if (other) { link(similar, n.id, other.id); link(similar, other.id, n.id); }
      if (other && p[1]) { pairs.add(n.id < other.id ? n.id + "\u0000" + other.id : other.id + "\u0000" + n.id); }
    });
  });
  var leaves = [];
  nodes.forEach(function (n, i) { if (!parent.has(i)) { leaves.push(n.id); } });
  var ids = new Set(nodes.map(function (n) { return n.id; }));
  var siblings = new Map();
  nodes.forEach(function (n) {
    if (typeof n.parent === "number" && nodes[n.parent]) { siblings.set(n.id, kin.get(n.parent) || []); }
  });
  return { leaves: leaves, cells: cells, realized: pairs, ids: ids, similar: similar, siblings: siblings,
    weights: new Map(nodes.map(function (n) { return [n.id, n.weight]; })) };
}
// Where a new cell grows from: its most similar node that was already
// there (a constraint partner), else a sibling that was, else nowhere.
function origin(id, before, after) {
  var near = (after.similar.get(id) || []).concat(after.siblings.get(id) || []);
  for (var k = 0; k < near.length; k++) {
    if (near[k] !== id && before.cells.has(near[k])) { return before.cells.get(near[k]); }
  }
  return null;
}
function figures(before, after, viewBox) {
  var diag = Math.hypot(viewBox[2], viewBox[3]) || 1;
  var n = 0, sum = 0, max = 0, maxId = null, changed = 0;
  after.leaves.forEach(function (id) {
    var a = before.cells.get(id), b = after.cells.get(id);
    if (!a || !b) { return; }
    var ca = centroid(points(a.getAttribute("d"))), cb = centroid(points(b.getAttribute("d")));
    var moved = Math.hypot(cb[0] - ca[0], cb[1] - ca[1]) / diag;
    n++; sum += moved;
    if (moved > max) { max = moved; maxId = id; }
    if (before.weights.get(id) !== after.weights.get(id)) { changed++; }
  });
  var realized = 0, kept = 0;
  before.realized.forEach(function (key) {
    var two = key.split("\u0000");
    if (!after.ids.has(two[0]) || !after.ids.has(two[1])) { return; }
    realized++;
    if (after.realized.has(key)) { kept++; }
  });
  return { leaves: n, changed: changed, mean: n ? sum / n : 0, max: max, largest: maxId, realized: realized, kept: kept };
}
function pct(x) { return (100 * x).toFixed(x < 0.001 ? 2 : 1) + "%"; }
function showFigures(f) {
  live.figures = f;
  figuresLine.textContent = "Last update: cells moved " + pct(f.mean) + " on average, at most " + pct(f.max) +
    " of the diagonal" + (f.largest ? " (" + f.largest + ")" : "") + "; " + f.changed + " of " + f.leaves +
    " leaves changed weight; constraints kept " + f.kept + " / " + f.realized;
}

// ---- the update ----
var FADING = ".np-labels, .np-group-labels, .np-tabs, .np-unlinked, .np-unlinked-count, .np-unrealized";
function animate(ms, step, done) { morphFrames(live, ms, step, done); }

function apply(html, done) {
  var doc = new DOMParser().parseFromString(html, "text/html");
  var next = doc.querySelector(".nptreemap");
  var old = container();
  if (!next || !old) { done(); return; }
  var oldSvg = pictureOf(old), newSvg = pictureOf(next);
  if (!oldSvg || !newSvg) { done(); return; }
  var before = model(old), after = model(next);
  var full = (newSvg.getAttribute("viewBox") || "0 0 1 1").split(/[\s,]+/).map(Number);
  showFigures(figures(before, after, full));
  var instant = still() || after.leaves.length > BIG || before.leaves.length > BIG;
  if (instant) { swap(old, next, false); done(); return; }

  // Tracks: kept cells morph, new ones fade in, gone ones fade out.
  var tracks = [], incoming = [], outgoing = [];
  after.cells.forEach(function (el, id) {
    var was = before.cells.get(id);
    if (was) {
      var t = track(was, was.getAttribute("d"), el.getAttribute("d"), was.getAttribute("fill"), el.getAttribute("fill"));
      if (t) { tracks.push(t); }
    } else {
      var group = el.parentNode && el.parentNode.getAttribute("class");
      var into = group ? oldSvg.querySelector("g." + group.split(/\s+/)[0]) : null;
      var copy = document.importNode(el, true);
      copy.style.opacity = "0";
      (into || oldSvg).appendChild(copy);
      incoming.push(copy);
      var from = origin(id, before, after);
      if (from) {
        var grow = track(copy, from.getAttribute("d"), el.getAttribute("d"), null, null);
        if (grow) { tracks.push(grow); }
      }
    }
  });
  before.cells.forEach(function (el, id) { if (!after.cells.has(id)) { outgoing.push(el); } });
  var fading = Array.prototype.slice.call(old.querySelectorAll(FADING));
  var hover = old.querySelector(".np-map > svg.np-hover");
  if (hover) { fading.push(hover); }
  root().setAttribute("data-np-morphing", "");
  animate(MORPH_MS, function (k) {
    draw(tracks, k);
    fade(incoming, 0, 1, k);
    fade(outgoing, 1, 0, k);
    fade(fading, 1, 0, k);
  }, function () {
    root().removeAttribute("data-np-morphing");
    swap(old, next, true);
    done();
  });
}
function root() { return document.documentElement; }

// The new map in place of the old, its script run again for it (with
// this document's nonce), the view carried over.
function swap(old, next, fadeIn) {
  var state = null;
  try { state = old.npView ? old.npView.get() : null; } catch (err) { state = null; }
  var active = document.activeElement;
  var focusId = active && old.contains(active) && active.getAttribute ? active.getAttribute("data-id") : null;
  var searchFocused = active && old.contains(active) && active.classList.contains("np-search-box");
  var fresh = document.importNode(next, true);
  var code = "";
  Array.prototype.slice.call(fresh.querySelectorAll("script")).forEach(function (s) {
    var type = s.getAttribute("type");
    if (!type || type === "text/javascript" || type === "module") {
      if (!code) { code = s.textContent; }
      s.parentNode.removeChild(s);
    }
  });
  var fading = fadeIn ? Array.prototype.slice.call(fresh.querySelectorAll(FADING)) : [];
  fade(fading, 0, 0, 0);
  // The old map's listeners on the window and the document go with it.
  try { if (old.npRetire) { old.npRetire(); } } catch (err) { /* nothing to retire */ }
  old.parentNode.replaceChild(fresh, old);
  var run = document.createElement("script");
  run.nonce = NONCE;
  run.textContent = code;
  fresh.appendChild(run);
  try { if (state && fresh.npView) { fresh.npView.set(state); } } catch (err) { /* the view starts afresh */ }
  if (focusId) {
    var cell = pictureOf(fresh).querySelector("path[data-id=\"" + cssEscape(focusId) + "\"]");
    if (cell) { cell.focus({ preventScroll: true }); }
  } else if (searchFocused) {
    var box = fresh.querySelector(".np-search-box");
    if (box) { box.focus({ preventScroll: true }); }
  }
  live.updates++;
  root().setAttribute("data-np-live-updates", String(live.updates));
  if (fading.length) {
    animate(FADE_MS, function (k) { fade(fading, 0, 1, k); }, function () {
      fading.forEach(function (el) { el.style.opacity = ""; });
    });
  } else {
    fading.forEach(function (el) { el.style.opacity = ""; });
  }
}
function cssEscape(s) { return window.CSS && CSS.escape ? CSS.escape(s) : s.replace(/["\\]/g, "\\$&"); }

// ---- the patch ----
// What changed since the page shown, applied in place (issue 32): only the
// cells the patch names morph (at once past BIG of them), the picture's
// changed parts fade across, and the map's own script takes the rest
// (page/patch.js: `root.npPatch`). False when the map cannot take it: the
// whole page is loaded instead.
function patchIn(patch, done) {
  var c = container();
  var api = c && c.npPatch;
  var ready = api ? api.check(patch) : null;
  if (!ready) { return false; }
  var svg = pictureOf(c);
  var full = (svg.getAttribute("viewBox") || "0 0 1 1").split(/[\s,]+/).map(Number);
  var diag = Math.hypot(full[2], full[3]) || 1, sum = 0, max = 0, maxId = null;
  ready.cells.forEach(function (cell) {
    if (cell[2] === "none") { return; }
    var a = centroid(points(cell[0].getAttribute("d"))), b = centroid(points(cell[1]));
    var moved = Math.hypot(b[0] - a[0], b[1] - a[1]) / diag;
    sum += moved;
    if (moved > max) { max = moved; maxId = cell[0].getAttribute("data-id"); }
  });
  var olds = ready.parts.map(function (p) { return p[0]; });
  var news = ready.parts.map(function (p) { return p[1]; });
  function finish() {
    root().removeAttribute("data-np-morphing");
    var f = api.apply(ready, patch);
    fade(news, 0, 0, 0);
    f.mean = f.leaves ? sum / f.leaves : 0;
    f.max = max;
    f.largest = maxId;
    showFigures(f);
    KEY = patch.key;
    live.patches++;
    live.patched = ready.cells.length;
    live.updates++;
    root().setAttribute("data-np-live-updates", String(live.updates));
    if (still()) {
      fade(news, 1, 1, 1);
      done();
      return;
    }
    animate(FADE_MS, function (k) { fade(news, 0, 1, k); }, function () {
      news.forEach(function (el) { el.style.opacity = ""; });
      done();
    });
  }
  if (still() || ready.cells.length > BIG) { finish(); return true; }
  var tracks = [];
  ready.cells.forEach(function (cell) {
    var t = track(cell[0], cell[0].getAttribute("d"), cell[1], cell[0].getAttribute("fill"), cell[2]);
    if (t) { tracks.push(t); }
  });
  root().setAttribute("data-np-morphing", "");
  animate(MORPH_MS, function (k) {
    draw(tracks, k);
    fade(olds, 1, 0, k);
  }, finish);
  return true;
}

// One update at a time, in order; a whole page replaces whatever waits
// before it, a patch waits its turn (it builds on what came before it).
var waiting = [], busy = false;
function show(item) {
  if (item.html !== undefined) { waiting = [item]; } else { waiting.push(item); }
  if (!busy) { pump(); }
}
function pump() {
  if (!waiting.length) { busy = false; return; }
  busy = true;
  var item = waiting.shift();
  if (item.html !== undefined) { apply(item.html, pump); return; }
  if (!patchIn(item.patch, pump)) {
    // The map could not take it: what waits builds on it, so it goes too,
    // and no patch is asked for until the whole page is here (`update`).
    waiting = [];
    KEY = "";
    busy = false;
    load();
  }
}

// ---- the stream ----
// The key a fetched page was served with (its live script's data-key).
function keyOf(html) {
  var m = /<script src="\/_np\/live\.js"[^>]* data-key="([^"]*)"/.exec(html);
  return m ? m[1] : "";
}
// Fetches the current page; of several fetches under way only the last
// started is shown.
var fetches = 0;
function load() {
  var mine = ++fetches;
  return fetch(location.pathname, { cache: "no-store", credentials: "same-origin" })
    .then(function (r) { return r.ok ? r.text() : Promise.reject(new Error("HTTP " + r.status)); })
    .then(function (html) {
      if (mine !== fetches) { return; }
      KEY = keyOf(html);
      live.loads++;
      show({ html: html });
    })
    .catch(function (err) { statusLine.textContent = "live: cannot fetch the page (" + err.message + ")"; });
}
// Asks for what changed since the page shown (or waiting to be); a server
// that cannot say (it no longer has that page, or the change is more than
// cells, parts and nodes: 204) gets the whole page asked for.
function update() {
  if (!KEY) { return load(); }
  var mine = ++fetches;
  var since = KEY;
  return fetch(location.pathname + "?since=" + encodeURIComponent(since), { cache: "no-store", credentials: "same-origin" })
    .then(function (r) { return r.status === 200 ? r.json() : null; })
    .then(function (patch) {
      if (mine !== fetches) { return; }
      if (!patch || since !== KEY) { load(); return; }
      KEY = patch.key;
      show({ patch: patch });
    })
    .catch(function () { if (mine === fetches) { load(); } });
}
var source = new EventSource(EVENTS);
source.onopen = function () { statusLine.textContent = "live: following " + DATASET; };
source.onerror = function () { statusLine.textContent = "live: reconnecting\u2026"; };
source.onmessage = function (m) {
  var e;
  try { e = JSON.parse(m.data); } catch (err) { return; }
  if (e.kind === "current") {
    // A new stream: what stood before is sent again after this.
    problems.clear();
    showProblems();
    var now = (e.keys && Object.prototype.hasOwnProperty.call(e.keys, DATASET)) ? e.keys[DATASET] : e.instance + ".0";
    if (now !== KEY) { load(); }
  } else if (e.kind === "problem") {
    if (e.dataset !== DATASET && e.dataset !== "config") { return; }
    live.errors++;
    problems.set(e.dataset, e);
    showProblems();
  } else if (e.kind === "cleared") {
    if (problems.delete(e.dataset)) { showProblems(); }
  } else if (e.kind === "built") {
    if (e.dataset !== DATASET) { return; }
    problems.delete(DATASET);
    problems.delete("config");
    showProblems();
    if (e.key !== KEY) { if (live.whole) { load(); } else { update(); } }
  }
};
