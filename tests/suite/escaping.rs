//! Hostile text (issue 5): ids, labels and the title carrying `<script>`,
//! `</svg>`, `]]>`, `<!--`, `&` and quotes go through `nptreemap layout` to SVG,
//! HTML, PNG and layout JSON. The SVG must parse as XML and give every string
//! back exactly as text; the HTML page must carry no script but its own and a
//! data block that parses back to the same strings; the PNG must render.

use std::path::Path;
use std::sync::OnceLock;

use resvg::usvg::{self, roxmltree};
use serde_json::{json, Value};

use crate::support;

const SCRIPT: &str = "<script>alert(1)</script>";
const TITLE: &str = "Map <script>alert(1)</script> & \"double\" 'single' ]]> </svg>";

/// `(id, label)` of every leaf, grouped in two parents; each id is as hostile
/// as its label because ids reach the SVG (`data-id`) and the page's data too.
const LEAVES: [[(&str, &str); 4]; 2] = [
    [
        (SCRIPT, SCRIPT),
        ("a&b", "Tom & \"Jerry\" 'quoted'"),
        ("x]]>y", "CDATA end ]]> here"),
        ("</svg>", "</svg> closes"),
    ],
    [
        ("c<!--", "<!-- comment --> <ScRiPt>alert(2)</ScRiPt>"),
        ("</script><script>alert(3)</script>", "</SCRIPT>break out"),
        ("plain", "Plain"),
        ("q\"'", "\"><svg onload=alert(4)>"),
    ],
];

/// Ids and labels of the two groups.
const GROUPS: [(&str, &str); 2] = [
    ("g&<\"1\">", "</svg><script>alert(1)</script>"),
    ("g2]]>", "Group & <b>two</b>"),
];

/// The dataset as hierarchy JSON; every leaf "borders" the next in its group,
/// so the overlay writes tabs whose `data-a`/`data-b` carry the hostile ids.
fn hostile_input() -> Value {
    let groups: Vec<Value> = GROUPS
        .iter()
        .zip(&LEAVES)
        .map(|((gid, gname), leaves)| {
            let children: Vec<Value> = leaves
                .iter()
                .enumerate()
                .map(|(k, (id, name))| {
                    let next = leaves[(k + 1) % leaves.len()].0;
                    json!({"id": id, "name": name, "value": 10 + k, "neighbors": [next]})
                })
                .collect();
            json!({"id": gid, "name": gname, "children": children})
        })
        .collect();
    json!({"name": TITLE, "useNeighborLeafs": true, "children": groups})
}

/// Every node's label, root included.
fn all_labels() -> Vec<&'static str> {
    let mut labels = vec![TITLE];
    labels.extend(GROUPS.iter().map(|g| g.1));
    labels.extend(LEAVES.iter().flatten().map(|l| l.1));
    labels
}

/// Every drawn node's id (the root's cell is not drawn).
fn drawn_ids() -> Vec<&'static str> {
    let mut ids: Vec<&str> = GROUPS.iter().map(|g| g.0).collect();
    ids.extend(LEAVES.iter().flatten().map(|l| l.0));
    ids
}

struct Outputs {
    svg: String,
    html: String,
    png: Vec<u8>,
    json: String,
}

/// The four outputs, rendered once for all tests of this module.
fn render() -> &'static Outputs {
    static OUTPUTS: OnceLock<Outputs> = OnceLock::new();
    OUTPUTS.get_or_init(render_once)
}

fn render_once() -> Outputs {
    let dir = support::temp_dir("escaping");
    let input = dir.join("hostile.json");
    std::fs::write(&input, hostile_input().to_string()).expect("write input");
    let out = |ext: &str| dir.join(format!("map.{ext}"));
    let paths = [out("svg"), out("html"), out("png"), out("json")];
    let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
    support::layout(
        &input,
        &refs,
        &["--width", "800", "--height", "800", "--seed", "1"],
    );
    let text = |p: &Path| std::fs::read_to_string(p).expect("read output");
    Outputs {
        svg: text(&paths[0]),
        html: text(&paths[1]),
        png: std::fs::read(&paths[2]).expect("read png"),
        json: text(&paths[3]),
    }
}

