//! Issue 30 items 6 and 7, and the issue's acceptance test: `nptreemap
//! watch` never serves stale outputs. A `render:` edit made during a rebuild
//! survives an input saved again with the same bytes; `page:` and `history:`
//! edits reach the page; and a seeded random sequence of config and data
//! edits (identical rewrites, render, page, history and title edits, output
//! reorders, weight edits, edits during a rebuild) leaves, after every quiet
//! period, the outputs a one-shot `nptreemap build` of the same files makes,
//! with `build --check` passing. Quiet is the daemon's own word for it: its
//! debug log's `batch` and `idle` lines ([`Daemon::settle`]), never a sleep.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::support;
use crate::watch::{
    gated_adapter, initial_leaves, nodes_csv, pairs_csv, signal, wait_for_file, Daemon, Gate, TREE,
};

/// Runs `nptreemap ARGS CONFIG`: exit code and everything it printed.
fn run(args: &[&str], config: &Path) -> (Option<i32>, String) {
    let o = support::bin().args(args).arg(config).output().expect("run");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code(), text)
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Saves the config as editors do, by a rename: a config written in place
/// can be read while it is empty, which is a config without datasets for a
/// moment (every dataset removed, then added again), and the input events
/// of that moment are not the daemon's.
fn save(config: &Path, text: &str) {
    let tmp = config.with_extension("yaml.tmp");
    std::fs::write(&tmp, text).expect("config");
    std::fs::rename(&tmp, config).expect("rename");
}

/// The debug form of a path, as the daemon's `batch` lines print it.
fn quoted(path: &Path) -> String {
    format!("{:?}", path.display().to_string())
}

/// Issue 30 item 6: a `render:` edit made while the dataset rebuilds,
/// followed by its input saved again with the same bytes (an editor's save,
/// a cron job), was lost: the queue replaced the waiting render by a rebuild
/// for the edit, which found the bytes unchanged and did nothing. No line,
/// the old title for good, and `build --check` said stale.
#[test]
fn a_render_edit_during_a_rebuild_survives_an_identical_save() {
    let dir = support::temp_dir("watch_render_kept");
    let tree = dir.join("tree.json");
    std::fs::write(&tree, TREE).expect("tree");
    let config = dir.join("nptreemap.yaml");
    let text = |title: &str| {
        format!(
            "render: {{title: {title}}}\ndatasets:\n  - name: exe\n    format: exec\n    command: {}\n    timeout: 900\n    files: {{tree: tree.json}}\n    outputs: [out/exe.svg, out/exe.json]\n",
            gated_adapter("exe")
        )
    };
    std::fs::write(&config, text("Before")).expect("config");
    let gate = Gate(dir.join("gate"));
    let mut daemon = Daemon::start_logged(&config);
    // The start build runs, held by its adapter until the gate opens.
    wait_for_file(&dir.join("started-exe"));
    save(&config, &text("Afterwards"));
    daemon.expect_log(&["batch", &quoted(&config)]);
    std::fs::write(&tree, TREE).expect("the same bytes again");
    daemon.expect_log(&["batch", &quoted(&tree)]);
    gate.open();
    daemon.expect_log(&["idle"]);
    let svg = String::from_utf8(read(&dir.join("out/exe.svg"))).expect("svg");
    assert!(
        svg.contains("Afterwards"),
        "the render edit was lost; lines: {:?}",
        daemon.seen
    );
    let (code, out) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{out}");
    signal(&daemon.child, "TERM");
    daemon.expect(&["stopped"]);
    assert!(
        daemon
            .seen
            .iter()
            .any(|l| l.starts_with("exe: config: render")),
        "{:?}",
        daemon.seen
    );
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// The grid of `crate::watch` with a page whose link is the name column.
fn grid_config(extra: &str, page: &str) -> String {
    format!(
        "{extra}datasets:
  - name: grid
    format: border-list
    files: {{nodes: data/nodes.csv, pairs: data/pairs.csv}}
    fields: {{id: id, label: name, weight: weight, groups: [group]}}
    page: {{{page}}}
    outputs: [out/grid.svg, out/grid.html]
"
    )
}

/// Issue 30 item 7: `page:` edits (`link_target`) were ignored (the config
/// diff never compared `page`), and so was `history:` (3 → 0 kept the past
/// layouts in the page); `build --check` said stale until some later data
/// edit.
#[test]
fn page_and_history_edits_reach_the_page() {
    let dir = support::temp_dir("watch_page_edits");
    std::fs::create_dir_all(dir.join("data")).expect("data");
    let nodes = dir.join("data/nodes.csv");
    let mut leaves = initial_leaves();
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("nodes");
    std::fs::write(dir.join("data/pairs.csv"), pairs_csv()).expect("pairs");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(&config, grid_config("history: 2\n", "link: name")).expect("config");
    let html = dir.join("out/grid.html");
    let mut daemon = Daemon::start_logged(&config);
    daemon.expect(&["grid: start", "wrote"]);
    // A weight edit: the page now steps back to the start's layout.
    leaves[3].1 *= 1.5;
    std::fs::write(&nodes, nodes_csv(&leaves)).expect("edit");
    daemon.settle(&nodes);
    let before = read(&html);

    save(
        &config,
        &grid_config("history: 2\n", "link: name, link_target: same-tab"),
    );
    daemon.settle(&config);
    assert!(read(&html) != before, "the page: edit was ignored");

    let with_history = read(&html);
    save(
        &config,
        &grid_config("history: 0\n", "link: name, link_target: same-tab"),
    );
    daemon.settle(&config);
    assert!(read(&html) != with_history, "the history: edit was ignored");
    let (code, out) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{out}");
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
}

/// Issue 30 item 7, for `build --check`: the manifest records each
/// output's render key, which covers the page settings, so a `page:` edit
/// makes the page stale (and only it) until it is built.
#[test]
fn build_check_sees_page_edits() {
    let dir = support::temp_dir("check_page_edits");
    std::fs::create_dir_all(dir.join("data")).expect("data");
    std::fs::write(dir.join("data/nodes.csv"), nodes_csv(&initial_leaves())).expect("nodes");
    std::fs::write(dir.join("data/pairs.csv"), pairs_csv()).expect("pairs");
    let config = dir.join("nptreemap.yaml");
    std::fs::write(&config, grid_config("", "link: name")).expect("config");
    let (code, out) = run(&["build"], &config);
    assert_eq!(code, Some(0), "{out}");
    std::fs::write(
        &config,
        grid_config("", "link: name, link_target: same-tab"),
    )
    .expect("config");
    let (code, out) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(1), "{out}");
    let stale: Vec<&str> = out.lines().filter(|l| l.starts_with("stale ")).collect();
    assert_eq!(
        stale,
        [format!("stale {}", dir.join("out/grid.html").display())],
        "{out}"
    );
    let (code, out) = run(&["build"], &config);
    assert_eq!(code, Some(0), "{out}");
    let (code, out) = run(&["build", "--check"], &config);
    assert_eq!(code, Some(0), "{out}");
}

