//! Legibility of the default pictures (issue 13): on Flare, a generated
//! 1,000-leaf similarity hierarchy, every example and the committed real
//! datasets (`tests/data/real/`), built by the real
//! binary at 1,000 × 1,000, no leaf label is covered by a count marker or a
//! tab, no label is below the minimum size, no overlay leaves the map's
//! outline, count markers cover at most 2 % of the map, adjacent top-level
//! groups do not look alike, and the group names are on the map.
//!
//! Label boxes are usvg's own text layout (the box it lays each `<text>` out
//! in from the built-in font's advances and ascent/descent), not estimates;
//! marker circles and tab polygons are read from the SVG; cells, groups and
//! the outline from the layout JSON written in the same run. Nothing here
//! calls the renderer's placement code.
//!
//! `NPTREEMAP_LEGIBILITY=a.svg,b.svg cargo test --test suite legibility_report
//! -- --ignored --nocapture` prints the same figures for any pictures (each
//! with its layout JSON beside it, same stem), e.g. those of an older binary.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use resvg::usvg::{self, roxmltree};
use serde_json::Value;

use crate::support;
use crate::tabs::shared_segments;

type P = [f64; 2];

/// The default minimum label size at scale 1 (`render.labels.min_size`).
const MIN_SIZE: f64 = 9.0;
/// Marker area allowed, as a share of the map (issue 13's acceptance).
const MAX_MARKER_SHARE: f64 = 0.02;
/// Two adjacent groups whose colours (see [`measure`]) are closer than this in
/// OKLab look alike: 0.02 is a just noticeable difference for small patches,
/// and large areas side by side need a few of them.
const ALIKE: f64 = 0.05;

/// What one picture measures.
#[derive(Debug, Default)]
struct Figures {
    leaves: usize,
    labels: usize,
    small: Vec<String>,
    covered: Vec<String>,
    outside: Vec<String>,
    marker_share: f64,
    groups: usize,
    adjacent_groups: usize,
    alike: Vec<(String, String, f64)>,
    group_names: usize,
}

/// A label as usvg lays it out: its text, its smallest font size and its box.
struct TextBox {
    text: String,
    class: String,
    min_size: f64,
    rect: [f64; 4],
}

/// Every `<text>` of the SVG with its class (the nearest ancestor's) and the
/// box usvg lays it out in. Each `<text` gets an id first, so usvg's text
/// nodes can be matched to the source's elements (user text is escaped, so
/// `<text` only ever starts an element).
fn text_boxes(svg: &str) -> Vec<TextBox> {
    let mut tagged = String::with_capacity(svg.len() + 16 * 1024);
    let mut k = 0usize;
    let mut rest = svg;
    while let Some(at) = rest.find("<text") {
        let (before, after) = rest.split_at(at + 5);
        tagged.push_str(before);
        if after.starts_with([' ', '>', '\n', '\t']) {
            tagged.push_str(&format!(" id=\"np-t{k}\""));
            k += 1;
        }
        rest = after;
    }
    tagged.push_str(rest);
    let doc = roxmltree::Document::parse(&tagged).expect("the SVG is XML");
    let classes: BTreeMap<String, (String, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            let class = n
                .ancestors()
                .find_map(|a| a.attribute("class"))
                .unwrap_or("")
                .to_owned();
            let text: String = n
                .descendants()
                .filter(|d| d.is_text())
                .filter_map(|d| d.text())
                .collect::<Vec<_>>()
                .join(" ");
            (n.attribute("id").expect("tagged").to_owned(), (class, text))
        })
        .collect();
    let mut options = usvg::Options::default();
    options
        .fontdb_mut()
        .load_font_data(include_bytes!("../../src/render/fonts/DejaVuSans.ttf").to_vec());
    options.font_family = "DejaVu Sans".to_owned();
    options.fontdb_mut().set_sans_serif_family("DejaVu Sans");
    let tree = usvg::Tree::from_str(&tagged, &options).expect("usvg parses the SVG");
    let mut out = Vec::new();
    collect(tree.root(), &classes, &mut out);
    out
}

