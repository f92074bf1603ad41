//! `nptreemap build` and `check` on a temporary copy of an example: outputs
//! written and checker-clean, byte-identical rebuilds, bad config and bad data
//! rejected with file and line, exit code 2, and existing outputs untouched.

use std::path::Path;

use crate::support;

fn run(args: &[&str]) -> std::process::Output {
    support::bin().args(args).output().expect("run nptreemap")
}

#[test]
fn countries_example_builds_and_rebuilds_identically() {
    let config = support::example("countries", "countries");
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
    let config = support::example("countries", "bad_key");
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
    let config = support::example("countries", "bad_data");
    let cfg = config.to_str().expect("utf8");
    assert!(run(&["build", cfg]).status.success());
    let svg = config.parent().expect("dir").join("out/countries.svg");
    let before = std::fs::read(&svg).expect("svg");
    let borders = config.parent().expect("dir").join("borders.csv");
    let text = std::fs::read_to_string(&borders).expect("read");
    // A row with a third field where the header has two. (An unknown id is
    // only a warning by default: see `short_outputs_state_dir_and_unknown_ids`.)
    std::fs::write(&borders, text.replacen("CN,IN", "CN,IN,XX", 1)).expect("write");
    let out = run(&["build", cfg]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    let line = 1 + text
        .lines()
        .position(|l| l == "CN,IN")
        .expect("a CN,IN row");
    assert!(
        stderr.contains(&format!("borders.csv: line {line}")),
        "{stderr}"
    );
    assert!(
        before == std::fs::read(&svg).expect("svg"),
        "output changed after a failed build"
    );
}

#[test]
fn check_validates_without_writing() {
    let config = support::example("countries", "check");
    let out = run(&["check", config.to_str().expect("utf8")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("ok countries: 36 nodes, 29 leaves"));
    assert!(!config.parent().expect("dir").join("out").exists());
}

/// Copies a folder tree (the examples) into `to`.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let path = entry.expect("entry").path();
        let name = path.file_name().expect("name");
        if name == "out" {
            continue;
        }
        if path.is_dir() {
            copy_tree(&path, &to.join(name));
        } else {
            std::fs::copy(&path, to.join(name)).expect("copy");
        }
    }
}

