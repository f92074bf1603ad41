//! `nptreemap watch` end to end (issue 6 item 8): the daemon runs on a temp
//! folder while the test edits its data the ways people do (a weight change,
//! an added node, a removed node, a malformed edit and its fix, an atomic save
//! by rename, a bad config and its fix, a deleted file) and asserts that the
//! outputs follow, pass `tests/tools/check_layout.py`, are never seen partially
//! written, and that SIGTERM and SIGINT end the daemon with exit code 0.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support;

/// Groups and leaves of the test dataset: enough leaves (> 64 nodes) that the
/// layout skips the small-hierarchy lookahead and stays quick in debug builds.
const GROUPS: [&str; 4] = ["north", "east", "south", "west"];
const PER_GROUP: usize = 20;

/// Rows `id,name,weight,group`, weights from `weight(i)`.
fn nodes_csv(leaves: &[(String, f64)]) -> String {
    let mut s = String::from("id,name,weight,group\n");
    for (k, (id, w)) in leaves.iter().enumerate() {
        s.push_str(&format!(
            "{id},Node {id},{w},{}\n",
            GROUPS[k / PER_GROUP % GROUPS.len()]
        ));
    }
    s
}

fn initial_leaves() -> Vec<(String, f64)> {
    (0..GROUPS.len() * PER_GROUP)
        .map(|i| (format!("n{i:03}"), 10.0 + (i * 37 % 50) as f64))
        .collect()
}

/// A ring of similar pairs inside each group plus a few across groups.
fn pairs_csv() -> String {
    let mut s = String::from("a,b\n");
    for g in 0..GROUPS.len() {
        for k in 0..PER_GROUP {
            let a = g * PER_GROUP + k;
            let b = g * PER_GROUP + (k + 1) % PER_GROUP;
            s.push_str(&format!("n{a:03},n{b:03}\n"));
        }
        let next = (g + 1) % GROUPS.len();
        s.push_str(&format!(
            "n{:03},n{:03}\n",
            g * PER_GROUP,
            next * PER_GROUP + 5
        ));
    }
    s
}

const CONFIG: &str = "datasets:
  - name: grid
    format: border-list
    files: {nodes: data/nodes.csv, pairs: data/pairs.csv}
    fields: {id: id, label: name, weight: weight, groups: [group]}
    outputs:
      - path: out/grid.svg
      - path: out/grid.png
      - path: out/grid.json
";

/// The running daemon: its status lines arrive on a channel; killed on drop.
/// (`exec` drives it too.)
pub(crate) struct Daemon {
    pub(crate) child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Daemon {
    pub(crate) fn start(config: &Path) -> Self {
        let mut child = support::bin()
            .arg("watch")
            .arg(config)
            .env("RUST_LOG", "nptreemap=debug")
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(config.with_extension("log")).expect("log"))
            .spawn()
            .expect("start nptreemap watch");
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Waits for the next status line containing every one of `parts`.
    pub(crate) fn expect(&mut self, parts: &[&str]) -> String {
        let deadline = Instant::now() + Duration::from_secs(120);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if parts.iter().all(|p| line.contains(p)) {
                        return line;
                    }
                }
                Err(RecvTimeoutError::Timeout) | Err(RecvTimeoutError::Disconnected) => panic!(
                    "no status line with {parts:?}; lines so far:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// Lines that arrive within `wait` (to show nothing else happened).
    fn drain(&mut self, wait: Duration) -> Vec<String> {
        let mut got = Vec::new();
        while let Ok(line) = self.lines.recv_timeout(wait) {
            self.seen.push(line.clone());
            got.push(line);
        }
        got
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Reads the outputs in a loop while the test runs and records every read
/// that is not a whole file: JSON that does not parse, SVG without its end,
/// a PNG that does not decode. Atomic writes make this impossible.
struct TornReadProbe {
    stop: Arc<AtomicBool>,
    reads: Arc<AtomicUsize>,
    torn: Arc<Mutex<Vec<String>>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl TornReadProbe {
    fn start(out: &Path) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let reads = Arc::new(AtomicUsize::new(0));
        let torn = Arc::new(Mutex::new(Vec::new()));
        let (s, r, t, out) = (stop.clone(), reads.clone(), torn.clone(), out.to_path_buf());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                for name in ["grid.json", "grid.svg", "grid.png"] {
                    let Ok(bytes) = std::fs::read(out.join(name)) else {
                        continue;
                    };
                    r.fetch_add(1, Ordering::Relaxed);
                    let whole = match name {
                        "grid.json" => serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(),
                        "grid.svg" => bytes.ends_with(b"</svg>\n"),
                        _ => resvg::tiny_skia::Pixmap::decode_png(&bytes).is_ok(),
                    };
                    if !whole {
                        t.lock()
                            .expect("probe lock")
                            .push(format!("{name}: {} bytes", bytes.len()));
                    }
                }
                std::thread::sleep(Duration::from_millis(2));
            }
        });
        Self {
            stop,
            reads,
            torn,
            thread: Some(thread),
        }
    }

    fn finish(mut self) -> (usize, Vec<String>) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().expect("probe thread");
        }
        let torn = self.torn.lock().expect("probe lock").clone();
        (self.reads.load(Ordering::Relaxed), torn)
    }
}

