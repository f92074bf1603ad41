//! Tests of the HTML page (`src/render/html.rs`): its parts, its escaping, its
//! determinism and its data block (real nodes only, relations written once).

use super::*;
use crate::render::svg::{svg, SvgStyle};
use crate::render::test_support::sample;
use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

/// Page data for the sample: every node, neighbours and partners made up.
fn sample_data(dataset: &Dataset, title: &str) -> HtmlData {
    let at = |id: &str| dataset.find(id).expect("sample id");
    let nodes = dataset
        .nodes()
        .iter()
        .enumerate()
        .map(|(i, node)| {
            let (neighbors, partners) = match node.id.as_str() {
                "A1" => (vec![at("A2"), at("B")], vec![(at("B"), true)]),
                "A2" => (Vec::new(), vec![(at("A3"), false)]),
                _ => (Vec::new(), Vec::new()),
            };
            HtmlNode {
                id: node.id.clone(),
                label: (node.label != node.id).then(|| node.label.clone()),
                parent: node.parent,
                weight: format_value(node.value, ""),
                neighbors: neighbors.into_iter().filter(|&j| j > i).collect(),
                partners,
                ..HtmlNode::default()
            }
        })
        .collect();
    HtmlData {
        title: title.to_owned(),
        heading: Some(title.to_owned()),
        legend: vec![
            LegendItem::Tab,
            LegendItem::Swatch {
                color: crate::render::Rgb::new(1, 2, 3),
                label: HOSTILE.to_owned(),
                group: Some(HOSTILE.to_owned()),
            },
        ],
        unit: " KiB".to_owned(),
        nodes,
        ..HtmlData::default()
    }
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
    let parsed: serde_json::Value = serde_json::from_str(data_block(&page)).expect("valid JSON");
    assert_eq!(parsed, serde_json::to_value(&data).expect("serialisable"));
    assert_eq!(
        parsed["nodes"][2]["label"],
        "<script>alert(1)</script> \"q\""
    );
    assert_eq!(
        parsed["nodes"][3]["partners"][0],
        serde_json::json!([2, true])
    );
    assert_eq!(parsed["nodes"][4]["partners"][0][1], false);
    // Labels equal to ids are not written twice; the root has no parent.
    assert!(parsed["nodes"][3].get("label").is_none());
    assert!(parsed["nodes"][0].get("parent").is_none());
    assert_eq!(parsed["unit"], " KiB");
}

#[test]
fn hostile_text_appears_only_escaped() {
    let (page, _) = page();
    assert!(!page.contains("<script>alert"));
    assert!(!page.to_lowercase().contains("</script><script>alert"));
    assert!(page.contains("<title>Map &lt;script&gt;alert(1)&lt;/script&gt;</title>"));
    // The heading and the legend are HTML text, escaped too.
    assert!(page.contains(">Map &lt;script&gt;alert(1)&lt;/script&gt;</h1>"));
    assert!(page
        .contains("<span class=\"np-legend-text\">&lt;script&gt;alert(1)&lt;/script&gt;</span>"));
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
        .split("<path data-id=\"")
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
        "<input type=\"search\" class=\"np-search-box\"",
        "class=\"np-legend\"",
        ".np-veil",
        ".np-partner",
        ".np-ring-outer",
        "<svg xmlns=",
    ] {
        assert!(page.contains(part), "{part}");
    }
    for script in [SCRIPT, SCRIPT_WITH_HISTORY] {
        assert!(!script.contains("innerHTML"));
        assert!(!script.contains("insertAdjacentHTML"));
        assert!(!script.contains("document.write"));
        // One function scope, in the page as it is.
        assert!(script.starts_with("(function () {\n\"use strict\";\n"));
        assert!(page.contains(SCRIPT) && script.ends_with("})();\n"));
    }
    assert!(STYLE.starts_with("/* "));
    // Every id carries the page's key, and two maps get two keys.
    let key = page_key("a", "b");
    for id in page.split(" id=\"").skip(1) {
        let id = &id[..id.find('"').expect("quote")];
        assert!(id.starts_with("np-") && id.len() >= 11, "{id}");
    }
    assert_ne!(key, page_key("a", "c"));
}

