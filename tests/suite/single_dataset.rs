//! `layout`, `eval` and `bench` on a configured dataset (`--config FILE
//! --dataset NAME`): they read it through the format registry like `build`
//! does, so any dataset a config can build can be laid out and evaluated on
//! its own, and the bytes are the ones `build` writes.

use std::path::Path;

use super::support;

/// Leaves of the countries example, counted from its node table (one row per
/// country, a header line).
fn countries_rows(config: &Path) -> usize {
    let csv = config.with_file_name("countries.csv");
    let text = std::fs::read_to_string(csv).expect("countries.csv");
    text.lines().filter(|l| !l.trim().is_empty()).count() - 1
}

#[test]
fn eval_reads_a_configured_csv_dataset_and_agrees_with_the_checker() {
    let config = support::example("countries", "eval_config");
    let dir = config.parent().expect("folder").to_path_buf();
    let json = dir.join("eval.json");
    let out = support::bin()
        .arg("eval")
        .args(["--config"])
        .arg(&config)
        .args(["--dataset", "countries", "--json", "--out"])
        .arg(&json)
        .output()
        .expect("run eval");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let row: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("one JSON line on stdout");
    assert_eq!(row["leaves"], countries_rows(&config));
    assert_eq!(row["file"], "countries");
    // The independent checker recomputes constraints and adjacency from the
    // written polygons; eval's row must say the same.
    let report = support::check_layout(&json);
    assert_eq!(row["leaf_constraints"], report["constraints_lowest"]);
    assert_eq!(row["realized"], report["realized_lowest"]);
    assert!(row["realized"].as_u64().expect("count") > 0);
    support::assert_area_error(&report, 0.01);
}

#[test]
fn layout_of_a_configured_dataset_writes_what_build_writes() {
    let config = support::example("countries", "layout_config");
    let dir = config.parent().expect("folder").to_path_buf();
    let built = support::bin()
        .arg("build")
        .arg("--cold")
        .arg(&config)
        .output()
        .expect("run build");
    assert!(built.status.success());
    let single = dir.join("single.svg");
    let out = support::bin()
        .arg("layout")
        .arg("--config")
        .arg(&config)
        .arg("--out")
        .arg(&single)
        .output()
        .expect("run layout");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let from_build = std::fs::read(dir.join("out/countries.svg")).expect("build's SVG");
    assert_eq!(std::fs::read(&single).expect("layout's SVG"), from_build);
    // A flag overrides the config's setting: another seed, another picture.
    let other = dir.join("other.svg");
    let out = support::bin()
        .arg("layout")
        .arg("--config")
        .arg(&config)
        .args(["--seed", "7", "--out"])
        .arg(&other)
        .output()
        .expect("run layout");
    assert!(out.status.success());
    assert_ne!(std::fs::read(&other).expect("SVG"), from_build);
}

#[test]
fn a_config_dataset_that_is_not_there_is_a_usage_error_listing_the_names() {
    let config = support::example("countries", "missing_dataset");
    for command in ["layout", "eval", "bench"] {
        let mut cmd = support::bin();
        cmd.arg(command)
            .arg("--config")
            .arg(&config)
            .args(["--dataset", "nowhere"]);
        if command == "layout" {
            cmd.args(["--out", "x.svg"]);
        }
        let out = cmd.output().expect("run");
        assert_eq!(out.status.code(), Some(2), "{command}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("no dataset \"nowhere\" (it has: countries)"),
            "{command}: {err}"
        );
    }
    // INPUT and --config together are refused by the argument parser.
    let out = support::bin()
        .args(["eval", "in.json", "--config"])
        .arg(&config)
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(2));
}