fn layout_json(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("grid.json")).expect("layout json");
    serde_json::from_str(&text).expect("layout json parses")
}

/// The leaf weights in the layout JSON, by id.
fn weights(layout: &serde_json::Value) -> Vec<(String, f64)> {
    let mut v: Vec<(String, f64)> = layout["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .filter(|n| {
            n["id"]
                .as_str()
                .is_some_and(|id| id.starts_with('n') && !id.contains(':'))
        })
        .map(|n| {
            (
                n["id"].as_str().expect("id").to_string(),
                n["weight"].as_f64().expect("weight"),
            )
        })
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// Same ids and the same weights up to the JSON's rounding (1e-6).
fn same_weights(got: &[(String, f64)], want: &[(String, f64)]) -> bool {
    got.len() == want.len()
        && got
            .iter()
            .zip(want)
            .all(|(g, w)| g.0 == w.0 && (g.1 - w.1).abs() <= 1e-6 * w.1.abs().max(1.0))
}

fn assert_outputs_match(out: &Path, leaves: &[(String, f64)]) {
    support::check_layout(&out.join("grid.json"));
    let mut want = leaves.to_vec();
    want.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(
        same_weights(&weights(&layout_json(out)), &want),
        "layout JSON = the data"
    );
    let svg = std::fs::read_to_string(out.join("grid.svg")).expect("svg");
    for (id, _) in leaves {
        assert!(svg.contains(&format!("data-id=\"{id}\"")), "{id} drawn");
    }
}

fn setup(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = support::temp_dir(name);
    std::fs::create_dir_all(dir.join("data")).expect("data dir");
    std::fs::write(dir.join("data/nodes.csv"), nodes_csv(&initial_leaves())).expect("nodes");
    std::fs::write(dir.join("data/pairs.csv"), pairs_csv()).expect("pairs");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(&config, CONFIG).expect("config");
    let out = dir.join("out");
    (dir, config, out)
}

/// Sends SIG`name` to the daemon. Through python3 (which the suite needs for
/// the checker anyway) rather than `kill`, which minimal images may lack.
fn signal(child: &Child, name: &str) {
    let status = std::process::Command::new("python3")
        .args([
            "-c",
            &format!(
                "import os, signal; os.kill({}, signal.SIG{name})",
                child.id()
            ),
        ])
        .status()
        .expect("run python3");
    assert!(status.success(), "could not send SIG{name}");
}

