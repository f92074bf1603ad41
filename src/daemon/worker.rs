//! One dataset's rebuilds, on a thread of its own (issue 21 item 3), so that
//! no dataset waits for another: a slow adapter or a long layout holds up
//! only its own dataset, and the daemon's loop stays free to batch events,
//! dispatch work and report. A worker keeps its dataset's last good layout
//! (the source of render-only rebuilds and of the next warm start) and the
//! outputs it could not write; it hands each task's input files to the
//! dataset's stage graph ([`crate::graph`], kept in memory between
//! rebuilds), which decides what to run, and answers with an [`Outcome`].
//! A panic in a task is caught and is that dataset's failure: the daemon
//! lives on.

use std::ops::ControlFlow;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::Instant;

use crate::config::DatasetConfig;
use crate::graph::memo::ms_since;
use crate::graph::{self, DatasetGraph, GraphOptions, LayoutStep, Stage, StageReport};
use crate::layout::{LayoutError, ProgressSink, Request};
use crate::measure::stability::{stability, Stability};
use crate::pipeline::{self, BuildError, Rendered, Written};
use crate::render::Style;
use crate::workspace;

use super::change::Reason;
use super::queue::{data_only, Next};
use super::status::{escape, LayoutKind};
use super::watcher::Message;
use super::FirstBuildProgress;

/// The stack of a worker thread: as large as a main thread's, since the
/// readers and the layout ran on the main thread before and their depth
/// limits were set there.
const STACK: usize = 8 << 20;

/// One task for a worker, with the config it runs under.
pub struct Task {
    /// When the batch that asked for it ended (its debounce over): the
    /// rebuild's time is counted from it.
    pub since: Instant,
    /// What to do.
    pub next: Next,
    /// The dataset, as the config says now.
    pub dataset: DatasetConfig,
    /// Its layout request (without a previous layout: the worker has it).
    pub request: Request,
    /// Its picture style.
    pub style: Style,
    /// Rebuild even when the inputs did not change (a problem is open, and
    /// the rebuild should find out whether it is gone).
    pub force: bool,
    /// How many past layouts its HTML page carries (`history:`).
    pub history: usize,
}

/// A finished rebuild that wrote (or tried to write) its outputs.
pub struct Built {
    /// Why it ran.
    pub reason: Reason,
    /// How the layout came about.
    pub layout: LayoutKind,
    /// Why it was laid out cold, when it was.
    pub why: Option<String>,
    /// The constraints realised and in all, when there are any.
    pub realized: Option<(usize, usize)>,
    /// Wall time, ms.
    pub ms: f64,
    /// What writing the outputs did.
    pub written: Written,
    /// The input warnings of the dataset, one line each.
    pub warnings: Vec<String>,
    /// Why the layout could not be stored for warm starts, if it could not.
    pub unsaved: Option<std::io::Error>,
    /// What each stage did (empty for a retry).
    pub stages: StageReport,
    /// How far the cells moved against the dataset's previous picture, when
    /// it was laid out and there was one.
    pub stability: Option<Stability>,
}

/// How the layout came about, as the status line says it, and why it was
/// laid out cold when it was.
fn layout_kind(step: &LayoutStep) -> (LayoutKind, Option<String>) {
    match step {
        LayoutStep::Cold(why) => (LayoutKind::Cold, Some(why.clone())),
        LayoutStep::Warm => (LayoutKind::Warm, None),
        LayoutStep::Reused => (LayoutKind::Reused, None),
        LayoutStep::UpToDate => (LayoutKind::UpToDate, None),
    }
}

