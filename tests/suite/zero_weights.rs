//! Items of weight 0 (issue 34 item 2), through the binary: with
//! `layout.zero_weights: hide` (the default) they have no cell in any output
//! and every output says how many there are (the legend of the SVG, the PNG
//! and the page, the page's data for its tooltips, the layout JSON's
//! `hidden`, the build and check lines), the picture being the one of the
//! same data without them; with `floor` each has a cell, the legend says
//! they are drawn at a minimum size, and the layout JSON gives the weight
//! each is drawn at, against which its area errors are measured. A weight
//! edited to 0 and back is laid out warm; data of nothing but zeros is a
//! picture that says so.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use resvg::tiny_skia::Pixmap;
use serde_json::{json, Value};

use crate::support;

/// A source tree: (id, label, size, similar ids). `a/` and `b/` hold empty
/// files among others, `c/` nothing but empty files; empty files have
/// neighbours too (which must not become constraints once hidden).
const FILES: [(&str, &str, f64, &[&str]); 11] = [
    ("a/__init__.py", "__init__.py", 0.0, &["b/__init__.py"]),
    ("a/core.py", "core.py", 12_000.0, &["b/io.py", "b/net.py"]),
    ("a/util.py", "util.py", 3_000.0, &["b/fmt.py"]),
    ("a/empty.py", "empty.py", 0.0, &["b/net.py"]),
    ("b/__init__.py", "__init__.py", 0.0, &[]),
    ("b/io.py", "io.py", 8_000.0, &["a/util.py"]),
    ("b/net.py", "net.py", 25_000.0, &[]),
    ("b/fmt.py", "fmt.py", 1_500.0, &["a/core.py"]),
    ("c/__init__.py", "__init__.py", 0.0, &["a/__init__.py"]),
    ("c/x.py", "x.py", 0.0, &["b/io.py"]),
    ("setup.py", "setup.py", 900.0, &[]),
];

/// Leaves of weight 0 in [`FILES`].
const EMPTY: usize = 5;

/// The hierarchy JSON of [`FILES`] (neighbour lists as the similarity),
/// keeping the files `keep` accepts; a folder left empty is left out.
pub(crate) fn tree(keep: impl Fn(f64) -> bool) -> Value {
    let file = |(id, label, size, near): &(&str, &str, f64, &[&str])| json!({"id": id, "name": label, "size": size, "neighbors": near});
    let mut children = Vec::new();
    for folder in ["a", "b", "c"] {
        let files: Vec<Value> = FILES
            .iter()
            .filter(|f| f.0.starts_with(&format!("{folder}/")) && keep(f.2))
            .map(file)
            .collect();
        if !files.is_empty() {
            children.push(json!({"id": folder, "name": folder, "children": files}));
        }
    }
    children.extend(
        FILES
            .iter()
            .filter(|f| !f.0.contains('/') && keep(f.2))
            .map(file),
    );
    json!({"name": "src", "useNeighborLeafs": true, "weightAttribute": "size", "children": children})
}

/// Writes `tree` as `name` in `dir`.
fn write(dir: &Path, name: &str, tree: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, tree.to_string()).expect("write input");
    path
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).expect("read")).expect("JSON")
}

