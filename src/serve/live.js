// The live preview's browser side (src/serve/mod.rs serves it; the page as
// served loads it, the page on disk never does). It listens to the server's
// event stream; when its dataset is rebuilt it fetches the page again and
// morphs every cell of the picture from its old polygon to its new one
// (matched by node id; new cells grow from their most similar sibling and
// fade in, removed ones fade out; labels and
// tabs fade across) in under half a second, then puts the new map in place
// of the old one in the same document (no reload) and carries the view
// over: zoom, search text, hovered or focused cell. With
// prefers-reduced-motion, or on a big map, it swaps at once. A failed
// rebuild shows its message over the last good picture until the next good
// one. A small panel gives the last update's stability figures (as `eval
// --previous` defines them: leaf centroid displacement as a share of the
// canvas diagonal, mean and largest; realised constraints kept), and steps
// through the last layouts of the session (`history:`).
(function () {
  "use strict";
  var me = document.currentScript;
  var NONCE = me.nonce || me.getAttribute("nonce") || "";
  var DATASET = me.getAttribute("data-dataset");
  var HISTORY = parseInt(me.getAttribute("data-history"), 10) || 0;
  var EVENTS = me.getAttribute("data-events") || "/_np/events";
  // The morph, then the new labels fading in: 360 + 120 ms, under 500.
  var MORPH_MS = 360, FADE_MS = 120;
  // Maps with more leaves than this swap at once (as the page's zoom does).
  var BIG = 3000;
  // Test hooks and counters: `slow` stretches the animation (screenshots
  // of the morph midway), `frames` counts this script's animation frames.
  var live = window.npLive = { updates: 0, frames: 0, slow: 1, figures: null, errors: 0, animating: 0 };

  function still() {
    return !!(window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)").matches);
  }
  function container() { return document.querySelector(".nptreemap"); }
  function pictureOf(c) { return c ? c.querySelector(".np-map > svg:not(.np-hover)") : null; }
  function frame(f) { live.frames++; return window.requestAnimationFrame(f); }

  // ---- the panel: status, figures, history ----
  var panel = document.createElement("div");
  panel.className = "np-live-panel";
  panel.setAttribute("role", "status");
  var statusLine = document.createElement("div");
  statusLine.className = "np-live-status";
  statusLine.textContent = "live: connecting";
  var figuresLine = document.createElement("div");
  figuresLine.className = "np-live-figures";
  figuresLine.textContent = "no update yet";
  var steps = document.createElement("div");
  steps.className = "np-live-history";
  var back = document.createElement("button"), ahead = document.createElement("button");
  back.type = ahead.type = "button";
  back.textContent = "\u25c0";
  ahead.textContent = "\u25b6";
  back.setAttribute("aria-label", "Previous layout");
  ahead.setAttribute("aria-label", "Next layout");
  var stepLabel = document.createElement("span");
  steps.appendChild(back); steps.appendChild(stepLabel); steps.appendChild(ahead);
  panel.appendChild(statusLine);
  panel.appendChild(figuresLine);
  if (HISTORY > 0) { panel.appendChild(steps); }
  document.body.appendChild(panel);

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

  // ---- geometry ----
  function points(d) {
    var n = (d || "").match(/-?[0-9.]+(?:e-?[0-9]+)?/g) || [];
    var p = [];
    for (var k = 0; k + 1 < n.length; k += 2) { p.push([+n[k], +n[k + 1]]); }
    return p;
  }
  function centroid(p) {
    var a = 0, cx = 0, cy = 0;
    for (var k = 0; k < p.length; k++) {
      var q = p[k], r = p[(k + 1) % p.length], c = q[0] * r[1] - r[0] * q[1];
      a += c; cx += (q[0] + r[0]) * c; cy += (q[1] + r[1]) * c;
    }
    if (Math.abs(a) < 1e-12) {
      var sx = 0, sy = 0;
      p.forEach(function (q) { sx += q[0]; sy += q[1]; });
      return p.length ? [sx / p.length, sy / p.length] : [0, 0];
    }
    return [cx / (3 * a), cy / (3 * a)];
  }
  // m points evenly spaced along the outline, starting where it crosses
  // the upward ray from its centroid, so two outlines of one cell line up.
  function resample(p, m) {
    if (p.length < 2) { return null; }
    var c = centroid(p), start = 0, best = Infinity, k;
    for (k = 0; k < p.length; k++) {
      var ang = Math.atan2(p[k][0] - c[0], -(p[k][1] - c[1]));
      if (Math.abs(ang) < best) { best = Math.abs(ang); start = k; }
    }
    var q = p.slice(start).concat(p.slice(0, start));
    var len = [0];
    for (k = 0; k < q.length; k++) {
      var a = q[k], b = q[(k + 1) % q.length];
      len.push(len[k] + Math.hypot(b[0] - a[0], b[1] - a[1]));
    }
    var total = len[q.length], out = [], e = 0;
    for (var j = 0; j < m; j++) {
      var t = total * j / m;
      while (e < q.length - 1 && len[e + 1] < t) { e++; }
      var s = len[e + 1] - len[e], f = s > 0 ? (t - len[e]) / s : 0;
      var a2 = q[e], b2 = q[(e + 1) % q.length];
      out.push([a2[0] + (b2[0] - a2[0]) * f, a2[1] + (b2[1] - a2[1]) * f]);
    }
    return out;
  }
  // [r, g, b] of a "#rrggbb" fill, else null.
  function rgb(fill) {
    var m = /^#([0-9a-f]{2})([0-9a-f]{2})([0-9a-f]{2})$/i.exec(fill || "");
    return m ? [parseInt(m[1], 16), parseInt(m[2], 16), parseInt(m[3], 16)] : null;
  }
  function pathOf(p) {
    return "M" + p.map(function (q) { return q[0].toFixed(2) + "," + q[1].toFixed(2); }).join("L") + "Z";
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
  function fade(els, from, to, k) {
    var v = String(from + (to - from) * k);
    els.forEach(function (el) { el.style.opacity = v; });
  }
  function ease(k) { return k < 0.5 ? 2 * k * k : 1 - Math.pow(-2 * k + 2, 2) / 2; }

  // Runs `step(k)` for k from 0 to 1 over `ms`, then `done`.
  function animate(ms, step, done) {
    var t0 = null, total = ms * (live.slow || 1);
    live.animating++;
    function tick(t) {
      if (t0 === null) { t0 = t; }
      var k = Math.min(1, (t - t0) / total);
      step(ease(k));
      if (k < 1) { frame(tick); } else { live.animating--; done(); }
    }
    frame(tick);
  }

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
        var a = points(was.getAttribute("d")), b = points(el.getAttribute("d"));
        var m = Math.min(96, Math.max(12, 2 * Math.max(a.length, b.length)));
        var ra = resample(a, m), rb = resample(b, m);
        if (ra && rb) { tracks.push({ el: was, a: ra, b: rb, fa: rgb(was.getAttribute("fill")), fb: rgb(el.getAttribute("fill")) }); }
      } else {
        var group = el.parentNode && el.parentNode.getAttribute("class");
        var into = group ? oldSvg.querySelector("g." + group.split(/\s+/)[0]) : null;
        var copy = document.importNode(el, true);
        copy.style.opacity = "0";
        (into || oldSvg).appendChild(copy);
        incoming.push(copy);
        var from = origin(id, before, after);
        if (from) {
          var pa = points(from.getAttribute("d")), pb = points(el.getAttribute("d"));
          var mm = Math.min(96, Math.max(12, 2 * Math.max(pa.length, pb.length)));
          var sa = resample(pa, mm), sb = resample(pb, mm);
          if (sa && sb) { tracks.push({ el: copy, a: sa, b: sb, fa: null, fb: null }); }
        }
      }
    });
    before.cells.forEach(function (el, id) { if (!after.cells.has(id)) { outgoing.push(el); } });
    var fading = Array.prototype.slice.call(old.querySelectorAll(FADING));
    var hover = old.querySelector(".np-map > svg.np-hover");
    if (hover) { fading.push(hover); }
    root().setAttribute("data-np-morphing", "");
    animate(MORPH_MS, function (k) {
      tracks.forEach(function (t) {
        var p = new Array(t.a.length);
        for (var j = 0; j < t.a.length; j++) {
          p[j] = [t.a[j][0] + (t.b[j][0] - t.a[j][0]) * k, t.a[j][1] + (t.b[j][1] - t.a[j][1]) * k];
        }
        t.el.setAttribute("d", pathOf(p));
        // A group's colour may change with the layout: it blends across.
        if (t.fa && t.fb && t.fa.join() !== t.fb.join()) {
          t.el.setAttribute("fill", "rgb(" + t.fa.map(function (v, j) { return Math.round(v + (t.fb[j] - v) * k); }).join(",") + ")");
        }
      });
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

  // One update at a time; a newer one waiting replaces an older one.
  var waiting = null, busy = false;
  function show(html) {
    waiting = html;
    if (!busy) { pump(); }
  }
  function pump() {
    if (waiting === null) { busy = false; return; }
    busy = true;
    var html = waiting;
    waiting = null;
    apply(html, pump);
  }

  // ---- history ----
  var pages = [], at = -1;
  function remember(html) {
    if (HISTORY <= 0) { return; }
    pages.push(html);
    while (pages.length > HISTORY + 1) { pages.shift(); }
    at = pages.length - 1;
    showStep();
  }
  function showStep() {
    stepLabel.textContent = pages.length ? " layout " + (at + 1) + " of " + pages.length + (at === pages.length - 1 ? " (latest) " : " ") : " no history yet ";
    back.disabled = at <= 0;
    ahead.disabled = at < 0 || at >= pages.length - 1;
  }
  function step(by) {
    var k = at + by;
    if (k < 0 || k >= pages.length) { return; }
    at = k;
    showStep();
    show(pages[at]);
  }
  back.addEventListener("click", function () { step(-1); });
  ahead.addEventListener("click", function () { step(1); });
  showStep();

  // ---- the stream ----
  function load(first) {
    return fetch(location.pathname, { cache: "no-store", credentials: "same-origin" })
      .then(function (r) { return r.ok ? r.text() : Promise.reject(new Error("HTTP " + r.status)); })
      .then(function (html) {
        remember(html);
        if (!first) { show(html); }
      })
      .catch(function (err) { statusLine.textContent = "live: cannot fetch the page (" + err.message + ")"; });
  }
  if (HISTORY > 0) { load(true); }
  var lastSeq = 0;
  var source = new EventSource(EVENTS);
  source.onopen = function () { statusLine.textContent = "live: following " + DATASET; };
  source.onerror = function () { statusLine.textContent = "live: reconnecting\u2026"; };
  source.onmessage = function (m) {
    var e;
    try { e = JSON.parse(m.data); } catch (err) { return; }
    if (e.kind === "problem") {
      if (e.dataset !== DATASET && e.dataset !== "config") { return; }
      live.errors++;
      problems.set(e.dataset, e);
      showProblems();
    } else if (e.kind === "built") {
      if (e.dataset !== DATASET) { return; }
      problems.delete(DATASET);
      problems.delete("config");
      showProblems();
      if (e.changed && e.seq !== lastSeq) {
        lastSeq = e.seq;
        load(false);
      }
    }
  };
})();