/// How a task ended.
pub enum Outcome {
    /// The inputs did not change: nothing was done.
    Unchanged,
    /// A stop was asked for: abandoned, nothing written.
    Abandoned,
    /// An input could not be read; the consequence for the outputs.
    Unreadable(BuildError, &'static str),
    /// Parsing, laying out or rendering failed; the consequence.
    Failed(BuildError, &'static str),
    /// Outputs were written, or failed to be.
    Built(Built),
    /// The task panicked (a bug), with the panic's message.
    Panicked(String),
    /// After its rebuild was reported, the state folder could not be
    /// written (the outputs were): kept, and written again by a retry.
    /// Sent after the rebuild's own outcome, by a worker still busy.
    Unsaved(std::io::Error),
}

/// A task's outcome, for the daemon's loop.
pub struct Done {
    /// The dataset.
    pub name: String,
    /// Why the task ran.
    pub reason: Reason,
    /// How it ended.
    pub outcome: Outcome,
}

/// What every worker shares with the daemon.
pub struct Shared {
    /// Where outcomes go.
    pub done: Sender<Done>,
    /// The daemon's own channel, woken after each outcome.
    pub wake: Sender<Message>,
    /// Set when the daemon stops: a task under way abandons at its next
    /// stage (or the layout's next progress report) and writes nothing.
    pub stop: Arc<AtomicBool>,
    /// `--cold`: the start build ignores the stored layout.
    pub cold: bool,
    /// Progress reporters for start builds.
    pub progress: Option<FirstBuildProgress>,
    /// Held by the one start build that shows a progress reporter: one bar
    /// on a terminal at a time.
    pub bar: AtomicBool,
}

impl Shared {
    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// A dataset's worker thread, as the daemon holds it.
pub struct Worker {
    jobs: Sender<Task>,
    /// Whether a task was sent and its outcome has not come back yet.
    pub busy: bool,
}

impl Worker {
    /// Starts the worker of dataset `name`.
    pub fn spawn(name: &str, shared: Arc<Shared>) -> std::io::Result<Self> {
        let (jobs, rx) = std::sync::mpsc::channel();
        let owned = name.to_string();
        std::thread::Builder::new()
            // Escaped: a thread name may not hold a NUL, which a dataset name may.
            .name(format!("watch {}", escape(name)))
            .stack_size(STACK)
            .spawn(move || {
                serve(&owned, &rx, &shared, &mut |state, job, shared| {
                    state.run(&owned, job, shared)
                });
            })?;
        Ok(Worker { jobs, busy: false })
    }

    /// Hands the worker a task; false when the worker is gone.
    pub fn send(&mut self, job: Task) -> bool {
        let sent = self.jobs.send(job).is_ok();
        self.busy = sent;
        sent
    }
}

/// What runs a task (a parameter so that tests can make one panic).
type Run<'a> = dyn FnMut(&mut Remembered, &Task, &Shared) -> Outcome + 'a;

/// The worker's loop: one task at a time until the daemon drops its end.
fn serve(name: &str, jobs: &Receiver<Task>, shared: &Shared, run: &mut Run<'_>) {
    let mut state = Remembered::default();
    for job in jobs {
        let outcome = catch_unwind(AssertUnwindSafe(|| run(&mut state, &job, shared)))
            .unwrap_or_else(|panic| {
                // What the task left half-done cannot be trusted: start over
                // (the next rebuild is a full one, cold unless a layout is
                // stored).
                state = Remembered::default();
                Outcome::Panicked(panic_message(panic.as_ref()))
            });
        let done = Done {
            name: name.to_string(),
            reason: match &job.next {
                Next::Build(reason) => reason.clone(),
                Next::Render => Reason::Render,
                Next::Retry => Reason::Retry,
            },
            outcome,
        };
        if shared.done.send(done).is_err() || shared.wake.send(Message::Wake).is_err() {
            return;
        }
        if !state.after_report(name, shared) {
            return;
        }
    }
}

/// The message a panic carries (`panic!` with a literal or a format).
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_string())
}

/// What a worker remembers of its dataset between tasks.
struct Remembered {
    /// The dataset's stage graph: the last result of every stage (the last
    /// good layout among them: the source of render-only rebuilds and of the
    /// next warm start) and the state a commit could not write.
    graph: DatasetGraph,
    /// The outputs of the last rebuild when some could not be written: the
    /// whole set, so that a retry leaves it consistent (the ones that were
    /// written are skipped as unchanged).
    unwritten: Option<Vec<Rendered>>,
}

impl Default for Remembered {
    fn default() -> Self {
        Remembered {
            // `NPTREEMAP_NO_CACHE=1` turns reuse off here too, as for `build`.
            graph: DatasetGraph::new(GraphOptions::from_env()),
            unwritten: None,
        }
    }
}

/// What happens to a failed dataset's outputs, truthfully: kept when there
/// are some, else none yet.
pub fn kept(d: &DatasetConfig, missing_input: bool) -> &'static str {
    let any = d.outputs.iter().any(|o| workspace::is_file(&o.path));
    match (any, missing_input) {
        (true, true) => "last outputs kept; rebuilt when the file is back",
        (true, false) => "last good outputs kept",
        (false, true) => "no outputs yet; built when the file is back",
        (false, false) => "no outputs yet",
    }
}