/// The ids of the cells a picture or page draws (`path data-id="..."`).
fn cell_ids(text: &str) -> BTreeSet<String> {
    text.split("data-id=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .map(str::to_string)
        .collect()
}

/// The legend's texts of an SVG (its `np-legend-labels` group).
fn legend_texts(svg: &str) -> Vec<String> {
    let Some(at) = svg.find("np-legend-labels") else {
        return Vec::new();
    };
    svg[at..]
        .split("</g>")
        .next()
        .unwrap_or("")
        .split("<text")
        .skip(1)
        .filter_map(|t| t.split('>').nth(1)?.split('<').next())
        .map(str::to_string)
        .collect()
}

/// Pixels of the band below row `from` darker than mid grey: legend text.
fn dark_pixels_below(png: &Path, from: u32) -> usize {
    let pix = Pixmap::load_png(png).expect("a valid PNG");
    pix.pixels()
        .iter()
        .enumerate()
        .filter(|(i, _)| *i as u32 / pix.width() >= from)
        .filter(|(_, p)| u32::from(p.red()) + u32::from(p.green()) + u32::from(p.blue()) < 3 * 100)
        .count()
}

/// Pixels of the top `rows` rows (the map, above the legend band) in which
/// two PNGs differ by more than 2 in a channel (anti-aliasing varies a
/// little with the picture's height, which decides the PNG's strips).
fn map_pixels_differing(a: &Path, b: &Path, rows: u32) -> usize {
    let (a, b) = (
        Pixmap::load_png(a).expect("PNG"),
        Pixmap::load_png(b).expect("PNG"),
    );
    assert_eq!(a.width(), b.width());
    let n = (rows * a.width()) as usize;
    a.pixels()[..n]
        .iter()
        .zip(&b.pixels()[..n])
        .filter(|(p, q)| {
            let d = |x: u8, y: u8| x.abs_diff(y) > 2;
            d(p.red(), q.red()) || d(p.green(), q.green()) || d(p.blue(), q.blue())
        })
        .count()
}

/// Lays out `input` into SVG, PNG, layout JSON and HTML named `stem`.
fn outputs(dir: &Path, input: &Path, stem: &str, extra: &[&str]) -> [PathBuf; 4] {
    let outs = ["svg", "png", "json", "html"].map(|e| dir.join(format!("{stem}.{e}")));
    let refs: Vec<&Path> = outs.iter().map(PathBuf::as_path).collect();
    let mut args = vec!["--width", "400", "--height", "300"];
    args.extend_from_slice(extra);
    support::layout(input, &refs, &args);
    outs
}

/// The page's data block (its nodes, with what each holds hidden).
fn page_nodes(html: &str) -> Vec<Value> {
    let at = html.find("class=\"np-data\"").expect("data block");
    let start = at + html[at..].find('>').expect("end of the tag") + 1;
    let end = start + html[start..].find("</script>").expect("end of data");
    let data: Value = serde_json::from_str(&html[start..end]).expect("page data");
    data["nodes"].as_array().expect("nodes").clone()
}

#[test]
fn hidden_items_have_no_cell_anywhere_and_every_output_counts_them() {
    let dir = support::temp_dir("zero_hide");
    let full = write(&dir, "full-input.json", &tree(|_| true));
    let stripped = write(&dir, "stripped-input.json", &tree(|w| w > 0.0));
    // The default is `hide`: no flag.
    let [svg, png, json, html] = outputs(&dir, &full, "hide", &[]);
    let [s_svg, s_png, s_json, s_html] = outputs(&dir, &stripped, "stripped", &[]);

    // Layout JSON: checker-clean; the drawn nodes, their cells and their
    // constraints are those of the same data without the empty files (no
    // constraint to a hidden file, though they had neighbours); what was
    // hidden is listed with its parent.
    let report = support::check_layout(&json);
    support::assert_area_error(&report, 0.01);
    let doc = read_json(&json);
    let bare = read_json(&s_json);
    assert_eq!(doc["nodes"], bare["nodes"]);
    assert_eq!(doc["constraints"], bare["constraints"]);
    assert!(!doc["constraints"]
        .as_array()
        .expect("constraints")
        .is_empty());
    assert_eq!(doc["zero_weights"], json!({"mode": "hide", "items": EMPTY}));
    assert_eq!(bare.get("zero_weights"), None);
    assert_eq!(bare.get("hidden"), None);
    let hidden: BTreeSet<(String, String)> = doc["hidden"]
        .as_array()
        .expect("hidden")
        .iter()
        .map(|h| {
            assert_eq!(h["weight"], 0);
            (
                h["id"].as_str().expect("id").into(),
                h["parent"].as_str().expect("parent").into(),
            )
        })
        .collect();
    let mut expected: BTreeSet<(String, String)> = FILES
        .iter()
        .filter(|f| f.2 == 0.0)
        .map(|f| {
            (
                f.0.to_string(),
                f.0.split('/').next().expect("folder").to_string(),
            )
        })
        .collect();
    expected.insert(("c".into(), "src".into()));
    assert_eq!(hidden, expected);

    // SVG: the cells of the stripped data, and the legend counts the rest.
    let svg = std::fs::read_to_string(&svg).expect("svg");
    let s_svg = std::fs::read_to_string(&s_svg).expect("svg");
    assert_eq!(cell_ids(&svg), cell_ids(&s_svg));
    assert!(!cell_ids(&svg).contains("a/__init__.py"));
    let legend = legend_texts(&svg);
    assert_eq!(
        legend.first().map(String::as_str),
        Some("5 items of weight 0 not drawn"),
        "{legend:?}"
    );
    assert!(!legend_texts(&s_svg).iter().any(|t| t.contains("weight 0")));

    // PNG: the map is the stripped data's (give or take the anti-aliasing
    // of a few edge pixels: under 0.05% of them); the legend band below it
    // carries more text (the note).
    let differing = map_pixels_differing(&png, &s_png, 300);
    assert!(differing <= 60, "{differing} map pixels differ");
    assert!(dark_pixels_below(&png, 300) > dark_pixels_below(&s_png, 300) + 50);

    // The page: the note in its legend, and per folder what it holds
    // hidden for the tooltips of its cells.
    let html = std::fs::read_to_string(&html).expect("html");
    assert!(html.contains(">5 items of weight 0 not drawn</span>"));
    let s_html = std::fs::read_to_string(&s_html).expect("html");
    assert_eq!(cell_ids(&html), cell_ids(&s_html));
    let nodes = page_nodes(&html);
    let of = |id: &str| nodes.iter().find(|n| n["id"] == id).expect("node")["empty"].clone();
    assert_eq!(
        of("a"),
        json!({"items": 2, "names": ["__init__.py", "empty.py"], "more": 0})
    );
    assert_eq!(
        of("b"),
        json!({"items": 1, "names": ["__init__.py"], "more": 0})
    );
    assert_eq!(of("src"), json!({"items": 2, "names": ["c"], "more": 0}));
    assert_eq!(of("a/core.py"), Value::Null);
}

#[test]
fn floored_items_have_small_cells_that_the_outputs_call_so() {
    let dir = support::temp_dir("zero_floor");
    let full = write(&dir, "full-input.json", &tree(|_| true));
    let [svg, png, json, html] = outputs(&dir, &full, "floor", &["--zero-weights", "floor"]);
    let [_, h_png, _, _] = outputs(&dir, &full, "hide", &["--zero-weights", "hide"]);

    // Every file has a cell; the empty ones are small.
    let doc = read_json(&json);
    let nodes = doc["nodes"].as_array().expect("nodes");
    let area = |n: &Value| {
        let p: Vec<(f64, f64)> = n["polygon"]
            .as_array()
            .expect("polygon")
            .iter()
            .map(|q| (q[0].as_f64().expect("x"), q[1].as_f64().expect("y")))
            .collect();
        0.5 * (0..p.len())
            .map(|i| p[i].0 * p[(i + 1) % p.len()].1 - p[(i + 1) % p.len()].0 * p[i].1)
            .sum::<f64>()
            .abs()
    };
    let svg = std::fs::read_to_string(&svg).expect("svg");
    for (id, _, size, _) in FILES {
        let node = nodes
            .iter()
            .find(|n| n["id"] == id)
            .expect("every file is drawn");
        assert!(cell_ids(&svg).contains(id), "{id} has a cell in the SVG");
        if size == 0.0 {
            // Stated: the weight it is drawn at, which is not its own.
            let drawn = node["drawn_weight"].as_f64().expect("drawn_weight");
            assert!(drawn > 0.0 && node["weight"] == 0, "{node}");
            assert!(
                area(node) > 0.0 && area(node) < 0.01 * 400.0 * 300.0,
                "{id}"
            );
        } else {
            assert_eq!(node.get("drawn_weight"), None, "{id}");
        }
    }
    assert_eq!(
        doc["zero_weights"],
        json!({"mode": "floor", "items": EMPTY})
    );
    assert_eq!(doc.get("hidden"), None);

    // Area errors are those of the promise (each empty file at its drawn
    // weight): the repository's checker, which reads `drawn_weight`, finds
    // what the document says, within the target.
    let report = support::check_layout(&json);
    support::assert_area_error(&report, 0.01);
    let own = doc["metrics"]["area_error_diagram_mean"]
        .as_f64()
        .expect("metric");
    let checked = report["area_error_diagram_mean"].as_f64().expect("checker");
    assert!(
        (own - checked).abs() <= 1e-5,
        "metrics {own}, checker {checked}"
    );
    // The shared checker, which knows no `drawn_weight`, accepts the document.
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/tools/check-layout");
    if shared.is_file() {
        let out = std::process::Command::new("python3")
            .arg(&shared)
            .arg(&json)
            .output()
            .expect("run the shared checker");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stdout)
        );
    }

    // The legend of the SVG, the PNG and the page says so.
    let legend = legend_texts(&svg);
    assert_eq!(
        legend.first().map(String::as_str),
        Some("5 items of weight 0 drawn at a minimum size"),
        "{legend:?}"
    );
    let html = std::fs::read_to_string(&html).expect("html");
    assert!(html.contains(">5 items of weight 0 drawn at a minimum size</span>"));
    assert!(page_nodes(&html).iter().all(|n| n.get("empty").is_none()));
    // The floored cells change the map: not the hidden picture's.
    assert!(map_pixels_differing(&png, &h_png, 300) > 1000);
    assert!(dark_pixels_below(&png, 300) > 0);
}

