//! Issue 22: a rebuild costs what the change costs, and outputs follow from
//! committed files. Builds run as `nptreemap build` runs them (a new stage
//! graph per dataset and run, state from the state folder) and the
//! assertions read the stage counts of its report. Each reuse test fails
//! with the caches off (`NPTREEMAP_NO_CACHE=1 cargo test --test suite
//! incremental::`), which is how they were checked.

use std::path::{Path, PathBuf};

use nptreemap::config::Config;
use nptreemap::graph::{DatasetBuild, DatasetGraph, GraphOptions, Job, LayoutStep, Stage};

use crate::support;

/// Builds every dataset of `config` and writes what changed, as the binary
/// does; returns each dataset's build (with its stage report).
fn build(config: &Path) -> Vec<DatasetBuild> {
    let c = Config::from_path(config).expect("config");
    c.datasets
        .iter()
        .map(|d| {
            let job = Job {
                dataset: d,
                request: c.request(d),
                style: c.style(d),
                cold: false,
            };
            let mut graph = DatasetGraph::new(GraphOptions::from_env());
            let mut built = graph.build(&job).expect("build");
            let written = graph.commit(&job, &mut built);
            assert!(written.failed.is_empty(), "{:?}", written.failed);
            built
        })
        .collect()
}

/// The countries example in a fresh folder.
fn countries(tag: &str) -> PathBuf {
    support::example("countries", &format!("incremental_{tag}"))
}

/// Multiplies the population of the first country by `factor`.
fn edit_weight(config: &Path, factor: f64) {
    let csv = config.with_file_name("countries.csv");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[1].split(',').map(str::to_string).collect();
    let population: f64 = cells[2].parse().expect("a number");
    cells[2] = format!("{}", (population * factor).round());
    lines[1] = cells.join(",");
    std::fs::write(&csv, lines.join("\n") + "\n").expect("write csv");
}

/// Replaces `from` by `to` in the config (which must contain it).
fn edit_config(config: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(config).expect("config");
    assert!(text.contains(from), "{from:?} not in the config");
    std::fs::write(config, text.replacen(from, to, 1)).expect("write config");
}

fn out(config: &Path, name: &str) -> Vec<u8> {
    std::fs::read(config.with_file_name("out").join(name)).expect("output")
}

#[test]
fn a_weight_edit_recomputes_no_constraint() {
    let config = countries("weight");
    let first = build(&config);
    assert_eq!(first[0].stages.ran(Stage::Constraints), 1);
    let svg = out(&config, "countries.svg");
    edit_weight(&config, 1.1);
    let second = build(&config);
    let s = &second[0].stages;
    assert_eq!(s.ran(Stage::Constraints), 0, "{s:?}");
    assert_eq!(s.reused(Stage::Constraints), 1, "{s:?}");
    assert_eq!(second[0].layout, LayoutStep::Warm, "{s:?}");
    assert_ne!(out(&config, "countries.svg"), svg, "the edit shows");
}

#[test]
fn a_render_edit_runs_no_layout() {
    let config = countries("render");
    build(&config);
    let svg = out(&config, "countries.svg");
    let json = out(&config, "countries.json");
    edit_config(
        &config,
        "layout:\n",
        "render:\n  border_width: 4\nlayout:\n",
    );
    let second = build(&config);
    let s = &second[0].stages;
    assert_eq!(s.ran(Stage::Layout), 0, "{s:?}");
    assert_eq!(s.ran(Stage::Constraints), 0, "{s:?}");
    assert_eq!(second[0].layout, LayoutStep::Reused, "{s:?}");
    // The SVG and PNG are drawn again; the layout JSON has no style.
    assert_eq!(s.ran(Stage::Render), 2, "{s:?}");
    assert_ne!(out(&config, "countries.svg"), svg);
    assert_eq!(out(&config, "countries.json"), json);
}