/// Checks an SVG document (on its own or cut out of the page) as XML: it
/// parses, has no `<script>` element, every `data-id` and `data-a`/`data-b` is
/// one of ours, every cell title (when `titles`: the page's copy has none,
/// its script names cells) and label reads back exactly, and the hostile
/// labels are really drawn.
fn check_svg_document(svg: &str, what: &str, titles: bool) {
    let doc = roxmltree::Document::parse(svg)
        .unwrap_or_else(|e| panic!("{what}: the SVG is not well-formed XML: {e}"));
    let root = doc.root_element();
    assert!(root.has_tag_name("svg"), "{what}: root is <svg>");
    let elements: Vec<_> = root.descendants().filter(|n| n.is_element()).collect();
    assert!(
        elements
            .iter()
            .all(|n| !n.tag_name().name().eq_ignore_ascii_case("script")),
        "{what}: a <script> element got in"
    );
    assert_eq!(
        elements.iter().filter(|n| n.has_tag_name("svg")).count(),
        1,
        "{what}: a label opened or closed an <svg>"
    );
    // Only the attributes we write, so no label smuggled in `onload` & co.
    for n in &elements {
        for a in n.attributes() {
            assert!(
                !a.name().starts_with("on"),
                "{what}: event attribute {}",
                a.name()
            );
        }
    }

    let ids = drawn_ids();
    let data_ids: Vec<&str> = elements
        .iter()
        .filter_map(|n| n.attribute("data-id"))
        .collect();
    assert_eq!(data_ids.len(), ids.len(), "{what}: one cell per drawn node");
    for id in &ids {
        assert!(data_ids.contains(id), "{what}: data-id {id:?} reads back");
    }
    let tab_ends: Vec<&str> = elements
        .iter()
        .flat_map(|n| [n.attribute("data-a"), n.attribute("data-b")])
        .flatten()
        .collect();
    assert!(!tab_ends.is_empty(), "{what}: the overlay drew tabs");
    assert!(
        tab_ends.iter().all(|id| ids.contains(id)),
        "{what}: tab ends {tab_ends:?}"
    );

    // Cell tooltips are `label (id)` when the two differ, else the label.
    let cell_titles: Vec<&str> = elements
        .iter()
        .filter(|n| n.has_tag_name("title"))
        .filter_map(|n| n.text())
        .collect();
    let (g, leaf) = (GROUPS[0], LEAVES[0][1]);
    if !titles {
        assert!(titles_are_absent(&elements), "{what}: cell titles");
    }
    for expected in [
        g.1.to_owned() + " (" + g.0 + ")",
        leaf.1.to_owned() + " (" + leaf.0 + ")",
        SCRIPT.to_owned(),
    ] {
        if !titles {
            break;
        }
        assert!(
            cell_titles.contains(&expected.as_str()),
            "{what}: title {expected:?}"
        );
    }

    // Drawn text, per `<text>`: its lines (the element's own text, or its
    // `<tspan>`s when a label wraps). Every line is part of a label, read
    // back exactly (a cut label ends in an ellipsis).
    let labels = all_labels();
    let drawn: Vec<Vec<&str>> = elements
        .iter()
        .filter(|n| n.has_tag_name("text") && n.attribute("class") != Some("np-title"))
        .filter(|n| {
            !n.ancestors().any(|a| {
                a.attribute("class")
                    .is_some_and(|c| c.starts_with("np-legend") || c == "np-unlinked-count")
            })
        })
        .map(|n| {
            let spans: Vec<&str> = n
                .children()
                .filter(|c| c.has_tag_name("tspan"))
                .filter_map(|c| c.text())
                .collect();
            if spans.is_empty() {
                n.text().into_iter().collect()
            } else {
                spans
            }
        })
        .collect();
    for line in drawn.iter().flatten() {
        let part = line.trim_end_matches('…');
        assert!(
            labels.iter().any(|l| l.contains(part)),
            "{what}: drawn {line:?} is no label's text"
        );
    }
    let whole: Vec<(String, String)> = drawn
        .iter()
        .map(|lines| (lines.join(" "), lines.concat()))
        .collect();
    for must in [SCRIPT, LEAVES[0][2].1, LEAVES[1][3].1] {
        assert!(
            whole
                .iter()
                .any(|(spaced, joined)| spaced == must || joined == must),
            "{what}: label {must:?} drawn: {drawn:?}"
        );
    }
}

