//! One dataset's rebuilds, on a thread of its own (issue 21 item 3), so that
//! no dataset waits for another: a slow adapter or a long layout holds up
//! only its own dataset, and the daemon's loop stays free to batch events,
//! dispatch work and report. A worker keeps its dataset's last good layout
//! (the source of render-only rebuilds and of the next warm start) and the
//! outputs it could not write; it runs one task at a time through the
//! [`pipeline`]'s stages and answers each with an [`Outcome`]. A panic in a
//! task is caught and is that dataset's failure: the daemon lives on.
//!
//! [`pipeline`]: crate::pipeline

use std::ops::ControlFlow;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::Instant;

use crate::config::DatasetConfig;
use crate::layout::{Computed, LayoutError, ProgressSink, Request, Start};
use crate::pipeline::{self, BuildError, Rendered, Written};
use crate::render::Style;

use super::change::Reason;
use super::queue::Next;
use super::status::{escape, LayoutKind};
use super::watcher::Message;
use super::FirstBuildProgress;

/// The stack of a worker thread: as large as a main thread's, since the
/// readers and the layout ran on the main thread before and their depth
/// limits were set there.
const STACK: usize = 8 << 20;

/// One task for a worker, with the config it runs under.
pub struct Job {
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
}

/// A finished rebuild that wrote (or tried to write) its outputs.
pub struct Built {
    /// Why it ran.
    pub reason: Reason,
    /// How the layout came about.
    pub layout: LayoutKind,
    /// Wall time, ms.
    pub ms: f64,
    /// What writing the outputs did.
    pub written: Written,
    /// The input warnings of the dataset, one line each.
    pub warnings: Vec<String>,
    /// Why the layout could not be stored for warm starts, if it could not.
    pub unsaved: Option<std::io::Error>,
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
}

/// A task's outcome, for the daemon's loop.
pub struct Done {
    /// The dataset.
    pub name: String,
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
    jobs: Sender<Job>,
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
    pub fn send(&mut self, job: Job) -> bool {
        let sent = self.jobs.send(job).is_ok();
        self.busy = sent;
        sent
    }
}

/// What runs a task (a parameter so that tests can make one panic).
type Run<'a> = dyn FnMut(&mut State, &Job, &Shared) -> Outcome + 'a;