/// A seeded SplitMix64: the sequence of edits is a function of the seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number below `n` (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The grid's outputs, in two folders (so that their order could move the
/// state folder, issue 30 item 8).
const OUTPUTS: [&str; 3] = ["out/grid.svg", "pages/grid.html", "out/grid.json"];

/// What the random test has its config say.
#[derive(Clone, Debug)]
struct Settings {
    seed: u64,
    history: usize,
    legend: bool,
    title: Option<String>,
    dataset_title: Option<String>,
    link: bool,
    same_tab: bool,
    /// The grid's outputs, as indices into [`OUTPUTS`].
    order: Vec<usize>,
}

impl Settings {
    fn text(&self) -> String {
        let title = self
            .title
            .as_ref()
            .map_or(String::new(), |t| format!(", title: {t:?}"));
        let dataset_title = self
            .dataset_title
            .as_ref()
            .map_or(String::new(), |t| format!("    title: {t:?}\n"));
        let page = match (self.link, self.same_tab) {
            (false, false) => String::new(),
            (false, true) => "link_target: same-tab".to_string(),
            (true, false) => "link: name".to_string(),
            (true, true) => "link: name, link_target: same-tab".to_string(),
        };
        let outputs: Vec<&str> = self.order.iter().map(|&k| OUTPUTS[k]).collect();
        format!(
            "layout: {{seed: {}}}\nrender: {{legend: {}{title}}}\nhistory: {}\ndatasets:
  - name: grid
    format: border-list
    files: {{nodes: data/nodes.csv, pairs: data/pairs.csv}}
    fields: {{id: id, label: name, weight: weight, groups: [group]}}
{dataset_title}    page: {{{page}}}
    outputs: [{}]
  - name: beacon
    format: hierarchy-json
    files: {{hierarchy: beacon.json}}
    outputs: [out/beacon.json]
",
            self.seed,
            self.legend,
            self.history,
            outputs.join(", ")
        )
    }
}

