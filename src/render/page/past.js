// The page's steps through the session's past layouts (issue 25).
// The second entry module of a page with history, after main.js
// (src/render/html.rs). A page written by `watch` with `history:` carries
// them in `data.history`, oldest first; the picture as drawn is the latest. ◀
// and ▶ morph every cell to its outline and fill in that layout
// (page/history.js, the live preview's morph); cells a layout lacks fade out,
// cells only a past layout has are drawn in a layer of their own. While a
// past layout shows, the labels, tabs and markers (which are the latest
// layout's) are hidden. With prefers-reduced-motion the picture changes at
// once. Only path data and colours are set; ids reach the document as
// attribute values.
import { NS, data, forgetOutlines, part, root, svg } from "./model.js";
import { animate, draw, fade, still, stepper, track } from "./history.js";

(function () {
  var back = part("history-back");
  if (!back || !data.history || !data.history.length) { return; }
  var stats = window.npHistory = { frames: 0, slow: 1, animating: 0, at: 0, count: 0 };
  var drawn = new Map(), latest = [];
  Array.prototype.forEach.call(svg.querySelectorAll("path[data-id]"), function (el) {
    var id = el.getAttribute("data-id");
    drawn.set(id, el);
    latest.push([id, el.getAttribute("d"), el.getAttribute("fill")]);
  });
  var layouts = data.history.concat([latest]);
  // Cells of past layouts only, above the picture's cells, never hovered.
  var layer = document.createElementNS(NS, "g");
  layer.setAttribute("class", "np-history-layer");
  layer.setAttribute("pointer-events", "none");
  var cellGroup = svg.querySelector(".np-cells");
  layer.setAttribute("stroke", cellGroup ? cellGroup.getAttribute("stroke") || "#ffffff" : "#ffffff");
  if (cellGroup) { cellGroup.parentNode.insertBefore(layer, cellGroup.nextSibling); } else { svg.appendChild(layer); }
  var extra = new Map();
  var busy = false, wanted = -1, shown = layouts.length - 1;

  function show(k) {
    wanted = k;
    if (!busy) { next(); }
  }
  function next() {
    if (wanted < 0 || wanted === shown) { busy = false; return; }
    busy = true;
    var k = wanted, target = new Map();
    layouts[k].forEach(function (c) { target.set(c[0], c); });
    var tracks = [], incoming = [], outgoing = [], all = [];
    target.forEach(function (c, id) {
      if (drawn.has(id) || extra.has(id)) { return; }
      var p = document.createElementNS(NS, "path");
      p.setAttribute("data-past-id", id);
      p.setAttribute("d", c[1]);
      p.setAttribute("fill", c[2]);
      p.style.opacity = "0";
      layer.appendChild(p);
      extra.set(id, p);
    });
    function each(el, id) {
      var c = target.get(id);
      all.push([el, c]);
      var hidden = el.style.opacity === "0";
      if (!c) { if (!hidden) { outgoing.push(el); } return; }
      if (hidden) { incoming.push(el); }
      var t = track(el, el.getAttribute("d"), c[1], el.getAttribute("fill"), c[2]);
      if (t) { tracks.push(t); }
    }
    drawn.forEach(each);
    extra.forEach(each);
    var past = k < layouts.length - 1;
    function finish() {
      // Exactly the layout's own path data and fills, not the morph's.
      all.forEach(function (e) {
        if (e[1]) {
          e[0].setAttribute("d", e[1][1]);
          e[0].setAttribute("fill", e[1][2]);
          e[0].style.opacity = "";
        } else {
          e[0].style.opacity = "0";
        }
      });
      // The model's outlines are parsed again from the cells as they are.
      forgetOutlines();
      root.toggleAttribute("data-np-past", past);
      shown = k;
      stats.at = k;
      stats.count++;
      root.setAttribute("data-np-history-at", String(k));
      next();
    }
    if (past) { root.toggleAttribute("data-np-past", true); }
    if (still()) { finish(); return; }
    animate(stats, 360, function (t) {
      draw(tracks, t);
      fade(incoming, 0, 1, t);
      fade(outgoing, 1, 0, t);
    }, finish);
  }
  var steps = stepper(back, part("history-ahead"), part("history-label"), show);
  steps.set(layouts.length, layouts.length - 1);
  root.setAttribute("data-np-history-at", String(layouts.length - 1));
})();
