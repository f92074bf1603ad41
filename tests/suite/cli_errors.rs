//! Bad input and bad arguments: a clear message naming the file (and line), exit
//! code 2, and existing outputs left byte-identical.

use crate::support;

fn fails_with(args: &[&str], needle: &str) {
    let out = support::bin().args(args).output().expect("run nptreemap");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains(needle), "expected {needle:?} in: {stderr}");
}

#[test]
fn missing_input_names_the_file() {
    let dir = support::temp_dir("cli_missing");
    let out = dir.join("x.json");
    fails_with(
        &[
            "layout",
            "no/such/file.json",
            "--out",
            out.to_str().expect("utf8"),
        ],
        "no/such/file.json",
    );
    assert!(!out.exists());
}

#[test]
fn malformed_json_names_file_line_and_column_and_keeps_outputs() {
    let dir = support::temp_dir("cli_malformed");
    let input = dir.join("broken.json");
    std::fs::write(
        &input,
        "{\n  \"children\": [\n    {\"id\": \"a\", \"weight\": 1},\n    {\"id\": \n",
    )
    .expect("write");
    let out = dir.join("old.svg");
    std::fs::write(&out, "previous picture").expect("write");
    fails_with(
        &[
            "layout",
            input.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        "broken.json: line 5",
    );
    assert_eq!(
        std::fs::read_to_string(&out).expect("read"),
        "previous picture"
    );
}

#[test]
fn negative_weight_names_the_node() {
    let dir = support::temp_dir("cli_negative");
    let input = dir.join("neg.json");
    std::fs::write(
        &input,
        r#"{"id": "root", "children": [{"id": "a", "weight": 2}, {"id": "bad", "weight": -1}]}"#,
    )
    .expect("write");
    let out = dir.join("x.json");
    fails_with(
        &[
            "layout",
            input.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        "\"bad\"",
    );
    assert!(!out.exists());
}

#[test]
fn unknown_output_kind_is_a_usage_error() {
    let input = support::paper_data().join("syntheticPoints_4.json");
    fails_with(
        &[
            "layout",
            input.to_str().expect("utf8"),
            "--out",
            "picture.bmp",
        ],
        "picture.bmp",
    );
}

/// Misspelt names get a "did you mean" naming the likely fix: a column, a
/// format, an input role and a config key, each with exit code 2.
#[test]
fn misspelt_names_get_a_did_you_mean() {
    let dir = support::temp_dir("cli_did_you_mean");
    std::fs::write(
        dir.join("c.csv"),
        "iso,name,population\nDE,Germany,84\nFR,France,68\n",
    )
    .expect("write table");
    for (dataset, wanted) in [
        (
            "format: border-list\n    files: {nodes: c.csv, pairs: c.csv}\n    fields: {id: iso, weight: populaton}",
            "did you mean \"population\"?",
        ),
        (
            "format: border_list\n    files: {nodes: c.csv, pairs: c.csv}",
            "did you mean \"border-list\"?",
        ),
        (
            "format: border-list\n    files: {nodes: c.csv, pair: c.csv}",
            "did you mean \"pairs\"?",
        ),
        (
            "format: border-list\n    files: {nodes: c.csv, pairs: c.csv}\n    feilds: {id: iso}",
            "did you mean `fields`?",
        ),
    ] {
        let config = dir.join("nptreemap.yaml");
        std::fs::write(
            &config,
            format!("datasets:\n  - name: c\n    {dataset}\n    outputs: [{{path: out/c.svg}}]\n"),
        )
        .expect("write config");
        fails_with(&["check", config.to_str().expect("utf8")], wanted);
    }
}
