//! Light layout JSON (issue 23 item 7): a tree whose leaves sit at uneven
//! depths (so the paper's virtual copies repeat them down to the deepest
//! level) is laid out by the binary; its layout JSON passes the checker, is
//! no heavier than what the format needs, lists no constraint twice, and
//! seeds a warm start that gives the same picture back.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::support;

/// A hierarchy JSON tree with leaves at depths 1 to 4 and 2-d embeddings
/// (cosine): leaves at depth 1 get three virtual copies below them, so
/// their constraints would repeat on three levels.
fn uneven_tree(dir: &Path) -> PathBuf {
    let leaf = |k: usize| {
        let angle = k as f64 * 0.37;
        json!({
            "id": format!("leaf-{k}"),
            "name": format!("Leaf number {k}"),
            "weight": 1 + (k * 7) % 13,
            "embeddings": [angle.cos(), angle.sin()],
        })
    };
    let mut root_children: Vec<Value> = (0..12).map(leaf).collect();
    let deep: Vec<Value> = (12..30).map(leaf).collect();
    root_children.push(json!({"id": "g", "name": "g", "children": [
        {"id": "g1", "name": "g1", "children": [
            {"id": "g11", "name": "g11", "children": deep[..9].to_vec()},
            {"id": "g12", "name": "g12", "children": deep[9..].to_vec()},
        ]},
    ]}));
    let tree = json!({
        "id": "root",
        "name": "root",
        "similarityMeasure": "cosine",
        "children": root_children,
    });
    let path = dir.join("uneven.json");
    std::fs::write(&path, tree.to_string()).expect("write tree");
    path
}

/// The characters a coordinate needs on the default 1000 × 1000 canvas: a
/// tenth of the checker's shortest contact (1e-6 of the 1414 diagonal) is
/// 1.4e-4, so four decimals: `1000.0000` at most, and a separator.
const COORD: usize = "1000.0000,".len();

/// The bytes the contract needs for `doc`: per node its fields' names and
/// punctuation, its strings, its small numbers, and its polygon and site at
/// [`COORD`] each; per constraint the same. Only the constraints no only
/// child repeats count: the others are the same pair one level down.
fn needed_bytes(doc: &Value) -> usize {
    let repeated: std::collections::HashSet<usize> = repeated_constraints(doc)
        .into_iter()
        .map(|(i, _)| i)
        .collect();
    let node_keys = r#"{"id":"","label":"","parent":"","depth":,"weight":,"virtual":false,"site":[],"power_weight":,"polygon":[]},"#.len() + "\n".len();
    let number = "-1234567.1234".len();
    let mut total = 200; // format, canvas, metrics, brackets
    for n in doc["nodes"].as_array().expect("nodes") {
        let text = |k: &str| n[k].as_str().map_or(4, |s| s.len());
        let vertices = n["polygon"].as_array().expect("polygon").len();
        total += node_keys + text("id") + text("label") + text("parent") + 2 * number;
        total += (vertices + 1) * (2 * COORD + "[]".len());
    }
    let con_keys =
        r#"{"a":"","b":"","similarity":0.1234,"strength":1,"realized":false,"also_above":10},"#
            .len()
            + 1;
    for (i, c) in doc["constraints"]
        .as_array()
        .expect("constraints")
        .iter()
        .enumerate()
    {
        if repeated.contains(&i) {
            continue;
        }
        let id = |k: &str| c[k].as_str().map_or(0, str::len);
        total += con_keys + id("a") + id("b");
    }
    total
}