#[test]
fn a_no_op_build_runs_neither_layout_nor_render_and_writes_nothing() {
    let config = countries("noop");
    build(&config);
    let dir = config.with_file_name("out");
    let before = snapshot(&dir);
    let second = build(&config);
    let s = &second[0].stages;
    assert_eq!(second[0].layout, LayoutStep::UpToDate, "{s:?}");
    for stage in [
        Stage::Parse,
        Stage::Constraints,
        Stage::Layout,
        Stage::Render,
        Stage::Write,
    ] {
        assert_eq!(s.ran(stage), 0, "{stage:?} ran: {s:?}");
    }
    assert_eq!(snapshot(&dir), before, "a no-op build touched a file");

    // The binary: building twice writes nothing and prints the same.
    let run = || {
        let o = support::build(&config);
        String::from_utf8(o.stdout).expect("utf-8")
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b);
    assert!(a.contains("up to date") && !a.contains("wrote"), "{a}");
    assert_eq!(snapshot(&dir), before, "a no-op build touched a file");
}

#[test]
fn a_seed_edit_lays_out_cold_and_changes_the_picture() {
    let config = countries("seed");
    build(&config);
    edit_weight(&config, 1.1);
    let warm = build(&config);
    assert_eq!(warm[0].layout, LayoutStep::Warm, "{:?}", warm[0].stages);
    let seed1 = out(&config, "countries.svg");
    edit_config(&config, "layout:\n", "layout:\n  seed: 2\n");
    let cold = build(&config);
    match &cold[0].layout {
        LayoutStep::Cold(why) => assert!(why.contains("settings changed"), "{why}"),
        other => panic!("a seed edit laid out {other:?}"),
    }
    assert_eq!(cold[0].stages.ran(Stage::Layout), 1);
    let seed2 = out(&config, "countries.svg");
    assert_ne!(seed2, seed1, "a seed change must change the picture");
    // It is the layout a cold build with seed 2 makes from scratch (the
    // picture keeps the groups' colours of the builds before it, so only
    // the layout is compared).
    let fresh = countries("seed_fresh");
    edit_weight(&fresh, 1.1);
    edit_config(&fresh, "layout:\n", "layout:\n  seed: 2\n");
    build(&fresh);
    assert_eq!(
        out(&fresh, "countries.json"),
        out(&config, "countries.json")
    );
}

/// A docs repository commits its outputs and the state folder, not the
/// state folder's `cache/` (README, "What to commit"); a fresh clone's
/// `build --check` passes. The outputs went through a warm edit, so a cold
/// layout would not reproduce them.
#[test]
fn a_fresh_clone_passes_build_check() {
    let config = countries("clone_src");
    build(&config);
    edit_weight(&config, 1.1);
    build(&config);
    let src = config.parent().expect("folder");
    let clone = support::temp_dir("incremental_clone");
    copy_tree(src, &clone, &|p: &Path| p.ends_with("out/.nptreemap/cache"));
    assert!(clone.join("out/.nptreemap/countries.layout.json").is_file());
    assert!(!clone.join("out/.nptreemap/cache").exists());
    let check = |dir: &Path| {
        support::bin()
            .args(["build", "--check"])
            .arg(dir.join("nptreemap.yaml"))
            .output()
            .expect("run")
    };
    let o = check(&clone);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    // Without the manifests too, the stored layout reproduces the outputs.
    for f in std::fs::read_dir(clone.join("out/.nptreemap")).expect("state") {
        let p = f.expect("entry").path();
        if p.to_string_lossy().ends_with(".manifest.json") {
            std::fs::remove_file(p).expect("rm");
        }
    }
    let o = check(&clone);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

fn copy_tree(from: &Path, to: &Path, skip: &dyn Fn(&Path) -> bool) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let path = entry.expect("entry").path();
        if skip(&path) {
            continue;
        }
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_tree(&path, &target, skip);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}

/// Every file under `dir` with its bytes and modification time.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>, std::time::SystemTime)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read_dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let meta = std::fs::metadata(&p).expect("meta");
                out.push((
                    p.clone(),
                    std::fs::read(&p).expect("read"),
                    meta.modified().expect("mtime"),
                ));
            }
        }
    }
    out.sort();
    out
}

/// Two counts from the render note of `output` in a build's stage report:
/// the two numbers after `marker` (`bands: 3 painted, 30 kept`).
fn note_counts(build: &DatasetBuild, output: &str, marker: &str) -> (usize, usize) {
    let run = build
        .stages
        .runs
        .iter()
        .find(|r| r.stage == Stage::Render && r.output.as_deref() == Some(output))
        .expect("the output rendered");
    let counts = run.note.split(marker).nth(1).expect("counts");
    let numbers: Vec<usize> = counts
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .take(2)
        .map(|s| s.parse().expect("a count"))
        .collect();
    (numbers[0], numbers[1])
}