/// The README's main job: every example builds to SVG, PNG and JSON, every JSON
/// passes the checker, and a second build changes no byte.
#[test]
fn readme_main_job_builds_every_example() {
    let dir = support::temp_dir("all_examples");
    copy_tree(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples"),
        &dir,
    );
    let config = dir.join("nptreemap.yaml");
    let cfg = config.to_str().expect("utf8");
    let first = run(&["build", cfg]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let out = dir.join("out");
    let names = ["countries", "movies", "foods", "stocks", "world"];
    let mut snapshot = Vec::new();
    for name in names {
        let report = support::check_layout(&out.join(format!("{name}.json")));
        support::assert_area_error(&report, 0.01);
        let png = std::fs::read(out.join(format!("{name}.png"))).expect("png written");
        let image = resvg::tiny_skia::Pixmap::decode_png(&png).expect("a valid PNG");
        // One pixel per canvas unit: 1,000 wide, and as tall as the SVG's view
        // (the canvas plus the title band the example config asks for and the
        // legend band).
        let svg = std::fs::read_to_string(out.join(format!("{name}.svg"))).expect("svg");
        let view: Vec<f64> = svg
            .split("viewBox=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .expect("viewBox")
            .split(' ')
            .map(|v| v.parse().expect("number"))
            .collect();
        assert!(
            view[1] < 0.0 && view[3] > 1000.0,
            "{name}: title band {view:?}"
        );
        assert_eq!(image.width(), 1000, "{name}");
        assert_eq!(f64::from(image.height()), view[3].round(), "{name}");
        for ext in ["svg", "png", "json"] {
            snapshot.push(std::fs::read(out.join(format!("{name}.{ext}"))).expect("output"));
        }
    }
    let page = std::fs::read_to_string(out.join("countries.html")).expect("html written");
    assert!(page.contains("data-id=\"CN\"") && page.contains("class=\"np-data\""));
    // Nothing is fetched: no attribute, CSS url() or import names another
    // origin (the page's script mentions `https:` only to vet the data's own
    // link column, which it never loads).
    let compact: String = page.split_whitespace().collect();
    let external: Vec<&str> = [
        "src=\"http",
        "src='http",
        "src=\"//",
        "href=\"http",
        "href=\"//",
        "url(http",
        "url(\"http",
        "url('http",
        "url(//",
        "@import",
        "fetch(\"http",
        "<link",
    ]
    .into_iter()
    .filter(|needle| compact.contains(needle))
    .collect();
    assert!(
        external.is_empty(),
        "the page must not load anything from the network: {external:?}"
    );
    let second = run(&["build", cfg]);
    assert!(second.status.success());
    let mut again = Vec::new();
    for name in names {
        for ext in ["svg", "png", "json"] {
            again.push(std::fs::read(out.join(format!("{name}.{ext}"))).expect("output"));
        }
    }
    assert!(snapshot == again, "a second build changed an output");
}

/// The config keys of the second round: outputs as bare paths, `state_dir:`
/// (the stored layout moves there and the next build starts from it), and
/// `fields.on_unknown_id` (default: a pair naming a removed node is skipped
/// with a warning; `error` refuses it, naming the file, line and id).
#[test]
fn short_outputs_state_dir_and_unknown_ids() {
    let config = support::example("countries", "config_keys");
    let dir = config.parent().expect("dir").to_path_buf();
    std::fs::write(
        &config,
        "state_dir: state\n\
         datasets:\n  - name: countries\n    format: border-list\n    \
         files: {nodes: countries.csv, pairs: borders.csv}\n    \
         fields: {id: iso, label: name, weight: population, groups: [continent]}\n    \
         outputs: [out/c.svg, out/c.json]\n",
    )
    .expect("write config");
    let cfg = config.to_str().expect("utf8");
    let first = run(&["build", cfg]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(dir.join("out/c.svg").is_file() && dir.join("out/c.json").is_file());
    let state = dir.join("state/countries.layout.json");
    assert!(state.is_file(), "no stored layout in state/");
    assert!(
        !dir.join("out/.nptreemap").exists(),
        "state also beside the outputs"
    );
    // The next build starts from it: nothing changes.
    let second = run(&["build", cfg]);
    assert!(String::from_utf8_lossy(&second.stdout).contains("unchanged"));

    // Drop a country from the node table; its pairs stay in borders.csv.
    let nodes = dir.join("countries.csv");
    let table = std::fs::read_to_string(&nodes).expect("nodes");
    // The first country of the first pair.
    let pairs = std::fs::read_to_string(dir.join("borders.csv")).expect("pairs");
    let gone = pairs
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').next())
        .expect("a first pair")
        .to_string();
    assert!(
        table.contains(&format!("\n{gone},")),
        "{gone} is not a node"
    );
    let kept: Vec<&str> = table
        .lines()
        .filter(|l| !l.starts_with(&format!("{gone},")))
        .collect();
    std::fs::write(&nodes, kept.join("\n") + "\n").expect("write nodes");
    let warned = run(&["build", cfg]);
    let stderr = String::from_utf8_lossy(&warned.stderr);
    assert!(warned.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("unknown id {gone:?}")) && stderr.contains("skipped"),
        "no warning: {stderr}"
    );
    let svg = std::fs::read(dir.join("out/c.svg")).expect("svg");
    std::fs::write(
        &config,
        std::fs::read_to_string(&config).expect("config").replace(
            "groups: [continent]}",
            "groups: [continent], on_unknown_id: error}",
        ),
    )
    .expect("write config");
    let refused = run(&["build", cfg]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("borders.csv: line") && stderr.contains(&format!("unknown id {gone:?}")),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(dir.join("out/c.svg")).expect("svg"),
        svg,
        "an output changed"
    );
}