#[test]
fn many_groups_fold_into_the_legend_disclosure() {
    let items: Vec<LegendItem> = (0..20)
        .map(|k| LegendItem::Swatch {
            color: crate::render::Rgb::new(k, k, k),
            label: format!("group {k}"),
            group: Some(format!("g{k}")),
        })
        .collect();
    let text = legend_html(&items, "np-00000000");
    // The first twelve, then every group in the full list.
    assert_eq!(
        text.matches("class=\"np-legend-item\"").count(),
        LEGEND_SHOWN + 20
    );
    let all = &text[text.find("np-legend-list").expect("the full list")..];
    for k in 0..20 {
        assert!(all.contains(&format!("data-id=\"g{k}\"")), "g{k} in {all}");
    }
    assert!(text.contains("class=\"np-legend-filter\""));
    assert!(text.contains(&format!("and {} more groups", 20 - LEGEND_SHOWN)));
    let shown = &text[..text.find("<details>").expect("disclosure")];
    assert_eq!(shown.matches("class=\"np-swatch\"").count(), LEGEND_SHOWN);
    assert_eq!(legend_html(&[], "k"), "");
}

/// A hierarchy with leaves at depths 1 and 2 and similar leaves across
/// groups: the layout pads it with virtual copies.
fn uneven() -> Dataset {
    let mut b = DatasetBuilder::new();
    b.similarity_hint(nptreemap_formats::SimilarityHint::Cosine);
    b.add(NodeSpec::new("root"))
        .add(NodeSpec::new("G").parent("root"))
        .add(NodeSpec::new("H").parent("root"))
        .add(
            NodeSpec::new("solo")
                .parent("root")
                .weight(30.0)
                .features(vec![1.0, 0.0, 0.2]),
        )
        .add(
            NodeSpec::new("g1")
                .parent("G")
                .weight(10.0)
                .features(vec![1.0, 0.05, 0.2]),
        )
        .add(
            NodeSpec::new("g2")
                .parent("G")
                .weight(12.0)
                .features(vec![0.0, 1.0, 0.0]),
        )
        .add(
            NodeSpec::new("h1")
                .parent("H")
                .weight(9.0)
                .features(vec![0.1, 1.0, 0.1]),
        )
        .add(
            NodeSpec::new("h2")
                .parent("H")
                .weight(11.0)
                .features(vec![0.0, 0.1, 1.0]),
        );
    b.build().expect("valid")
}

#[test]
fn the_page_carries_real_nodes_only() {
    let dataset = uneven();
    let computed =
        crate::layout::compute(&dataset, &crate::layout::Request::default()).expect("layout");
    assert!(
        computed.dataset.nodes().iter().any(|n| n.is_virtual),
        "the layout pads the short leaf with copies"
    );
    let page = html_page(&computed, &Style::default());
    let data: serde_json::Value =
        serde_json::from_str(data_block(&page)).expect("data block parses");
    let nodes = data["nodes"].as_array().expect("nodes");
    let ids: Vec<&str> = nodes.iter().filter_map(|n| n["id"].as_str()).collect();
    let mut want: Vec<&str> = dataset.nodes().iter().map(|n| n.id.as_str()).collect();
    let mut got = ids.clone();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want, "exactly the input's nodes");
    // No copy reaches the picture either.
    for id in page.split("data-id=\"").skip(1) {
        let id = &id[..id.find('"').expect("quote")];
        assert!(dataset.find(id).is_some(), "{id} is a real node");
    }
    // The short leaf is a leaf again, with its own weight, and its
    // constraint to g1 (a leaf one level deeper) is there, once.
    let solo = ids.iter().position(|id| *id == "solo").expect("solo");
    assert_eq!(nodes[solo]["weight"], "30");
    assert!(nodes.iter().all(|n| n["parent"] != solo));
    let g1 = ids.iter().position(|id| *id == "g1").expect("g1");
    let (lo, hi) = (solo.min(g1), solo.max(g1));
    let listed = |from: usize, to: usize| {
        nodes[from]["partners"]
            .as_array()
            .is_some_and(|ps| ps.iter().any(|p| p[0] == to))
    };
    assert!(listed(lo, hi), "{}", nodes[lo]);
    assert!(!listed(hi, lo), "written once: {}", nodes[hi]);
}

