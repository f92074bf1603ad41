// The morph between two layouts, shared by the page and the live preview.
// A module bundled by src/render/page/bundle.rs that imports nothing; the
// page's steps through its past layouts (page/past.js) and the live preview
// (src/serve/live.js) import it: outlines resampled to matching points and
// interpolated, fills blended, elements faded, eased over a few hundred
// milliseconds, and nothing animated with prefers-reduced-motion. Pure
// geometry and timing: it reads and writes only the elements it is given, and
// user text never passes through it.
export function still() {
  return !!(window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)").matches);
}
export function points(d) {
  var n = (d || "").match(/-?[0-9.]+(?:e-?[0-9]+)?/g) || [];
  var p = [];
  for (var k = 0; k + 1 < n.length; k += 2) { p.push([+n[k], +n[k + 1]]); }
  return p;
}
export function centroid(p) {
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
// Element `el` moving from outline `from` to `to` (path data), its fill
// from `fa` to `fb` when both are colours; null when an outline is empty.
export function track(el, from, to, fa, fb) {
  var a = points(from), b = points(to);
  var m = Math.min(96, Math.max(12, 2 * Math.max(a.length, b.length)));
  var ra = resample(a, m), rb = resample(b, m);
  return ra && rb ? { el: el, a: ra, b: rb, fa: rgb(fa), fb: rgb(fb) } : null;
}
// Every track at k (0 = where it starts, 1 = where it ends).
export function draw(tracks, k) {
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
}
export function fade(els, from, to, k) {
  var v = String(from + (to - from) * k);
  els.forEach(function (el) { el.style.opacity = v; });
}
function ease(k) { return k < 0.5 ? 2 * k * k : 1 - Math.pow(-2 * k + 2, 2) / 2; }
// Runs `step(k)` for k from 0 to 1 over `ms` (times `stats.slow`, a test
// hook for screenshots midway), then `done`; counts its animation frames
// in `stats.frames` and running animations in `stats.animating`.
export function animate(stats, ms, step, done) {
  var t0 = null, total = ms * (stats.slow || 1);
  stats.animating++;
  function tick(t) {
    if (t0 === null) { t0 = t; }
    var k = Math.min(1, (t - t0) / total);
    step(ease(k));
    if (k < 1) { stats.frames++; window.requestAnimationFrame(tick); } else { stats.animating--; done(); }
  }
  stats.frames++;
  window.requestAnimationFrame(tick);
}
// The ◀/▶ control over a list of layouts: `back` and `ahead` buttons and
// a `label`; `go(k)` shows layout k. `set(n, at)` tells it the list's
// length and the layout shown.
export function stepper(back, ahead, label, go) {
  var s = { n: 0, at: -1 };
  function show() {
    label.textContent = s.n ? " layout " + (s.at + 1) + " of " + s.n + (s.at === s.n - 1 ? " (latest) " : " ") : " no history yet ";
    back.disabled = s.at <= 0;
    ahead.disabled = s.at < 0 || s.at >= s.n - 1;
  }
  function step(by) {
    var k = s.at + by;
    if (k < 0 || k >= s.n) { return; }
    s.at = k;
    show();
    go(k);
  }
  back.addEventListener("click", function () { step(-1); });
  ahead.addEventListener("click", function () { step(1); });
  s.set = function (n, at) { s.n = n; s.at = at; show(); };
  return s;
}
