//! The runtime format plugin, `format: exec`, through the binary: the shipped
//! example adapter builds (its stdout parsed as hierarchy JSON, its declared
//! file passed as an argument) from any folder, and a failing adapter is the
//! user's error naming the dataset and the whole command line, quoting its
//! stderr, writing nothing. Adapters run in a box of time and size (issue 21):
//! a timeout that covers their whole process group, nothing of the group left
//! running after a timeout or a stop signal, and output read up to a cap in
//! bounded memory.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::support;
use crate::watch::Daemon;

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
    std::fs::write(dir.join("my data.txt"), "x\n").expect("data");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        "datasets:\n  - name: mine\n    format: exec\n    command: [sh, -c, 'echo \"row 7 is bad\" >&2; exit 4', adapter]\n    files: {data: my data.txt}\n    outputs: [{path: out/a.svg}]\n",
    )
    .expect("config");
    let out = build(&dir.join("nptreemap.yaml"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("failed (exit status: 4)"), "{stderr}");
    assert!(stderr.contains("row 7 is bad"), "{stderr}");
    assert!(!dir.join("out").exists(), "nothing is written");
    // The whole command line, as a user can paste it into a shell in the
    // config's folder: a shell (here Python's POSIX shlex) splits it into
    // the command and its file.
    let shown = stderr
        .split_once("dataset \"mine\": `")
        .and_then(|(_, rest)| rest.split_once('`'))
        .map(|(line, _)| line)
        .unwrap_or_else(|| panic!("no command line in {stderr}"));
    let words = std::process::Command::new("python3")
        .args([
            "-c",
            "import json, shlex, sys; print(json.dumps(shlex.split(sys.argv[1])))",
        ])
        .arg(shown)
        .output()
        .expect("python3");
    let words: Vec<String> = serde_json::from_slice(&words.stdout).expect("words");
    assert_eq!(
        words,
        [
            "sh",
            "-c",
            "echo \"row 7 is bad\" >&2; exit 4",
            "adapter",
            "my data.txt"
        ],
        "{shown}"
    );
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
    ] {
        let config = dir.join("nptreemap.yaml");
        std::fs::write(&config, format!("datasets:\n  - name: d\n    {dataset}\n")).expect("write");
        let out = build(&config);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{dataset}: {stderr}");
    }
}

/// A hierarchy an adapter may print.
const TREE: &str =
    r#"{"name": "r", "children": [{"name": "a", "value": 1}, {"name": "b", "value": 2}]}"#;

/// A folder with `adapter.sh` (the `script`) and a config running it through
/// `sh` with the given extra dataset keys and top-level text.
fn adapter_dir(name: &str, script: &str, keys: &str, top: &str) -> (PathBuf, PathBuf) {
    let dir = support::temp_dir(name);
    std::fs::write(dir.join("adapter.sh"), script).expect("script");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(
        &config,
        format!(
            "{top}datasets:\n  - name: mine\n    format: exec\n    command: [sh, adapter.sh]\n    files: {{}}\n{keys}    outputs: [out/a.svg]\n"
        ),
    )
    .expect("config");
    (dir, config)
}

/// The pid a script wrote to `file`, waiting (at most a minute) for it.
fn pid_in(file: &Path) -> i32 {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(pid) = std::fs::read_to_string(file)
            .ok()
            .and_then(|t| t.trim().parse().ok())
        {
            return pid;
        }
        assert!(
            Instant::now() < deadline,
            "{} never written",
            file.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Whether `pid` is a live process (a zombie is as good as gone).
fn running(pid: i32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        !stat
            .rsplit(')')
            .next()
            .unwrap_or("")
            .trim_start()
            .starts_with('Z')
    })
}

/// Kills what a test's adapter left running (only when the test failed: a
/// failing test must not leave `sleep`s behind): the pids it wrote to
/// `adapter.pid` and `bg.pid` in its folder.
struct Reap(PathBuf);

impl Drop for Reap {
    fn drop(&mut self) {
        for file in ["adapter.pid", "bg.pid"] {
            let pid = std::fs::read_to_string(self.0.join(file))
                .ok()
                .and_then(|t| t.trim().parse().ok());
            if let Some(pid) = pid.filter(|&p| running(p)) {
                unsafe { libc::kill(pid, libc::SIGKILL) };
            }
        }
    }
}

