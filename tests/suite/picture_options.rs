//! The picture options of issue 13 end to end, through `nptreemap build` on a
//! copy of `examples/countries`: `palette: colorblind` paints the groups in
//! Okabe–Ito, the legend lists the groups by weight (or in the order of
//! `labels.names`) under their display names, `labels.names` renames groups
//! on the map too, `labels.value` adds the value with thousands separators and
//! the unit, `labels.min_size` is a floor for every leaf label, and a title
//! with a line break still gives a PNG (issue 11, item 7).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use resvg::usvg::roxmltree;

use crate::support;

/// Okabe & Ito (2008), "Color Universal Design", as published (not read from
/// the renderer): black is left out, the map needs fills that carry text.
const OKABE_ITO: [&str; 7] = [
    "#e69f00", "#56b4e9", "#009e73", "#f0e442", "#0072b2", "#d55e00", "#cc79a7",
];

/// Population by continent in `examples/countries/countries.csv`, summed here.
fn continent_weights(dir: &Path) -> BTreeMap<String, f64> {
    let text = std::fs::read_to_string(dir.join("countries.csv")).expect("countries.csv");
    let mut sums = BTreeMap::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        *sums.entry(f[3].to_owned()).or_insert(0.0) += f[2].parse::<f64>().expect("population");
    }
    sums
}

/// Builds the copied example with `render` as the config's `render:` section
/// (YAML, indented by two) and `title` as the dataset's title; returns the SVG.
fn build(tag: &str, render: &str, title: Option<&str>) -> (PathBuf, String) {
    let config = support::example("countries", tag);
    let dir = config.parent().expect("dir").to_owned();
    let mut text = std::fs::read_to_string(&config).expect("config");
    text = text.replace(
        "layout:\n  outline: ngon\n",
        &format!("layout:\n  outline: ngon\nrender:\n{render}\n"),
    );
    if let Some(title) = title {
        text = text.replace(
            "    format: border-list\n",
            &format!("    title: {title}\n    format: border-list\n"),
        );
    }
    std::fs::write(&config, text).expect("write config");
    let run = support::bin()
        .arg("build")
        .arg(&config)
        .output()
        .expect("run nptreemap");
    assert!(
        run.status.success(),
        "build failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let svg = std::fs::read_to_string(dir.join("out/countries.svg")).expect("SVG");
    (dir, svg)
}

/// The `<text>` contents (lines joined by a space) and font sizes under the
/// `<g>` of class `class`.
fn texts(doc: &roxmltree::Document, class: &str) -> Vec<(String, f64)> {
    let Some(group) = doc
        .descendants()
        .find(|n| n.has_tag_name("g") && n.attribute("class") == Some(class))
    else {
        return Vec::new();
    };
    let inherited: f64 = group
        .attribute("font-size")
        .and_then(|s| s.parse().ok())
        .unwrap_or(f64::NAN);
    group
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|t| {
            let size = t
                .attribute("font-size")
                .and_then(|s| s.parse().ok())
                .unwrap_or(inherited);
            let words: Vec<&str> = t
                .descendants()
                .filter(|n| n.is_text())
                .filter_map(|n| n.text())
                .collect();
            (words.join(" "), size)
        })
        .collect()
}

/// The legend's group entries: swatch fill and text, in drawing order.
fn legend_groups(doc: &roxmltree::Document) -> Vec<(String, String)> {
    let fills: Vec<String> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("np-legend-item"))
        .filter_map(|item| {
            let first = item.first_element_child()?;
            (first.has_tag_name("rect") && item.children().filter(|c| c.is_element()).count() == 1)
                .then(|| first.attribute("fill").map(str::to_owned))
                .flatten()
        })
        .collect();
    // The keys (tab, count) come first in the legend; the group entries are
    // the last texts, one per swatch.
    let labels = texts(doc, "np-legend-labels");
    let names: Vec<String> = labels[labels.len() - fills.len()..]
        .iter()
        .map(|(t, _)| t.clone())
        .collect();
    fills.into_iter().zip(names).collect()
}