/// Every constraint between two only children's parents that repeats the
/// children's one (its index and pair): what `also_above` replaces.
fn repeated_constraints(doc: &Value) -> Vec<(usize, String)> {
    let nodes = doc["nodes"].as_array().expect("nodes");
    let mut children: std::collections::HashMap<&str, Vec<&str>> = Default::default();
    for n in nodes {
        if let Some(p) = n["parent"].as_str() {
            children
                .entry(p)
                .or_default()
                .push(n["id"].as_str().expect("id"));
        }
    }
    let only = |id: &str| match children.get(id).map(Vec::as_slice) {
        Some([one]) => Some(*one),
        _ => None,
    };
    let cons = doc["constraints"].as_array().expect("constraints");
    let key = |a: &str, b: &str| {
        if a < b {
            (a.to_string(), b.to_string())
        } else {
            (b.to_string(), a.to_string())
        }
    };
    let listed: std::collections::HashMap<(String, String), &Value> = cons
        .iter()
        .map(|c| {
            (
                key(
                    c["a"].as_str().expect("layout json shape"),
                    c["b"].as_str().expect("layout json shape"),
                ),
                c,
            )
        })
        .collect();
    let mut out = Vec::new();
    for (i, c) in cons.iter().enumerate() {
        let (a, b) = (
            c["a"].as_str().expect("layout json shape"),
            c["b"].as_str().expect("layout json shape"),
        );
        if let (Some(ca), Some(cb)) = (only(a), only(b)) {
            if let Some(down) = listed.get(&key(ca, cb)) {
                let same = ["similarity", "strength", "realized"]
                    .iter()
                    .all(|k| down[*k] == c[*k]);
                if same {
                    out.push((i, format!("{a} / {b}")));
                }
            }
        }
    }
    out
}

fn read(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).expect("read layout")).expect("layout json")
}

#[test]
fn the_layout_json_is_as_light_as_the_contract_needs_and_checker_clean() {
    let dir = support::temp_dir("light_json");
    let input = uneven_tree(&dir);
    let out = dir.join("layout.json");
    support::layout(&input, &[&out], &[]);
    let report = support::check_layout(&out);
    assert_eq!(report["ok"], true);
    let doc = read(&out);
    let virtuals = doc["nodes"]
        .as_array()
        .expect("layout json shape")
        .iter()
        .filter(|n| n["virtual"] == true)
        .count();
    assert!(virtuals >= 30, "the tree has virtual copies: {virtuals}");

    let bytes = std::fs::metadata(&out).expect("size").len() as usize;
    let needed = needed_bytes(&doc);
    assert!(
        bytes <= needed,
        "{bytes} bytes for a document that needs at most {needed}"
    );
    let repeated = repeated_constraints(&doc);
    assert!(repeated.is_empty(), "listed twice: {repeated:?}");
    assert!(
        doc["constraints"]
            .as_array()
            .expect("layout json shape")
            .iter()
            .any(|c| c["also_above"].as_u64().is_some_and(|k| k >= 1)),
        "the leaf constraints say which levels above repeat them"
    );
}

#[test]
fn a_warm_start_from_the_rounded_file_gives_the_same_picture() {
    let dir = support::temp_dir("light_json_warm");
    let input = uneven_tree(&dir);
    let first = dir.join("first.json");
    support::layout(&input, &[&first], &[]);
    let warm = dir.join("warm.json");
    support::layout(
        &input,
        &[&warm],
        &["--previous", first.to_str().expect("utf8")],
    );
    support::check_layout(&warm);
    let (a, b) = (read(&first), read(&warm));
    let (na, nb) = (
        a["nodes"].as_array().expect("layout json shape"),
        b["nodes"].as_array().expect("layout json shape"),
    );
    assert_eq!(na.len(), nb.len());
    // Same data, same previous layout: every cell as the file had it, within
    // the file's grid (1e-4 on this canvas).
    for (x, y) in na.iter().zip(nb) {
        assert_eq!(x["id"], y["id"]);
        let (px, py) = (
            x["polygon"].as_array().expect("layout json shape"),
            y["polygon"].as_array().expect("layout json shape"),
        );
        assert_eq!(px.len(), py.len(), "{}", x["id"]);
        for (p, q) in px.iter().zip(py) {
            for k in 0..2 {
                let d = (p[k].as_f64().expect("layout json shape")
                    - q[k].as_f64().expect("layout json shape"))
                .abs();
                assert!(d <= 1e-4, "{}: {p} against {q}", x["id"]);
            }
        }
    }
    assert_eq!(
        a["constraints"], b["constraints"],
        "the same constraints and flags"
    );
}
