//! Colours that stay (issue 32, item 4) on a real table this suite did not
//! make for the purpose, `tests/data/real/debian-packages` (707 packages
//! in 28 sections, more groups than Tableau 20 has colours): an edit that
//! makes a mid-ranked section the heaviest by far changes no cell's fill,
//! its revert gives back every fill, a package that outgrows the rest of
//! its section shifts no sibling's shade, and a build after a build is up
//! to date (the colours recorded are the colours drawn). Its legend's 28
//! colours are no two alike.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use resvg::usvg::roxmltree;

use crate::support;

/// A copy of the Debian table with the SVG as its only output.
fn debian(tag: &str) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/debian-packages");
    let dir = support::temp_dir(&format!("colors_{tag}"));
    std::fs::copy(src.join("packages.csv"), dir.join("packages.csv")).expect("copy");
    let config = std::fs::read_to_string(src.join("nptreemap.yaml")).expect("config");
    let svg_only: String = config
        .lines()
        .filter(|l| !l.contains("- path:") || l.ends_with(".svg"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(svg_only.contains("out/debian-packages.svg"), "{svg_only}");
    std::fs::write(dir.join("nptreemap.yaml"), svg_only).expect("write config");
    dir
}

/// Every cell's fill in the SVG, by node id.
fn fills(dir: &Path) -> BTreeMap<String, String> {
    let svg = std::fs::read_to_string(dir.join("out/debian-packages.svg")).expect("SVG");
    let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
    doc.descendants()
        .filter(|n| n.has_tag_name("path"))
        .filter_map(|n| {
            let fill = n.attribute("fill").filter(|f| f.starts_with('#'))?;
            Some((n.attribute("data-id")?.to_owned(), fill.to_owned()))
        })
        .collect()
}

/// The ids whose fill differs between two pictures.
fn changed(before: &BTreeMap<String, String>, after: &BTreeMap<String, String>) -> Vec<String> {
    before
        .keys()
        .filter(|id| after.get(*id) != before.get(*id))
        .cloned()
        .collect()
}

/// The table's rows as (section, size) with the header's column positions.
fn sections(text: &str) -> (Vec<String>, usize, usize) {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).expect(name);
    (
        lines.map(str::to_owned).collect(),
        at("section"),
        at("installed_size_kib"),
    )
}

/// Section weights, heaviest first.
fn ranked(text: &str) -> Vec<(String, f64)> {
    let (rows, section, size) = sections(text);
    let mut sums: BTreeMap<String, f64> = BTreeMap::new();
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        *sums.entry(f[section].to_owned()).or_default() += f[size].parse::<f64>().expect("size");
    }
    let mut v: Vec<(String, f64)> = sums.into_iter().collect();
    v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    v
}

/// The fills of the legend's group swatches, in legend order.
fn legend_fills(dir: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(dir.join("out/debian-packages.svg")).expect("SVG");
    let doc = roxmltree::Document::parse(&svg).expect("SVG parses");
    doc.descendants()
        .filter(|n| n.attribute("class") == Some("np-legend-item"))
        .filter_map(|item| item.children().find(|c| c.has_tag_name("rect")))
        .filter_map(|rect| rect.attribute("fill").map(str::to_owned))
        .collect()
}

#[test]
fn no_two_sections_in_the_legend_look_alike() {
    use nptreemap::render::color_difference::delta_e;
    use nptreemap::render::distinct::LEGEND_DISTANCE;
    let dir = debian("legend");
    support::build(&dir.join("nptreemap.yaml"));
    let fills = legend_fills(&dir);
    assert_eq!(fills.len(), 28, "{fills:?}");
    let rgb = |hex: &str| nptreemap::render::palette::Rgb::from_hex(hex).expect(hex);
    for (i, a) in fills.iter().enumerate() {
        for b in &fills[..i] {
            let d = delta_e(rgb(a), rgb(b));
            assert!(d >= LEGEND_DISTANCE, "{a} and {b}: ΔE00 {d:.1}");
        }
    }
}

#[test]
fn an_edit_that_reorders_the_groups_changes_no_fill_and_its_revert_gives_them_back() {
    let dir = debian("reorder");
    let config = dir.join("nptreemap.yaml");
    support::build(&config);
    let before = fills(&dir);
    assert!(before.len() > 700, "{} cells", before.len());

    // Every package of the middle section scaled to twice the heaviest
    // section's weight: it becomes the heaviest by far.
    let table = dir.join("packages.csv");
    let original = std::fs::read_to_string(&table).expect("table");
    let order = ranked(&original);
    assert!(
        order.len() > 20,
        "more sections than Tableau 20 has colours"
    );
    let middle = order[order.len() / 2].0.clone();
    let factor = (2.0 * order[0].1 / order[order.len() / 2].1).ceil();
    let (rows, section, size) = sections(&original);
    let mut edited = original.lines().next().expect("header").to_owned() + "\n";
    for row in rows {
        let mut f: Vec<String> = row.split(',').map(str::to_owned).collect();
        if f[section] == middle {
            f[size] = format!("{}", f[size].parse::<f64>().expect("size") * factor);
        }
        edited.push_str(&f.join(","));
        edited.push('\n');
    }
    assert_eq!(
        ranked(&edited)[0].0,
        middle,
        "the edit makes {middle} the heaviest"
    );
    std::fs::write(&table, &edited).expect("edit");
    support::build(&config);
    let moved = changed(&before, &fills(&dir));
    assert!(
        moved.is_empty(),
        "{} of {} fills changed: {moved:?}",
        moved.len(),
        before.len()
    );

    // The revert: every fill as it was.
    std::fs::write(&table, &original).expect("revert");
    support::build(&config);
    assert_eq!(fills(&dir), before);

    // The lightest package of a section outgrows its heaviest: the child
    // that wears the section's colour stays, so no sibling's shade moves.
    let (rows, section, size) = sections(&original);
    let parse = |row: &String| -> (String, f64) {
        let f: Vec<&str> = row.split(',').collect();
        (f[section].to_owned(), f[size].parse().expect("size"))
    };
    let crowded = order
        .iter()
        .map(|(name, _)| name)
        .find(|name| rows.iter().filter(|r| parse(r).0 == **name).count() >= 4)
        .expect("a section of four packages or more");
    let members: Vec<usize> = (0..rows.len())
        .filter(|&k| parse(&rows[k]).0 == *crowded)
        .collect();
    let lightest = *members
        .iter()
        .min_by(|&&a, &&b| parse(&rows[a]).1.total_cmp(&parse(&rows[b]).1))
        .expect("members");
    let heaviest = members
        .iter()
        .map(|&k| parse(&rows[k]).1)
        .fold(0.0, f64::max);
    let mut grown = original.lines().next().expect("header").to_owned() + "\n";
    for (k, row) in rows.iter().enumerate() {
        let mut f: Vec<String> = row.split(',').map(str::to_owned).collect();
        if k == lightest {
            f[size] = format!("{}", 2.0 * heaviest);
        }
        grown.push_str(&f.join(","));
        grown.push('\n');
    }
    std::fs::write(&table, &grown).expect("grow one package");
    support::build(&config);
    let moved = changed(&before, &fills(&dir));
    assert!(moved.is_empty(), "{crowded}: {moved:?} changed");

    // The colours recorded are those drawn: nothing is stale.
    let check = support::bin()
        .args(["build", "--check"])
        .arg(&config)
        .output()
        .expect("run");
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
}