/// The PNG's bands: (painted, kept).
fn png_bands(build: &DatasetBuild) -> (usize, usize) {
    note_counts(build, "out/countries.png", "bands: ")
}

/// The labels: (fitted, reused).
fn label_counts(build: &DatasetBuild) -> (usize, usize) {
    note_counts(build, "out/countries.svg", "labels: ")
}

/// Issue 32, item 2: a one-shot build after a weight edit fits only the
/// labels of the cells that moved and repaints only the PNG's bands that
/// the edit changed, over the picture its file holds (the state folder
/// keeps the labels and what the file was painted from), and its outputs
/// are those of a build without any of it: the PNG is the whole paint of
/// the SVG written beside it, and a build of the same layout with the
/// caches deleted writes the same bytes. Records that do not match cost
/// only the reuse.
#[test]
fn a_build_after_an_edit_reuses_the_labels_and_the_png_it_finds() {
    let config = countries("png_bands");
    let first = build(&config);
    assert_eq!(png_bands(&first[0]).1, 0, "nothing to repaint over");
    let (fitted_first, _) = label_counts(&first[0]);
    // A name edit moves no cell: one label is fitted anew, the rest come
    // from the state folder, and only the bands around it are painted.
    let csv = config.with_file_name("countries.csv");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let name = text
        .lines()
        .nth(1)
        .expect("a row")
        .split(',')
        .nth(1)
        .expect("a name");
    std::fs::write(&csv, text.replacen(name, "Renamed", 1)).expect("write csv");
    let second = build(&config);
    let (painted, kept) = png_bands(&second[0]);
    assert!(
        painted > 0 && kept > 2 * painted,
        "{painted} painted, {kept} kept"
    );
    let (fitted, reused) = label_counts(&second[0]);
    assert!(
        fitted == 1 && reused > 0 && fitted_first > 10,
        "{fitted} fitted, {reused} reused (the first build fitted {fitted_first})"
    );
    // A weight edit moves the cells: the PNG still keeps what it can.
    edit_weight(&config, 1.1);
    let second = build(&config);
    let (painted, kept) = png_bands(&second[0]);
    assert!(painted > 0 && kept > 0, "{painted} painted, {kept} kept");
    let svg = String::from_utf8(out(&config, "countries.svg")).expect("utf-8");
    let whole = nptreemap::render::png(&svg, 1.0).expect("a whole paint");
    assert_eq!(
        out(&config, "countries.png"),
        whole,
        "a whole paint's bytes"
    );
    // The same layout drawn without the caches: the same bytes.
    let folder = config.with_file_name("out");
    let names = ["countries.svg", "countries.png", "countries.json"];
    let made: Vec<Vec<u8>> = names.iter().map(|n| out(&config, n)).collect();
    for cache in ["labels", "pictures"] {
        let file = folder.join(format!(".nptreemap/cache/countries.{cache}.bin"));
        std::fs::remove_file(file).expect("no cache");
    }
    for n in names {
        std::fs::remove_file(folder.join(n)).expect("no output");
    }
    let again = build(&config);
    assert_eq!(png_bands(&again[0]).1, 0, "{:?}", again[0].stages);
    for (n, bytes) in names.iter().zip(&made) {
        assert!(
            out(&config, n) == *bytes,
            "{n} differs drawn without the caches"
        );
    }
    // Records that are not this version's (or are cut short): a whole paint.
    let records = config
        .with_file_name("out")
        .join(".nptreemap/cache/countries.pictures.bin");
    let bytes = std::fs::read(&records).expect("the records");
    std::fs::write(&records, &bytes[..bytes.len() - 1]).expect("cut");
    edit_weight(&config, 1.1);
    let third = build(&config);
    assert_eq!(png_bands(&third[0]).1, 0, "nothing kept from cut records");
    let svg = String::from_utf8(out(&config, "countries.svg")).expect("utf-8");
    let whole = nptreemap::render::png(&svg, 1.0).expect("a whole paint");
    assert_eq!(out(&config, "countries.png"), whole);
    // A PNG file that is not the one recorded: a whole paint.
    edit_weight(&config, 1.1);
    let png = config.with_file_name("out").join("countries.png");
    let mut changed = std::fs::read(&png).expect("png");
    let last = changed.len() - 1;
    changed[last] ^= 0xff;
    std::fs::write(&png, changed).expect("write");
    let fourth = build(&config);
    assert_eq!(png_bands(&fourth[0]).1, 0, "nothing kept from another file");
}

