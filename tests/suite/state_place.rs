//! Issue 30 items 8 and 9: where a dataset's state lives. Its folder does not
//! depend on the order of the outputs, two configs that write into one
//! output folder keep their own state, and the state an older version left
//! (under the dataset's plain name, beside the first output) still gives a
//! warm start. Runs the binary, as users do.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support;

/// The countries example in a fresh folder, its config replaced by `name`
/// with the outputs `outputs` (`layout:` lines first when given).
fn countries(tag: &str, name: &str, layout: &str, outputs: &[&str]) -> PathBuf {
    let example = support::example("countries", &format!("state_{tag}"));
    let dir = example.parent().expect("folder").to_path_buf();
    let config = dir.join(name);
    std::fs::write(&config, config_text(layout, outputs)).expect("config");
    config
}

fn config_text(layout: &str, outputs: &[&str]) -> String {
    format!(
        "{layout}datasets:
  - name: countries
    format: border-list
    files: {{nodes: countries.csv, pairs: borders.csv}}
    fields: {{id: iso, label: name, weight: population, groups: [continent]}}
    outputs: [{}]
",
        outputs.join(", ")
    )
}

/// Runs `nptreemap ARGS CONFIG`; its exit code and what it printed.
fn run(args: &[&str], config: &Path) -> (Option<i32>, String) {
    let o: Output = support::bin().args(args).arg(config).output().expect("run");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code(), text)
}

/// Builds and asserts success; returns what it printed.
fn build(config: &Path) -> String {
    let (code, text) = run(&["build"], config);
    assert_eq!(code, Some(0), "{text}");
    text
}

/// Multiplies the population of the first country by 1.1 (a warm edit: a
/// cold layout of the edited data does not reproduce its picture).
fn edit_weight(dir: &Path) {
    let csv = dir.join("countries.csv");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[1].split(',').map(str::to_string).collect();
    let population: f64 = cells[2].parse().expect("a number");
    cells[2] = format!("{}", (population * 1.1).round());
    lines[1] = cells.join(",");
    std::fs::write(&csv, lines.join("\n") + "\n").expect("write csv");
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Issue 30 item 8: with outputs in two folders, reordering them moved the
/// state folder (it sat beside the first output): the next build found no
/// stored layout, laid out cold and redrew the picture an edit had made
/// warm. Now it finds everything up to date and writes nothing.
#[test]
fn reordering_the_outputs_keeps_the_state() {
    let config = countries(
        "reorder",
        "nptreemap.yaml",
        "",
        &["out/countries.svg", "json/countries.json"],
    );
    let dir = config.parent().expect("folder").to_path_buf();
    build(&config);
    edit_weight(&dir);
    let text = build(&config);
    assert!(text.contains("laid out warm"), "{text}");
    let svg = read(&dir.join("out/countries.svg"));
    std::fs::write(
        &config,
        config_text("", &["json/countries.json", "out/countries.svg"]),
    )
    .expect("reordered");
    let (code, text) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{text}");
    let text = build(&config);
    assert!(text.contains("countries: up to date"), "{text}");
    assert_eq!(
        read(&dir.join("out/countries.svg")),
        svg,
        "the picture was redrawn"
    );
}

/// Issue 30 item 9: two configs in one folder whose datasets share a name
/// and an output folder shared one state: building `b.yaml` made
/// `a.yaml`'s unchanged picture redraw (cold, over its warm edit) and
/// `build --check a.yaml` never passed. Each config keeps its own now, under
/// names that start with the config's name (deterministic, no absolute path,
/// fit to be committed).
#[test]
fn two_configs_sharing_an_output_folder_keep_their_own_state() {
    let a = countries("two_configs", "a.yaml", "", &["out/a.svg", "out/a.json"]);
    let dir = a.parent().expect("folder").to_path_buf();
    let b = dir.join("b.yaml");
    std::fs::write(
        &b,
        config_text("layout: {seed: 2}\n", &["out/b.svg", "out/b.json"]),
    )
    .expect("b.yaml");
    build(&a);
    edit_weight(&dir);
    let text = build(&a);
    assert!(text.contains("laid out warm"), "{text}");
    let svg = read(&dir.join("out/a.svg"));
    build(&b);
    let (code, text) = run(&["build", "--check"], &a);
    assert_eq!(
        code,
        Some(0),
        "b.yaml's build made a.yaml's outputs stale: {text}"
    );
    let text = build(&a);
    assert!(text.contains("countries: up to date"), "{text}");
    assert_eq!(read(&dir.join("out/a.svg")), svg);
    let (code, text) = run(&["build", "--check"], &b);
    assert_eq!(code, Some(0), "{text}");
    let state = dir.join("out/.nptreemap");
    for name in [
        "a.countries.layout.json",
        "a.countries.manifest.json",
        "b.countries.layout.json",
        "b.countries.manifest.json",
    ] {
        assert!(state.join(name).is_file(), "{name}");
    }
    assert!(!state.join("countries.layout.json").exists());
}

/// What an older version left is still found, once: its state under the
/// dataset's plain name (`countries.layout.json`) beside the first output
/// of the config, which is no longer where this version keeps it. A fresh
/// clone of a repository committed with it passes `build --check`, and the
/// next edit lays out warm from it and keeps the state in its new place.
#[test]
fn the_state_an_older_version_left_is_found() {
    let config = countries(
        "older",
        "site.yaml",
        "",
        &["out/countries.svg", "json/countries.json"],
    );
    let dir = config.parent().expect("folder").to_path_buf();
    build(&config);
    edit_weight(&dir);
    build(&config);
    // This version keeps it beside the output folder that sorts first,
    // under the config's name.
    let now = dir.join("json/.nptreemap");
    assert!(now.join("site.countries.layout.json").is_file());
    // As an older version left it: beside the first output, plain names.
    let older = dir.join("out/.nptreemap");
    std::fs::create_dir_all(&older).expect("mkdir");
    for kind in ["layout.json", "manifest.json"] {
        std::fs::rename(
            now.join(format!("site.countries.{kind}")),
            older.join(format!("countries.{kind}")),
        )
        .expect("move");
    }
    std::fs::remove_dir_all(&now).expect("rm");
    let (code, text) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{text}");
    edit_weight(&dir);
    let text = build(&config);
    // Warm: with ticks, or none when the edit is too small to need one.
    assert!(
        text.contains("laid out warm") || text.contains("layout reused"),
        "{text}"
    );
    assert!(now.join("site.countries.layout.json").is_file());
    let (code, text) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{text}");
}
