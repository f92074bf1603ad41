//! Issue 34 item 3: `--method plain` never uses the constraints, so it
//! computes none (the stage report says so), unless a realised count is asked
//! for (`eval`, `bench --realized`), which still counts what plain realises.

use nptreemap::config::Config;
use nptreemap::graph::{DatasetGraph, GraphOptions, Stage};

use crate::support;

/// The countries example (border pairs) laid out by the plain method.
fn plain_countries(tag: &str) -> std::path::PathBuf {
    let config = support::example("countries", &format!("plain_method_{tag}"));
    let text = std::fs::read_to_string(&config).expect("config");
    let text = text.replacen("layout:\n", "layout:\n  method: plain\n", 1);
    std::fs::write(&config, text).expect("write config");
    config
}

#[test]
fn a_plain_build_computes_no_constraint() {
    let config = plain_countries("build");
    let c = Config::from_path(&config).expect("config");
    let job = support::first_job(&c, true);
    let mut graph = DatasetGraph::new(GraphOptions::from_env());
    let mut built = graph.build(&job).expect("build");
    let s = &built.stages;
    assert_eq!(s.ran(Stage::Constraints), 0, "{s:?}");
    assert_eq!(s.ran(Stage::Layout), 1, "{s:?}");
    assert_eq!(built.constraints, 0, "{s:?}");
    let written = graph.commit(&job, &mut built);
    assert!(written.failed.is_empty(), "{:?}", written.failed);
    let json = config.with_file_name("out").join("countries.json");
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("layout JSON")).expect("JSON");
    assert_eq!(
        doc["constraints"].as_array().map(Vec::len),
        Some(0),
        "{}",
        doc["constraints"]
    );
    support::check_layout(&json);
}

#[test]
fn eval_and_bench_realized_still_count_what_plain_realises() {
    let config = plain_countries("eval");
    let bench = |method: &str, extra: &[&str]| -> serde_json::Value {
        let mut cmd = support::bin();
        cmd.args(["bench", "--config"]).arg(&config);
        cmd.args(["--method", method, "--repeat", "1"]).args(extra);
        let out = cmd.output().expect("bench runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("one JSON line")
    };
    let plain = bench("plain", &[]);
    assert_eq!(plain["constraints"], 0, "{plain}");
    let counted = bench("plain", &["--realized"]);
    // The same constraints as the neighbourhood method's, on the same layout.
    let neighbor = bench("neighbor", &[]);
    assert!(neighbor["constraints"].as_u64() > Some(0), "{neighbor}");
    assert_eq!(counted["constraints"], neighbor["constraints"], "{counted}");
    assert_eq!(
        counted["area_error_diagram_max"],
        plain["area_error_diagram_max"]
    );
    assert!(counted["realized"].as_u64() > Some(0), "{counted}");

    let out = support::bin()
        .args(["eval", "--json", "--method", "plain", "--config"])
        .arg(&config)
        .output()
        .expect("eval runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let row: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON row");
    assert!(row["leaf_constraints"].as_u64() > Some(0), "{row}");
    assert_eq!(row["method"], "plain", "{row}");
}
