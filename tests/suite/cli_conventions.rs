//! The conventions of a Rust CLI: `init` on the examples' tables with their
//! configs deleted (the written config builds), `build --check` (exit 0 when
//! every output is current, 1 naming the stale ones, nothing written),
//! `completions` (enum flags complete their values), the man pages (one per
//! subcommand; EXIT STATUS, ENVIRONMENT, FILES), `config --defaults`, `-q`,
//! log lines without colour codes off a terminal, and the config found upward.

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

/// Asserts success; returns stdout.
pub(crate) fn ok(out: &Output) -> String {
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
                "groups:",
                "- continent",
            ][..],
        ),
        (
            "foods",
            &["foods.csv", "vectors.tsv"][..],
            "embedding-matrix",
            &[
                "id: id",
                "label: label",
                "weight: kcal",
                "groups:",
                "- group",
            ][..],
        ),
        (
            "stocks",
            &["prices.csv", "stocks.csv"][..],
            "time-series",
            &[
                "id: id",
                "label: name",
                "weight: market_cap",
                "groups:",
                "- sector",
            ][..],
        ),
        (
            "movies",
            &["films.csv"][..],
            "genre-table",
            &[
                "label: title",
                "weight: runtime",
                "groups:",
                "- director",
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

/// The names of the `.SH` sections of a man page.
fn sections(man: &str) -> Vec<String> {
    man.lines()
        .filter_map(|l| l.strip_prefix(".SH "))
        .map(|s| s.trim().trim_matches('"').to_string())
        .collect()
}

/// The text of section `name` of a man page, with roff's `\-` read as `-`
/// and its font changes (`\fB`, `\fI`, `\fR`) left out.
fn section(man: &str, name: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for line in man.lines() {
        if let Some(s) = line.strip_prefix(".SH ") {
            inside = s.trim().trim_matches('"') == name;
            continue;
        }
        if inside {
            let plain = ["\\fB", "\\fI", "\\fR"]
                .iter()
                .fold(line.replace("\\-", "-"), |l, font| l.replace(font, ""));
            out.push_str(&plain);
            out.push('\n');
        }
    }
    out
}

/// Every environment variable the binary's code reads (`env::var("NAME")` or
/// `env::var_os("NAME")` in `src/`).
fn variables_read() -> std::collections::BTreeSet<String> {
    fn walk(dir: &Path, out: &mut std::collections::BTreeSet<String>) {
        for entry in std::fs::read_dir(dir).expect("read src") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).expect("read");
                for marker in ["env::var(\"", "env::var_os(\""] {
                    for (at, _) in text.match_indices(marker) {
                        let rest = &text[at + marker.len()..];
                        let name = &rest[..rest.find('"').expect("closing quote")];
                        out.insert(name.to_string());
                    }
                }
            }
        }
    }
    let mut out = std::collections::BTreeSet::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut out);
    out
}

#[test]
fn the_man_page_documents_exit_status_environment_and_files() {
    let dir = support::temp_dir("man_sections");
    let man = ok(&run_in(&dir, &["man"]));
    let names = sections(&man);
    for wanted in ["EXIT STATUS", "ENVIRONMENT", "FILES"] {
        assert!(
            names.iter().any(|n| n == wanted),
            "no {wanted} in {names:?}"
        );
    }
    let exit = section(&man, "EXIT STATUS");
    for code in ["0", "1", "2"] {
        assert!(
            exit.lines().any(|l| l.trim() == code),
            "exit code {code} not described:\n{exit}"
        );
    }
    let environment = section(&man, "ENVIRONMENT");
    let mut wanted = variables_read();
    assert!(wanted.contains("NPTREEMAP_PROGRESS_AFTER_MS"), "{wanted:?}");
    wanted.extend(["RUST_LOG".to_string(), "NO_COLOR".to_string()]);
    for name in &wanted {
        assert!(
            environment.contains(name.as_str()),
            "{name} missing:\n{environment}"
        );
    }
    let files = section(&man, "FILES");
    for name in ["nptreemap.yaml", ".nptreemap/", "state_dir"] {
        assert!(files.contains(name), "{name} missing:\n{files}");
    }
}