impl Remembered {
    /// What follows a task's report, before the next task: the state
    /// folder (a failure is a late outcome of its own, `Outcome::Unsaved`,
    /// which the daemon retries), the written files made durable (their
    /// fsyncs wait for this: `store::sync_later`) and what the next warm
    /// start needs. False when the daemon is gone.
    fn after_report(&mut self, name: &str, shared: &Shared) -> bool {
        let stored = catch_unwind(AssertUnwindSafe(|| self.graph.finish_commit()));
        if let Ok(Err(e)) = stored {
            let unsaved = Done {
                name: name.to_string(),
                reason: Reason::Retry,
                outcome: Outcome::Unsaved(e),
            };
            if shared.done.send(unsaved).is_err() || shared.wake.send(Message::Wake).is_err() {
                return false;
            }
        }
        if let Err(e) = crate::store::sync_pending() {
            tracing::warn!(dataset = name, error = %e, "cannot sync the files written");
        }
        let _ = catch_unwind(AssertUnwindSafe(|| self.graph.ready_next()));
        true
    }

    fn run(&mut self, name: &str, job: &Task, shared: &Shared) -> Outcome {
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        match &job.next {
            Next::Build(reason) => self.build(name, reason.clone(), job, shared),
            // The graph re-renders from the layout it holds (and lays out
            // only when it holds none: the last build failed).
            Next::Render => self.build(name, Reason::Render, job, shared),
            Next::Retry => self.retry(job, shared),
        }
    }

    /// Hands the dataset's files to its graph, which runs the stages their
    /// changes call for (warm or cold is its decision, `graph::start`), and
    /// writes what changed.
    fn build(&mut self, name: &str, reason: Reason, job: &Task, shared: &Shared) -> Outcome {
        let d = &job.dataset;
        let started = Instant::now();
        let files = match pipeline::read_inputs(d) {
            Ok(files) => files,
            Err(e) => {
                let consequence = kept(d, e.missing_file().is_some());
                return Outcome::Unreadable(e, consequence);
            }
        };
        let mut stages = StageReport::default();
        stages.record(name, Stage::Read, true, ms_since(started), "");
        // The graph keeps the dataset's last layouts (the page's history):
        // it knows each one's fingerprint, which keys the page's render.
        self.graph.keep_history(job.history);
        let bar = Bar::take(shared, &reason, name);
        let mut request = job.request.clone();
        // A stop ends the layout itself (see `progress`).
        request.progress = Some(progress(shared.stop.clone(), bar.sink()));
        let graph_job = graph::Job {
            dataset: d,
            request,
            style: job.style.clone(),
            cold: reason == Reason::Start && shared.cold,
        };
        let result = self.graph.build_from(&graph_job, &files, stages);
        // Done with the reporter: a terminal bar clears before the status
        // line prints.
        drop(bar);
        let mut build = match result {
            Err(BuildError::Layout {
                source: LayoutError::Cancelled,
                ..
            }) => return Outcome::Abandoned,
            Err(e) => return Outcome::Failed(e, kept(d, false)),
            Ok(build) => build,
        };
        // The graph's one "nothing changed" decision (`graph::start`): the
        // inputs, settings, style and history are those the outputs on disk
        // were made from. An event that changed nothing (a touch, a save
        // without edits) then says nothing; a render edit or an open
        // problem is answered with a line.
        if build.layout == LayoutStep::UpToDate && data_only(&reason) && !job.force {
            return Outcome::Unchanged;
        }
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        let (layout, why) = layout_kind(&build.layout);
        let realized = (build.constraints > 0).then_some((build.realized, build.constraints));
        // How far the cells moved from the layout the warm start began with
        // (cheap next to the layout: one pass over the leaves and the
        // realised pairs), figured on a thread of its own while the outputs
        // are written (the commit keeps to this one: it takes the write
        // lock).
        let moved = (build.started_from.clone(), build.computed.clone());
        let (stability, written) = std::thread::scope(|scope| {
            let figures = scope.spawn(|| match &moved {
                (Some(before), Some(after)) => Some(stability(before, after)),
                _ => None,
            });
            // The state folder follows the report (`serve`).
            let written = self.graph.commit_outputs(&graph_job, &mut build);
            // A panic in the figures is a bug of ours: no figures, not a
            // lost build.
            (figures.join().ok().flatten(), written)
        });
        // Kept for the retry only when some output could not be written.
        self.unwritten = (!written.failed.is_empty()).then(|| {
            build
                .outputs
                .iter()
                .filter_map(|o| {
                    o.bytes.as_ref().map(|bytes| Rendered {
                        path: o.path.clone(),
                        bytes: bytes.clone(),
                    })
                })
                .collect()
        });
        let unsaved = if written.failed.is_empty() && self.graph.unstored() {
            Some(std::io::Error::other(
                "the state folder could not be written; retried",
            ))
        } else {
            None
        };
        for note in &build.notes {
            tracing::info!(dataset = name, "{note}");
        }
        let mut warnings = build.warnings;
        warnings.extend(build.notes);
        Outcome::Built(Built {
            reason,
            layout,
            why,
            realized,
            ms: ms_since(job.since.min(started)),
            written,
            warnings,
            unsaved,
            stages: build.stages,
            stability,
        })
    }

