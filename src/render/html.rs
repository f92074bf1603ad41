//! The interactive HTML page: one self-contained HTML5 file wrapping a finished
//! SVG with inline style, inline script and the node data as JSON, for the hover
//! behaviour of the paper's prototype (method reference §8.5). Owns the page's
//! structure, its style and script and the escaping of the data block; may not
//! build the SVG, do I/O, or reference anything over the network.
//! Output is deterministic: identical input gives identical bytes.

use serde::Serialize;

use super::labels::display_name;
use super::picture::{colors, picture, Style};
use super::svg::{escape, path_data};
use crate::layout::Computed;
use nptreemap_formats::Dataset;

/// What the page knows about the map beyond its picture.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HtmlData {
    /// Page title, shown in the browser tab (escaped; any text is safe).
    pub title: String,
    /// Every node the script may look up, in the caller's order (written so).
    pub nodes: Vec<HtmlNode>,
    /// Snapshots of the optimisation for the slider, in order; the page shows
    /// no slider when empty (layouts made without frames).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<HtmlFrame>,
}

/// One snapshot of the optimisation as the slider draws it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HtmlFrame {
    /// What the moment is (`level 2: tick 40`); shown beside the slider.
    pub label: String,
    /// The cells then: node id, SVG path data, fill colour.
    pub cells: Vec<(String, String, String)>,
}

/// One node of the map as the page's script sees it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HtmlNode {
    /// Node id; equals the `data-id` of its cell `<path>` in the SVG.
    pub id: String,
    /// Display label.
    pub label: String,
    /// Labels from the root to this node, both included; the tooltip text.
    pub path: Vec<String>,
    /// The node's weight, shown in the tooltip.
    pub weight: f64,
    /// Depth in the hierarchy; the root has depth 0.
    pub depth: usize,
    /// Whether the node is a leaf (only leaves react to hovering).
    pub leaf: bool,
    /// The parent's id; `None` for the root.
    pub parent: Option<String>,
    /// The view box (`x y width height`) that zooms into this group, with the
    /// picture's aspect; `None` for leaves and for groups too large to zoom.
    pub zoom: Option<[f64; 4]>,
    /// Ids of the cells at the same depth sharing an edge with this one
    /// (`neighbours` in the page's data, which its script reads).
    #[serde(rename = "neighbours")]
    pub neighbors: Vec<String>,
    /// Ids of the node's constraint partners, each with whether the constraint
    /// is realised (the two cells share an edge).
    pub partners: Vec<(String, bool)>,
}

/// Class of the JSON data block, which the script reads.
const DATA_CLASS: &str = "np-data";