#[test]
fn the_daemon_follows_edits_and_survives_bad_ones() {
    let (dir, config, out) = setup("watch_edits");
    let nodes = dir.join("data/nodes.csv");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote grid.svg, grid.png, grid.json"]);
    let mut leaves = initial_leaves();
    assert_outputs_match(&out, &leaves);
    let probe = TornReadProbe::start(&out);

    // 1. A weight change of one leaf.
    leaves[7].1 *= 1.1;
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    daemon.expect(&["grid: data: nodes.csv", "wrote"]);
    assert_outputs_match(&out, &leaves);

    // 2. An added node.
    leaves.push(("n900".to_string(), 33.0));
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    daemon.expect(&["grid: data: nodes.csv", "wrote"]);
    assert_outputs_match(&out, &leaves);

    // 3. A removed node (its pairs must go too: the border list checks ids).
    leaves.retain(|(id, _)| id != "n900");
    leaves.remove(30);
    let removed = "n030";
    let pairs: String = pairs_csv()
        .lines()
        .filter(|l| !l.split(',').any(|id| id == removed))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("data/pairs.csv"), pairs).expect("edit pairs");
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    daemon.expect(&["grid: data: nodes.csv", "wrote"]);
    assert_outputs_match(&out, &leaves);

    // 4. A malformed edit: reported with file and line, outputs untouched.
    let before: Vec<Vec<u8>> = ["grid.svg", "grid.png", "grid.json"]
        .iter()
        .map(|n| std::fs::read(out.join(n)).expect("output"))
        .collect();
    let mut bad = nodes_csv(&leaves);
    bad.push_str("n999,Broken,not-a-number,north\n");
    std::fs::write(&nodes, &bad).expect("edit");
    let line = daemon.expect(&["grid: error"]);
    let bad_line = bad.lines().count();
    assert!(
        line.contains("nodes.csv") && line.contains(&format!("line {bad_line}")),
        "{line}"
    );
    assert!(line.contains("last good outputs kept"), "{line}");
    for (name, old) in ["grid.svg", "grid.png", "grid.json"].iter().zip(&before) {
        assert_eq!(
            &std::fs::read(out.join(name)).expect("output"),
            old,
            "{name}"
        );
    }

    // 5. Its fix (an atomic save: temp file, then rename over the original).
    leaves[3].1 = 77.0;
    let tmp = dir.join("data/.nodes.csv.swp");
    std::fs::write(&tmp, nodes_csv(&leaves)).expect("temp");
    std::fs::rename(&tmp, &nodes).expect("rename");
    let line = daemon.expect(&["grid: ", "data: nodes.csv", "wrote"]);
    // The error of step 4 was reported, so its fix is announced.
    assert!(
        line.starts_with("grid: ok again, data: nodes.csv"),
        "{line}"
    );
    assert_outputs_match(&out, &leaves);

    // 6. An invalid config keeps the previous one; its fix applies.
    std::fs::write(&config, format!("{CONFIG}  - name: [\n")).expect("bad yaml");
    let line = daemon.expect(&["config: error"]);
    assert!(
        line.contains("nptreemap.yaml") && line.contains("line "),
        "{line}"
    );
    std::fs::write(&config, format!("render: {{legend: false}}\n{CONFIG}")).expect("fix");
    let line = daemon.expect(&["grid: config: render"]);
    assert!(
        line.contains("re-rendered"),
        "a render-only change reuses the layout: {line}"
    );
    assert_outputs_match(&out, &leaves);

    // 7. A deleted data file is reported; the outputs stay.
    let kept = std::fs::read(out.join("grid.json")).expect("json");
    std::fs::remove_file(dir.join("data/pairs.csv")).expect("delete");
    let line = daemon.expect(&["grid: error"]);
    assert!(
        line.contains("pairs.csv") && line.contains("outputs kept"),
        "{line}"
    );
    assert_eq!(std::fs::read(out.join("grid.json")).expect("json"), kept);

    let (reads, torn) = probe.finish();
    assert!(reads > 50, "the probe read the outputs ({reads} reads)");
    assert!(torn.is_empty(), "partially written outputs seen: {torn:?}");
    // Our atomic writes leave no temp files behind.
    let stray: Vec<_> = std::fs::read_dir(&out)
        .expect("out")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");

    // SIGTERM ends it cleanly.
    signal(&daemon.child, "TERM");
    daemon.expect(&["stopped"]);
    let status = daemon.child.wait().expect("wait");
    assert_eq!(status.code(), Some(0), "exit code after SIGTERM");
}

