//! Warm start through the binary (issue 6 items 2 and 6): `layout --previous`
//! gives checker-clean layouts that barely move after a small edit, the same
//! bytes on every run, a cold layout with `--cold` or when the previous one
//! does not fit, and a named field when the previous file is broken. `eval
//! --previous` prints the stability figures of both starts. No timing
//! assertions: speed belongs to `benches/stability.py`.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support;

/// The `k`-th leaf (depth first) of a hierarchy JSON tree.
fn nth_leaf<'a>(node: &'a mut Value, k: &mut usize) -> Option<&'a mut Value> {
    let leaf = node
        .get("children")
        .and_then(Value::as_array)
        .is_none_or(Vec::is_empty);
    if leaf {
        if *k == 0 {
            return Some(node);
        }
        *k -= 1;
        return None;
    }
    for child in node["children"].as_array_mut()? {
        if let Some(found) = nth_leaf(child, k) {
            return Some(found);
        }
    }
    None
}

/// Writes `input` with `edit` applied to its tree, as `name` in `dir`.
fn edited(input: &Path, dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut tree: Value =
        serde_json::from_slice(&std::fs::read(input).expect("read")).expect("json");
    edit(&mut tree);
    let path = dir.join(name);
    std::fs::write(&path, tree.to_string()).expect("write");
    path
}

/// Scales the weight of the `k`-th leaf by `factor`.
fn scale_leaf(tree: &mut Value, k: usize, factor: f64) {
    let leaf = nth_leaf(tree, &mut { k }).expect("enough leaves");
    let w = leaf["weight"].as_f64().expect("leaf weight");
    leaf["weight"] = Value::from(w * factor);
}

/// `eval --previous --json`: the (warm, cold) stability lines.
fn stability(input: &Path, previous: &Path, extra: &[&str]) -> (Value, Value) {
    let out = support::bin()
        .arg("eval")
        .arg(input)
        .arg("--previous")
        .arg(previous)
        .arg("--json")
        .args(extra)
        .output()
        .expect("run nptreemap");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .filter(|v: &Value| v.get("start").is_some())
        .collect();
    assert_eq!(lines.len(), 2, "one warm and one cold line");
    assert_eq!(
        (&lines[0]["start"], &lines[1]["start"]),
        (&"warm".into(), &"cold".into())
    );
    (lines[0].clone(), lines[1].clone())
}