/// Inline style, scoped to the map's container so that pages can be inlined
/// into any document (two maps on one page included): the hover classes, the
/// tooltip, the zoom, a picture that fits its container's width (keeping its
/// aspect, legend in view) and a dark variant.
const STYLE: &str = r#".nptreemap { font: 14px Helvetica, Arial, sans-serif; color: #1a1a1a; max-width: 100%; }
.nptreemap .np-map { margin: 0 auto; }
.nptreemap .np-map svg { display: block; width: 100%; height: auto; }
.nptreemap .np-map path { transition: opacity .1s; }
.nptreemap .np-map path.np-dim { opacity: .25; }
.nptreemap .np-map path.np-outside { opacity: .12; pointer-events: none; }
.nptreemap .np-map path.np-partner { stroke: #000; stroke-width: 4px; }
.nptreemap .np-map path.np-partner-unrealized { stroke-dasharray: 6 3; }
.nptreemap .np-map path:focus { outline: none; stroke: #000; stroke-width: 3px; }
.nptreemap.np-hide-unrealized .np-unrealized { display: none; }
.nptreemap .np-tooltip { position: fixed; z-index: 10; pointer-events: none; background: #fff; color: #1a1a1a;
  border: 1px solid #888; padding: .3em .5em; max-width: 40em; box-shadow: 0 1px 4px rgba(0,0,0,.3); }
.nptreemap .np-tooltip[hidden] { display: none; }
.nptreemap .np-controls { display: flex; flex-wrap: wrap; gap: .3em 1.2em; align-items: center; margin: .3em 0; }
.nptreemap .np-frames input { width: 16em; max-width: 60vw; vertical-align: middle; }
.nptreemap .np-crumbs button { font: inherit; border: 0; background: none; color: #1f5fa8; cursor: pointer; padding: 0; }
.nptreemap .np-crumbs button[aria-current] { color: inherit; cursor: default; font-weight: bold; }
@media (prefers-color-scheme: dark) {
  .nptreemap { color: #e8e8e8; color-scheme: dark; }
  .nptreemap .np-background { fill: #161616; }
  .nptreemap .np-cells, .nptreemap .np-tabs { stroke: #161616; }
  .nptreemap .np-labels { fill: #f2f2f2; stroke: #161616; }
  .nptreemap .np-legend-labels, .nptreemap .np-title { fill: #e8e8e8; }
  .nptreemap .np-map path.np-partner { stroke: #fff; }
  .nptreemap .np-tooltip { background: #262626; color: #e8e8e8; border-color: #555; }
  .nptreemap .np-crumbs button { color: #8ab8ff; }
}
"#;

/// Inline script: hover (and focus, and tap) highlighting, the tooltip, the
/// unrealised-links toggle, the optimisation slider and the zoom into groups
/// with a breadcrumb back. It finds everything inside its own container, so
/// several maps can share a document. User text reaches the page only
/// through `textContent`.
const SCRIPT: &str = r##"(function () {
  "use strict";
  var root = document.currentScript.parentNode;
  function part(name) { return root.querySelector(".np-" + name); }
  var data = JSON.parse(part("data").textContent);
  // Maps and sets, never plain objects: ids such as "constructor",
  // "toString" or "__proto__" are keys like any other (issue 11, item 14).
  var nodes = new Map();
  data.nodes.forEach(function (n) { nodes.set(n.id, n); });
  var map = part("map");
  var svg = map.querySelector("svg");
  var tip = part("tooltip");
  var crumbs = part("crumbs");
  var cells = new Map();
  var leaves = [];
  Array.prototype.forEach.call(map.querySelectorAll("path[data-id]"), function (el) {
    var id = el.getAttribute("data-id");
    var n = nodes.get(id);
    cells.set(id, el);
    if (n && n.leaf) {
      leaves.push(el);
      el.setAttribute("tabindex", "0");
      el.setAttribute("role", "img");
      el.setAttribute("aria-label", n.path.join(" \u203a ") + ", weight " + n.weight.toLocaleString());
    }
  });
  var current = null;

  function clear() {
    current = null;
    leaves.forEach(function (el) { el.classList.remove("np-dim"); });
    Array.prototype.forEach.call(map.querySelectorAll(".np-partner"), function (el) {
      el.classList.remove("np-partner", "np-partner-unrealized");
    });
    tip.hidden = true;
  }

  function show(el) {
    var n = nodes.get(el.getAttribute("data-id"));
    current = el;
    // The hovered cell and its neighbours stay; every other leaf greys out.
    var near = new Set(n.neighbours);
    near.add(n.id);
    leaves.forEach(function (c) {
      if (!near.has(c.getAttribute("data-id"))) { c.classList.add("np-dim"); }
    });
    n.partners.forEach(function (p) {
      var c = cells.get(p[0]);
      if (c) {
        c.classList.add("np-partner");
        if (!p[1]) { c.classList.add("np-partner-unrealized"); }
      }
    });
    tip.textContent = n.path.join(" \u203a ") + " \u2014 weight " + n.weight.toLocaleString();
    tip.hidden = false;
  }

  function place(cx, cy) {
    // Beside the point, flipped to its other side near the window's edge so
    // the tooltip never runs out of view.
    var x = cx + 14, y = cy + 14;
    if (x + tip.offsetWidth > window.innerWidth) { x = Math.max(0, cx - 14 - tip.offsetWidth); }
    if (y + tip.offsetHeight > window.innerHeight) { y = Math.max(0, cy - 14 - tip.offsetHeight); }
    tip.style.left = x + "px";
    tip.style.top = y + "px";
  }

  function leafAt(target) {
    var el = target && target.closest ? target.closest("path[data-id]") : null;
    var n = el && nodes.get(el.getAttribute("data-id"));
    return n && n.leaf ? el : null;
  }

  map.addEventListener("mouseover", function (e) {
    var el = leafAt(e.target);
    if (el === current) { return; }
    clear();
    if (el) { show(el); }
  });
  map.addEventListener("mouseleave", clear);
  map.addEventListener("mousemove", function (e) { place(e.clientX, e.clientY); });
  // Keyboard: Tab moves through the cells, the focused one behaves as hovered.
  map.addEventListener("focusin", function (e) {
    var el = leafAt(e.target);
    if (!el) { return; }
    clear();
    show(el);
    var r = el.getBoundingClientRect();
    place(r.left + r.width / 2, r.top + r.height / 2);
  });
  map.addEventListener("focusout", function (e) {
    if (!map.contains(e.relatedTarget)) { clear(); }
  });

  // Zoom: a click (Enter on a focused cell) opens the group under the
  // current view that holds the cell; the breadcrumb (Escape) goes back.
  var full = svg.getAttribute("viewBox").split(" ").map(Number);
  var top = data.nodes.length ? data.nodes[0].id : null;
  var view = top;
  function ancestors(id) {
    var out = [];
    for (var n = nodes.get(id); n; n = n.parent === null ? null : nodes.get(n.parent)) { out.unshift(n.id); }
    return out;
  }
  function setView(box) { svg.setAttribute("viewBox", box.map(function (v) { return v.toFixed(2); }).join(" ")); }
  function animate(from, to) {
    var start = null;
    function step(t) {
      if (start === null) { start = t; }
      var k = Math.min(1, (t - start) / 250);
      var e = k < 0.5 ? 2 * k * k : 1 - Math.pow(-2 * k + 2, 2) / 2;
      setView(from.map(function (v, i) { return v + (to[i] - v) * e; }));
      if (k < 1) { requestAnimationFrame(step); } else { setView(to); }
    }
    requestAnimationFrame(step);
  }
  function zoomTo(id) {
    var n = nodes.get(id);
    if (!n) { return; }
    var target = n.zoom || full;
    var from = svg.getAttribute("viewBox").split(" ").map(Number);
    view = id;
    clear();
    var inside = new Set();
    data.nodes.forEach(function (m) {
      if (id === top || ancestors(m.id).indexOf(id) >= 0) { inside.add(m.id); }
    });
    cells.forEach(function (el, cid) {
      var out = !inside.has(cid);
      el.classList.toggle("np-outside", out);
      if (nodes.get(cid) && nodes.get(cid).leaf) { el.setAttribute("tabindex", out ? "-1" : "0"); }
    });
    root.classList.toggle("np-zoomed", id !== top);
    root.setAttribute("data-zoom", id);
    drawCrumbs();
    animate(from, target);
  }
  function drawCrumbs() {
    while (crumbs.firstChild) { crumbs.removeChild(crumbs.firstChild); }
    ancestors(view).forEach(function (id, k, all) {
      if (k > 0) { crumbs.appendChild(document.createTextNode(" \u203a ")); }
      var b = document.createElement("button");
      b.type = "button";
      b.textContent = nodes.get(id).label;
      b.setAttribute("data-id", id);
      if (k === all.length - 1) { b.setAttribute("aria-current", "location"); }
      b.addEventListener("click", function () { zoomTo(id); });
      crumbs.appendChild(b);
    });
  }
  function zoomInto(el) {
    // The first group below the view on the way to the cell that can be
    // zoomed into (virtual levels and whole-map groups are passed over).
    var path = ancestors(el.getAttribute("data-id"));
    for (var k = path.indexOf(view) + 1; k > 0 && k < path.length; k++) {
      var n = nodes.get(path[k]);
      if (n.leaf) { return; }
      if (n.zoom) { zoomTo(path[k]); return; }
    }
  }
  var pointer = "mouse";
  map.addEventListener("pointerdown", function (e) { pointer = e.pointerType || "mouse"; });
  map.addEventListener("click", function (e) {
    var el = e.target.closest ? e.target.closest("path[data-id]") : null;
    if (!el) { return; }
    // Touch: the first tap acts as hover, a second tap on the same cell zooms.
    if (pointer === "touch" && leafAt(el) && el !== current) {
      clear();
      show(el);
      var r = el.getBoundingClientRect();
      place(r.left + r.width / 2, r.top + r.height / 2);
      return;
    }
    zoomInto(el);
  });
  map.addEventListener("keydown", function (e) {
    var el = leafAt(e.target);
    if ((e.key === "Enter" || e.key === " ") && el) { e.preventDefault(); zoomInto(el); }
    if (e.key === "Escape" && view !== top) {
      var path = ancestors(view);
      zoomTo(path[path.length - 2]);
    }
  });
  drawCrumbs();

  // The optimisation slider: frame k drawn over the map, the last position
  // the finished picture.
  var slider = part("frame");
  if (slider && data.frames) {
    var NS = svg.namespaceURI;
    var layer = document.createElementNS(NS, "g");
    layer.setAttribute("class", "np-frame-layer");
    layer.setAttribute("pointer-events", "none");
    layer.setAttribute("stroke", "#ffffff");
    layer.setAttribute("stroke-width", "1");
    svg.appendChild(layer);
    var caption = part("frame-label");
    var showFrame = function () {
      var k = parseInt(slider.value, 10);
      while (layer.firstChild) { layer.removeChild(layer.firstChild); }
      var frame = data.frames[k];
      if (!frame) { caption.textContent = "final layout"; return; }
      frame.cells.forEach(function (c) {
        var p = document.createElementNS(NS, "path");
        p.setAttribute("d", c[1]);
        p.setAttribute("fill", c[2]);
        p.setAttribute("data-frame-id", c[0]);
        layer.appendChild(p);
      });
      caption.textContent = (k + 1) + " / " + data.frames.length + ": " + frame.label;
    };
    slider.addEventListener("input", showFrame);
    showFrame();
  }

  var box = part("unrealized-toggle");
  function toggle() { root.classList.toggle("np-hide-unrealized", !box.checked); }
  box.addEventListener("change", toggle);
  toggle();
})();
"##;

/// Width over height of the SVG's `viewBox`.
fn view_aspect(svg: &str) -> Option<f64> {
    let start = svg.find("viewBox=\"")? + 9;
    let end = start + svg[start..].find('"')?;
    let v: Vec<f64> = svg[start..end]
        .split_whitespace()
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    (v.len() == 4 && v[2] > 0.0 && v[3] > 0.0).then(|| v[2] / v[3])
}

/// A short key for the page's ids, from its content: two maps' pages get
/// different ids, the same map always the same (FNV-1a, 32 bits).
fn page_key(svg: &str, data: &str) -> String {
    let mut h: u32 = 0x811c_9dc5;
    for b in svg.bytes().chain(data.bytes()) {
        h ^= u32::from(b);
        h = h.wrapping_mul(0x0100_0193);
    }
    format!("np-{h:08x}")
}

/// Writes one self-contained HTML5 page showing `svg` (inserted verbatim, so it
/// must be our own SVG text, whose cell `<path>`s carry `data-id`) with `data`.
///
/// The page has no network references: style, script and data are inline. The
/// data is JSON in `<script type="application/json" id="nptreemap-data">`, with
/// every `<` written as `\u003c` so no label can close the block. Hovering a
/// leaf dims every leaf cell outside its neighbour set (not itself, unlike the
/// prototype, which greys the hovered cell too), outlines its constraint partners (dashed where unrealised)
/// and shows its root-to-leaf path and weight in a tooltip; a checkbox "Show
/// unrealized links" (off by default) shows or hides SVG elements of class
/// `np-unrealized`. Identical input gives identical bytes.
pub fn html(svg: &str, data: &HtmlData) -> String {
    let json = data_json(data);
    let key = page_key(svg, &json);
    let mut out = String::with_capacity(svg.len() + STYLE.len() + SCRIPT.len() + 1024);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str(
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>",
    );
    out.push_str(&escape(&data.title));
    out.push_str("</title>\n<style>\nbody { margin: 1em; }\n@media (prefers-color-scheme: dark) { body { background: #161616; } }\n</style>\n</head>\n<body>\n");
    // Everything of the map lives in one container with ids under one key:
    // it can be copied into another document as it is.
    out.push_str(&format!(
        "<div class=\"nptreemap\" id=\"{key}\">\n<style>\n"
    ));
    out.push_str(STYLE);
    out.push_str("</style>\n<div class=\"np-controls\">\n");
    out.push_str(&format!(
        "<label><input type=\"checkbox\" class=\"np-unrealized-toggle\" id=\"{key}-unrealized\"> \
         Show unrealized links</label>\n"
    ));
    if !data.frames.is_empty() {
        // The last position is the finished picture; the others are frames.
        out.push_str(&format!(
            "<div class=\"np-frames\"><label>Optimisation <input type=\"range\" class=\"np-frame\" id=\"{key}-frame\" \
             min=\"0\" max=\"{n}\" value=\"{n}\" step=\"1\"></label> \
             <span class=\"np-frame-label\" id=\"{key}-frame-label\">final layout</span></div>\n",
            n = data.frames.len()
        ));
    }
    out.push_str(&format!(
        "<nav class=\"np-crumbs\" id=\"{key}-crumbs\" aria-label=\"Zoom\"></nav>\n</div>\n"
    ));
    // As wide as the container, and no wider than keeps the whole picture
    // (legend included) within the window's height.
    let aspect = view_aspect(svg).unwrap_or(1.0);
    out.push_str(&format!(
        "<div class=\"np-map\" id=\"{key}-map\" style=\"max-width: calc((100vh - 4.5em) * {aspect:.4})\">\n"
    ));
    out.push_str(svg);
    if !svg.ends_with('\n') {
        out.push('\n');
    }
    out.push_str(&format!(
        "</div>\n<div class=\"np-tooltip\" id=\"{key}-tooltip\" role=\"tooltip\" hidden></div>\n"
    ));
    out.push_str(&format!(
        "<script type=\"application/json\" class=\"{DATA_CLASS}\" id=\"{key}-data\">\n"
    ));
    out.push_str(&json);
    out.push_str("\n</script>\n<script>\n");
    out.push_str(SCRIPT);
    out.push_str("</script>\n</div>\n</body>\n</html>\n");
    out
}

/// The interactive page of a finished computation: the picture (its
/// unrealised links drawn, for the page's checkbox to show or hide), and per
/// cell its path from the root, weight, neighbours and constraint partners for
/// the hover highlight.
pub fn html_page(computed: &Computed, style: &Style) -> String {
    let dataset = &computed.dataset;
    // The links are always drawn on the page; its checkbox shows or hides them.
    let mut page_style = style.clone();
    page_style.overlay.show_unrealized = true;
    let svg_text = picture(computed, &page_style);
    let adjacency = computed.adjacency();
    let mut partners: Vec<Vec<(String, bool)>> = vec![Vec::new(); dataset.len()];
    for (c, r) in computed.constraints.iter().zip(&computed.realized) {
        partners[c.a].push((dataset.node(c.b).id.clone(), *r));
        partners[c.b].push((dataset.node(c.a).id.clone(), *r));
    }
    let nodes = dataset
        .nodes()
        .iter()
        .enumerate()
        .map(|(i, node)| HtmlNode {
            id: node.id.clone(),
            label: display_name(dataset, i, &style.cells.labels.names),
            path: path_labels(dataset, i, &style.cells.labels.names),
            weight: node.value,
            depth: node.depth,
            leaf: node.children.is_empty(),
            parent: node.parent.map(|p| dataset.node(p).id.clone()),
            zoom: zoom_box(computed, i),
            neighbors: adjacency[node.depth]
                .neighbors(i)
                .iter()
                .map(|j| dataset.node(*j).id.clone())
                .collect(),
            partners: std::mem::take(&mut partners[i]),
        })
        .collect();
    let title = style
        .title
        .clone()
        .unwrap_or_else(|| dataset.node(dataset.root()).label.clone());
    let colors = colors(computed, style);
    let frames = computed
        .report
        .frames
        .iter()
        .map(|f| HtmlFrame {
            label: format!("level {}: {}", f.depth, f.label),
            cells: f
                .cells
                .iter()
                .map(|(i, polygon)| {
                    let mut d = String::new();
                    path_data(&mut d, polygon);
                    let fill = colors[*i].map_or("#cccccc".to_string(), |c| c.to_string());
                    (dataset.node(*i).id.clone(), d, fill)
                })
                .collect(),
        })
        .collect();
    html(
        &svg_text,
        &HtmlData {
            title,
            nodes,
            frames,
        },
    )
}

/// Groups whose cell spans more than this share of the canvas in both
/// directions are not worth zooming into.
const ZOOM_MIN_GAIN: f64 = 0.97;

/// The view box that shows group `i` as large as the picture allows: its
/// cell's bounding box with a margin, widened to the canvas's aspect.
fn zoom_box(computed: &Computed, i: usize) -> Option<[f64; 4]> {
    let node = computed.dataset.node(i);
    if node.children.is_empty() || node.parent.is_none() || node.is_virtual {
        return None;
    }
    let layout = &computed.layout;
    let (lo, hi) = layout.cells.get(i)?.polygon.bbox();
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);
    let margin = 0.03 * (hi.x - lo.x).max(hi.y - lo.y);
    let (mut w, mut h) = (hi.x - lo.x + 2.0 * margin, hi.y - lo.y + 2.0 * margin);
    if w / h < cw / ch {
        w = h * cw / ch;
    } else {
        h = w * ch / cw;
    }
    if w > ZOOM_MIN_GAIN * cw && h > ZOOM_MIN_GAIN * ch {
        return None;
    }
    let (cx, cy) = (0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y));
    let r = |v: f64| (v * 100.0).round() / 100.0;
    Some([r(cx - 0.5 * w), r(cy - 0.5 * h), r(w), r(h)])
}

/// The names from the root to node `i`, both included: the tooltip's text.
fn path_labels(
    dataset: &Dataset,
    i: usize,
    names: &std::collections::BTreeMap<String, String>,
) -> Vec<String> {
    dataset
        .path(i)
        .iter()
        .map(|k| display_name(dataset, *k, names))
        .collect()
}

/// `data` as JSON safe inside a `<script>` element: every `<` becomes the JSON
/// escape `\u003c`, so neither `</script` nor `<!--` can appear, and the text
/// still parses to the same value.
fn data_json(data: &HtmlData) -> String {
    // Serialising strings, numbers and bools cannot fail (non-finite numbers
    // become `null`); the fallback only keeps the page well-formed.
    let json = serde_json::to_string(data).unwrap_or_else(|_| "{\"nodes\":[]}".to_owned());
    json.replace('<', "\\u003c")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::svg::{svg, SvgStyle};
    use crate::render::test_support::sample;

    /// Page data for the sample: every node, neighbours and partners made up.
    fn sample_data(dataset: &Dataset, title: &str) -> HtmlData {
        let nodes = dataset
            .nodes()
            .iter()
            .enumerate()
            .map(|(i, node)| {
                let path = path_labels(dataset, i, &Default::default());
                let (neighbors, partners) = match node.id.as_str() {
                    "A1" => (vec!["A2".into(), "B".into()], vec![("B".into(), true)]),
                    "A3" => (vec!["A2".into()], vec![("A1".into(), false)]),
                    _ => (Vec::new(), Vec::new()),
                };
                HtmlNode {
                    id: node.id.clone(),
                    label: node.label.clone(),
                    path,
                    weight: node.value,
                    depth: node.depth,
                    leaf: dataset.is_leaf(i),
                    parent: node.parent.map(|p| dataset.node(p).id.clone()),
                    zoom: None,
                    neighbors,
                    partners,
                }
            })
            .collect();
        HtmlData {
            title: title.to_owned(),
            nodes,
            frames: Vec::new(),
        }
    }

    #[test]
    fn frames_bring_a_slider_and_travel_escaped() {
        let (ds, layout) = sample();
        let svg_text = svg(&ds, &layout, &SvgStyle::default());
        let plain = html(&svg_text, &sample_data(&ds, "t"));
        assert!(
            !plain.contains("class=\"np-frame\""),
            "no frames, no slider"
        );
        let mut data = sample_data(&ds, "t");
        data.frames = vec![
            HtmlFrame {
                label: format!("level 1: {HOSTILE}"),
                cells: vec![("A".into(), "M0,0L1,0L1,1Z".into(), "#ff0000".into())],
            },
            HtmlFrame {
                label: "level 1: final".into(),
                cells: Vec::new(),
            },
        ];
        let page = html(&svg_text, &data);
        // Two frames and the finished map: positions 0..=2, starting at the end.
        assert!(page.contains("min=\"0\" max=\"2\" value=\"2\""));
        assert!(page.contains("class=\"np-frame\""));
        assert!(!page.contains(HOSTILE));
        let block: serde_json::Value =
            serde_json::from_str(data_block(&page)).expect("data block parses");
        assert_eq!(block["frames"][0]["label"], format!("level 1: {HOSTILE}"));
        assert_eq!(block["frames"][0]["cells"][0][0], "A");
    }

    const HOSTILE: &str = "<script>alert(1)</script>";

    fn page() -> (String, HtmlData) {
        let (dataset, layout) = sample();
        let data = sample_data(&dataset, &format!("Map {HOSTILE}"));
        (
            html(&svg(&dataset, &layout, &SvgStyle::default()), &data),
            data,
        )
    }

    /// The text of the JSON data block.
    fn data_block(page: &str) -> &str {
        let open = format!("<script type=\"application/json\" class=\"{DATA_CLASS}\"");
        let at = page.find(&open).expect("data block");
        let start = at + page[at..].find('>').expect("tag end") + 1;
        let len = page[start..].find("</script>").expect("block end");
        &page[start..start + len]
    }

    #[test]
    fn no_network_references() {
        let (page, _) = page();
        let without_ns = page.replace("xmlns=\"http://www.w3.org/2000/svg\"", "");
        assert!(!without_ns.contains("http://"));
        assert!(!without_ns.contains("https://"));
        assert!(!page.contains(" src="));
        assert!(!page.contains("<link"));
        assert!(!page.contains("@import"));
        assert!(!page.contains("url("));
    }

    #[test]
    fn data_block_round_trips() {
        let (page, data) = page();
        let parsed: serde_json::Value =
            serde_json::from_str(data_block(&page)).expect("valid JSON");
        assert_eq!(parsed, serde_json::to_value(&data).expect("serialisable"));
        assert_eq!(
            parsed["nodes"][2]["label"],
            "<script>alert(1)</script> \"q\""
        );
        assert_eq!(parsed["nodes"][5]["partners"][0][1], false);
    }

    #[test]
    fn hostile_text_appears_only_escaped() {
        let (page, _) = page();
        assert!(!page.contains("<script>alert"));
        assert!(!page.to_lowercase().contains("</script><script>alert"));
        assert!(page.contains("<title>Map &lt;script&gt;alert(1)&lt;/script&gt;</title>"));
        assert!(page.contains("<title>&lt;script&gt;alert(1)&lt;/script&gt; &quot;q&quot; (B)"));
        let block = data_block(&page);
        assert!(block.contains("\\u003cscript>alert(1)\\u003c/script>"));
        assert!(!block.contains('<'));
        // Exactly the two scripts of the page, plus none smuggled in.
        assert_eq!(page.matches("<script").count(), 2);
        assert_eq!(page.matches("</script>").count(), 2);
    }

    #[test]
    fn identical_input_identical_bytes() {
        assert_eq!(page().0, page().0);
    }

    #[test]
    fn every_data_id_is_a_node() {
        let (page, data) = page();
        let unescape = |s: &str| {
            s.replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&")
        };
        let ids: Vec<String> = page
            .split("data-id=\"")
            .skip(1)
            .map(|rest| unescape(&rest[..rest.find('"').expect("closing quote")]))
            .collect();
        assert_eq!(ids.len(), 5, "every node but the root");
        for id in &ids {
            assert!(data.nodes.iter().any(|n| &n.id == id), "{id} has data");
        }
    }

    #[test]
    fn page_has_its_parts() {
        let (page, _) = page();
        assert!(page.starts_with("<!DOCTYPE html>\n"));
        assert!(page.ends_with("</html>\n"));
        for part in [
            "class=\"np-tooltip\"",
            "<input type=\"checkbox\" class=\"np-unrealized-toggle\"",
            "Show unrealized links",
            ".np-dim",
            ".np-partner",
            "<svg xmlns=",
        ] {
            assert!(page.contains(part), "{part}");
        }
        assert!(!SCRIPT.contains("innerHTML"));
        assert!(SCRIPT.contains("part(\"data\")"));
        // Every id carries the page's key, and two maps get two keys.
        let key = page_key("a", "b");
        for id in page.split(" id=\"").skip(1) {
            let id = &id[..id.find('"').expect("quote")];
            assert!(id.starts_with("np-") && id.len() >= 11, "{id}");
        }
        assert_ne!(key, page_key("a", "c"));
    }
}