    /// Writes again what the last rebuild could not write: its outputs, and
    /// the state folder.
    fn retry(&mut self, job: &Task, shared: &Shared) -> Outcome {
        if self.unwritten.is_none() && !self.graph.unstored() {
            return Outcome::Unchanged;
        }
        let started = Instant::now();
        let written = match self.unwritten.take() {
            Some(mut outputs) => {
                // Only outputs the config still has (it may have changed
                // since; a render of the new config comes first anyway).
                outputs.retain(|r| job.dataset.outputs.iter().any(|o| o.path == r.path));
                let written = pipeline::write_outputs(&outputs);
                if !written.failed.is_empty() {
                    self.unwritten = Some(outputs);
                }
                written
            }
            None => Written::default(),
        };
        let unsaved = if written.failed.is_empty() {
            self.graph.store_again(&job.dataset).err()
        } else {
            None
        };
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        Outcome::Built(Built {
            reason: Reason::Retry,
            layout: LayoutKind::Kept,
            why: None,
            realized: None,
            ms: ms_since(started),
            written,
            warnings: Vec::new(),
            unsaved,
            stages: StageReport::default(),
            stability: None,
        })
    }
}

/// The progress reporter of a task: ends the layout when the daemon stops
/// (at its next report, between ticks and diagrams, well inside the signal
/// handler's grace period), and feeds a start build's bar when it has one.
fn progress(stop: Arc<AtomicBool>, shown: Option<ProgressSink>) -> ProgressSink {
    ProgressSink::new(move |p| {
        if stop.load(Ordering::Relaxed) {
            return ControlFlow::Break(());
        }
        match &shown {
            Some(sink) => (sink.0)(p),
            None => ControlFlow::Continue(()),
        }
    })
}

/// The one progress bar of the start builds (see [`Shared::bar`]); given
/// back when dropped.
struct Bar<'a> {
    shared: &'a Shared,
    sink: Option<ProgressSink>,
}

impl<'a> Bar<'a> {
    fn take(shared: &'a Shared, reason: &Reason, name: &str) -> Self {
        let sink = match (&shared.progress, reason) {
            (Some(make), Reason::Start) if !shared.bar.swap(true, Ordering::AcqRel) => {
                let sink = (make.0)(name);
                if sink.is_none() {
                    shared.bar.store(false, Ordering::Release);
                }
                sink
            }
            _ => None,
        };
        Bar { shared, sink }
    }

    fn sink(&self) -> Option<ProgressSink> {
        self.sink.clone()
    }
}