/// A config building `input.json` into SVG and layout JSON.
fn config(dir: &Path, zero: &str) -> PathBuf {
    let path = dir.join("nptreemap.yaml");
    std::fs::write(
        &path,
        format!(
            "layout: {{width: 400, height: 300, zero_weights: {zero}}}\n\
             datasets:\n  - name: src\n    format: hierarchy-json\n\
             \x20   files: {{hierarchy: input.json}}\n    outputs: [out/src.svg, out/src.json]\n"
        ),
    )
    .expect("config");
    path
}

fn stdout(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_weight_edited_to_zero_and_back_is_laid_out_warm() {
    let dir = support::temp_dir("zero_warm");
    let cfg = config(&dir, "hide");
    let edit = |util: f64| {
        let mut t = tree(|_| true);
        let a = &mut t["children"][0]["children"];
        for f in a.as_array_mut().expect("a's files") {
            if f["id"] == "a/util.py" {
                f["size"] = json!(util);
            }
        }
        write(&dir, "input.json", &t);
    };
    edit(3_000.0);
    let check = support::bin()
        .arg("check")
        .arg(&cfg)
        .output()
        .expect("check");
    assert!(
        stdout(&check).contains("; 5 items of weight 0 not drawn (layout.zero_weights: hide)"),
        "{}",
        stdout(&check)
    );
    let first = stdout(&support::build(&cfg));
    assert!(
        first.contains("laid out cold") && first.contains("; 5 items of weight 0 not drawn"),
        "{first}"
    );
    let json = dir.join("out/src.json");

    // util.py emptied: warm, one item more, no cell for it.
    edit(0.0);
    let second = stdout(&support::build(&cfg));
    assert!(
        second.contains("laid out warm") && second.contains("; 6 items of weight 0 not drawn"),
        "{second}"
    );
    support::check_layout(&json);
    let doc = read_json(&json);
    assert!(doc["hidden"]
        .as_array()
        .expect("hidden")
        .iter()
        .any(|h| h["id"] == "a/util.py"));
    assert!(!doc["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .any(|n| n["id"] == "a/util.py"));

    // And back: warm again, its cell back, checker-clean.
    edit(3_000.0);
    let third = stdout(&support::build(&cfg));
    assert!(
        third.contains("laid out warm") && third.contains("; 5 items"),
        "{third}"
    );
    let report = support::check_layout(&json);
    support::assert_area_error(&report, 0.01);
    let doc = read_json(&json);
    assert!(doc["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .any(|n| n["id"] == "a/util.py"));
    assert!(!doc["hidden"]
        .as_array()
        .expect("hidden")
        .iter()
        .any(|h| h["id"] == "a/util.py"));
}

#[test]
fn data_of_nothing_but_zeros_is_a_picture_that_says_so() {
    let dir = support::temp_dir("zero_all");
    let only_empty = tree(|w| w == 0.0);
    write(&dir, "input.json", &only_empty);
    // Cells drawn (the leaves and the top-level groups) and nodes laid out.
    for (zero, note, cells, nodes) in [
        ("hide", "all 5 items weigh 0: none drawn", 1, 1),
        ("floor", "all 5 items weigh 0: drawn at equal sizes", 8, 9),
    ] {
        let cfg = config(&dir, zero);
        let out = support::build(&cfg);
        assert!(stdout(&out).contains(note), "{zero}: {}", stdout(&out));
        let svg = std::fs::read_to_string(dir.join("out/src.svg")).expect("svg");
        assert_eq!(cell_ids(&svg).len(), cells, "{zero}: {:?}", cell_ids(&svg));
        assert_eq!(legend_texts(&svg).first().map(String::as_str), Some(note));
        let report = support::check_layout(&dir.join("out/src.json"));
        assert_eq!(report["nodes"], nodes, "{zero}");
    }
}