#[test]
fn the_page_leaves_out_cell_titles_and_link_lines() {
    let svg_text = "<svg>\n<g class=\"np-cells\">\n\
        <path data-id=\"a\" d=\"M0,0Z\" fill=\"#fff\"><title>A &lt;b&gt; (a)</title></path>\n\
        <path data-id=\"b\" d=\"M1,1Z\" fill=\"none\"><title>B</title></path>\n</g>\n\
        <g class=\"np-unrealized\" stroke=\"#d62728\" stroke-width=\"1.50\">\n\
        <line x1=\"0\" y1=\"0\" x2=\"1\" y2=\"1\"/>\n<line x1=\"1\" y1=\"0\" x2=\"0\" y2=\"1\"/>\n</g>\n\
        <g class=\"np-unlinked\"><circle cx=\"1\" cy=\"1\" r=\"2\"><title>3 unrealized link(s)</title></circle>\n</g>\n</svg>\n";
    let light = lighten(svg_text);
    assert_eq!(
        light,
        "<svg>\n<g class=\"np-cells\">\n\
        <path data-id=\"a\" d=\"M0,0Z\" fill=\"#fff\"></path>\n\
        <path data-id=\"b\" d=\"M1,1Z\" fill=\"none\"></path>\n</g>\n\
        <g class=\"np-unrealized\" stroke=\"#d62728\" stroke-width=\"1.50\">\n</g>\n\
        <g class=\"np-unlinked\"><circle cx=\"1\" cy=\"1\" r=\"2\"><title>3 unrealized link(s)</title></circle>\n</g>\n</svg>\n",
        "the markers keep their titles"
    );
    // Nothing else is touched: a picture without either comes back as it was.
    let (ds, layout) = sample();
    let plain = svg(&ds, &layout, &SvgStyle::default()).replace("<title>", "<desc>");
    assert_eq!(lighten(&plain), plain);
}

#[test]
fn label_texts_count_the_leaf_label_group_only() {
    let svg_text = "<g class=\"np-group-labels\"><text>G</text></g>\n\
        <g class=\"np-labels\" font-size=\"9\">\n<text x=\"1\">a</text>\n\
        <text font-size=\"9\"><tspan>b</tspan><tspan>c</tspan></text>\n</g>\n<text>legend</text>";
    assert_eq!(label_texts(svg_text), 2);
    assert_eq!(label_texts("<svg/>"), 0);
}

/// `uneven()` with hostile ids on two leaves and `w` as the weight of g1.
pub(super) fn hostile_uneven(w: f64) -> crate::layout::Computed {
    let mut b = DatasetBuilder::new();
    b.similarity_hint(nptreemap_formats::SimilarityHint::Cosine);
    b.add(NodeSpec::new("root"))
        .add(NodeSpec::new("G").parent("root"))
        .add(NodeSpec::new("H").parent("root"));
    for (id, parent, weight, f) in [
        ("</script><b>g1", "G", w, [1.0, 0.05, 0.2]),
        ("g2 \"q\" & 'a'", "G", 12.0, [0.0, 1.0, 0.0]),
        ("h1", "H", 9.0, [0.1, 1.0, 0.1]),
        ("h2", "H", 11.0, [0.0, 0.1, 1.0]),
    ] {
        b.add(
            NodeSpec::new(id)
                .parent(parent)
                .weight(weight)
                .features(f.to_vec()),
        );
    }
    let dataset = b.build().expect("valid");
    crate::layout::compute(&dataset, &crate::layout::Request::default()).expect("layout")
}

/// The picture's cells in a page: id (unescaped), path data, fill.
pub(super) fn drawn_cells(page: &str) -> Vec<(String, String, String)> {
    let attr = |s: &str, name: &str| -> String {
        let at = s.find(&format!(" {name}=\"")).expect("attribute") + name.len() + 3;
        s[at..at + s[at..].find('"').expect("quote")].to_owned()
    };
    let unescape = |s: String| {
        s.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&amp;", "&")
    };
    page.split("<path data-id=\"")
        .skip(1)
        .map(|rest| {
            let id = &rest[..rest.find('"').expect("id end")];
            let tag = &rest[..rest.find('>').expect("tag end")];
            (unescape(id.to_owned()), attr(tag, "d"), attr(tag, "fill"))
        })
        .collect()
}

