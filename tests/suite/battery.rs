//! Issue 12's degenerate battery: the default similarity method never fails
//! on valid input. Every case is laid out at seeds 1 to 5 by the binary and
//! must come out checker-clean (`shared/tools/check-layout`) with a
//! per-diagram area error of at most 0.01: sibling groups of 300 and 3,000,
//! weights spanning 1:10⁶, many identical vectors, all-identical vectors, zero
//! vectors, isolated nodes, a group in which every pair is a constraint, one
//! huge leaf among hundreds of tiny ones, and the real Debian packages that
//! failed with "cells stayed empty" before (seeds 1 and 2). Every diagram's
//! area error is judged against the real weights, also where they span more
//! than the layout's `min_weight_ratio` (1:1000): the floor that keeps tiny
//! leaves visible may not cost a diagram its areas (issue 23 item 6; before,
//! `/usr/bin` ended at 0.1355 with no diagram reported unconverged).
//!
//! The inputs are generated here (hierarchy JSON with `embeddings`, or with
//! `neighbors` lists for relation data) from a fixed seed, so they are the
//! same on every machine.

use std::path::Path;

use serde_json::{json, Value};

use crate::support;
use nptreemap::rng::Rng;

const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// Lays `input` out at every seed (extra flags after), checking each layout;
/// `checker` flags go to `check_layout.py`.
fn lay_out_at_every_seed(name: &str, input: &Path, extra: &[&str], checker: &[&str]) {
    let dir = input.parent().expect("input in a folder");
    for seed in SEEDS {
        let out = dir.join(format!("{name}_{seed}.json"));
        let seed = seed.to_string();
        let mut args = vec!["--seed", seed.as_str()];
        args.extend_from_slice(extra);
        support::layout(input, &[&out], &args);
        let report = support::check_layout_with(&out, checker);
        support::assert_area_error(&report, 0.01);
        assert_diagram_error_max(&report, 0.01);
    }
}

/// Every diagram, not only the mean, within `limit` of its weights.
fn assert_diagram_error_max(report: &Value, limit: f64) {
    let err = report["area_error_diagram_max"]
        .as_f64()
        .expect("area_error_diagram_max is a number");
    assert!(err <= limit, "area_error_diagram_max {err} > {limit}");
}

/// Writes a hierarchy JSON file (root flags merged in) and lays it out.
fn run(name: &str, root: Value) {
    run_checked(name, root, &[]);
}

/// [`run`] with flags for the checker.
fn run_checked(name: &str, root: Value, checker: &[&str]) {
    let dir = support::temp_dir(&format!("battery_{name}"));
    let input = dir.join("input.json");
    std::fs::write(&input, serde_json::to_vec(&root).expect("json")).expect("write input");
    lay_out_at_every_seed(name, &input, &[], checker);
}

/// A random vector near `center` (Gaussian-ish noise of size `noise`).
fn near(center: &[f64], noise: f64, rng: &mut Rng) -> Vec<f64> {
    center
        .iter()
        .map(|c| c + noise * (rng.next_f64() + rng.next_f64() - 1.0))
        .collect()
}

fn random_vector(dim: usize, rng: &mut Rng) -> Vec<f64> {
    (0..dim).map(|_| rng.next_f64() - 0.5).collect()
}

/// A root with one group per entry of `groups`; `leaf(g, i)` gives leaf i of
/// group g its weight and embedding.
fn grouped(
    groups: &[usize],
    mut leaf: impl FnMut(usize, usize) -> (f64, Vec<f64>),
) -> serde_json::Map<String, Value> {
    let children: Vec<Value> = groups
        .iter()
        .enumerate()
        .map(|(g, &n)| {
            let leaves: Vec<Value> = (0..n)
                .map(|i| {
                    let (weight, vector) = leaf(g, i);
                    json!({"id": format!("g{g}n{i}"), "weight": weight, "embeddings": vector})
                })
                .collect();
            json!({"id": format!("g{g}"), "children": leaves})
        })
        .collect();
    let mut root = serde_json::Map::new();
    root.insert("id".into(), json!("root"));
    root.insert("weightAttribute".into(), json!("weight"));
    root.insert("similarityMeasure".into(), json!("cosine"));
    root.insert("children".into(), Value::Array(children));
    root
}

/// Clustered embeddings: each group has a centre, leaves scatter around it.
fn clustered(groups: &[usize], dim: usize, seed: u64) -> serde_json::Map<String, Value> {
    let mut rng = Rng::new(seed);
    let centers: Vec<Vec<f64>> = groups
        .iter()
        .map(|_| random_vector(dim, &mut rng))
        .collect();
    grouped(groups, |g, _| {
        let w = 1.0 + 9.0 * rng.next_f64();
        (w, near(&centers[g], 0.6, &mut rng))
    })
}