#[test]
fn every_man_page_the_main_page_lists_can_be_generated() {
    let dir = support::temp_dir("man_pages");
    let man = ok(&run_in(&dir, &["man"]));
    let text = man.replace("\\-", "-");
    let listed: Vec<&str> = text
        .match_indices("nptreemap-")
        .filter_map(|(at, _)| {
            let rest = &text[at + "nptreemap-".len()..];
            let end = rest.find("(1)")?;
            let name = &rest[..end];
            name.chars().all(|c| c.is_ascii_lowercase()).then_some(name)
        })
        .collect();
    assert!(
        listed.contains(&"build") && listed.contains(&"init"),
        "{listed:?}"
    );
    for sub in listed {
        let page = ok(&run_in(&dir, &["man", sub]));
        assert!(
            page.contains(&format!(".TH nptreemap-{sub} 1")),
            "nptreemap man {sub}:\n{page}"
        );
        assert!(sections(&page).iter().any(|s| s == "SYNOPSIS"), "{page}");
        // An option that takes a value shows it in the synopsis.
        let synopsis = page
            .split(".SH SYNOPSIS")
            .nth(1)
            .and_then(|rest| rest.split(".SH").next())
            .expect("synopsis");
        if synopsis.contains("\\-\\-config\\fR") {
            assert!(
                synopsis.contains("\\-\\-config\\fR \\fI<FILE>\\fR"),
                "nptreemap man {sub}: {synopsis}"
            );
        }
        if synopsis.contains("\\-\\-jobs") {
            assert!(synopsis.contains("\\fI<N>\\fR"), "{synopsis}");
        }
    }
    let build = ok(&run_in(&dir, &["man", "build"]));
    assert!(build.contains("\\fI<FILE>\\fR"), "{build}");
    let unknown = run_in(&dir, &["man", "biuld"]);
    assert_eq!(unknown.status.code(), Some(2));
}

#[test]
fn completions_offer_the_values_of_enum_flags() {
    let dir = support::temp_dir("completions_values");
    let bash = ok(&run_in(&dir, &["completions", "bash"]));
    // In bash, a flag's case line is followed by what it completes: a word
    // list (compgen -W) for values, file names (compgen -f) otherwise.
    let completes = |flag: &str| -> Vec<String> {
        let lines: Vec<&str> = bash.lines().collect();
        lines
            .iter()
            .enumerate()
            .filter(|(_, l)| l.trim() == format!("{flag})"))
            .map(|(i, _)| lines[i + 1].trim().to_string())
            .collect()
    };
    for (flag, values) in [
        ("--outline", "rect circle ngon"),
        ("--similarity", "cosine"),
        ("--method", "neighbor"),
    ] {
        let found = completes(flag);
        assert!(!found.is_empty(), "{flag} not in the bash script");
        for line in &found {
            assert!(
                line.contains("compgen -W") && line.contains(values),
                "{flag} completes {line:?}"
            );
        }
    }
    // `man`'s SUBCOMMAND: the subcommands' names.
    let man = bash
        .split("nptreemap__subcmd__man)")
        .nth(1)
        .and_then(|rest| rest.lines().find(|l| l.trim().starts_with("opts=")))
        .expect("man's opts line");
    assert!(man.contains("build watch init"), "{man}");
    // eval's --method also takes `all`.
    assert!(
        completes("--method").iter().any(|l| l.contains(" all")),
        "{:?}",
        completes("--method")
    );
}