#[test]
fn a_page_without_history_is_the_page_as_before() {
    let computed = hostile_uneven(10.0);
    let style = Style::default();
    let page = html_page_with_history(&computed, &style, &[]);
    assert_eq!(page, html_page(&computed, &style));
    // Nothing of the steps: no control, no script, no style, no data.
    for part in [
        "np-history",
        "// src/render/page/history.js\n",
        "// src/render/page/past.js\n",
        "data-np-past",
        "\"history\"",
    ] {
        assert!(!page.contains(part), "{part} in a page without history");
    }
}

#[test]
fn past_layouts_are_the_earlier_pages_cells_and_stay_escaped() {
    let style = Style::default();
    let before = std::sync::Arc::new(hostile_uneven(10.0));
    let after = hostile_uneven(40.0);
    let earlier = html_page(&before, &style);
    let page = html_page_with_history(&after, &style, &[before.clone(), before]);
    let block = data_block(&page);
    assert!(!block.contains('<'), "no `<` in the data block");
    let data: serde_json::Value = serde_json::from_str(block).expect("data block parses");
    let past = data["history"].as_array().expect("history");
    assert_eq!(past.len(), 2);
    let mut want = drawn_cells(&earlier);
    want.sort();
    assert!(want.iter().any(|c| c.0 == "</script><b>g1"), "{want:?}");
    let mut got: Vec<(String, String, String)> =
        serde_json::from_value(past[0].clone()).expect("cells");
    got.sort();
    assert_eq!(got, want, "the earlier page's cells, exactly");
    assert_ne!(
        drawn_cells(&page),
        drawn_cells(&earlier),
        "the layout moved"
    );
    // The control says where it is; the script and its tags are the page's,
    // the steps' modules added.
    assert!(page.contains("layout 3 of 3 (latest)"));
    assert!(page.contains("// src/render/page/past.js\n"));
    let lower = page.to_lowercase();
    let plain = html_page(&after, &style).to_lowercase();
    for tag in ["<script", "</script", "<b>"] {
        assert_eq!(
            lower.matches(tag).count(),
            plain.matches(tag).count(),
            "{tag}"
        );
    }
    // Deterministic: the same layouts give the same bytes.
    let again = Arc::new(hostile_uneven(10.0));
    assert_eq!(
        page,
        html_page_with_history(&after, &style, &[again.clone(), again])
    );
}

#[test]
fn a_zoom_box_stays_inside_the_canvas_and_holds_its_group() {
    // Groups of uneven weight: some sit at the map's edges, where a box
    // centred on them reached past the canvas (blank page in the view).
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("root"));
    for g in 0..8 {
        let group = format!("g{g}");
        b.add(NodeSpec::new(group.clone()).parent("root"));
        for k in 0..3 {
            let weight = 1.0 + (g * 3 + k) as f64;
            b.add(
                NodeSpec::new(format!("{group}-{k}"))
                    .parent(group.as_str())
                    .weight(weight),
            );
        }
    }
    let dataset = b.build().expect("valid");
    let computed =
        crate::layout::compute(&dataset, &crate::layout::Request::default()).expect("layout");
    let (data, layout) = (&computed.dataset, &computed.layout);
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);
    let mut boxes = 0;
    for g in 0..8 {
        let i = data.find(&format!("g{g}")).expect("group");
        let Some([x, y, w, h]) = zoom_box(data, layout, i) else {
            continue;
        };
        boxes += 1;
        let (lo, hi) = layout.cells[i].polygon.bbox();
        // Rounded to hundredths.
        let eps = 0.01;
        assert!(x >= -eps && y >= -eps, "g{g}: {x},{y}");
        assert!(
            x + w <= cw + eps && y + h <= ch + eps,
            "g{g}: {x},{y} {w}x{h}"
        );
        assert!(
            x <= lo.x + eps && y <= lo.y + eps,
            "g{g} starts inside its box"
        );
        assert!(
            x + w >= hi.x - eps && y + h >= hi.y - eps,
            "g{g} ends inside its box"
        );
    }
    assert!(boxes >= 4, "{boxes} groups worth zooming into");
}