/// The edits the random test makes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Edit {
    /// One to three leaves get another weight.
    Weight,
    /// The node table saved again, the same bytes.
    SameNodes,
    /// The pair list saved again, the same bytes.
    SamePairs,
    /// The config saved again, the same bytes.
    SameConfig,
    /// `render.title`.
    Title,
    /// `render.legend`.
    Legend,
    /// The dataset's own `title`.
    DatasetTitle,
    /// `page.link_target`.
    LinkTarget,
    /// `page.link` (a column the reader carries).
    Link,
    /// `history:` 0 ↔ 2.
    History,
    /// The outputs reordered.
    Reorder,
    /// `layout.seed` (a cold layout).
    Seed,
}

const EDITS: [Edit; 12] = [
    Edit::Weight,
    Edit::SameNodes,
    Edit::SamePairs,
    Edit::SameConfig,
    Edit::Title,
    Edit::Legend,
    Edit::DatasetTitle,
    Edit::LinkTarget,
    Edit::Link,
    Edit::History,
    Edit::Reorder,
    Edit::Seed,
];

/// The files of the random test and what they hold.
struct Scene {
    dir: PathBuf,
    settings: Settings,
    leaves: Vec<(String, f64)>,
}

impl Scene {
    fn config(&self) -> PathBuf {
        self.dir.join("nptreemap.yaml")
    }

    /// Makes `edit` (drawing what it needs from `rng`); returns the file it
    /// wrote.
    fn apply(&mut self, edit: Edit, rng: &mut Rng, k: usize) -> PathBuf {
        let s = &mut self.settings;
        match edit {
            Edit::Weight => {
                for _ in 0..=rng.below(3) {
                    let i = rng.below(self.leaves.len());
                    self.leaves[i].1 = 5.0 + rng.below(60) as f64;
                }
            }
            Edit::SameNodes | Edit::SameConfig => {}
            Edit::SamePairs => {
                let pairs = self.dir.join("data/pairs.csv");
                std::fs::write(&pairs, pairs_csv()).expect("pairs");
                return pairs;
            }
            Edit::Title => s.title = (rng.below(3) > 0).then(|| format!("Title {k}")),
            Edit::Legend => s.legend = !s.legend,
            Edit::DatasetTitle => {
                s.dataset_title = (rng.below(3) > 0).then(|| format!("Grid {k}"));
            }
            Edit::LinkTarget => s.same_tab = !s.same_tab,
            Edit::Link => s.link = !s.link,
            Edit::History => s.history = if s.history == 0 { 2 } else { 0 },
            Edit::Reorder => {
                let mut order = s.order.clone();
                while order == s.order {
                    order.swap(rng.below(3), rng.below(3));
                }
                s.order = order;
            }
            Edit::Seed => s.seed += 1,
        }
        match edit {
            Edit::Weight | Edit::SameNodes => {
                let nodes = self.dir.join("data/nodes.csv");
                std::fs::write(&nodes, nodes_csv(&self.leaves)).expect("nodes");
                nodes
            }
            _ => {
                save(&self.config(), &self.settings.text());
                self.config()
            }
        }
    }
}

/// A hierarchy whose one weight is `k`: each quiet period ends with it, so
/// that the daemon's log names a batch after every edit of the step.
fn beacon(k: usize) -> String {
    format!(
        r#"{{"id": "root", "children": [{{"id": "a", "value": {}}}, {{"id": "b", "value": 1}}]}}"#,
        k + 1
    )
}