#[test]
fn palette_legend_order_and_display_names() {
    let weights =
        continent_weights(&Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/countries"));

    // Defaults: Tableau colours, legend by weight, heaviest first.
    let (_, svg) = build("options_default", "  border_width: 0", None);
    let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
    let legend = legend_groups(&doc);
    let names: Vec<&str> = legend.iter().map(|(_, t)| t.as_str()).collect();
    let mut by_weight: Vec<(&String, &f64)> = weights.iter().collect();
    by_weight.sort_by(|a, b| b.1.total_cmp(a.1));
    let expected: Vec<&str> = by_weight.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(names, expected, "legend by weight");

    // Okabe–Ito, the order of `labels.names`, and the names on the map.
    let render = "  palette: colorblind\n  legend_order: names\n  labels:\n    names:\n      Oceania: Australia and Oceania\n      Europe: Europa\n";
    let (_, svg) = build("options_names", render, None);
    let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
    let legend = legend_groups(&doc);
    assert_eq!(legend.len(), weights.len(), "{legend:?}");
    for (fill, name) in &legend {
        assert!(
            OKABE_ITO.contains(&fill.to_ascii_lowercase().as_str()),
            "{name}: {fill} is not an Okabe–Ito colour"
        );
    }
    let names: Vec<&str> = legend.iter().map(|(_, t)| t.as_str()).collect();
    let rest: Vec<&str> = expected
        .iter()
        .copied()
        .filter(|n| *n != "Oceania" && *n != "Europe")
        .collect();
    assert_eq!(names[..2], ["Australia and Oceania", "Europa"], "{names:?}");
    assert_eq!(names[2..], rest[..], "the unnamed groups follow by weight");
    let on_map: Vec<String> = texts(&doc, "np-group-labels")
        .into_iter()
        .map(|(t, _)| t)
        .collect();
    assert!(
        on_map.iter().any(|t| t == "Europa"),
        "the group name on the map is the display name: {on_map:?}"
    );
    assert!(!on_map.iter().any(|t| t == "Europe"), "{on_map:?}");
}

#[test]
fn value_line_and_minimum_size() {
    let render = "  labels:\n    value: true\n    unit: \" people\"\n    min_size: 12";
    let (_, svg) = build("options_value", render, None);
    let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
    let labels = texts(&doc, "np-labels");
    assert!(!labels.is_empty());
    for (text, size) in &labels {
        assert!(*size >= 12.0 - 1e-9, "{text:?} at {size} px, below 12");
    }
    // China's population from the CSV, formatted independently.
    let china = "1,411,778,724 people";
    assert!(
        labels
            .iter()
            .any(|(t, _)| t.contains("China") && t.contains(china)),
        "no China label with {china:?}: {labels:?}"
    );
}

#[test]
fn a_title_with_a_line_break_still_gives_a_png() {
    let (dir, svg) = build(
        "options_title",
        "  border_width: 0",
        Some("\"line one\\nline two\""),
    );
    assert!(
        svg.contains("line one") && svg.contains("line two"),
        "title"
    );
    let png = std::fs::read(dir.join("out/countries.png")).expect("the PNG was written");
    let pixmap = resvg::tiny_skia::Pixmap::decode_png(&png).expect("valid PNG");
    assert!(pixmap.width() > 0 && pixmap.height() > 0);
}

/// `render.colors` (issue 32, item 4): a pinned group keeps its colour
/// through a weight edit that makes it the heaviest group by far, the other
/// groups are coloured around it, and a name no group has is a warning.
#[test]
fn a_pinned_colour_holds_through_an_edit_and_a_typo_is_named() {
    let render = "  colors:\n    Europe: \"#123456\"\n    Atlantis: \"#654321\"";
    let (dir, svg) = build("options_pinned", render, None);
    let swatch = |svg: &str, group: &str| -> String {
        let doc = roxmltree::Document::parse(svg).expect("SVG parses");
        let legend = legend_groups(&doc);
        legend
            .iter()
            .find(|(_, name)| name == group)
            .unwrap_or_else(|| panic!("no {group} in {legend:?}"))
            .0
            .to_ascii_lowercase()
    };
    assert_eq!(swatch(&svg, "Europe"), "#123456");
    let others: Vec<String> = {
        let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
        legend_groups(&doc)
            .into_iter()
            .filter(|(_, n)| n != "Europe")
            .map(|(f, _)| f)
            .collect()
    };
    assert!(
        !others.iter().any(|f| f.eq_ignore_ascii_case("#123456")),
        "{others:?}"
    );
    // Every European country ×50: Europe outweighs all other continents.
    let table = dir.join("countries.csv");
    let text = std::fs::read_to_string(&table).expect("countries.csv");
    let edited: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(k, line)| {
            let mut f: Vec<String> = line.split(',').map(str::to_owned).collect();
            if k > 0 && f[3] == "Europe" {
                f[2] = format!("{}", f[2].parse::<f64>().expect("population") * 50.0);
            }
            f.join(",")
        })
        .collect();
    std::fs::write(&table, edited.join("\n") + "\n").expect("write");
    let run = support::build(&dir.join("nptreemap.yaml"));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("render.colors: no top-level group has the id or label \"Atlantis\""),
        "{stderr}"
    );
    assert!(!stderr.contains("\"Europe\""), "{stderr}");
    let svg = std::fs::read_to_string(dir.join("out/countries.svg")).expect("SVG");
    assert_eq!(swatch(&svg, "Europe"), "#123456");
}
