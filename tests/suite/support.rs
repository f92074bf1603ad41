//! Shared helpers: paths to the binary and to the paper's data, running the
//! independent checker, generating random hierarchies with the peers' generator.
//! Everything they read is inside the repository (`tests/data/paper/`,
//! `tests/tools/`); `NPTREEMAP_SHARED_CHECKER=1` adds a cross-check against
//! `../shared/tools/check-layout` when that folder is beside the repository.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The paper's datasets, `tests/data/paper/` (see its MANIFEST.md).
pub(crate) fn paper_data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/paper")
}

/// Every JSON file of [`paper_data`], sorted by name.
pub(crate) fn paper_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(paper_data())
        .expect("tests/data/paper exists")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
}

/// The repository's test tools, `tests/tools/` (the checker, the generator).
fn tools() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/tools")
}

/// The `nptreemap` binary built for this test run.
pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_nptreemap"))
}

/// A fresh temporary directory under the target dir, unique per test name.
pub(crate) fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Copies `examples/<name>` into a fresh temp dir and returns the config path.
pub(crate) fn example(name: &str, tag: &str) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name);
    let dir = temp_dir(&format!("example_{tag}"));
    for entry in std::fs::read_dir(&src).expect("example dir") {
        let path = entry.expect("entry").path();
        if path.is_file() {
            std::fs::copy(&path, dir.join(path.file_name().expect("name"))).expect("copy");
        }
    }
    dir.join("nptreemap.yaml")
}

/// Runs `nptreemap build CONFIG` and asserts success.
pub(crate) fn build(config: &Path) -> Output {
    let out = bin()
        .arg("build")
        .arg(config)
        .output()
        .expect("run nptreemap");
    assert!(
        out.status.success(),
        "nptreemap build {} failed: {}",
        config.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `nptreemap layout INPUT --out ...` and asserts success.
pub(crate) fn layout(input: &Path, outs: &[&Path], extra: &[&str]) -> Output {
    let mut cmd = bin();
    cmd.arg("layout").arg(input);
    for o in outs {
        cmd.arg("--out").arg(o);
    }
    cmd.args(extra);
    let out = cmd.output().expect("run nptreemap");
    assert!(
        out.status.success(),
        "nptreemap layout {} failed: {}",
        input.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `tests/tools/check_layout.py` on a layout file and returns its report;
/// with `NPTREEMAP_SHARED_CHECKER=1`, also `../shared/tools/check-layout`, which
/// must agree on validity and on the realised counts.
pub(crate) fn check_layout(json: &Path) -> serde_json::Value {
    check_layout_with(json, &[])
}

/// [`check_layout`] with extra flags for `check_layout.py` (such as
/// `--min-weight-ratio`); the shared checker, which has none, runs plain.
pub(crate) fn check_layout_with(json: &Path, flags: &[&str]) -> serde_json::Value {
    let (passed, report) = run_checker(&tools().join("check_layout.py"), json, flags);
    assert!(
        passed && report["ok"] == true,
        "check_layout.py failed on {}: {report}",
        json.display()
    );
    if std::env::var_os("NPTREEMAP_SHARED_CHECKER").is_some_and(|v| v == "1") {
        let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/tools/check-layout");
        if shared.is_file() {
            let (_, theirs) = run_checker(&shared, json, &[]);
            for key in [
                "ok",
                "constraints_lowest",
                "realized_lowest",
                "constraints_by_depth",
            ] {
                assert_eq!(
                    report[key],
                    theirs[key],
                    "{key}: check_layout.py and shared/tools/check-layout disagree on {}",
                    json.display()
                );
            }
        } else {
            eprintln!(
                "NPTREEMAP_SHARED_CHECKER=1 but {} is missing: cross-check skipped",
                shared.display()
            );
        }
    }
    report
}

/// Runs one checker script on a layout file: whether it exited 0, and the JSON
/// it printed.
fn run_checker(script: &Path, json: &Path, flags: &[&str]) -> (bool, serde_json::Value) {
    let out = Command::new("python3")
        .arg(script)
        .arg(json)
        .args(flags)
        .output()
        .expect("run the layout checker (needs python3)");
    let report = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{} printed no JSON ({e}) on {}: {}",
            script.display(),
            json.display(),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out.status.success(), report)
}

/// Asserts the checker's per-diagram area error is within d3's default target.
pub(crate) fn assert_area_error(report: &serde_json::Value, limit: f64) {
    let err = report["area_error_diagram_mean"]
        .as_f64()
        .expect("area_error_diagram_mean is a number");
    assert!(err <= limit, "area_error_diagram_mean {err} > {limit}");
}

/// Writes a random hierarchy with `tests/tools/gen.py` and returns its path.
pub(crate) fn generate(dir: &Path, leaves: usize, depth: usize, seed: u64) -> PathBuf {
    let path = dir.join(format!("h{leaves}_d{depth}_s{seed}.json"));
    let status = Command::new("python3")
        .arg(tools().join("gen.py"))
        .args(["--n", &leaves.to_string()])
        .args(["--depth", &depth.to_string()])
        .args(["--seed", &seed.to_string()])
        .arg("--out")
        .arg(&path)
        .output()
        .expect("run gen.py (needs python3)");
    assert!(status.status.success(), "gen.py failed");
    path
}

/// The shortest bound a test waits for an event (a command's end, a status
/// line) before it fails: the suite runs on loaded machines (a debug build
/// at load 8 takes many times its usual time), so a bound only tells a hang
/// from slowness when it is generous; tests never assert how fast
/// something happened.
pub(crate) const WAIT: std::time::Duration = std::time::Duration::from_secs(120);

/// Runs `cmd` to completion, or kills it and fails the test after `secs`
/// seconds, or [`WAIT`] when that is longer: a command that hangs (a FIFO
/// read, a runaway layout) must not hang the suite, and one that is only
/// slow on a busy machine must not fail it.
pub(crate) fn output_within(cmd: &mut Command, secs: u64) -> Output {
    use std::io::Read;
    let mut child = cmd
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    // Drain the pipes on threads so a chatty child cannot block on a full pipe.
    let mut out_pipe = child.stdout.take().expect("stdout");
    let mut err_pipe = child.stderr.take().expect("stderr");
    let out_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out_pipe.read_to_end(&mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = err_pipe.read_to_end(&mut v);
        v
    });
    let bound = std::time::Duration::from_secs(secs).max(WAIT);
    let deadline = std::time::Instant::now() + bound;
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} did not finish within {bound:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    Output {
        status,
        stdout: out_reader.join().expect("stdout reader"),
        stderr: err_reader.join().expect("stderr reader"),
    }
}

/// Makes a FIFO at `path` (through python3, which the suite needs anyway;
/// std has no mkfifo).
pub(crate) fn mkfifo(path: &Path) {
    let status = Command::new("python3")
        .args(["-c", "import os, sys; os.mkfifo(sys.argv[1])"])
        .arg(path)
        .status()
        .expect("run python3");
    assert!(status.success(), "mkfifo {}", path.display());
}

/// The build job of `config`'s first dataset, as the binary makes it.
pub(crate) fn first_job(
    config: &nptreemap::config::Config,
    cold: bool,
) -> nptreemap::graph::Job<'_> {
    let d = &config.datasets[0];
    nptreemap::graph::Job {
        dataset: d,
        request: config.request(d),
        style: config.style(d),
        cold,
    }
}