/// The layout stage's note of a build.
fn layout_note(build: &DatasetBuild) -> String {
    build
        .stages
        .runs
        .iter()
        .find(|r| r.stage == Stage::Layout)
        .map(|r| r.note.clone())
        .expect("a layout stage")
}

/// Issue 32, item 2: the state folder keeps the stored layout's adjacency
/// per level beside it, so a later process that starts warm from it
/// compares only the pairs of the cells that moved (the layout's note says
/// `adjacency kept`), and writes the bytes of a build that finds no such
/// file; a file beside another stored layout is not used.
#[test]
fn a_build_after_an_edit_takes_over_the_stored_layouts_adjacency() {
    let kept = countries("levels_kept");
    let found = countries("levels_found");
    let levels = |config: &Path| {
        config
            .with_file_name("out")
            .join(".nptreemap/cache/countries.levels.bin")
    };
    for config in [&kept, &found] {
        build(config);
        assert!(levels(config).exists(), "kept beside the stored layout");
    }
    std::fs::remove_file(levels(&found)).expect("remove");
    for config in [&kept, &found] {
        edit_weight(config, 1.1);
    }
    let with = build(&kept);
    let without = build(&found);
    assert!(
        layout_note(&with[0]).contains("adjacency kept"),
        "{:?}",
        with[0].stages
    );
    assert!(
        !layout_note(&without[0]).contains("adjacency kept"),
        "{:?}",
        without[0].stages
    );
    assert_eq!(with[0].layout, LayoutStep::Warm);
    assert_eq!(without[0].layout, LayoutStep::Warm);
    for name in ["countries.svg", "countries.png", "countries.json"] {
        assert!(out(&kept, name) == out(&found, name), "{name} differs");
    }
    let stored = |config: &Path| {
        std::fs::read(
            config
                .with_file_name("out")
                .join(".nptreemap/countries.layout.json"),
        )
        .expect("stored layout")
    };
    assert!(stored(&kept) == stored(&found), "the stored layouts differ");
    // The file of the layout before beside a newer stored layout: not used.
    let old = std::fs::read(levels(&kept)).expect("levels");
    edit_weight(&kept, 1.1);
    build(&kept);
    std::fs::write(levels(&kept), old).expect("write");
    edit_weight(&kept, 1.1);
    let stale = build(&kept);
    assert!(
        !layout_note(&stale[0]).contains("adjacency kept"),
        "{:?}",
        stale[0].stages
    );
}

/// Issue 32: the watch daemon's commit writes the outputs first and the
/// state folder only when asked after the report: until then a build
/// finds the last state (here none: the next build lays out again and
/// writes the same outputs), after it the manifest vouches for the outputs
/// (the next build does nothing) and the stored layout is there.
#[test]
fn the_daemons_commit_writes_the_state_folder_after_the_outputs() {
    let config = countries("later");
    let c = Config::from_path(&config).expect("config");
    let job = support::first_job(&c, false);
    let state = config.with_file_name("out").join(".nptreemap");
    let manifest = state.join("countries.manifest.json");
    let stored = state.join("countries.layout.json");
    let mut graph = DatasetGraph::new(GraphOptions::from_env());
    let mut built = graph.build(&job).expect("build");
    let written = graph.commit_outputs(&job, &mut built);
    assert!(written.failed.is_empty(), "{:?}", written.failed);
    let svg = out(&config, "countries.svg");
    assert!(!manifest.exists() && !stored.exists(), "the state waits");
    // Another process now: it finds no state, builds again, the same bytes.
    let again = build(&config);
    assert_ne!(again[0].layout, LayoutStep::UpToDate);
    assert_eq!(out(&config, "countries.svg"), svg);
    std::fs::remove_dir_all(&state).expect("rm state");

    graph.finish_commit().expect("state written");
    assert!(manifest.is_file() && stored.is_file());
    assert!(graph.finish_commit().is_ok(), "nothing left: a no-op");
    let next = build(&config);
    assert_eq!(next[0].layout, LayoutStep::UpToDate, "the manifest vouches");
}