#[test]
fn svg_parses_and_gives_every_string_back() {
    let out = render();
    check_svg_document(&out.svg, "SVG", true);
    assert!(!out.svg.to_lowercase().contains("<script"));
    assert!(out.svg.contains("&lt;script&gt;alert(1)&lt;/script&gt;"));
    // The renderer's own parser accepts it too (the PNG path depends on it).
    usvg::Tree::from_str(&out.svg, &usvg::Options::default()).expect("usvg parses the SVG");

    // The layout JSON is JSON and keeps the ids.
    let layout: Value = serde_json::from_str(&out.json).expect("layout JSON parses");
    let text = layout.to_string();
    for id in drawn_ids() {
        assert!(
            text.contains(&serde_json::to_string(id).expect("string")),
            "{id:?}"
        );
    }
}

#[test]
fn html_page_runs_no_hostile_script_and_its_data_round_trips() {
    let out = render();
    let page = &out.html;
    let lower = page.to_lowercase();
    assert!(!lower.contains("<script>alert"), "a hostile script tag");

    // The page's own script tags, counted on a harmless page made by the same
    // template, are all there are.
    let benign = nptreemap::render::html(
        "<svg xmlns=\"http://www.w3.org/2000/svg\"/>",
        &nptreemap::render::HtmlData {
            title: "t".to_owned(),
            ..Default::default()
        },
    )
    .to_lowercase();
    for tag in ["<script", "</script"] {
        assert_eq!(
            lower.matches(tag).count(),
            benign.matches(tag).count(),
            "{tag}"
        );
    }
    assert!(!lower.contains("<svg onload"));

    // <title> holds the escaped root label.
    let start = page.find("<title>").expect("title") + "<title>".len();
    let end = start + page[start..].find("</title>").expect("title end");
    assert_eq!(
        unescape(&page[start..end]),
        TITLE,
        "the page title reads back"
    );

    // The inline SVG is the same well-formed document.
    let open = "<div class=\"np-map\"";
    let at = page.find(open).expect("map div");
    let svg_start = at + page[at..].find(">\n").expect("div end") + 2;
    let svg_end = svg_start + page[svg_start..].find("</svg>\n").expect("svg end") + 7;
    check_svg_document(&page[svg_start..svg_end], "HTML's SVG", false);

    // The data block holds no `<` at all (so neither `</script` nor `<!--`),
    // and parses back to exactly the strings we put in.
    let open = "<script type=\"application/json\" class=\"np-data\"";
    let at = page.find(open).expect("data block");
    let start = at + page[at..].find('>').expect("tag end") + 1;
    let end = start + page[start..].find("</script>").expect("block end");
    let block = &page[start..end];
    assert!(!block.contains('<'), "raw `<` in the data block");
    let data: Value = serde_json::from_str(block).expect("the data block is JSON");
    assert_eq!(data["title"], TITLE);
    let nodes = data["nodes"].as_array().expect("nodes");
    for (id, label) in LEAVES.iter().flatten() {
        let node = nodes
            .iter()
            .find(|n| n["id"] == *id)
            .unwrap_or_else(|| panic!("node {id:?} in the data"));
        // A label equal to the id is not written twice.
        let name = node["label"].as_str().or(node["id"].as_str());
        assert_eq!(name, Some(*label));
        // The parents lead to the root, whose label is the title.
        let mut path = Vec::new();
        let mut at = node;
        loop {
            path.push(at["label"].as_str().or(at["id"].as_str()).expect("name"));
            match at["parent"].as_u64() {
                Some(p) => at = &nodes[p as usize],
                None => break,
            }
        }
        assert_eq!(path.last(), Some(&TITLE));
        assert_eq!(path.first(), Some(label));
    }
}

#[test]
fn png_renders() {
    let out = render();
    let image = resvg::tiny_skia::Pixmap::decode_png(&out.png).expect("a valid PNG");
    // 800 wide; taller by the title band and the legend.
    assert_eq!(image.width(), 800);
    assert!(image.height() > 800, "{}", image.height());
    // Something dark was drawn: the labels (the cells are mid-tone colours).
    let dark = image
        .pixels()
        .iter()
        .filter(|p| p.red() < 60 && p.green() < 60 && p.blue() < 60)
        .count();
    assert!(dark > 500, "only {dark} dark pixels");
}

/// Whether no cell `<path>` carries a `<title>`.
fn titles_are_absent(elements: &[roxmltree::Node<'_, '_>]) -> bool {
    elements
        .iter()
        .filter(|n| n.has_tag_name("path") && n.attribute("data-id").is_some())
        .all(|n| !n.children().any(|c| c.has_tag_name("title")))
}

/// Undoes the renderer's XML escaping (the five entities it writes).
fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}
