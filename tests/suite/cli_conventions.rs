//! The conventions of a Rust CLI: `init` on the examples' tables with their
//! configs deleted (the written config builds), `build --check` (exit 0 when
//! every output is current, 1 naming the stale ones, nothing written),
//! `completions`, the man page, `-q`, and the config found upward.

use std::path::Path;
use std::process::Output;

use crate::support;

fn run_in(dir: &Path, args: &[&str]) -> Output {
    support::bin()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run nptreemap")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The example's tables in a fresh folder, its config deleted.
fn tables(example: &str, tag: &str) -> std::path::PathBuf {
    let config = support::example(example, tag);
    std::fs::remove_file(&config).expect("delete the config");
    config.parent().expect("dir").to_path_buf()
}

#[test]
fn init_writes_a_config_that_builds_for_three_examples() {
    for (example, files, format, fields) in [
        (
            "countries",
            &["countries.csv", "borders.csv"][..],
            "border-list",
            &[
                "id: iso",
                "label: name",
                "weight: population",
                "groups: [continent]",
            ][..],
        ),
        (
            "foods",
            &["foods.csv", "vectors.tsv"][..],
            "embedding-matrix",
            &["id: id", "label: label", "weight: kcal", "groups: [group]"][..],
        ),
        (
            "stocks",
            &["prices.csv", "stocks.csv"][..],
            "time-series",
            &[
                "id: id",
                "label: name",
                "weight: market_cap",
                "groups: [sector]",
            ][..],
        ),
        (
            "movies",
            &["films.csv"][..],
            "genre-table",
            &[
                "label: title",
                "weight: runtime",
                "groups: [director]",
                "genres: genres",
            ][..],
        ),
    ] {
        let dir = tables(example, &format!("init_{example}"));
        let mut args = vec!["init"];
        args.extend_from_slice(files);
        ok(&run_in(&dir, &args));
        let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
        assert!(
            yaml.contains(&format!("format: {format}")),
            "{example}:\n{yaml}"
        );
        for field in fields {
            assert!(yaml.contains(field), "{example}: no {field:?} in\n{yaml}");
        }
        // It builds at once, from the folder (the config found there).
        let built = ok(&run_in(&dir, &["build"]));
        assert!(built.contains("wrote"), "{built}");
        let name = Path::new(
            files
                .iter()
                .find(|f| {
                    !f.starts_with("prices")
                        && !f.starts_with("borders")
                        && !f.starts_with("vectors")
                })
                .expect("nodes"),
        )
        .file_stem()
        .expect("stem")
        .to_string_lossy()
        .into_owned();
        assert!(dir.join(format!("out/{name}.svg")).is_file(), "{example}");
        assert!(dir.join(format!("out/{name}.html")).is_file(), "{example}");
        // A second init does not overwrite without --force.
        let again = run_in(&dir, &args);
        assert_eq!(again.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    }
}

#[test]
fn init_without_any_similarity_says_what_to_add() {
    let dir = support::temp_dir("init_plain");
    std::fs::write(dir.join("t.csv"), "id,size\na,1\nb,2\n").expect("write");
    let out = run_in(&dir, &["init", "t.csv"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("t.csv: found no similarity"), "{stderr}");
    assert!(!dir.join("nptreemap.yaml").exists());
}

#[test]
fn build_check_exits_1_naming_stale_outputs_and_writes_nothing() {
    let config = support::example("countries", "check");
    let dir = config.parent().expect("dir").to_path_buf();
    // Nothing built yet: every output is stale, and none is written.
    let out = run_in(&dir, &["build", "--check"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("out of date"), "{stderr}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("stale "));
    assert!(!dir.join("out").exists(), "--check wrote outputs");
    ok(&run_in(&dir, &["build"]));
    let fresh = ok(&run_in(&dir, &["build", "--check"]));
    assert!(fresh.contains("outputs up to date"), "{fresh}");
    // One output edited by hand: exactly it is named.
    let svg = dir.join("out/countries.svg");
    std::fs::write(&svg, "<svg/>").expect("edit");
    let out = run_in(&dir, &["build", "--check"]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.matches("stale ").count(), 1, "{stdout}");
    assert!(stdout.contains("countries.svg"), "{stdout}");
    assert_eq!(std::fs::read(&svg).expect("read"), b"<svg/>");
}

#[test]
fn quiet_drops_status_lines_and_the_config_is_found_upward() {
    let config = support::example("countries", "quiet");
    let sub = config.parent().expect("dir").join("docs/deep");
    std::fs::create_dir_all(&sub).expect("dirs");
    let out = run_in(&sub, &["build", "-q"]);
    assert_eq!(ok(&out), "");
    assert!(config
        .parent()
        .expect("dir")
        .join("out/countries.svg")
        .is_file());
    let none = run_in(Path::new("/"), &["check"]);
    assert_eq!(none.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&none.stderr).contains("no nptreemap.yaml in /"));
}

#[test]
fn completions_and_man_page_describe_the_commands() {
    let dir = support::temp_dir("completions");
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let script = ok(&run_in(&dir, &["completions", shell]));
        for sub in ["build", "watch", "init", "layout"] {
            assert!(script.contains(sub), "{shell}: no {sub}");
        }
    }
    let bash = ok(&run_in(&dir, &["completions", "bash"]));
    assert!(bash.contains("complete -F _nptreemap"), "{bash}");
    let man = ok(&run_in(&dir, &["man"]));
    assert!(
        man.starts_with(".ie") || man.contains(".TH nptreemap"),
        "{man}"
    );
    assert!(
        man.contains(".SH NAME") && man.contains(".SH SUBCOMMANDS"),
        "{man}"
    );
    let bad = run_in(&dir, &["completions", "tcsh"]);
    assert_eq!(bad.status.code(), Some(2));
}

/// `script(1)` runs `command` on a pseudo-terminal (so stderr is a
/// terminal); its stdout carries everything the command printed.
fn on_a_terminal(command: &str) -> std::process::Command {
    let mut c = std::process::Command::new("script");
    c.args(["-qec", command, "/dev/null"]);
    c
}

/// [`on_a_terminal`], with the bar shown from the first tick rather than after
/// a second (`NPTREEMAP_PROGRESS_AFTER_MS=0`): whether a layout lasts a second
/// depends on the machine, and the bar's presence should not.
fn on_a_terminal_now(command: &str) -> std::process::Command {
    let mut c = on_a_terminal(command);
    c.env("NPTREEMAP_PROGRESS_AFTER_MS", "0");
    c
}

/// A neighbourhood layout of several hundred ticks (800 leaves with 16-d
/// embeddings, one level): about a second in the test profile.
fn slow_input(dir: &Path) -> std::path::PathBuf {
    let input = dir.join("flat800.json");
    let gen = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/gen_similar.py");
    let out = std::process::Command::new("python3")
        .arg(gen)
        .args([
            "--n", "800", "--depth", "1", "--dim", "16", "--seed", "1", "--out",
        ])
        .arg(&input)
        .output()
        .expect("run gen_similar.py (needs python3)");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    input
}

#[test]
fn a_progress_bar_shows_on_a_terminal_only() {
    let dir = support::temp_dir("progress_bar");
    let input = slow_input(&dir);
    let bin = env!("CARGO_BIN_EXE_nptreemap");
    // Not a terminal: no bar, even when asked for one from the first tick.
    let out = std::process::Command::new(bin)
        .arg("layout")
        .arg(&input)
        .arg("--out")
        .arg(dir.join("a.json"))
        .env("NPTREEMAP_PROGRESS_AFTER_MS", "0")
        .output()
        .expect("run nptreemap layout");
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("level 1/1"),
        "a bar without a terminal: {stderr}"
    );
    // A terminal: the bar names the level; with -q, no bar.
    let on_tty = |flags: &str, out: &str| {
        let cmd = format!(
            "{bin} layout {flags} {} --out {}",
            input.display(),
            dir.join(out).display()
        );
        let run = on_a_terminal_now(&cmd).output().expect("run script(1)");
        let text = String::from_utf8_lossy(&run.stdout).into_owned();
        assert!(run.status.success(), "{cmd}: {text}");
        text
    };
    let shown = on_tty("", "b.json");
    assert!(
        shown.contains("level 1/1"),
        "no bar on a terminal: {shown:?}"
    );
    let quiet = on_tty("-q", "c.json");
    assert!(!quiet.contains("level 1/1"), "a bar with -q: {quiet:?}");
}

#[test]
fn the_first_build_of_watch_shows_a_progress_bar_on_a_terminal() {
    use std::io::Read;
    let dir = support::temp_dir("progress_watch");
    let input = slow_input(&dir);
    let config = dir.join("nptreemap.yaml");
    std::fs::write(
        &config,
        format!(
            "datasets:\n  - name: flat\n    format: hierarchy-json\n    files: {{hierarchy: {}}}\n    outputs:\n      - path: out/flat.json\n",
            input.file_name().and_then(|n| n.to_str()).expect("name")
        ),
    )
    .expect("write config");
    let bin = env!("CARGO_BIN_EXE_nptreemap");
    // `timeout` ends the daemon (SIGTERM: exit 0) once the first build is done.
    let mut child = on_a_terminal_now(&format!(
        "timeout -s TERM 300 {bin} watch --cold {}",
        config.display()
    ))
    .stdout(std::process::Stdio::piped())
    .spawn()
    .expect("run script(1)");
    let mut stdout = child.stdout.take().expect("stdout");
    let mut seen = String::new();
    let mut buf = [0u8; 4096];
    // Read until the first build's status line, then stop the daemon.
    while !seen.contains("flat: start") {
        match stdout.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => seen.push_str(&String::from_utf8_lossy(&buf[..n])),
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(seen.contains("flat: start"), "no status line: {seen:?}");
    let before = &seen[..seen.find("flat: start").expect("status line")];
    assert!(
        before.contains("level 1/1"),
        "no bar before the first status line: {seen:?}"
    );
}