/// The worker's loop: one task at a time until the daemon drops its end.
fn serve(name: &str, jobs: &Receiver<Job>, shared: &Shared, run: &mut Run<'_>) {
    let mut state = State::default();
    for job in jobs {
        let outcome = catch_unwind(AssertUnwindSafe(|| run(&mut state, &job, shared)))
            .unwrap_or_else(|panic| {
                // What the task left half-done cannot be trusted: start over
                // (the next rebuild is a full one, cold unless a layout is
                // stored).
                state = State::default();
                Outcome::Panicked(panic_message(panic.as_ref()))
            });
        let done = Done {
            name: name.to_string(),
            outcome,
        };
        if shared.done.send(done).is_err() || shared.wake.send(Message::Wake).is_err() {
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
#[derive(Default)]
struct State {
    /// The last good layout.
    computed: Option<Computed>,
    /// Fingerprint of the input bytes last built (or last failed on), so an
    /// event that changed nothing (a touch, a save without edits) costs nothing.
    fingerprint: Option<u64>,
    /// The outputs of the last rebuild when some could not be written: the
    /// whole set, so that a retry leaves it consistent (the ones that were
    /// written are skipped as unchanged).
    unwritten: Option<Vec<Rendered>>,
    /// Whether the last layout could not be stored for warm starts.
    unsaved: bool,
}

/// What happens to a failed dataset's outputs, truthfully: kept when there
/// are some, else none yet.
pub fn kept(d: &DatasetConfig, missing_input: bool) -> &'static str {
    let any = d.outputs.iter().any(|o| o.path.is_file());
    match (any, missing_input) {
        (true, true) => "last outputs kept; rebuilt when the file is back",
        (true, false) => "last good outputs kept",
        (false, true) => "no outputs yet; built when the file is back",
        (false, false) => "no outputs yet",
    }
}

impl State {
    fn run(&mut self, name: &str, job: &Job, shared: &Shared) -> Outcome {
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        match &job.next {
            Next::Build(reason) => self.build(name, reason.clone(), job, shared),
            Next::Render => match self.computed.take() {
                Some(computed) => self.render(computed, job, shared),
                // No good layout yet (its last build failed): a full build.
                None => self.build(name, Reason::Render, job, shared),
            },
            Next::Retry => self.retry(job, shared),
        }
    }

    /// Reads, lays out (warm when a previous layout exists), renders and
    /// writes the dataset.
    fn build(&mut self, name: &str, reason: Reason, job: &Job, shared: &Shared) -> Outcome {
        let d = &job.dataset;
        let started = Instant::now();
        let files = match pipeline::read_inputs(d) {
            Ok(files) => files,
            Err(e) => {
                self.fingerprint = None;
                let consequence = kept(d, e.missing_file().is_some());
                return Outcome::Unreadable(e, consequence);
            }
        };
        let fingerprint = fingerprint(&files);
        let data_only = matches!(reason, Reason::Data(_) | Reason::Reload);
        if data_only
            && self.fingerprint == Some(fingerprint)
            && self.computed.is_some()
            && !job.force
        {
            tracing::debug!(dataset = name, "inputs unchanged; nothing to do");
            return Outcome::Unchanged;
        }
        self.fingerprint = Some(fingerprint);
        // Warm from the last good layout in memory; at start, from the one
        // stored beside the outputs (unless --cold).
        let mut request = job.request.clone();
        let mut warnings = Vec::new();
        request.previous = match &self.computed {
            Some(computed) => Some(Arc::new(computed.previous())),
            None if reason == Reason::Start && shared.cold => None,
            None => {
                let stored = pipeline::stored_layout(d);
                warnings.extend(stored.warning);
                stored.previous
            }
        };
        let read_ms = ms_since(started);
        let bar = Bar::take(shared, &reason, name);
        request.progress = Some(progress(shared.stop.clone(), bar.sink()));
        let result = pipeline::parse_inputs(d, &files).and_then(|dataset| {
            let parsed = Instant::now();
            warnings.extend(pipeline::warnings(&files, &dataset));
            if shared.stopping() {
                return Ok(None);
            }
            // A stop ends the layout itself (see `progress`).
            let computed = match pipeline::lay_out(d, &dataset, &request) {
                Err(BuildError::Layout {
                    source: LayoutError::Cancelled,
                    ..
                }) => return Ok(None),
                other => other?,
            };
            // Done with the reporter: a terminal bar clears before the
            // status line prints.
            request.progress = None;
            drop(bar);
            let laid_out = Instant::now();
            if shared.stopping() {
                return Ok(None);
            }
            let outputs = pipeline::render_outputs(&computed, &job.style, &d.outputs)?;
            tracing::debug!(
                dataset = name,
                read_ms,
                parse_ms = ms_between(started, parsed) - read_ms,
                layout_ms = ms_between(parsed, laid_out),
                render_ms = ms_since(laid_out),
                "rebuilt in memory"
            );
            Ok(Some((computed, outputs)))
        });
        match result {
            Ok(None) => Outcome::Abandoned,
            Ok(Some((computed, outputs))) => {
                let layout = match computed.start {
                    Start::Warm { .. } => LayoutKind::Warm,
                    Start::Cold | Start::Refused(_) => LayoutKind::Cold,
                };
                self.finish(reason, layout, started, computed, outputs, warnings, job, shared)
            }
            Err(e) => Outcome::Failed(e, kept(d, false)),
        }
    }

    /// Renders the last good layout again (a render-only config change).
    fn render(&mut self, computed: Computed, job: &Job, shared: &Shared) -> Outcome {
        let started = Instant::now();
        match pipeline::render_outputs(&computed, &job.style, &job.dataset.outputs) {
            Ok(outputs) => self.finish(
                Reason::Render,
                LayoutKind::Reused,
                started,
                computed,
                outputs,
                Vec::new(),
                job,
                shared,
            ),
            Err(e) => {
                self.computed = Some(computed);
                Outcome::Failed(e, kept(&job.dataset, false))
            }
        }
    }

    /// Writes the outputs that changed (atomically) and stores the layout;
    /// keeps the outputs for a retry when some could not be written.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &mut self,
        reason: Reason,
        layout: LayoutKind,
        started: Instant,
        computed: Computed,
        outputs: Vec<Rendered>,
        warnings: Vec<String>,
        job: &Job,
        shared: &Shared,
    ) -> Outcome {
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        let written = pipeline::write_outputs(&outputs);
        self.unwritten = (!written.failed.is_empty()).then_some(outputs);
        let unsaved = pipeline::store_layout(&job.dataset, &computed).err();
        self.unsaved = unsaved.is_some();
        self.computed = Some(computed);
        Outcome::Built(Built {
            reason,
            layout,
            ms: ms_since(started),
            written,
            warnings,
            unsaved,
        })
    }

    /// Writes again what the last rebuild could not write: its outputs, and
    /// the stored layout.
    fn retry(&mut self, job: &Job, shared: &Shared) -> Outcome {
        if self.unwritten.is_none() && !self.unsaved {
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
        let unsaved = match (&self.computed, self.unsaved) {
            (Some(computed), true) => pipeline::store_layout(&job.dataset, computed).err(),
            _ => None,
        };
        self.unsaved = unsaved.is_some();
        if shared.stopping() {
            return Outcome::Abandoned;
        }
        Outcome::Built(Built {
            reason: Reason::Retry,
            layout: LayoutKind::Kept,
            ms: ms_since(started),
            written,
            warnings: Vec::new(),
            unsaved,
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

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1000.0
}

fn ms_between(a: Instant, b: Instant) -> f64 {
    b.duration_since(a).as_secs_f64() * 1000.0
}

/// A fingerprint of a dataset's input bytes (roles, paths and contents).
fn fingerprint(files: &[pipeline::InputFile]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for f in files {
        f.role.hash(&mut h);
        f.path.hash(&mut h);
        f.bytes.hash(&mut h);
    }
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// Issue 21 item 3: a task that panics is its dataset's failure, with
    /// the panic's message; the worker forgets what the task left behind
    /// and goes on with the next task.
    #[test]
    fn a_panicking_task_is_a_failure_and_the_worker_goes_on() {
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
        let config = Config::from_str(
            "datasets:\n  - name: d\n    format: hierarchy-json\n    files: {hierarchy: t.json}\n    outputs: [{path: out/d.svg}]\n",
            std::path::Path::new("/nowhere"),
        )
        .expect("config");
        let d = config.datasets[0].clone();
        let job = |next| Job {
            next,
            request: config.request(&d),
            style: config.style(&d),
            dataset: d.clone(),
            force: false,
        };
        let (jobs, rx) = std::sync::mpsc::channel();
        jobs.send(job(Next::Build(Reason::Start))).expect("send");
        jobs.send(job(Next::Retry)).expect("send");
        drop(jobs);
        let mut calls = 0;
        serve("d", &rx, &shared, &mut |state, _job, _shared| {
            calls += 1;
            if calls == 1 {
                state.unsaved = true;
                panic!("bad input made a bug show");
            }
            assert!(!state.unsaved, "the panicked task's state was dropped");
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
}