fn collect(
    group: &usvg::Group,
    classes: &BTreeMap<String, (String, String)>,
    out: &mut Vec<TextBox>,
) {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => collect(g, classes, out),
            usvg::Node::Text(t) => {
                let Some((class, text)) = classes.get(t.id()) else {
                    continue;
                };
                // In the text's user space (the map's units: no group moves
                // the labels), not the viewBox-transformed absolute one.
                let r = t.bounding_box();
                let min_size = t
                    .chunks()
                    .iter()
                    .flat_map(|c| c.spans())
                    .map(|s| f64::from(s.font_size().get()))
                    .fold(f64::INFINITY, f64::min);
                out.push(TextBox {
                    text: text.clone(),
                    class: class.clone(),
                    min_size,
                    rect: [
                        f64::from(r.left()),
                        f64::from(r.top()),
                        f64::from(r.right()),
                        f64::from(r.bottom()),
                    ],
                });
            }
            _ => {}
        }
    }
}

/// The overlays drawn over the cells: tab polygons and marker circles.
#[derive(Default)]
struct Overlays {
    tabs: Vec<(String, Vec<P>)>,
    markers: Vec<(P, f64)>,
}

fn numbers(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect()
}

fn attr(node: roxmltree::Node, name: &str) -> f64 {
    node.attribute(name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("<{}> has a numeric {name}", node.tag_name().name()))
}

fn overlays(svg: &str) -> Overlays {
    let doc = roxmltree::Document::parse(svg).expect("XML");
    let mut out = Overlays::default();
    for g in doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("np-tab"))
    {
        let name = format!(
            "{}-{}",
            g.attribute("data-a").unwrap_or("?"),
            g.attribute("data-b").unwrap_or("?")
        );
        for shape in g.descendants() {
            let pts = match shape.tag_name().name() {
                "polygon" => numbers(shape.attribute("points").unwrap_or("")),
                "path" => {
                    let d = shape.attribute("d").unwrap_or("");
                    assert!(
                        d.chars()
                            .all(|c| !c.is_ascii_alphabetic() || "MLZ".contains(c)),
                        "tab paths are polygons: {d}"
                    );
                    numbers(d)
                }
                _ => continue,
            };
            let pts: Vec<P> = pts.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
            out.tabs.push((name.clone(), pts));
        }
    }
    for c in doc.descendants().filter(|n| {
        n.has_tag_name("circle")
            && n.ancestors()
                .any(|a| a.attribute("class") == Some("np-unlinked"))
    }) {
        out.markers
            .push(([attr(c, "cx"), attr(c, "cy")], attr(c, "r")));
    }
    out
}

fn inside_polygon(p: P, poly: &[P]) -> bool {
    // Even-odd ray casting; fine for the convex and simple shapes here.
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]
        {
            inside = !inside;
        }
    }
    inside
}

fn segments_cross(a: P, b: P, c: P, d: P) -> bool {
    let o = |p: P, q: P, r: P| (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    (d1 > 0.0) != (d2 > 0.0) && (d3 > 0.0) != (d4 > 0.0)
}

/// Whether a polygon and an axis-aligned rectangle overlap (with area).
fn polygon_hits_rect(poly: &[P], r: [f64; 4]) -> bool {
    let corners = [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]];
    let in_rect = |p: &P| p[0] > r[0] && p[0] < r[2] && p[1] > r[1] && p[1] < r[3];
    if poly.iter().any(in_rect) || corners.iter().any(|c| inside_polygon(*c, poly)) {
        return true;
    }
    (0..poly.len()).any(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        (0..4).any(|k| segments_cross(a, b, corners[k], corners[(k + 1) % 4]))
    })
}

fn circle_hits_rect((c, radius): (P, f64), r: [f64; 4]) -> bool {
    let dx = c[0] - c[0].clamp(r[0], r[2]);
    let dy = c[1] - c[1].clamp(r[1], r[3]);
    dx * dx + dy * dy < radius * radius
}