/// Asserts that every one of `pids` is gone, waiting for the kernel to
/// finish the kills (at most 20 s).
fn assert_gone(pids: &[i32], what: &str) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while pids.iter().any(|&p| running(p)) && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    let left: Vec<i32> = pids.iter().copied().filter(|&p| running(p)).collect();
    assert!(
        left.is_empty(),
        "{what}: processes {left:?} of the adapter still run"
    );
}

#[test]
fn an_out_of_range_timeout_is_a_config_error_naming_file_line_and_range() {
    for value in ["1e20", "-1", ".nan", ".inf", "0", "86401"] {
        let (_dir, config) = adapter_dir(
            "exec_timeout_range",
            &format!("echo '{TREE}'\n"),
            &format!("    timeout: {value}\n"),
            "",
        );
        for command in ["build", "check"] {
            let out = support::output_within(support::bin().arg(command).arg(&config), 60);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{command} {value}: {stderr}");
            // The timeout is on line 6 of the config.
            for part in [&config.display().to_string(), "line 6", "timeout", "86400"] {
                assert!(
                    stderr.contains(part),
                    "{command} {value}: no {part:?} in {stderr}"
                );
            }
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
    }
}

/// Sends `signal` to `watch` and waits (at most 30 s) for it to end.
fn stop(watch: &mut Daemon, signal: libc::c_int) -> std::process::ExitStatus {
    unsafe { libc::kill(watch.child.id() as libc::pid_t, signal) };
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(status) = watch.child.try_wait().expect("wait") {
            return status;
        }
        assert!(
            Instant::now() < deadline,
            "watch still runs 30 s after a stop signal"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn watch_reports_an_out_of_range_timeout_as_a_status_line_and_goes_on() {
    let (dir, config) = adapter_dir(
        "exec_watch_timeout",
        // The tree follows the data, so an edit of it changes the output.
        "printf '{\"name\": \"r\", \"children\": [{\"name\": \"a\", \"value\": %s}, {\"name\": \"b\", \"value\": 2}]}' \"$(cat data.txt)\"\n",
        "    timeout: 30\n",
        "",
    );
    let text = std::fs::read_to_string(&config)
        .expect("config")
        .replace("files: {}", "files: {data: data.txt}");
    std::fs::write(&config, &text).expect("config");
    std::fs::write(dir.join("data.txt"), "1\n").expect("data");
    let mut watch = Daemon::start(&config);
    watch.expect(&["mine: start", "wrote a.svg"]);
    std::fs::write(&config, text.replace("timeout: 30", "timeout: 1e20")).expect("edit");
    watch.expect(&[
        "config",
        "line 6",
        "timeout",
        "86400",
        "previous config kept",
    ]);
    // Still running, and still building with the previous config.
    std::fs::write(dir.join("data.txt"), "2\n").expect("data edit");
    watch.expect(&["mine: data", "a.svg"]);
    assert_eq!(stop(&mut watch, libc::SIGTERM).code(), Some(0));
}

#[test]
fn a_background_child_holding_stdout_neither_delays_nor_outlives_the_build() {
    // The adapter prints its tree and exits, leaving a child that holds its
    // stdout for two minutes.
    let (dir, config) = adapter_dir(
        "exec_background_child",
        &format!("sleep 120 &\necho $! > bg.pid\necho '{TREE}'\n"),
        "    timeout: 100\n",
        "",
    );
    let _reap = Reap(dir.clone());
    // Generous: the build itself takes a fraction of a second, the child 120 s.
    let out = support::output_within(support::bin().arg("build").arg(&config), 60);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(dir.join("out/a.svg").is_file());
    assert_gone(&[pid_in(&dir.join("bg.pid"))], "after the adapter exited");
}

#[test]
fn a_timeout_stops_the_adapters_whole_group() {
    let (dir, config) = adapter_dir(
        "exec_timeout_group",
        "sleep 120 &\necho $! > bg.pid\necho $$ > adapter.pid\nsleep 120\n",
        "    timeout: 1\n",
        "",
    );
    let _reap = Reap(dir.clone());
    let out = support::output_within(support::bin().arg("build").arg(&config), 60);
    let pids = [
        pid_in(&dir.join("adapter.pid")),
        pid_in(&dir.join("bg.pid")),
    ];
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("dataset \"mine\""), "{stderr}");
    assert!(stderr.contains("did not finish within 1 s"), "{stderr}");
    assert!(!dir.join("out").exists(), "nothing is written");
    assert_gone(&pids, "after the timeout");
}

/// Runs `config`'s build under python3, which prints the largest resident
/// set of its children (nptreemap and what it ran) in KiB on its last line.
fn build_measuring_memory(config: &Path) -> (std::process::Output, u64) {
    let out = support::output_within(
        std::process::Command::new("python3")
            .args([
                "-c",
                "import resource, subprocess, sys\n\
                 r = subprocess.run(sys.argv[1:])\n\
                 print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n\
                 sys.exit(r.returncode)",
                env!("CARGO_BIN_EXE_nptreemap"),
                "build",
            ])
            .arg(config),
        120,
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let kib = stdout
        .lines()
        .last()
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or_else(|| panic!("no peak memory in {stdout:?}"));
    (out, kib)
}

#[test]
fn output_beyond_the_cap_is_refused_in_bounded_memory() {
    for (name, command, limits) in [
        // Endless output.
        ("exec_cap_yes", "yes", "limits: {max_adapter_mb: 8}\n"),
        // 300 MB of it; the cap follows max_file_mb unless set.
        (
            "exec_cap_zeros",
            "head -c 300000000 /dev/zero",
            "limits: {max_file_mb: 8}\n",
        ),
    ] {
        let (dir, config) = adapter_dir(name, &format!("{command}\n"), "    timeout: 10\n", limits);
        let (out, kib) = build_measuring_memory(&config);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        for part in [
            "dataset \"mine\"",
            "sh adapter.sh",
            "8 MiB",
            "limits.max_adapter_mb",
        ] {
            assert!(stderr.contains(part), "{name}: no {part:?} in {stderr}");
        }
        assert!(kib < 200 * 1024, "{name}: {kib} KiB at the peak");
        assert!(!dir.join("out").exists(), "nothing is written");
    }
}

/// The adapter of the stop-signal tests: it writes its pid and its child's,
/// then waits for the child (two minutes).
const LINGERING: &str = "echo $$ > adapter.pid\nsleep 120 &\necho $! > bg.pid\nwait\n";

#[test]
fn a_stop_signal_to_build_stops_the_adapters_group() {
    for (name, signal) in [
        ("exec_sigterm_build", libc::SIGTERM),
        ("exec_sigint_build", libc::SIGINT),
    ] {
        let (dir, config) = adapter_dir(name, LINGERING, "    timeout: 100\n", "");
        let mut build = support::bin()
            .arg("build")
            .arg(&config)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start build");
        let _reap = Reap(dir.clone());
        let pids = [
            pid_in(&dir.join("adapter.pid")),
            pid_in(&dir.join("bg.pid")),
        ];
        unsafe { libc::kill(build.id() as libc::pid_t, signal) };
        let deadline = Instant::now() + Duration::from_secs(30);
        while build.try_wait().expect("wait").is_none() {
            if Instant::now() > deadline {
                let _ = build.kill();
                panic!("{name}: build still runs 30 s after the signal");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        assert_gone(&pids, name);
    }
}

#[test]
fn a_stop_signal_to_watch_stops_the_adapters_group() {
    let (dir, config) = adapter_dir("exec_sigterm_watch", LINGERING, "    timeout: 100\n", "");
    let mut watch = Daemon::start(&config);
    let _reap = Reap(dir.clone());
    let pids = [
        pid_in(&dir.join("adapter.pid")),
        pid_in(&dir.join("bg.pid")),
    ];
    assert_eq!(stop(&mut watch, libc::SIGTERM).code(), Some(0));
    assert_gone(&pids, "after watch's SIGTERM");
}

#[test]
fn the_example_builds_from_another_folder() {
    let config = support::example("exec", "exec_cwd");
    let dir = config.parent().expect("dir");
    // From the folder above, with a relative config path, as
    // `nptreemap build examples/exec/nptreemap.yaml` from the repository root.
    let relative = Path::new(dir.file_name().expect("name")).join("nptreemap.yaml");
    let out = support::output_within(
        support::bin()
            .arg("build")
            .arg(&relative)
            .current_dir(dir.parent().expect("parent")),
        120,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("out/sources.svg").is_file());
}

#[test]
fn check_help_says_adapters_run() {
    let out = support::bin()
        .args(["check", "--help"])
        .output()
        .expect("run");
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(help.contains("format: exec"), "{help}");
    assert!(help.contains("runs"), "{help}");
}