impl Drop for Bar<'_> {
    fn drop(&mut self) {
        if self.sink.take().is_some() {
            self.shared.bar.store(false, Ordering::Release);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// A task for dataset `d` of `config`.
    fn job_of(config: &Config, d: &DatasetConfig, next: Next) -> Task {
        Task {
            since: Instant::now(),
            next,
            request: config.request(d),
            style: config.style(d),
            dataset: d.clone(),
            force: false,
            history: config.history,
        }
    }

    /// What a worker shares, with the ends its outcomes and wake-ups go to.
    fn shared() -> (Shared, Receiver<Done>, Receiver<Message>) {
        let (done, outcomes) = std::sync::mpsc::channel();
        let (wake, woken) = std::sync::mpsc::channel();
        let shared = Shared {
            done,
            wake,
            stop: Arc::new(AtomicBool::new(false)),
            cold: false,
            progress: None,
            bar: AtomicBool::new(false),
        };
        (shared, outcomes, woken)
    }

    /// Issue 21 item 3: a task that panics is its dataset's failure, with
    /// the panic's message; the worker forgets what the task left behind
    /// and goes on with the next task.
    #[test]
    fn a_panicking_task_is_a_failure_and_the_worker_goes_on() {
        let (shared, outcomes, woken) = shared();
        let config = Config::from_str(
            "datasets:\n  - name: d\n    format: hierarchy-json\n    files: {hierarchy: t.json}\n    outputs: [{path: out/d.svg}]\n",
            std::path::Path::new("/nowhere"),
        )
        .expect("config");
        let d = config.datasets[0].clone();
        let job = |next| job_of(&config, &d, next);
        let (jobs, rx) = std::sync::mpsc::channel();
        jobs.send(job(Next::Build(Reason::Start))).expect("send");
        jobs.send(job(Next::Retry)).expect("send");
        drop(jobs);
        let mut calls = 0;
        serve("d", &rx, &shared, &mut |state, _job, _shared| {
            calls += 1;
            if calls == 1 {
                state.unwritten = Some(Vec::new());
                panic!("bad input made a bug show");
            }
            assert!(state.unwritten.is_none(), "the panicked task's state was dropped");
            Outcome::Unchanged
        });
        let outcomes: Vec<Done> = outcomes.try_iter().collect();
        assert_eq!(outcomes.len(), 2);
        assert_eq!(woken.try_iter().count(), 2);
        match &outcomes[0].outcome {
            Outcome::Panicked(message) => assert_eq!(message, "bad input made a bug show"),
            _ => panic!("not a panic outcome"),
        }
        assert!(matches!(outcomes[1].outcome, Outcome::Unchanged));
    }

    /// A scratch copy of the countries example, with SVG and layout JSON
    /// outputs only (quick), and its config.
    fn countries(tag: &str) -> (std::path::PathBuf, Config) {
        let dir = std::env::temp_dir().join(format!("nptreemap-worker-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        let example = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/countries");
        for f in ["countries.csv", "borders.csv"] {
            std::fs::copy(example.join(f), dir.join(f)).expect("copy");
        }
        let text = std::fs::read_to_string(example.join("nptreemap.yaml"))
            .expect("config")
            .replace("      - path: out/countries.png\n", "");
        std::fs::write(dir.join("nptreemap.yaml"), text).expect("config");
        let config = Config::from_path(&dir.join("nptreemap.yaml")).expect("config");
        (dir, config)
    }

    /// Issue 30 item 6: "nothing changed" covers every input of every stage,
    /// not only the input bytes: an edit that rewrote a file with the same
    /// bytes, handed over with a config whose title (or output list) changed
    /// meanwhile, draws the new title (it was skipped, and the title stayed
    /// old for good); with the same config as well it is skipped, and with
    /// the outputs reordered too (the same files), while an added output is
    /// made. One decision (the graph's) covers it all.
    /// A task run as `serve` runs it: then what follows its report.
    fn run_reported(state: &mut Remembered, job: &Task, shared: &Shared) -> Outcome {
        let outcome = state.run("countries", job, shared);
        assert!(state.after_report("countries", shared));
        outcome
    }

    #[test]
    fn unchanged_bytes_under_a_changed_config_are_not_skipped() {
        let (dir, config) = countries("skip");
        let (shared, _outcomes, _woken) = shared();
        let mut state = Remembered::default();
        let edit = || Next::Build(Reason::Data(vec!["countries.csv".to_string()]));
        let d = config.datasets[0].clone();
        let first = run_reported(&mut state, &job_of(&config, &d, Next::Build(Reason::Start)), &shared);
        assert!(matches!(first, Outcome::Built(_)));
        let same = run_reported(&mut state, &job_of(&config, &d, edit()), &shared);
        assert!(matches!(same, Outcome::Unchanged), "nothing changed: skipped");

        let text = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("config");
        let titled = Config::from_str(
            &format!("render: {{title: A new title}}\n{text}"),
            &dir,
        )
        .expect("config");
        let d = titled.datasets[0].clone();
        let Outcome::Built(built) = run_reported(&mut state, &job_of(&titled, &d, edit()), &shared)
        else {
            panic!("the title change was skipped");
        };
        let svg = dir.join("out/countries.svg");
        assert!(built.written.written.contains(&svg), "{:?}", built.written);
        assert!(std::fs::read_to_string(&svg).expect("svg").contains("A new title"));

        // The same outputs in another order make the same files: nothing
        // to do. One more output is made.
        let mut moved = titled.clone();
        moved.datasets[0].outputs.reverse();
        let d = moved.datasets[0].clone();
        let outcome = run_reported(&mut state, &job_of(&moved, &d, edit()), &shared);
        assert!(matches!(outcome, Outcome::Unchanged), "reordered outputs make the same files");
        let mut extra = moved.datasets[0].outputs.last().expect("an SVG output").clone();
        extra.path = dir.join("out/extra.svg");
        moved.datasets[0].outputs.push(extra);
        let d = moved.datasets[0].clone();
        let Outcome::Built(built) = run_reported(&mut state, &job_of(&moved, &d, edit()), &shared)
        else {
            panic!("an output added was skipped");
        };
        assert_eq!(built.written.written, vec![dir.join("out/extra.svg")]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Issue 22 item 1: the daemon's worker hands its dataset's changes to
    /// the stage graph it keeps between rebuilds: a weight edit recomputes
    /// no constraint and lays out warm (with the stability figures of the
    /// move), and a bad edit's event names the file and line. Fails with
    /// the caches off (`NPTREEMAP_NO_CACHE=1`), and on the worker that
    /// re-composed the pipeline (no stage report).
    #[test]
    fn a_weight_edit_in_watch_recomputes_no_constraint() {
        let (dir, config) = countries("weight");
        let d = config.datasets[0].clone();
        let job = |next| job_of(&config, &d, next);
        let (shared, outcomes, _woken) = shared();
        let shared = Arc::new(shared);
        let (jobs, rx) = std::sync::mpsc::channel();
        let worker = std::thread::spawn(move || {
            serve("countries", &rx, &shared, &mut |state, job, shared| {
                state.run("countries", job, shared)
            });
        });
        let next = |task| {
            jobs.send(job(task)).expect("send");
            let done = outcomes
                .recv_timeout(std::time::Duration::from_secs(300))
                .expect("an outcome");
            assert_eq!(done.name, "countries");
            done
        };

        let first = next(Next::Build(Reason::Start));
        let Outcome::Built(built) = &first.outcome else {
            panic!("the start build failed");
        };
        assert_eq!(built.stages.ran(Stage::Constraints), 1, "{:?}", built.stages);
        assert!(built.written.failed.is_empty());

        let csv = dir.join("countries.csv");
        let text = std::fs::read_to_string(&csv).expect("csv");
        let edited = text.replacen("AU,Australia,24992369,", "AU,Australia,27491606,", 1);
        assert_ne!(edited, text);
        std::fs::write(&csv, &edited).expect("edit");
        let second = next(Next::Build(Reason::Data(vec!["countries.csv".to_string()])));
        let Outcome::Built(built) = &second.outcome else {
            panic!("the rebuild failed");
        };
        let s = &built.stages;
        assert_eq!(s.ran(Stage::Constraints), 0, "{s:?}");
        assert_eq!(s.reused(Stage::Constraints), 1, "{s:?}");
        assert_eq!(built.layout, LayoutKind::Warm, "{s:?}");
        assert!(!built.written.written.is_empty(), "the edit shows");
        let moved = built.stability.expect("stability figures of a warm layout");
        assert!(moved.leaves > 0 && moved.unchanged + 1 == moved.leaves, "{moved:?}");
        let event = super::super::event::of("countries", &second.reason, &second.outcome)
            .expect("an event");
        let outputs = event.result.expect("ok");
        assert_eq!(outputs.written, built.written.written);

        let bad_line = edited.lines().count() + 1;
        std::fs::write(&csv, format!("{edited}XX,Nowhere,not-a-number,Asia\n")).expect("bad");
        let third = next(Next::Build(Reason::Data(vec!["countries.csv".to_string()])));
        let event = super::super::event::of("countries", &third.reason, &third.outcome)
            .expect("an event");
        let failure = event.result.expect_err("a bad edit fails");
        assert_eq!(failure.file.as_deref(), Some(csv.as_path()), "{failure:?}");
        assert_eq!(failure.line, Some(bad_line), "{failure:?}");
        assert!(failure.message.contains("countries.csv"), "{failure:?}");

        drop(jobs);
        worker.join().expect("the worker ends");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