#[test]
fn sibling_groups_of_300_and_3000() {
    run("big_groups", Value::Object(clustered(&[300, 3000], 8, 11)));
}

#[test]
fn weights_spanning_a_million() {
    let mut rng = Rng::new(12);
    let centers: Vec<Vec<f64>> = (0..4).map(|_| random_vector(8, &mut rng)).collect();
    let root = grouped(&[60, 60, 60, 60], |g, _| {
        let w = 10f64.powf(6.0 * rng.next_f64());
        (w, near(&centers[g], 0.5, &mut rng))
    });
    // Leaves under a thousandth of the heaviest: the floor may not cost the
    // diagram its areas (it did: 0.011 against the real weights).
    run("weights_1e6", Value::Object(root));
}

/// `/usr/bin`'s shape (issue 23 item 6): one flat level, sizes from a few
/// bytes to 10⁸, most of them under the 1:1000 floor of the heaviest.
#[test]
fn a_flat_level_of_sizes_spanning_1e8() {
    let mut rng = Rng::new(23);
    let centers: Vec<Vec<f64>> = (0..6).map(|_| random_vector(8, &mut rng)).collect();
    let leaves: Vec<Value> = (0..400)
        .map(|i| {
            let w = if i == 0 {
                1.3e8
            } else {
                10f64.powf(1.0 + 6.0 * rng.next_f64())
            };
            let v = near(&centers[i % 6], 0.5, &mut rng);
            json!({"id": format!("p{i}"), "weight": w, "embeddings": v})
        })
        .collect();
    let root = json!({
        "id": "root",
        "weightAttribute": "weight",
        "similarityMeasure": "cosine",
        "children": leaves,
    });
    run("flat_1e8", root);
}

#[test]
fn many_identical_vectors() {
    // Two thirds of every group share one of three vectors.
    let mut rng = Rng::new(13);
    let shared: Vec<Vec<f64>> = (0..3).map(|_| random_vector(8, &mut rng)).collect();
    let root = grouped(&[120, 120, 60], |_, i| {
        let w = 1.0 + 9.0 * rng.next_f64();
        let v = if i % 3 == 0 {
            random_vector(8, &mut rng)
        } else {
            shared[i % 3].clone()
        };
        (w, v)
    });
    run("identical", Value::Object(root));
}

#[test]
fn all_identical_vectors() {
    let v = vec![0.3, -0.2, 0.9, 0.1];
    let mut rng = Rng::new(14);
    let root = grouped(&[80, 50, 20], |_, _| {
        (1.0 + 9.0 * rng.next_f64(), v.clone())
    });
    run("all_identical", Value::Object(root));
}

#[test]
fn zero_vectors() {
    // Every third leaf has an all-zero vector (no direction: cosine is 0).
    let mut rng = Rng::new(15);
    let centers: Vec<Vec<f64>> = (0..3).map(|_| random_vector(8, &mut rng)).collect();
    let root = grouped(&[60, 60, 60], |g, i| {
        let w = 1.0 + 9.0 * rng.next_f64();
        let v = if i % 3 == 0 {
            vec![0.0; 8]
        } else {
            near(&centers[g], 0.5, &mut rng)
        };
        (w, v)
    });
    run("zero_vectors", Value::Object(root));
}

/// A relation dataset: groups of leaves with `neighbors` lists from
/// `partners(group, index)` (ids of other leaves).
fn related(groups: &[usize], partners: impl Fn(usize, usize) -> Vec<String>) -> Value {
    let children: Vec<Value> = groups
        .iter()
        .enumerate()
        .map(|(g, &n)| {
            let leaves: Vec<Value> = (0..n)
                .map(|i| {
                    json!({
                        "id": format!("g{g}n{i}"),
                        "weight": 1.0 + ((g * 31 + i * 17) % 10) as f64,
                        "neighbors": partners(g, i),
                    })
                })
                .collect();
            json!({"id": format!("g{g}"), "children": leaves})
        })
        .collect();
    json!({
        "id": "root",
        "weightAttribute": "weight",
        "useNeighborLeafs": true,
        "children": children,
    })
}

#[test]
fn isolated_nodes() {
    // Half the leaves have no relation at all; the rest form chains.
    let root = related(&[60, 60, 40], |g, i| {
        if i % 2 == 1 {
            Vec::new()
        } else {
            vec![
                format!("g{g}n{}", (i + 2) % 60),
                format!("g{}n{i}", (g + 1) % 3),
            ]
        }
    });
    run("isolated", root);
}