fn distance_to_segment(x: P, a: P, b: P) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 > 0.0 {
        (((x[0] - a[0]) * d[0] + (x[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((x[0] - a[0] - t * d[0]).powi(2) + (x[1] - a[1] - t * d[1]).powi(2)).sqrt()
}

fn points(v: &Value) -> Vec<P> {
    v.as_array()
        .expect("polygon")
        .iter()
        .map(|p| [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")])
        .collect()
}

fn hex(color: &str) -> Option<[f64; 3]> {
    let h = color.strip_prefix('#')?;
    let c = |k: usize| u8::from_str_radix(&h[k..k + 2], 16).ok().map(f64::from);
    Some([c(0)?, c(2)?, c(4)?])
}

/// sRGB to OKLab (Ottosson 2020), written out independently of the renderer.
fn oklab([r, g, b]: [f64; 3]) -> [f64; 3] {
    let lin = |c: f64| {
        let c = c / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let (r, g, b) = (lin(r), lin(g), lin(b));
    let l = (0.4122214708 * r + 0.5363325363 * g + 0.0514459929 * b).cbrt();
    let m = (0.2119034982 * r + 0.6806995451 * g + 0.1073969566 * b).cbrt();
    let s = (0.0883024619 * r + 0.2817188376 * g + 0.6299787005 * b).cbrt();
    [
        0.2104542553 * l + 0.7936177850 * m - 0.0040720468 * s,
        1.9779984951 * l - 2.4285922050 * m + 0.4505937099 * s,
        0.0259040371 * l + 0.7827717662 * m - 0.8086757660 * s,
    ]
}

/// Measures one picture against its layout JSON.
fn measure(svg: &str, layout: &Value) -> Figures {
    let nodes = layout["nodes"].as_array().expect("nodes");
    let by_id: BTreeMap<&str, &Value> = nodes
        .iter()
        .map(|n| (n["id"].as_str().expect("id"), n))
        .collect();
    let root = nodes
        .iter()
        .find(|n| n["parent"].is_null())
        .expect("a root");
    let outline = points(&root["polygon"]);
    let (w, h) = (
        layout["canvas"]["width"].as_f64().expect("w"),
        layout["canvas"]["height"].as_f64().expect("h"),
    );
    let mut f = Figures {
        leaves: nodes
            .iter()
            .filter(|n| {
                n["children"].as_array().is_none_or(|c| c.is_empty()) && n["virtual"] != true
            })
            .count(),
        ..Figures::default()
    };
    let boxes = text_boxes(svg);
    let labels: Vec<&TextBox> = boxes.iter().filter(|b| b.class == "np-labels").collect();
    f.labels = labels.len();
    f.group_names = boxes
        .iter()
        .filter(|b| b.class == "np-group-labels")
        .count();
    let over = overlays(svg);
    for l in &labels {
        if l.min_size < MIN_SIZE - 1e-3 {
            f.small.push(format!("{} ({:.1} px)", l.text, l.min_size));
        }
        let by_tab = over.tabs.iter().find(|(_, p)| polygon_hits_rect(p, l.rect));
        let by_marker = over.markers.iter().any(|m| circle_hits_rect(*m, l.rect));
        if let Some((tab, _)) = by_tab {
            f.covered.push(format!("{} (tab {tab})", l.text));
        } else if by_marker {
            f.covered.push(format!("{} (marker)", l.text));
        }
    }
    // Overlays stay inside the outline (a hundredth of a unit for the SVG's
    // two decimals).
    let inside = |p: P, margin: f64| {
        inside_polygon(p, &outline)
            && (0..outline.len()).all(|i| {
                distance_to_segment(p, outline[i], outline[(i + 1) % outline.len()])
                    >= margin - 0.01
            })
    };
    for (name, poly) in &over.tabs {
        if let Some(p) = poly.iter().find(|p| !inside(**p, 0.0)) {
            f.outside.push(format!("tab {name} at {p:?}"));
        }
    }
    for (c, r) in &over.markers {
        if !inside(*c, *r) {
            f.outside.push(format!("marker at {c:?}"));
        }
    }
    f.marker_share = over
        .markers
        .iter()
        .map(|(_, r)| std::f64::consts::PI * r * r)
        .sum::<f64>()
        / (w * h)
        + 0.0;

    // Top-level groups: their colour from the SVG's cell fills, and which of
    // them share an edge.
    let doc = roxmltree::Document::parse(svg).expect("XML");
    let fills: BTreeMap<&str, [f64; 3]> = doc
        .descendants()
        .filter(|n| n.has_tag_name("path"))
        .filter_map(|n| Some((n.attribute("data-id")?, hex(n.attribute("fill")?)?)))
        .collect();
    let root_id = root["id"].as_str().expect("root id");
    let top = |start: &str| -> Option<String> {
        let mut id = start.to_owned();
        loop {
            let parent = by_id.get(id.as_str())?["parent"].as_str()?;
            if parent == root_id {
                return Some(id);
            }
            id = parent.to_owned();
        }
    };
    // Each group's colour: its leaf colour of median lightness (leaves vary
    // their group's colour in lightness only, so two groups of one base
    // colour meet in the middle whatever their sizes).
    let mut shades: BTreeMap<String, Vec<[f64; 3]>> = BTreeMap::new();
    for (id, fill) in &fills {
        let Some(group) = top(id) else { continue };
        if group == *id {
            continue;
        }
        shades.entry(group).or_default().push(oklab(*fill));
    }
    let sums: BTreeMap<String, [f64; 3]> = shades
        .into_iter()
        .map(|(g, mut v)| {
            v.sort_by(|a, b| a[0].total_cmp(&b[0]));
            (g, v[v.len() / 2])
        })
        .collect();
    let groups: Vec<(&str, Vec<P>)> = nodes
        .iter()
        .filter(|n| n["parent"].as_str() == Some(root_id))
        .filter(|n| sums.contains_key(n["id"].as_str().unwrap_or("")))
        .map(|n| (n["id"].as_str().expect("id"), points(&n["polygon"])))
        .collect();
    f.groups = groups.len();
    let diagonal = (w * w + h * h).sqrt();
    for (i, (a, pa)) in groups.iter().enumerate() {
        for (b, pb) in &groups[i + 1..] {
            let shared: f64 = shared_segments(pa, pb, 1e-3)
                .iter()
                .map(|(p, q)| ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt())
                .sum();
            if shared < 1e-3 * diagonal {
                continue;
            }
            f.adjacent_groups += 1;
            let (ma, mb) = (&sums[*a], &sums[*b]);
            let d = (0..3).map(|k| (ma[k] - mb[k]).powi(2)).sum::<f64>().sqrt();
            if d < ALIKE {
                f.alike.push((a.to_string(), b.to_string(), d));
            }
        }
    }
    f
}

fn row(name: &str, f: &Figures) -> String {
    format!(
        "| {name} | {} | {} | {} | {} | {:.2}% | {} of {} | {} of {} | {} |",
        f.leaves,
        f.labels,
        f.small.len(),
        f.covered.len(),
        100.0 * f.marker_share,
        f.alike.len(),
        f.adjacent_groups,
        f.group_names,
        f.groups,
        f.outside.len(),
    )
}

const HEADER: &str = "| picture | leaves | labels drawn | labels < 9 px | labels covered | marker area / map | adjacent groups alike | group names on the map | overlays outside |\n|---|--:|--:|--:|--:|--:|--:|--:|--:|";

fn read(svg: &Path) -> (String, Value) {
    let text = std::fs::read_to_string(svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
    let json = svg.with_extension("json");
    let layout: Value = serde_json::from_slice(
        &std::fs::read(&json).unwrap_or_else(|e| panic!("{}: {e}", json.display())),
    )
    .expect("layout JSON");
    (text, layout)
}

/// The pictures the test judges: every example, Flare and a generated
/// 1,000-leaf similarity hierarchy, as SVG with layout JSON beside it.
fn pictures() -> Vec<(String, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = support::temp_dir("legibility");
    let mut out = Vec::new();
    // Every example, with its own config (titles, outlines, border).
    let config = dir.join("examples/nptreemap.yaml");
    copy_dir(&root.join("examples"), &dir.join("examples"));
    support::build(&config);
    for name in ["countries", "movies", "foods", "stocks", "world"] {
        out.push((
            name.to_owned(),
            dir.join(format!("examples/out/{name}.svg")),
        ));
    }
    support::build(&dir.join("examples/countries/nptreemap.yaml"));
    out.push((
        "countries (n-gon)".to_owned(),
        dir.join("examples/countries/out/countries.svg"),
    ));
    // Flare at the default 1,000 × 1,000.
    let flare = support::paper_data().join("flare.json");
    let (svg, json) = (dir.join("flare.svg"), dir.join("flare.json"));
    support::layout(&flare, &[&svg, &json], &[]);
    out.push(("flare".to_owned(), svg));
    // A generated 1,000-leaf hierarchy with embeddings.
    let generated = dir.join("similar1000.json");
    let status = std::process::Command::new("python3")
        .arg(root.join("benches/gen_similar.py"))
        .args([
            "--n", "1000", "--depth", "3", "--dim", "16", "--seed", "1", "--out",
        ])
        .arg(&generated)
        .status()
        .expect("run gen_similar.py (needs python3)");
    assert!(status.success(), "gen_similar.py failed");
    let (svg, json) = (
        dir.join("similar1000.svg"),
        dir.join("similar1000-layout.json"),
    );
    support::layout(&generated, &[&svg, &json], &[]);
    std::fs::rename(&json, svg.with_extension("json")).expect("rename");
    out.push(("generated 1,000 leaves".to_owned(), svg));
    // The committed real datasets (700 to 1,400 leaves; one flat, whose 1,061
    // top-level leaves each take a group colour), each with its own config.
    for name in ["debian-packages", "python-stdlib", "man-pages", "usr-bin"] {
        let to = dir.join("real").join(name);
        copy_dir(&root.join("tests/data/real").join(name), &to);
        support::build(&to.join("nptreemap.yaml"));
        out.push((name.to_owned(), to.join(format!("out/{name}.svg"))));
    }
    out
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let path = entry.expect("entry").path();
        let name = path.file_name().expect("name");
        if path.is_dir() {
            if name != "out" {
                copy_dir(&path, &to.join(name));
            }
        } else {
            std::fs::copy(&path, to.join(name)).expect("copy");
        }
    }
}

#[test]
fn default_pictures_are_legible() {
    let mut table = vec![HEADER.to_owned()];
    let mut failures = Vec::new();
    for (name, svg) in pictures() {
        let (text, layout) = read(&svg);
        let f = measure(&text, &layout);
        table.push(row(&name, &f));
        let mut fail =
            |what: &str, items: String| failures.push(format!("{name}: {what}: {items}"));
        if !f.small.is_empty() {
            fail("labels below 9 px", format!("{:?}", f.small));
        }
        if !f.covered.is_empty() {
            fail("labels covered", format!("{:?}", f.covered));
        }
        if !f.outside.is_empty() {
            fail("overlays outside the outline", format!("{:?}", f.outside));
        }
        if f.marker_share > MAX_MARKER_SHARE {
            fail("marker area", format!("{:.2}%", 100.0 * f.marker_share));
        }
        if !f.alike.is_empty() {
            fail("adjacent groups alike", format!("{:?}", f.alike));
        }
        // Group names: every top-level group that has children of its own
        // (flat maps have none to name).
        if f.groups >= 2 && f.group_names == 0 {
            fail("group names", "none on the map".to_owned());
        }
        if name == "flare" && 2 * f.labels < f.leaves {
            fail(
                "flare labels",
                format!("{} of {} leaves", f.labels, f.leaves),
            );
        }
    }
    let _ = writeln!(std::io::stderr(), "{}", table.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
#[ignore = "a report: NPTREEMAP_LEGIBILITY=a.svg,b.svg"]
fn legibility_report() {
    let list = std::env::var("NPTREEMAP_LEGIBILITY").unwrap_or_default();
    let mut table = vec![HEADER.to_owned()];
    for svg in list.split(',').filter(|s| !s.is_empty()) {
        let (text, layout) = read(Path::new(svg));
        let f = measure(&text, &layout);
        table.push(row(svg, &f));
        for (a, b, d) in &f.alike {
            table.push(format!(
                "<!-- {svg}: {a} and {b} alike, OKLab distance {d:.3} -->"
            ));
        }
    }
    let _ = writeln!(std::io::stdout(), "{}", table.join("\n"));
}

/// Issue 24 item 8, on a generated 5,000-leaf map in three levels at the
/// default 1,000 × 1,000: a leaf label cut with an ellipsis keeps at least
/// four characters before it (`gcl…` names nothing), and with so few leaf
/// labels the group names carry the picture at two levels: most top-level
/// groups and many second-level groups are named on the map.
#[test]
fn big_maps_cut_no_stubs_and_name_two_levels() {
    let dir = support::temp_dir("legibility-5000");
    let input = support::generate(&dir, 5000, 3, 7);
    // Leaf names as long as real ones (`gen.py` writes `l123`), so that
    // many labels need cutting.
    let mut tree: Value =
        serde_json::from_slice(&std::fs::read(&input).expect("read")).expect("JSON");
    fn rename(node: &mut Value, k: &mut usize) {
        match node.get_mut("children").and_then(Value::as_array_mut) {
            Some(children) => children.iter_mut().for_each(|c| rename(c, k)),
            None => {
                const STEMS: [&str; 4] = [
                    "gcc-arm-none-eabi",
                    "python3-matplotlib",
                    "libreoffice-writer",
                    "texlive-fonts",
                ];
                node["name"] = Value::from(format!("{}-{k}", STEMS[*k % STEMS.len()]));
                *k += 1;
            }
        }
    }
    rename(&mut tree, &mut 0);
    std::fs::write(&input, tree.to_string()).expect("write");
    let (svg, json) = (dir.join("h5000.svg"), dir.join("h5000.json"));
    support::layout(&input, &[&svg, &json], &["--method", "plain"]);
    let (text, layout) = read(&svg);
    let boxes = text_boxes(&text);
    let stubs: Vec<&str> = boxes
        .iter()
        .filter(|b| b.class == "np-labels")
        .filter_map(|b| b.text.split_once('\u{2026}').map(|(kept, _)| kept))
        .filter(|kept| kept.trim_end().chars().count() < 4)
        .collect();
    let cut = boxes
        .iter()
        .filter(|b| b.class == "np-labels" && b.text.contains('\u{2026}'))
        .count();
    assert!(stubs.is_empty(), "labels cut to stubs: {stubs:?}");

    let nodes = layout["nodes"].as_array().expect("nodes");
    // Groups are the nodes some node names as its parent.
    let parents: std::collections::BTreeSet<&str> =
        nodes.iter().filter_map(|n| n["parent"].as_str()).collect();
    let names: Vec<&str> = boxes
        .iter()
        .filter(|b| b.class == "np-group-labels")
        .map(|b| b.text.as_str())
        .collect();
    let level = |d: usize| -> (usize, usize) {
        let groups: Vec<&str> = nodes
            .iter()
            .filter(|n| n["depth"].as_u64() == Some(d as u64) && n["virtual"] != true)
            .filter(|n| parents.contains(n["id"].as_str().expect("id")))
            .map(|n| n["label"].as_str().expect("label"))
            .collect();
        let named = groups.iter().filter(|g| names.contains(g)).count();
        (named, groups.len())
    };
    let (top, tops) = level(1);
    let (second, seconds) = level(2);
    let labels = boxes.iter().filter(|b| b.class == "np-labels").count();
    let _ = writeln!(
        std::io::stderr(),
        "5,000 leaves: {cut} cut labels, {labels} labels; top-level groups named {top} of {tops}, second-level {second} of {seconds}"
    );
    assert!(cut > 0, "the map has cut labels to check");
    assert!(
        tops >= 2 && seconds > tops,
        "three levels: {tops} {seconds}"
    );
    assert!(2 * top >= tops, "top-level groups named: {top} of {tops}");
    assert!(
        4 * second >= seconds,
        "second-level groups named: {second} of {seconds}"
    );
}
