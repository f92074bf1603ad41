// Fitting a leaf's label into its cell: the picture's rule
// (src/render/labels.rs, `place_leaf`), step for step, so that a zoomed
// page labels a cell as the picture drawn at that size would: the whole text
// on one line if it fits, on two lines at the break nearest its middle when
// that is clearly larger, else cut with an ellipsis after at least four
// characters; the block at the anchor where it fits largest (a compass
// search from the centroid), never below `min` or above `max`.
// A module of the page's script (bundled by src/render/page/bundle.rs). Pure:
// no document, no globals; text widths come from the caller (the page
// measures them in the browser; the test in src/render/labels.rs gives the
// picture's own font and holds the two fitters to the same placements on the
// same cells). A change here is a change there, and the test says so.

// Free space left and right of a label, and above and below, in font sizes.
const SIDE_PAD_EM = 0.3, END_PAD_EM = 0.08;
// A wrapped label must be this much larger than the one-line one.
const WRAP_GAIN = 1.25;
// Fewest characters kept before an ellipsis.
const MIN_KEPT = 4;
// Most rounds of the compass search (src/render/labels.rs says why 400).
const COMPASS_ROUNDS = 400;

function cross(ax, ay, bx, by) { return ax * by - ay * bx; }

// The area-weighted centroid of polygon `p` (flat x, y pairs, positive
// orientation), relative to its first vertex as the picture computes it;
// the mean of the vertices for a degenerate one.
export function polygonCentroid(p) {
  var n = p.length / 2, ox = p[0], oy = p[1], ax = 0, ay = 0, twice = 0;
  for (var k = 1; k + 1 < n; k++) {
    var x0 = p[2 * k] - ox, y0 = p[2 * k + 1] - oy, x1 = p[2 * k + 2] - ox, y1 = p[2 * k + 3] - oy;
    var c = cross(x0, y0, x1, y1);
    twice += c;
    ax += (x0 + x1) * c;
    ay += (y0 + y1) * c;
  }
  if (twice <= 0) {
    var sx = 0, sy = 0;
    for (var j = 0; j < n; j++) { sx += p[2 * j]; sy += p[2 * j + 1]; }
    return [sx / n, sy / n];
  }
  return [ox + ax / (3 * twice), oy + ay / (3 * twice)];
}

// `p` in positive orientation (the picture's), whichever way it was given.
export function positive(p) {
  var n = p.length / 2, area = 0;
  for (var k = 0; k < n; k++) {
    var j = (k + 1) % n;
    area += cross(p[2 * k], p[2 * k + 1], p[2 * j], p[2 * j + 1]);
  }
  if (area >= 0) { return p; }
  var q = new Float64Array(p.length);
  for (var m = 0; m < n; m++) { q[2 * m] = p[2 * (n - 1 - m)]; q[2 * m + 1] = p[2 * (n - 1 - m) + 1]; }
  return q;
}

// The largest scale at which a box of half extents (hx, hy) times it,
// centred at (cx, cy), lies in convex polygon `p`; 0 when the centre is out.
export function fitScale(p, cx, cy, hx, hy) {
  var n = p.length / 2, best = Infinity;
  var corners = [hx, hy, -hx, hy, hx, -hy, -hx, -hy];
  for (var k = 0; k < n; k++) {
    var ax = p[2 * k], ay = p[2 * k + 1], j = (k + 1) % n;
    var ex = p[2 * j] - ax, ey = p[2 * j + 1] - ay;
    var slack = cross(ex, ey, cx - ax, cy - ay);
    if (slack < 0) { return 0; }
    for (var u = 0; u < 8; u += 2) {
      var towards = cross(ex, ey, corners[u], corners[u + 1]);
      if (towards < 0) { best = Math.min(best, slack / -towards); }
    }
  }
  return best < Infinity ? Math.max(best, 0) : 0;
}

// The anchor and scale at which a box of half extents (hx, hy) per unit of
// scale fits `p` best: [x, y, scale].
export function bestFit(p, hx, hy) {
  var at = polygonCentroid(p), x = at[0], y = at[1];
  var best = fitScale(p, x, y, hx, hy);
  var lox = p[0], loy = p[1], hix = p[0], hiy = p[1];
  for (var k = 2; k < p.length; k += 2) {
    lox = Math.min(lox, p[k]); hix = Math.max(hix, p[k]);
    loy = Math.min(loy, p[k + 1]); hiy = Math.max(hiy, p[k + 1]);
  }
  var side = Math.min(hix - lox, hiy - loy), step = 0.25 * side, floor = 0.01 * side;
  for (var round = 0; round < COMPASS_ROUNDS; round++) {
    if (step !== step || step <= floor) { break; }
    var moved = false, dirs = [step, 0, -step, 0, 0, step, 0, -step];
    for (var d = 0; d < 8; d += 2) {
      var px = x + dirs[d], py = y + dirs[d + 1], s = fitScale(p, px, py, hx, hy);
      if (s > best * (1 + 1e-9)) { x = px; y = py; best = s; moved = true; }
    }
    if (!moved) { step *= 0.5; }
  }
  return [x, y, best];
}