fn number(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn a_small_edit_moves_a_warm_layout_little_and_stays_checker_clean() {
    let dir = support::temp_dir("warm_plain");
    let input = support::generate(&dir, 300, 3, 11);
    let old = dir.join("old.json");
    support::layout(&input, &[&old], &[]);
    let changed = edited(&input, &dir, "changed.json", |t| scale_leaf(t, 40, 1.1));

    let warm = dir.join("warm.json");
    let svg = dir.join("warm.svg");
    support::layout(
        &changed,
        &[&warm, &svg],
        &["--previous", old.to_str().expect("utf8")],
    );
    let report = support::check_layout(&warm);
    support::assert_area_error(&report, 0.01);

    // Same inputs and the same previous layout: the same bytes.
    let again = dir.join("again.json");
    support::layout(
        &changed,
        &[&again],
        &["--previous", old.to_str().expect("utf8")],
    );
    assert!(std::fs::read(&warm).ok() == std::fs::read(&again).ok());

    let (w, c) = stability(&changed, &old, &[]);
    assert_eq!(w["used_previous"], true);
    let moved = number(&w, "displacement_unchanged_mean");
    assert!(
        moved < 0.01,
        "unchanged leaves moved {moved} of the diagonal"
    );
    assert!(number(&c, "displacement_unchanged_mean") >= moved);
    assert!(number(&w, "iterations") < number(&c, "iterations"));
}

#[test]
fn neighborhoods_survive_a_warm_edit() {
    let dir = support::temp_dir("warm_similar");
    let input = dir.join("similar.json");
    let status = std::process::Command::new("python3")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/gen_similar.py"))
        .args([
            "--n", "120", "--depth", "3", "--dim", "16", "--seed", "3", "--out",
        ])
        .arg(&input)
        .status()
        .expect("run gen_similar.py (needs python3)");
    assert!(status.success());
    let old = dir.join("old.json");
    support::layout(&input, &[&old], &[]);
    let changed = edited(&input, &dir, "changed.json", |t| scale_leaf(t, 7, 1.1));
    let warm = dir.join("warm.json");
    support::layout(
        &changed,
        &[&warm],
        &["--previous", old.to_str().expect("utf8")],
    );
    support::check_layout(&warm);
    let (w, _) = stability(&changed, &old, &[]);
    assert!(number(&w, "realized_before") > 0.0);
    let kept = number(&w, "kept_share");
    assert!(kept >= 0.95, "only {kept} of the realised constraints kept");
    assert!(number(&w, "displacement_unchanged_mean") < 0.01);
}

#[test]
fn added_and_removed_leaves_are_laid_out_warm() {
    let dir = support::temp_dir("warm_add_remove");
    let input = support::generate(&dir, 200, 2, 4);
    let old = dir.join("old.json");
    support::layout(&input, &[&old], &[]);
    let changed = edited(&input, &dir, "changed.json", |tree| {
        let groups = tree["children"].as_array_mut().expect("groups");
        let first = groups[0]["children"].as_array_mut().expect("leaves");
        first.remove(0);
        first.push(serde_json::json!({"name": "brand-new", "weight": 2.0}));
    });
    let warm = dir.join("warm.json");
    let out = support::layout(
        &changed,
        &[&warm],
        &["--previous", old.to_str().expect("utf8")],
    );
    assert!(
        String::from_utf8_lossy(&out.stderr).is_empty(),
        "the previous layout is used without a note"
    );
    support::check_layout(&warm);
    let doc: Value = serde_json::from_slice(&std::fs::read(&warm).expect("read")).expect("json");
    let nodes = doc["nodes"].as_array().expect("nodes");
    assert!(nodes.iter().any(|n| n["id"] == "brand-new"));
    assert!(nodes.iter().all(|n| n["power_weight"].is_number()));
}

#[test]
fn cold_and_unfitting_previous_layouts_lay_out_from_scratch() {
    let dir = support::temp_dir("warm_cold");
    let input = support::generate(&dir, 100, 2, 9);
    let old = dir.join("old.json");
    support::layout(&input, &[&old], &[]);
    let changed = edited(&input, &dir, "changed.json", |t| scale_leaf(t, 3, 1.5));
    let plain = dir.join("plain.json");
    support::layout(&changed, &[&plain], &[]);
    let cold = dir.join("cold.json");
    let previous = old.to_str().expect("utf8");
    support::layout(&changed, &[&cold], &["--previous", previous, "--cold"]);
    assert!(std::fs::read(&plain).ok() == std::fs::read(&cold).ok());

    // Another canvas: the previous layout is not used, and the user is told.
    let wide = dir.join("wide.json");
    let out = support::layout(
        &changed,
        &[&wide],
        &["--previous", previous, "--width", "1600"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("not used"), "{stderr}");
    support::check_layout(&wide);
}

#[test]
fn a_broken_previous_layout_is_an_error_naming_the_field() {
    let dir = support::temp_dir("warm_broken");
    let input = support::generate(&dir, 30, 2, 1);
    let old = dir.join("old.json");
    support::layout(&input, &[&old], &[]);
    let broken = edited(&old, &dir, "broken.json", |doc| {
        doc["nodes"][2]["site"] = Value::from("here");
    });
    let out_path = dir.join("out.json");
    let out = support::bin()
        .arg("layout")
        .arg(&input)
        .arg("--previous")
        .arg(&broken)
        .arg("--out")
        .arg(&out_path)
        .output()
        .expect("run nptreemap");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("broken.json") && stderr.contains("nodes[2].site"),
        "{stderr}"
    );
    assert!(!out_path.exists());
}
