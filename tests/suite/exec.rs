//! The runtime format plugin, `format: exec`, through the binary: the shipped
//! example adapter builds (its stdout parsed as hierarchy JSON, its declared
//! file passed as an argument), and a failing adapter is the user's error
//! naming the dataset and the command, quoting its stderr, writing nothing.

use crate::support;

fn build(config: &std::path::Path) -> std::process::Output {
    support::bin()
        .arg("build")
        .arg(config)
        .output()
        .expect("run nptreemap")
}

#[test]
fn the_example_adapter_builds_a_checker_clean_layout() {
    let config = support::example("exec", "exec");
    let dir = config.parent().expect("dir").to_path_buf();
    let text = std::fs::read_to_string(&config).expect("read");
    std::fs::write(&config, format!("{text}      - path: out/sources.json\n")).expect("write");
    let out = build(&config);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = support::check_layout(&dir.join("out/sources.json"));
    support::assert_area_error(&report, 0.01);
    // One leaf per file line of sizes.du that no other line extends.
    let du = std::fs::read_to_string(dir.join("sizes.du")).expect("du");
    let paths: Vec<&str> = du.lines().filter_map(|l| l.split('\t').nth(1)).collect();
    let files = paths
        .iter()
        .filter(|p| !paths.iter().any(|q| q.starts_with(&format!("{p}/"))))
        .count();
    let layout: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/sources.json")).expect("json"))
            .expect("layout JSON");
    let nodes = layout["nodes"].as_array().expect("nodes");
    let parents: std::collections::BTreeSet<&str> =
        nodes.iter().filter_map(|n| n["parent"].as_str()).collect();
    let leaves = nodes
        .iter()
        .filter(|n| !parents.contains(n["id"].as_str().expect("id")))
        .count();
    assert_eq!(leaves, files);
    assert!(dir.join("out/sources.png").is_file());
}

#[test]
fn a_failing_adapter_names_the_command_and_quotes_its_stderr() {
    let dir = support::temp_dir("exec_failing");
    std::fs::write(dir.join("data.txt"), "x\n").expect("data");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        "datasets:\n  - name: mine\n    format: exec\n    command: [sh, -c, 'echo \"row 7 is bad\" >&2; exit 4', adapter]\n    files: {data: data.txt}\n    outputs: [{path: out/a.svg}]\n",
    )
    .expect("config");
    let out = build(&dir.join("nptreemap.yaml"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("dataset \"mine\": `sh -c"), "{stderr}");
    assert!(stderr.contains("failed (exit status: 4)"), "{stderr}");
    assert!(stderr.contains("row 7 is bad"), "{stderr}");
    assert!(!dir.join("out").exists(), "nothing is written");
}

#[test]
fn adapter_output_that_is_not_a_hierarchy_is_an_error_naming_the_command() {
    let dir = support::temp_dir("exec_garbage");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        "datasets:\n  - name: mine\n    format: exec\n    command: [sh, -c, 'echo \"{\\\"children\\\": 3}\"']\n    files: {}\n    outputs: [{path: out/a.svg}]\n",
    )
    .expect("config");
    let out = build(&dir.join("nptreemap.yaml"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("(stdout): line 1"), "{stderr}");
    assert!(!dir.join("out").exists(), "nothing is written");
}

#[test]
fn exec_keys_are_checked_against_the_format() {
    let dir = support::temp_dir("exec_keys");
    for (dataset, message) in [
        (
            "format: exec\n    files: {}",
            "datasets[0].command: format exec needs `command: [program, args...]`",
        ),
        (
            "format: hierarchy-json\n    files: {hierarchy: a.json}\n    command: [python3]",
            "datasets[0].command: only format exec runs a command",
        ),
        (
            "format: exec\n    files: {}\n    command: [python3]\n    timeout: 0",
            "datasets[0].timeout: must be a positive number of seconds",
        ),
    ] {
        let config = dir.join("nptreemap.yaml");
        std::fs::write(&config, format!("datasets:\n  - name: d\n    {dataset}\n")).expect("write");
        let out = build(&config);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{dataset}: {stderr}");
    }
}