/// Copies the files under `from` (the state folders' stored layouts and
/// manifests, the inputs, the config) into `to`, leaving the outputs.
fn copy_sources(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let path = entry.expect("entry").path();
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let target = to.join(&name);
        if path.is_dir() {
            copy_sources(&path, &target);
        } else if name.ends_with(".layout.json")
            || name.ends_with(".manifest.json")
            || name.ends_with(".csv")
            || name.ends_with(".yaml")
            || name == "beacon.json"
        {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}

/// The acceptance test of issue 30 for `watch`: a seeded random sequence of
/// config and data edits against a running daemon, some made while it
/// rebuilds (after the daemon read the previous edit's batch), the first
/// step the loss of item 6 (a weight edit, a render edit and an identical
/// save, each during the rebuild before it). After each quiet period every
/// output equals a one-shot `nptreemap build` of the same files (config,
/// inputs and the committed state: the stored layout, the warm start, and
/// the manifest, which keeps the colours; copied to a folder of its own),
/// and `build --check` passes in the daemon's folder; with
/// `history:` on, the page carries the session's past layouts, which
/// `build`'s page does not, so only it may differ. Every edit kind occurs.
/// `NPTREEMAP_WATCH_EDITS_SEED` and `NPTREEMAP_WATCH_EDITS_STEPS` run
/// another or a longer sequence (the default takes seconds).
#[test]
fn random_edits_leave_what_a_build_makes() {
    let env = |name: &str, default: u64| {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let seed = env("NPTREEMAP_WATCH_EDITS_SEED", 30);
    let steps = env("NPTREEMAP_WATCH_EDITS_STEPS", 30) as usize;
    let dir = support::temp_dir("watch_random_edits");
    std::fs::create_dir_all(dir.join("data")).expect("data");
    let mut scene = Scene {
        dir: dir.clone(),
        settings: Settings {
            seed: 1,
            history: 0,
            legend: true,
            title: None,
            dataset_title: None,
            link: false,
            same_tab: false,
            order: vec![0, 1, 2],
        },
        leaves: initial_leaves(),
    };
    std::fs::write(dir.join("data/nodes.csv"), nodes_csv(&scene.leaves)).expect("nodes");
    std::fs::write(dir.join("data/pairs.csv"), pairs_csv()).expect("pairs");
    let beacon_path = dir.join("beacon.json");
    std::fs::write(&beacon_path, beacon(0)).expect("beacon");
    let config = scene.config();
    std::fs::write(&config, scene.settings.text()).expect("config");
    let reference = dir.with_file_name("watch_random_edits_build");

    let started = Instant::now();
    let mut rng = Rng(seed);
    let mut daemon = Daemon::start_logged(&config);
    // Both start builds done.
    daemon.expect_log(&["idle"]);
    let mut bag: Vec<Edit> = Vec::new();
    let mut seen_kinds = Vec::new();
    for step in 0..steps {
        let edits: Vec<(Edit, bool)> = if step == 0 {
            vec![
                (Edit::Weight, false),
                (Edit::Title, true),
                (Edit::SameNodes, true),
            ]
        } else {
            (0..=rng.below(3))
                .map(|_| {
                    if bag.is_empty() {
                        bag = EDITS.to_vec();
                    }
                    let edit = bag.swap_remove(rng.below(bag.len()));
                    (edit, rng.below(2) == 0)
                })
                .collect()
        };
        let mut last: Option<PathBuf> = None;
        for (k, &(edit, during)) in edits.iter().enumerate() {
            if let (true, Some(path)) = (during, &last) {
                // The daemon has read the previous edit: its rebuild runs.
                daemon.expect_log(&["batch", &quoted(path)]);
            }
            last = Some(scene.apply(edit, &mut rng, step * 10 + k));
            seen_kinds.push(edit);
        }
        std::fs::write(&beacon_path, beacon(step + 1)).expect("beacon");
        daemon.settle(&beacon_path);
        let context = format!(
            "step {step} (seed {seed}): {edits:?}; config now {:?}; lines:\n{}",
            scene.settings,
            daemon.seen.join("\n")
        );
        assert!(
            !daemon.seen.iter().any(|l| l.contains("error")),
            "{context}"
        );

        // `build --check` where the daemon writes.
        let page = dir.join("pages/grid.html");
        let (code, out) = run(&["build", "--check"], &config);
        if scene.settings.history == 0 {
            assert_eq!(code, Some(0), "{out}\n{context}");
        } else if code != Some(0) {
            let stale: Vec<&str> = out.lines().filter(|l| l.starts_with("stale ")).collect();
            assert_eq!(
                stale,
                [format!("stale {}", page.display())],
                "{out}\n{context}"
            );
        }

        // A one-shot build of the same files, elsewhere.
        let _ = std::fs::remove_dir_all(&reference);
        copy_sources(&dir, &reference);
        let (code, out) = run(&["build"], &reference.join("nptreemap.yaml"));
        assert_eq!(code, Some(0), "{out}\n{context}");
        for output in OUTPUTS.iter().chain(&["out/beacon.json"]) {
            if output.ends_with(".html") && scene.settings.history > 0 {
                continue;
            }
            let (watched, built) = (read(&dir.join(output)), read(&reference.join(output)));
            assert!(
                watched == built,
                "{output} differs from a build of the same files\n{out}\n{context}"
            );
        }
    }
    for kind in EDITS {
        assert!(
            steps < 8 || seen_kinds.contains(&kind),
            "{kind:?} never made"
        );
    }
    signal(&daemon.child, "TERM");
    assert_eq!(daemon.child.wait().expect("wait").code(), Some(0));
    eprintln!(
        "{steps} steps, {} edits, in {:.1} s",
        seen_kinds.len(),
        started.elapsed().as_secs_f64()
    );
}