/// Many quick edits in a row (the CI-sized version of the 1,000-edit
/// benchmark): no crash, and the final outputs are the final data.
#[test]
fn a_burst_of_edits_ends_in_the_last_data() {
    let (dir, config, out) = setup("watch_burst");
    let nodes = dir.join("data/nodes.csv");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote"]);
    let mut leaves = initial_leaves();
    for edit in 0..40 {
        let k = edit * 7 % leaves.len();
        leaves[k].1 = 5.0 + (edit * 13 % 40) as f64;
        std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
        std::thread::sleep(Duration::from_millis(25));
    }
    // Wait until a rebuild has seen the final bytes: the daemon goes quiet
    // once its JSON holds them.
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut want = leaves.clone();
    want.sort_by(|a, b| a.0.cmp(&b.0));
    while !same_weights(&weights(&layout_json(&out)), &want) {
        assert!(
            Instant::now() < deadline,
            "outputs never reached the last edit; lines:\n{}",
            daemon.seen.join("\n")
        );
        daemon.drain(Duration::from_millis(200));
    }
    assert_outputs_match(&out, &leaves);
    let lines = daemon.drain(Duration::from_millis(300));
    assert!(
        daemon.seen.iter().all(|l| !l.contains("error")),
        "{}",
        daemon.seen.join("\n")
    );
    // Batching: far fewer rebuilds than edits.
    let rebuilds = daemon
        .seen
        .iter()
        .filter(|l| l.contains("data: nodes.csv"))
        .count();
    assert!(rebuilds < 40, "{rebuilds} rebuilds for 40 edits; {lines:?}");
    // So does SIGINT (Ctrl-C).
    signal(&daemon.child, "INT");
    daemon.expect(&["stopped"]);
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 11 item 3: a data folder deleted and created again is watched again
/// (the dead path used to stay in the watched set and nothing ever rebuilt),
/// and so is the config's own folder.
#[test]
fn a_recreated_folder_is_watched_again() {
    let dir = support::temp_dir("watch_recreated");
    let data = dir.join("data");
    let conf = dir.join("conf");
    std::fs::create_dir_all(&data).expect("data");
    std::fs::create_dir_all(&conf).expect("conf");
    let write_data = |leaves: &[(String, f64)]| {
        std::fs::write(data.join("nodes.csv"), nodes_csv(leaves)).expect("nodes");
        std::fs::write(data.join("pairs.csv"), pairs_csv()).expect("pairs");
    };
    let mut leaves = initial_leaves();
    write_data(&leaves);
    let config_text = CONFIG
        .replace("data/", "../data/")
        .replace("out/", "../out/");
    let config = conf.join("nptreemap.yaml");
    std::fs::write(&config, &config_text).expect("config");
    let out = dir.join("out");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote"]);

    std::fs::remove_dir_all(&data).expect("rm data");
    daemon.expect(&["grid: error", "nodes.csv"]);
    std::fs::create_dir_all(&data).expect("mkdir data");
    leaves[2].1 = 91.0;
    write_data(&leaves);
    let line = daemon.expect(&["grid: ", "wrote"]);
    assert!(line.contains("ok again"), "the recovery is said: {line}");
    assert_outputs_match(&out, &leaves);
    // And the new folder is watched: a later edit is seen.
    leaves[5].1 = 12.0;
    write_data(&leaves);
    daemon.expect(&["grid: data", "wrote"]);
    assert_outputs_match(&out, &leaves);

    // The config's own folder, deleted and made again with a changed config.
    std::fs::remove_dir_all(&conf).expect("rm conf");
    daemon.expect(&["config: error"]);
    std::fs::create_dir_all(&conf).expect("mkdir conf");
    std::fs::write(&config, format!("render: {{legend: false}}\n{config_text}")).expect("config");
    daemon.expect(&["grid: config: render"]);
    // Watched again: one more config edit is seen.
    std::fs::write(&config, format!("render: {{legend: true}}\n{config_text}")).expect("config");
    daemon.expect(&["grid: config: render"]);
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 11 item 4: a FIFO in place of an input is reported, never read (the
/// daemon used to block in the read and stop handling events).
#[test]
fn a_fifo_input_does_not_block_the_daemon() {
    let (dir, config, out) = setup("watch_fifo");
    let nodes = dir.join("data/nodes.csv");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote"]);
    std::fs::remove_file(&nodes).expect("rm nodes");
    support::mkfifo(&nodes);
    daemon.expect(&["grid: error", "nodes.csv", "not a regular file"]);
    // Still handling events: the file is back and the picture follows.
    let mut leaves = initial_leaves();
    leaves[1].1 = 66.0;
    std::fs::remove_file(&nodes).expect("rm fifo");
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("nodes");
    daemon.expect(&["grid: ", "wrote"]);
    assert_outputs_match(&out, &leaves);
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 11 item 12: SIGHUP reloads the config (it used to stop the daemon
/// with exit 0, so systemd's `Restart=on-failure` never restarted it).
#[test]
fn sighup_reloads_the_config() {
    let (_dir, config, out) = setup("watch_hup");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote"]);
    signal(&daemon.child, "HUP");
    daemon.expect(&["config: reloaded"]);
    // Still running, and the reloaded config applies.
    std::thread::sleep(Duration::from_millis(300));
    assert!(
        daemon.child.try_wait().expect("try_wait").is_none(),
        "SIGHUP stopped the daemon"
    );
    std::fs::write(&config, format!("render: {{legend: false}}\n{CONFIG}")).expect("config");
    daemon.expect(&["grid: config: render"]);
    assert_outputs_match(&out, &initial_leaves());
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// The shipped unit reloads with SIGHUP and stops with SIGTERM, which the
/// daemon answers as the tests above check; a failure exit (not 0, not 2)
/// restarts it.
#[test]
fn the_systemd_unit_matches_the_daemon() {
    let unit = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/systemd/nptreemap-watch.service"),
    )
    .expect("unit");
    let lines: Vec<&str> = unit.lines().map(str::trim).collect();
    for wanted in [
        "ExecReload=/bin/kill -HUP $MAINPID",
        "KillSignal=SIGTERM",
        "Restart=on-failure",
        "RestartPreventExitStatus=2",
    ] {
        assert!(lines.contains(&wanted), "the unit lacks {wanted:?}");
    }
    assert!(lines
        .iter()
        .any(|l| l.starts_with("ExecStart=") && l.contains("nptreemap watch")));
}

/// A dataset slow enough to be caught mid-layout: 1,500 leaves by the
/// neighbourhood method (seconds in the test build).
fn slow_setup(name: &str) -> (PathBuf, PathBuf) {
    let dir = support::temp_dir(name);
    let (n, g) = (1500, 30);
    let mut nodes = String::from("id,weight,group\n");
    let mut pairs = String::from("a,b\n");
    for i in 0..n {
        nodes.push_str(&format!("n{i},{},g{}\n", 1 + i % 17, i % g));
        pairs.push_str(&format!("n{i},n{}\n", (i + g) % n));
    }
    std::fs::write(dir.join("nodes.csv"), nodes).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), pairs).expect("pairs");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(
        &config,
        "datasets:\n  - name: slow\n    format: border-list\n    files: {nodes: nodes.csv, pairs: pairs.csv}\n    fields: {groups: [group]}\n    outputs: [{path: out/slow.svg}, {path: out/slow.json}]\n",
    )
    .expect("config");
    (dir, config)
}

/// Issue 11 item 12: SIGTERM during a long rebuild ends the daemon with exit
/// code 0 within a second (it used to wait for the layout, or need SIGKILL),
/// leaving no output half-written.
#[test]
fn sigterm_during_a_long_rebuild_ends_within_a_second() {
    let (dir, config) = slow_setup("watch_term_busy");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["watching"]);
    // The start build is under way now (it takes seconds).
    std::thread::sleep(Duration::from_millis(800));
    assert!(daemon.child.try_wait().expect("try_wait").is_none());
    let sent = Instant::now();
    // Directly, not through python3 (whose start-up takes a while on a busy
    // machine and would be counted).
    // SAFETY: kill(2) with the pid of our own child and a valid signal.
    let sent_ok = unsafe { libc::kill(daemon.child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(sent_ok, 0, "kill");
    let status = loop {
        if let Some(status) = daemon.child.try_wait().expect("try_wait") {
            break status;
        }
        assert!(
            sent.elapsed() < Duration::from_secs(10),
            "still running 10 s after SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = sent.elapsed();
    assert_eq!(status.code(), Some(0), "exit code after SIGTERM");
    // One second, plus scheduling slack on a loaded two-core machine.
    assert!(took < Duration::from_millis(1500), "took {took:?}");
    // Whatever is there is whole: the rebuild was interrupted before writing.
    for name in ["slow.svg", "slow.json"] {
        if let Ok(bytes) = std::fs::read(dir.join("out").join(name)) {
            assert!(
                bytes.ends_with(b">\n") || bytes.ends_with(b"}\n"),
                "{name} torn"
            );
        }
    }
}

/// Issue 11 item 13: every status line is true. An output folder replaced by
/// a file: the failures do not claim other outputs were written, the rebuild
/// line does not say "no output changed"; the fix is announced ("ok again").
#[test]
fn status_lines_tell_the_truth() {
    let (dir, config, out) = setup("watch_truth");
    let nodes = dir.join("data/nodes.csv");
    let mut daemon = Daemon::start(&config);
    daemon.expect(&["grid: start", "wrote"]);
    // The stored layout is written after the status line: wait for it, so
    // the folder is not removed while the daemon still writes in it.
    let state = out.join(".nptreemap/grid.layout.json");
    let deadline = Instant::now() + Duration::from_secs(30);
    while !state.exists() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    std::fs::remove_dir_all(&out).expect("rm out");
    std::fs::write(&out, "not a folder").expect("out as a file");
    let mut leaves = initial_leaves();
    leaves[0].1 = 44.0;
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    let first = daemon.expect(&["grid: error", "grid.svg"]);
    assert!(!first.contains("other outputs written"), "{first}");
    let summary = daemon.expect(&["grid: data: nodes.csv"]);
    assert!(!summary.contains("no output changed"), "{summary}");
    assert!(summary.contains("not written"), "{summary}");
    // The folder is back: the next rebuild writes and says it recovered.
    std::fs::remove_file(&out).expect("rm file");
    leaves[0].1 = 45.0;
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    let line = daemon.expect(&["grid: ", "wrote"]);
    assert!(line.contains("ok again"), "{line}");
    assert_outputs_match(&out, &leaves);

    // A data error, then its fix: the fix is announced.
    std::fs::write(
        &nodes,
        format!("{}n999,Broken,x,north\n", nodes_csv(&leaves)),
    )
    .expect("bad");
    daemon.expect(&["grid: error", "line "]);
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("fix");
    let line = daemon.expect(&["grid: ok again"]);
    assert!(!line.contains("error"), "{line}");
    // A bad config, then its fix.
    std::fs::write(&config, format!("{CONFIG}  - name: [\n")).expect("bad yaml");
    daemon.expect(&["config: error"]);
    std::fs::write(&config, CONFIG).expect("fix");
    daemon.expect(&["config: ok again"]);
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 11 item 13: with an input missing at start there are no last
/// outputs to keep, and the line does not claim any.
#[test]
fn no_outputs_kept_when_there_are_none() {
    let (dir, config, _out) = setup("watch_none_kept");
    std::fs::remove_file(dir.join("data/pairs.csv")).expect("rm");
    let mut daemon = Daemon::start(&config);
    let line = daemon.expect(&["grid: error", "pairs.csv"]);
    assert!(!line.contains("outputs kept"), "{line}");
    std::fs::write(dir.join("data/pairs.csv"), pairs_csv()).expect("pairs");
    daemon.expect(&["grid: ", "wrote"]);
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 11 item 15: what `check` warns about is a status line in `watch`:
/// a self pair, and a stored layout that cannot be read (a silent cold start
/// made the picture jump).
#[test]
fn warnings_are_status_lines() {
    let (dir, config, out) = setup("watch_warnings");
    std::fs::create_dir_all(out.join(".nptreemap")).expect("state dir");
    std::fs::write(
        out.join(".nptreemap/grid.layout.json"),
        "{\"format\": \"nptreemap-layout/1\", \"nod",
    )
    .expect("truncated state");
    std::fs::write(
        dir.join("data/pairs.csv"),
        format!("{}n001,n001\n", pairs_csv()),
    )
    .expect("pairs");
    let mut daemon = Daemon::start(&config);
    let state = daemon.expect(&["grid: warning", "grid.layout.json"]);
    assert!(state.contains("cold"), "{state}");
    let pair = daemon.expect(&["grid: warning", "pairs.csv", "itself"]);
    assert!(pair.contains("line "), "{pair}");
    daemon.expect(&["grid: start", "wrote"]);
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}