#[test]
fn a_group_where_every_pair_is_a_constraint() {
    let root = related(&[40, 30, 30], |g, i| {
        if g == 0 {
            (0..40)
                .filter(|&j| j != i)
                .map(|j| format!("g0n{j}"))
                .collect()
        } else {
            vec![format!("g{g}n{}", (i + 1) % 30)]
        }
    });
    run("all_pairs", root);
}

#[test]
fn one_huge_leaf_among_hundreds_of_tiny_ones() {
    let mut rng = Rng::new(16);
    let centers: Vec<Vec<f64>> = (0..2).map(|_| random_vector(8, &mut rng)).collect();
    let root = grouped(&[300, 100], |g, i| {
        let w = if g == 0 && i == 7 { 1e6 } else { 1.0 };
        (w, near(&centers[g], 0.5, &mut rng))
    });
    // The 300 tiny leaves (a raw share of 1e-6 each, under a pixel on a
    // 1000 × 1000 canvas) were floored to a thousandth of the huge one each,
    // 0.3 of the area in all; the floor now stays within the area target.
    run("huge_leaf", Value::Object(root));
}

#[test]
fn real_debian_packages_at_five_seeds() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/debian-packages");
    let dir = support::temp_dir("battery_debian");
    for name in ["nptreemap.yaml", "packages.csv"] {
        std::fs::copy(src.join(name), dir.join(name)).expect("copy dataset");
    }
    let config = dir.join("nptreemap.yaml");
    for seed in SEEDS {
        layout_real(&config, seed, &dir.join(format!("debian_{seed}.json")));
    }
}

/// Lays out the dataset of `config` at `seed` to `out` with the binary and
/// returns the checker's report, after checking the areas (within 1%).
fn layout_real(config: &Path, seed: u64, out: &Path) -> Value {
    let run = support::bin()
        .args(["layout", "--config", config.to_str().expect("utf8")])
        .args(["--seed", &seed.to_string()])
        .args(["--out", out.to_str().expect("utf8")])
        .output()
        .expect("run nptreemap");
    assert!(
        run.status.success(),
        "seed {seed}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report = support::check_layout(out);
    support::assert_area_error(&report, 0.01);
    report
}

/// Issue 23: "realised constraints at least today's" on every real dataset.
/// `/usr/bin` (1,200 programs in one diagram, sizes 1:10⁵) realised 145, 358
/// and 488 constraints at seeds 1–3 before the issue's work, median 358 as
/// the independent checker counts them; the area-floor fix of item 6 had
/// dropped that median to 332 until the swap polish learned to settle its
/// exchanges.
#[test]
fn real_usr_bin_realises_at_least_the_issue_baseline() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/usr-bin");
    let dir = support::temp_dir("battery_usr_bin");
    for name in ["nptreemap.yaml", "programs.csv", "vectors.tsv"] {
        std::fs::copy(src.join(name), dir.join(name)).expect("copy dataset");
    }
    let config = dir.join("nptreemap.yaml");
    let mut realized: Vec<u64> = [1, 2, 3]
        .iter()
        .map(|&seed| {
            let report = layout_real(&config, seed, &dir.join(format!("usr_bin_{seed}.json")));
            report["realized_lowest"].as_u64().expect("realized_lowest")
        })
        .collect();
    realized.sort_unstable();
    assert!(
        realized[1] >= 358,
        "median realised {} below the baseline 358 ({realized:?})",
        realized[1]
    );
}

/// How long a battery case may take before it counts as a hang: far above
/// what any takes here (seconds), so only a loop without end reaches it.
const HANG_SECS: u64 = 600;

/// Writes a flat border list of `rows` nodes (weights 1 to 13) with a pairs
/// file holding only its header, and a config drawing it to `outputs`.
fn flat_border_list(dir: &Path, rows: usize, outputs: &[&str]) -> std::path::PathBuf {
    let mut nodes = String::from("id,weight\n");
    for i in 0..rows {
        nodes.push_str(&format!("n{i},{}\n", 1 + (i * 7) % 13));
    }
    std::fs::write(dir.join("nodes.csv"), nodes).expect("write nodes");
    std::fs::write(dir.join("pairs.csv"), "a,b\n").expect("write pairs");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(
        &config,
        format!(
            "datasets:\n  - name: flat\n    format: border-list\n    files: {{nodes: nodes.csv, pairs: pairs.csv}}\n    fields: {{id: id, weight: weight}}\n    outputs: [{}]\n",
            outputs.join(", ")
        ),
    )
    .expect("write config");
    config
}