// Trims white space as the picture does.
function trim(s) { return s.replace(/^\s+/, "").replace(/\s+$/, ""); }

// The two halves of `text` split at the break nearest its middle (a space,
// or after `-`, `_`, `/`, `.`), or null.
export function wrap(text) {
  var chars = Array.from(text), mid = chars.length / 2, best = null;
  for (var k = 1; k < chars.length; k++) {
    var c = chars[k];
    // Where the line breaks, and whether a space goes with the break.
    var at = c === " " ? [k, 1] : null;
    if ((c === "-" || c === "_" || c === "/" || c === ".") && k + 1 < chars.length) { at = [k + 1, 0]; }
    if (at === null) { continue; }
    var d = Math.abs(at[0] - mid);
    if (best === null || d < best[0]) { best = [d, at[0], at[1]]; }
  }
  if (best === null) { return null; }
  var a = trim(chars.slice(0, best[1]).join("")), b = trim(chars.slice(best[1] + best[2]).join(""));
  return a && b ? [a, b] : null;
}

// Lines of text as a block: its width and height in font sizes, and the
// anchor and scale at which it fits `p`.
function fitBlock(p, lines, width, lineEm) {
  var w = 0;
  for (var k = 0; k < lines.length; k++) { w = Math.max(w, width(lines[k])); }
  var h = 0;
  for (var j = 0; j < lines.length; j++) { h += lineEm; }
  var at = bestFit(p, 0.5 * w + SIDE_PAD_EM, 0.5 * h + END_PAD_EM);
  return { lines: lines, width: w, height: h, x: at[0], y: at[1], size: at[2] };
}

// The largest font size at which one line `widthEm` ems wide fits `p`.
export function lineFit(p, widthEm, lineEm) {
  return bestFit(p, 0.5 * widthEm + SIDE_PAD_EM, 0.5 * lineEm + END_PAD_EM)[2];
}

// The label of a leaf whose text is `text` in convex polygon `p` (positive
// orientation), at font sizes within [min, max]: { lines: [{ text, x,
// baseline }], size, rect: [x0, y0, x1, y1] }, or null when not even four
// characters and the ellipsis fit. `width(s)` is the advance of `s` in ems;
// `lineEm` the line step and `ascentEm` the ascent, in ems.
export function placeLeaf(text, p, min, max, width, lineEm, ascentEm) {
  if (!text) { return null; }
  var one = fitBlock(p, [text], width, lineEm);
  var choice = one.size >= min ? one : null;
  if (choice === null || choice.size < max) {
    var halves = wrap(text);
    if (halves) {
      var two = fitBlock(p, halves, width, lineEm);
      var better = choice === null ? two.size >= min : two.size >= WRAP_GAIN * Math.min(choice.size, max) && two.size >= min;
      if (better) { choice = two; }
    }
  }
  if (choice === null) {
    // The longest prefix (at least MIN_KEPT characters) that fits with "…".
    var chars = Array.from(text), lo = MIN_KEPT, hi = Math.max(chars.length - 1, 0);
    while (lo <= hi) {
      var k = (lo + hi) >> 1;
      var cut = chars.slice(0, k).join("").replace(/\s+$/, "") + "\u2026";
      var block = fitBlock(p, [cut], width, lineEm);
      if (block.size >= min) { choice = block; lo = k + 1; }
      else if (k === 0) { break; }
      else { hi = k - 1; }
    }
    if (choice === null) { return null; }
  }
  var size = Math.min(choice.size, max), y = choice.y - 0.5 * choice.height * size, out = [];
  for (var m = 0; m < choice.lines.length; m++) {
    out.push({ text: choice.lines[m], x: choice.x, baseline: y + ascentEm * size });
    y += lineEm * size;
  }
  var hw = 0.5 * choice.width * size, hh = 0.5 * choice.height * size;
  return { lines: out, size: size, rect: [choice.x - hw, choice.y - hh, choice.x + hw, choice.y + hh] };
}