#[test]
fn config_defaults_prints_the_documented_defaults() {
    let dir = support::temp_dir("config_defaults");
    let printed = ok(&run_in(&dir, &["config", "--defaults"]));
    // `nptreemap config` alone is no error: it prints the same.
    assert_eq!(ok(&run_in(&dir, &["config"])), printed);
    let file =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/default.yaml"))
            .expect("config/default.yaml");
    assert_eq!(printed, file);
    for key in ["path_separator:", "root_label:"] {
        assert!(
            file.lines()
                .any(|l| l.trim_start_matches(['#', ' ']).starts_with(key)),
            "{key} is not documented in config/default.yaml"
        );
    }
    // init points to it, not to a file a `cargo install` user does not have.
    std::fs::write(dir.join("t.csv"), "id,size,tags\na,1,x|y\nb,2,y|z\nc,3,x\n").expect("t");
    ok(&run_in(&dir, &["init", "t.csv"]));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    assert!(yaml.contains("nptreemap config --defaults"), "{yaml}");
    assert!(!yaml.contains("config/default.yaml"), "{yaml}");
}

/// Lays out Flare with one iteration per diagram: a WARN log line.
fn warning_layout(dir: &Path) -> String {
    format!(
        "{} layout {} --method plain --max-iterations 1 --out {}",
        env!("CARGO_BIN_EXE_nptreemap"),
        support::paper_data().join("flare.json").display(),
        dir.join("x.json").display()
    )
}

#[test]
fn log_lines_carry_colour_only_on_a_terminal_without_no_color() {
    let dir = support::temp_dir("log_colour");
    let command = warning_layout(&dir);
    let warn_line = |text: &str| -> String {
        text.lines()
            .find(|l| l.contains("WARN"))
            .unwrap_or_else(|| panic!("no WARN line in {text:?}"))
            .to_string()
    };
    // stderr to a pipe: plain text.
    let piped = std::process::Command::new("sh")
        .args(["-c", &command])
        .env_remove("NO_COLOR")
        .output()
        .expect("run");
    assert!(piped.status.success());
    let line = warn_line(&String::from_utf8_lossy(&piped.stderr));
    assert!(!line.contains('\u{1b}'), "colour codes in a pipe: {line:?}");
    // A terminal: colour, unless NO_COLOR is set (to anything non-empty).
    let on_tty = |no_color: Option<&str>| {
        let mut c = on_a_terminal(&command);
        c.env_remove("NO_COLOR");
        if let Some(v) = no_color {
            c.env("NO_COLOR", v);
        }
        let out = c.output().expect("run script(1)");
        warn_line(&String::from_utf8_lossy(&out.stdout))
    };
    assert!(on_tty(None).contains('\u{1b}'), "no colour on a terminal");
    let plain = on_tty(Some("1"));
    assert!(
        !plain.contains('\u{1b}'),
        "colour despite NO_COLOR: {plain:?}"
    );
}

#[test]
fn verbose_lines_name_the_dataset_the_stage_and_the_output() {
    let config = support::example("countries", "verbose_lines");
    let dir = config.parent().expect("folder").to_path_buf();
    // A first build writes, a second one reuses: both name every output.
    for _ in 0..2 {
        let out = run_in(&dir, &["build", "-v", "nptreemap.yaml"]);
        ok(&out);
        let log = String::from_utf8_lossy(&out.stderr);
        assert!(!log.contains("nptreemap::"), "a module path: {log}");
        for stage in ["render", "write"] {
            for output in [
                "out/countries.svg",
                "out/countries.png",
                "out/countries.json",
            ] {
                let lines = log
                    .lines()
                    .filter(|l| l.contains(&format!("countries: {stage} {output} ")))
                    .count();
                assert_eq!(lines, 1, "{stage} {output}:\n{log}");
            }
            let unnamed = log
                .lines()
                .filter(|l| l.contains(&format!("countries: {stage} ")))
                .filter(|l| !l.contains(&format!("countries: {stage} out/")))
                .count();
            assert_eq!(unnamed, 0, "{log}");
        }
    }
}