/// Issue 21, item 1: 2,371 or more top-level groups hung every build (the
/// generated palette searched for a colour its rings do not have). A flat
/// table of 2,371 rows and a root with 2,400 groups of two leaves are drawn,
/// within a generous bound, with touching groups in distinct colours.
#[test]
fn thousands_of_top_level_groups() {
    let dir = support::temp_dir("battery_groups");
    let config = flat_border_list(&dir, 2_371, &["out/flat.svg", "out/flat.png"]);
    let run = support::output_within(support::bin().arg("build").arg(&config), HANG_SECS);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let svg = std::fs::read_to_string(dir.join("out/flat.svg")).expect("svg");
    assert_eq!(svg.matches("<path data-id=").count(), 2_371);
    let children: Vec<Value> = (0..2_400)
        .map(|g| {
            json!({"id": format!("g{g}"), "children": [
                {"id": format!("g{g}a"), "value": 1 + g % 5},
                {"id": format!("g{g}b"), "value": 2},
            ]})
        })
        .collect();
    let input = dir.join("groups.json");
    let root = json!({"id": "root", "children": children});
    std::fs::write(&input, root.to_string()).expect("write input");
    let out = dir.join("groups.svg");
    let run = support::output_within(
        support::bin()
            .arg("layout")
            .arg(&input)
            .arg("--out")
            .arg(&out),
        HANG_SECS,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(&out)
            .expect("svg")
            .matches("<path data-id=")
            .count(),
        2_400 * 3
    );
}

/// Issue 21, item 8 (issue 23, item 3): a flat border list without pairs
/// has nothing to preserve; under the neighbourhood method 100,000 rows never
/// finished. It is now the plain layout, byte for byte. 10,000 rows here (the
/// suite runs unoptimised); 100,000 are measured by
/// `benches/border_no_pairs.sh` (release build).
#[test]
fn a_flat_border_list_without_pairs_is_the_plain_layout() {
    let dir = support::temp_dir("battery_no_pairs");
    let config = flat_border_list(&dir, 10_000, &["out/flat.json"]);
    let layout = |method: &str| {
        let out = dir.join(format!("{method}.json"));
        let run = support::output_within(
            support::bin()
                .args(["layout", "--config"])
                .arg(&config)
                .args(["--method", method, "--out"])
                .arg(&out),
            HANG_SECS,
        );
        assert!(
            run.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        out
    };
    let (neighbor, plain) = (layout("neighbor"), layout("plain"));
    assert!(
        std::fs::read(&neighbor).expect("neighbor") == std::fs::read(&plain).expect("plain"),
        "nothing to preserve: the neighbourhood method's layout is the plain one"
    );
    let report = support::check_layout(&neighbor);
    support::assert_area_error(&report, 0.01);
}

/// Issue 21, item 8: embedding vectors scaled by 1e-200 lost every
/// constraint (their squared norms underflowed and they counted as zero
/// vectors). Cosine does not depend on the scale: the layout of the scaled
/// vectors has the constraints of the unscaled ones, and is checker-clean.
#[test]
fn vectors_of_1e_minus_200() {
    let root = clustered(&[40, 30, 30], 8, 17);
    let scaled = |factor: f64| {
        let mut r = root.clone();
        for group in r["children"].as_array_mut().expect("groups") {
            for leaf in group["children"].as_array_mut().expect("leaves") {
                let v: Vec<f64> = leaf["embeddings"]
                    .as_array()
                    .expect("vector")
                    .iter()
                    .map(|x| x.as_f64().expect("number") * factor)
                    .collect();
                leaf["embeddings"] = json!(v);
            }
        }
        Value::Object(r)
    };
    let dir = support::temp_dir("battery_tiny_vectors");
    let constraints = |name: &str, root: Value| {
        let input = dir.join(format!("{name}.json"));
        std::fs::write(&input, root.to_string()).expect("write input");
        let out = dir.join(format!("{name}_layout.json"));
        support::layout(&input, &[&out], &["--seed", "1"]);
        let report = support::check_layout(&out);
        support::assert_area_error(&report, 0.01);
        let doc: Value =
            serde_json::from_slice(&std::fs::read(&out).expect("layout")).expect("json");
        doc["constraints"]
            .as_array()
            .expect("constraints")
            .iter()
            .map(|c| (c["a"].to_string(), c["b"].to_string()))
            .collect::<Vec<_>>()
    };
    let reference = constraints("unscaled", scaled(1.0));
    assert!(reference.len() > 50, "{} constraints", reference.len());
    assert_eq!(constraints("tiny", scaled(1e-200)), reference);
}
