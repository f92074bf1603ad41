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
    /// Ids of the cells at the same depth sharing an edge with this one
    /// (`neighbours` in the page's data, which its script reads).
    #[serde(rename = "neighbours")]
    pub neighbors: Vec<String>,
    /// Ids of the node's constraint partners, each with whether the constraint
    /// is realised (the two cells share an edge).
    pub partners: Vec<(String, bool)>,
}

/// Id of the JSON data block, which the script reads.
const DATA_ID: &str = "nptreemap-data";

/// Inline style: the hover classes, the tooltip and a responsive picture.
const STYLE: &str = r#"body { margin: 1em; font: 14px Helvetica, Arial, sans-serif; color: #1a1a1a; }
#np-map svg { max-width: 100%; height: auto; display: block; }
#np-map path { transition: opacity .1s; }
#np-map path.np-dim { opacity: .25; }
#np-map path.np-partner { stroke: #000; stroke-width: 4px; }
#np-map path.np-partner-unrealized { stroke-dasharray: 6 3; }
body.np-hide-unrealized .np-unrealized { display: none; }
#np-tooltip { position: fixed; pointer-events: none; background: #fff; border: 1px solid #888;
  padding: .3em .5em; max-width: 40em; box-shadow: 0 1px 4px rgba(0,0,0,.3); }
#np-tooltip[hidden] { display: none; }
#np-frames { margin: .5em 0; }
#np-frames input { width: 24em; vertical-align: middle; }
"#;

/// Inline script: hover highlighting, tooltip, and the unrealised-links toggle.
/// User text reaches the page only through `textContent`.
const SCRIPT: &str = r##"(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("nptreemap-data").textContent);
  // Maps and sets, never plain objects: ids such as "constructor",
  // "toString" or "__proto__" are keys like any other (issue 11, item 14).
  var nodes = new Map();
  data.nodes.forEach(function (n) { nodes.set(n.id, n); });
  var map = document.getElementById("np-map");
  var tip = document.getElementById("np-tooltip");
  var cells = new Map();
  var leaves = [];
  Array.prototype.forEach.call(map.querySelectorAll("path[data-id]"), function (el) {
    var id = el.getAttribute("data-id");
    cells.set(id, el);
    if (nodes.has(id) && nodes.get(id).leaf) { leaves.push(el); }
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

  map.addEventListener("mouseover", function (e) {
    var el = e.target.closest ? e.target.closest("path[data-id]") : null;
    if (el === current) { return; }
    clear();
    var n = el && nodes.get(el.getAttribute("data-id"));
    if (n && n.leaf) { show(el); }
  });
  map.addEventListener("mouseleave", clear);
  map.addEventListener("mousemove", function (e) {
    // Beside the pointer, flipped to its other side near the window's edge
    // so the tooltip never runs out of view.
    var x = e.clientX + 14, y = e.clientY + 14;
    if (x + tip.offsetWidth > window.innerWidth) { x = Math.max(0, e.clientX - 14 - tip.offsetWidth); }
    if (y + tip.offsetHeight > window.innerHeight) { y = Math.max(0, e.clientY - 14 - tip.offsetHeight); }
    tip.style.left = x + "px";
    tip.style.top = y + "px";
  });

  // The optimisation slider: frame k drawn over the map, the last position
  // the finished picture.
  var slider = document.getElementById("np-frame");
  if (slider && data.frames) {
    var svgRoot = map.querySelector("svg");
    var NS = svgRoot.namespaceURI;
    var layer = document.createElementNS(NS, "g");
    layer.setAttribute("id", "np-frame-layer");
    layer.setAttribute("pointer-events", "none");
    layer.setAttribute("stroke", "#ffffff");
    layer.setAttribute("stroke-width", "1");
    svgRoot.appendChild(layer);
    var caption = document.getElementById("np-frame-label");
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

  var box = document.getElementById("np-unrealized");
  function toggle() { document.body.classList.toggle("np-hide-unrealized", !box.checked); }
  box.addEventListener("change", toggle);
  toggle();
})();
"##;

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
    let mut out = String::with_capacity(svg.len() + STYLE.len() + SCRIPT.len() + 1024);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str(
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>",
    );
    out.push_str(&escape(&data.title));
    out.push_str("</title>\n<style>\n");
    out.push_str(STYLE);
    out.push_str("</style>\n</head>\n<body>\n");
    out.push_str(
        "<label><input type=\"checkbox\" id=\"np-unrealized\"> \
         Show unrealized links</label>\n",
    );
    if !data.frames.is_empty() {
        // The last position is the finished picture; the others are frames.
        out.push_str(&format!(
            "<div id=\"np-frames\"><label>Optimisation <input type=\"range\" id=\"np-frame\" \
             min=\"0\" max=\"{n}\" value=\"{n}\" step=\"1\"></label> \
             <span id=\"np-frame-label\">final layout</span></div>\n",
            n = data.frames.len()
        ));
    }
    out.push_str("<div id=\"np-map\">\n");
    out.push_str(svg);
    if !svg.ends_with('\n') {
        out.push('\n');
    }
    out.push_str("</div>\n<div id=\"np-tooltip\" hidden></div>\n");
    out.push_str(&format!(
        "<script type=\"application/json\" id=\"{DATA_ID}\">\n"
    ));
    out.push_str(&data_json(data));
    out.push_str("\n</script>\n<script>\n");
    out.push_str(SCRIPT);
    out.push_str("</script>\n</body>\n</html>\n");
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
        assert!(!plain.contains("id=\"np-frame\""), "no frames, no slider");
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
        let open = format!("<script type=\"application/json\" id=\"{DATA_ID}\">");
        let start = page.find(&open).expect("data block") + open.len();
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
            "<div id=\"np-tooltip\" hidden></div>",
            "<input type=\"checkbox\" id=\"np-unrealized\">",
            "Show unrealized links",
            ".np-dim",
            ".np-partner",
            "<svg xmlns=",
        ] {
            assert!(page.contains(part), "{part}");
        }
        assert!(!SCRIPT.contains("innerHTML"));
        assert!(SCRIPT.contains(DATA_ID));
    }
}
