//! `nptreemap build` and `check` on a temporary copy of an example: outputs
//! written and checker-clean, byte-identical rebuilds, bad config and bad data
//! rejected with file and line, exit code 2, and existing outputs untouched.

use std::path::{Path, PathBuf};

use crate::support;

/// Copies `examples/<name>` into a fresh temp dir and returns the config path.
fn example(name: &str, tag: &str) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name);
    let dir = support::temp_dir(&format!("build_{tag}"));
    for entry in std::fs::read_dir(&src).expect("example dir") {
        let path = entry.expect("entry").path();
        if path.is_file() {
            std::fs::copy(&path, dir.join(path.file_name().expect("name"))).expect("copy");
        }
    }
    dir.join("nptreemap.yaml")
}

fn run(args: &[&str]) -> std::process::Output {
    support::bin().args(args).output().expect("run nptreemap")
}

#[test]
fn countries_example_builds_and_rebuilds_identically() {
    let config = example("countries", "countries");
    let cfg = config.to_str().expect("utf8");
    let first = run(&["build", cfg]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let out = config.parent().expect("dir").join("out");
    let json = out.join("countries.json");
    let report = support::check_layout(&json);
    support::assert_area_error(&report, 0.01);
    assert_eq!(report["constraints_lowest"].as_u64(), Some(18));
    let bytes = (
        std::fs::read(&json).expect("json"),
        std::fs::read(out.join("countries.svg")).expect("svg"),
    );
    let second = run(&["build", cfg]);
    assert!(second.status.success());
    assert!(String::from_utf8_lossy(&second.stdout).contains("unchanged"));
    assert!(
        bytes.0 == std::fs::read(&json).expect("json"),
        "JSON differs between builds"
    );
    assert!(
        bytes.1 == std::fs::read(out.join("countries.svg")).expect("svg"),
        "SVG differs"
    );
}

#[test]
fn unknown_config_key_names_line_and_column_and_writes_nothing() {
    let config = example("countries", "bad_key");
    let text = std::fs::read_to_string(&config).expect("read");
    std::fs::write(
        &config,
        text.replace("outline: ngon", "outline: ngon\n  colour: red"),
    )
    .expect("write");
    let out = run(&["build", config.to_str().expect("utf8")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("nptreemap.yaml: line ") && stderr.contains("colour"),
        "{stderr}"
    );
    assert!(!config.parent().expect("dir").join("out").exists());
}

#[test]
fn bad_data_names_file_and_line_and_keeps_existing_outputs() {
    let config = example("countries", "bad_data");
    let cfg = config.to_str().expect("utf8");
    assert!(run(&["build", cfg]).status.success());
    let svg = config.parent().expect("dir").join("out/countries.svg");
    let before = std::fs::read(&svg).expect("svg");
    let borders = config.parent().expect("dir").join("borders.csv");
    let text = std::fs::read_to_string(&borders).expect("read");
    std::fs::write(&borders, text.replacen("CN,IN", "CN,XX", 1)).expect("write");
    let out = run(&["build", cfg]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("borders.csv: line ") && stderr.contains("\"XX\""),
        "{stderr}"
    );
    assert!(
        before == std::fs::read(&svg).expect("svg"),
        "output changed after a failed build"
    );
}

#[test]
fn check_validates_without_writing() {
    let config = example("countries", "check");
    let out = run(&["check", config.to_str().expect("utf8")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("ok countries: 36 nodes, 29 leaves"));
    assert!(!config.parent().expect("dir").join("out").exists());
}
