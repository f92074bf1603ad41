//! `nptreemap watch`: the long-running loop that keeps a config's pictures
//! current (issue 6). Orchestration only: wait for a batch of file events
//! ([`watcher`]), sort it into work ([`change`]), run the [`pipeline`] for
//! each affected dataset, report one [`status`] line each, go on. A bad edit
//! is a reported problem that keeps the last good config and outputs; only a
//! failure to start (no usable config, no watcher) ends the loop with an error.
//!
//! [`pipeline`]: crate::pipeline

/// What a batch of changed paths means: relayout, re-render, added, removed.
pub mod change;
/// The status lines.
pub mod status;
/// notify over directories, and batching of its events.
pub mod watcher;

use std::collections::{BTreeMap, BTreeSet};
use std::hash::{Hash, Hasher};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::config::{Config, ConfigFileError, DatasetConfig};
use crate::layout::{Computed, LayoutError, ProgressSink, Start};
use crate::pipeline::{self, BuildError, Fault, Rendered};
use change::{ChangeSet, Reason};
use status::{LayoutKind, Status};
use watcher::{Batch, DirWatcher, Message, Timing};

/// How the daemon runs.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Lay every dataset out from scratch at start instead of warm from the
    /// layout stored beside its outputs. Later rebuilds start warm from the
    /// last good layout either way.
    pub cold: bool,
    /// Event batching windows.
    pub timing: Timing,
    /// Set (by a signal handler) when the daemon should stop: checked between
    /// the stages of a rebuild, so a rebuild under way writes nothing more
    /// and the loop ends. The [`Message::Stop`] that goes with it wakes an
    /// idle loop.
    pub stop: Option<Arc<AtomicBool>>,
    /// Gives each dataset's first build (the one at start, which may be a
    /// long cold layout) a progress reporter, such as the binary's terminal
    /// bar; `None` for none. Later rebuilds start warm and are short.
    pub first_build_progress: Option<FirstBuildProgress>,
}

/// A maker of progress reporters by dataset name, for
/// [`Options::first_build_progress`]; it returns `None` to report nothing.
#[derive(Clone)]
pub struct FirstBuildProgress(pub Arc<MakeProgress>);

/// What [`FirstBuildProgress`] holds: a dataset's name to its reporter.
pub type MakeProgress = dyn Fn(&str) -> Option<ProgressSink> + Send + Sync;

impl std::fmt::Debug for FirstBuildProgress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FirstBuildProgress")
    }
}

/// Why the daemon could not start (or had to stop).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DaemonError {
    /// The config could not be read at start: there is nothing to watch.
    #[error(transparent)]
    Config(#[from] ConfigFileError),
    /// The config's outputs are unsafe (over an input, the config, another
    /// output or a special file): nothing is built.
    #[error(transparent)]
    Outputs(BuildError),
    /// The config's path cannot be made absolute.
    #[error("{}: {source}", .path.display())]
    Path {
        /// The config path given.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The operating system's file watcher could not be set up.
    #[error("cannot watch files: {0}")]
    Watcher(#[from] notify::Error),
}

impl DaemonError {
    /// Whose fault it is that the daemon could not start: the config's
    /// (exit code 2) or the system's (1).
    pub fn fault(&self) -> Fault {
        match self {
            DaemonError::Config(_) | DaemonError::Outputs(_) => Fault::Input,
            DaemonError::Path { .. } | DaemonError::Watcher(_) => Fault::System,
        }
    }
}

/// What the daemon remembers of a dataset between rebuilds.
#[derive(Default)]
struct DatasetState {
    /// The last good layout: the source of render-only rebuilds, and (as
    /// [`Computed::previous`]) the warm start of the next layout.
    computed: Option<Computed>,
    /// Fingerprint of the input bytes last built (or last failed on), so an
    /// event that changed nothing (a touch, a save without edits) costs nothing.
    fingerprint: Option<u64>,
}

/// The daemon's state: the last good config and each dataset's last build.
struct Daemon<'a> {
    config_path: PathBuf,
    config: Config,
    options: Options,
    states: BTreeMap<String, DatasetState>,
    report: &'a mut dyn FnMut(Status),
    /// Parse failures not reported yet, by dataset, with when they happened:
    /// a file read while a writer is still at it (editors and scripts writing
    /// in place truncate first) fails to parse, and the write's own events
    /// bring a rebuild that succeeds. A failure is reported only when the
    /// inputs then stay quiet for [`SETTLE`]; a good rebuild forgets it.
    pending: BTreeMap<String, (Status, Instant)>,
    /// When the last relevant event arrived (for [`SETTLE`]).
    last_event: Instant,
    /// The last problem reported per subject (a dataset or `config`), until
    /// it is fixed: the same problem is not reported twice in a row, and the
    /// fix is announced ("ok again").
    troubled: BTreeMap<String, String>,
}

/// How long the inputs must stay unchanged after a parse failure before it
/// is reported (see `Daemon::pending`): long enough for a writer descheduled
/// mid-write on a busy machine, short for a person fixing a typo.
const SETTLE: Duration = Duration::from_millis(1000);

/// How often watched folders are looked at between events: a folder deleted
/// and made again, or one missing at start, is watched again within this.
const POLL: Duration = Duration::from_millis(500);

/// A channel for [`run`]: give the sender to whatever should stop the daemon
/// (a signal handler sends [`Message::Stop`]) or reload it ([`Message::Reload`]).
pub fn channel() -> (Sender<Message>, Receiver<Message>) {
    std::sync::mpsc::channel()
}

/// Runs the daemon on `config_path` until a [`Message::Stop`] arrives on
/// `rx` (whose sender `tx` also feeds the file watcher). Builds everything
/// once, then rebuilds what each batch of changes affects; a
/// [`Message::Reload`] reads the config and every input again. Every line of
/// output goes to `report`.
pub fn run(
    config_path: &Path,
    options: Options,
    tx: Sender<Message>,
    rx: &Receiver<Message>,
    report: &mut dyn FnMut(Status),
) -> Result<(), DaemonError> {
    let config_path = std::path::absolute(config_path).map_err(|source| DaemonError::Path {
        path: config_path.to_path_buf(),
        source,
    })?;
    let config = Config::from_path(&config_path)?;
    let (reads, writes) = pipeline::files_of(&config_path, &config.datasets);
    pipeline::check_outputs(&reads, &writes).map_err(DaemonError::Outputs)?;
    pipeline::remove_stale_temps(&writes);
    let mut watcher = DirWatcher::new(tx)?;
    let mut daemon = Daemon {
        config_path,
        config,
        options,
        states: BTreeMap::new(),
        report,
        pending: BTreeMap::new(),
        last_event: Instant::now(),
        troubled: BTreeMap::new(),
    };
    daemon.sync_watches(&mut watcher);
    (daemon.report)(Status::Watching {
        config: daemon.config_path.clone(),
        datasets: daemon.config.datasets.len(),
        dirs: watcher.watched().len(),
    });
    let start: Vec<String> = daemon
        .config
        .datasets
        .iter()
        .map(|d| d.name.clone())
        .collect();
    for name in start {
        if daemon.stopping() {
            break;
        }
        daemon.rebuild(&name, Reason::Start);
    }
    while !daemon.stopping() {
        let inputs = change::inputs_of(&daemon.config, &daemon.config_path);
        let batch = watcher::next_batch(
            rx,
            daemon.options.timing,
            &|p: &Path| inputs.contains(p),
            Some(daemon.wait()),
        );
        let (mut paths, reload) = match batch {
            Batch::Stop => break,
            Batch::Idle => (BTreeSet::new(), false),
            Batch::Paths(paths) => (paths, false),
            Batch::Reload(paths) => (paths, true),
        };
        // Folders deleted and made again (or appeared) since the last look:
        // their files may have changed without an event.
        for dir in watcher.check() {
            paths.extend(inputs.iter().filter(|p| p.parent() == Some(&dir)).cloned());
        }
        if !paths.is_empty() {
            daemon.last_event = Instant::now();
            tracing::debug!(?paths, "batch");
        }
        let mut work = ChangeSet::default();
        if reload || paths.contains(&daemon.config_path) {
            if let Some(set) = daemon.reload_config(reload) {
                work = set;
                daemon.sync_watches(&mut watcher);
            }
        }
        for (name, reason) in change::touched(&daemon.config, &paths).relayout {
            work.relayout.entry(name).or_insert(reason);
        }
        if reload {
            for d in &daemon.config.datasets {
                work.relayout
                    .entry(d.name.clone())
                    .or_insert(Reason::Reload);
            }
        }
        daemon.apply(work);
        daemon.report_settled();
    }
    // No adapter outlives the daemon.
    crate::exec::terminate_all();
    (daemon.report)(Status::Stopped);
    Ok(())
}

impl Daemon<'_> {
    fn dataset(&self, name: &str) -> Option<&DatasetConfig> {
        self.config.datasets.iter().find(|d| d.name == name)
    }

    /// Whether a stop was asked for (see [`Options::stop`]).
    fn stopping(&self) -> bool {
        self.options
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// How long the loop may wait for events: until the next pending problem
    /// is due, and at most [`POLL`].
    fn wait(&self) -> Duration {
        let now = Instant::now();
        self.pending
            .values()
            .map(|(_, at)| (*at).max(self.last_event) + SETTLE)
            .map(|due| due.saturating_duration_since(now))
            .fold(POLL, Duration::min)
    }

    /// Reports the pending problems whose inputs stayed quiet for [`SETTLE`].
    fn report_settled(&mut self) {
        let now = Instant::now();
        let due: Vec<String> = self
            .pending
            .iter()
            .filter(|(_, (_, at))| now >= (*at).max(self.last_event) + SETTLE)
            .map(|(name, _)| name.clone())
            .collect();
        for name in due {
            if let Some((problem, _)) = self.pending.remove(&name) {
                self.problem(&name, problem);
            }
        }
    }

    /// Reports a problem about `subject`, unless it is the one reported last.
    fn problem(&mut self, subject: &str, problem: Status) {
        let text = problem.to_string();
        if self.troubled.get(subject) == Some(&text) {
            return;
        }
        self.troubled.insert(subject.to_string(), text);
        (self.report)(problem);
    }

    /// Forgets `subject`'s problem; true when there was one (it is ok again).
    fn fixed(&mut self, subject: &str) -> bool {
        self.troubled.remove(subject).is_some()
    }

    /// Watches the folders of the config and of every input; reports folders
    /// that cannot be watched (missing ones are polled until they exist).
    fn sync_watches(&mut self, watcher: &mut DirWatcher) {
        let dirs = change::dirs_of(&change::inputs_of(&self.config, &self.config_path));
        for (dir, e) in watcher.sync(&dirs) {
            let subject = dir.display().to_string();
            (self.report)(Status::problem(subject, &e, "watched as soon as it exists"));
        }
    }

    /// Reads the config again (it changed, or `forced` by SIGHUP). One that
    /// does not parse, or whose outputs are unsafe, is reported and the
    /// previous one kept; otherwise returns what changed.
    fn reload_config(&mut self, forced: bool) -> Option<ChangeSet> {
        let new = match Config::from_path(&self.config_path) {
            Ok(new) => new,
            Err(e) => {
                self.problem(
                    "config",
                    Status::problem("config", &e, "previous config kept"),
                );
                return None;
            }
        };
        let (reads, writes) = pipeline::files_of(&self.config_path, &new.datasets);
        if let Err(e) = pipeline::check_outputs(&reads, &writes) {
            self.problem(
                "config",
                Status::problem("config", &e, "previous config kept"),
            );
            return None;
        }
        pipeline::remove_stale_temps(&writes);
        let set = change::diff(&self.config, &new);
        self.config = new;
        let again = self.fixed("config");
        let message = match (again, forced) {
            (true, true) => "ok again; reloaded on SIGHUP",
            (true, false) => "ok again",
            (false, true) => "reloaded on SIGHUP",
            (false, false) => "",
        };
        if !message.is_empty() {
            (self.report)(Status::Note {
                subject: "config".to_string(),
                message: message.to_string(),
            });
        }
        Some(set)
    }

    fn apply(&mut self, work: ChangeSet) {
        for name in &work.removed {
            self.states.remove(name);
            self.pending.remove(name);
            self.troubled.remove(name);
            (self.report)(Status::Note {
                subject: name.clone(),
                message: "no longer in the config; its outputs are left as they are".to_string(),
            });
        }
        for (name, reason) in work.relayout {
            if self.stopping() {
                return;
            }
            self.rebuild(&name, reason);
        }
        for name in work.rerender {
            if self.stopping() {
                return;
            }
            self.rerender(&name);
        }
    }

    /// What happens to a failed dataset's outputs, truthfully: kept when
    /// there are some, else none yet.
    fn kept(d: &DatasetConfig, missing_input: bool) -> &'static str {
        let any = d.outputs.iter().any(|o| o.path.is_file());
        match (any, missing_input) {
            (true, true) => "last outputs kept; rebuilt when the file is back",
            (true, false) => "last good outputs kept",
            (false, true) => "no outputs yet; built when the file is back",
            (false, false) => "no outputs yet",
        }
    }

    /// Reads, lays out (warm when a previous layout exists), renders and
    /// writes one dataset; reports one line (and its warnings). A stop asked
    /// for meanwhile ends it between stages, writing nothing.
    fn rebuild(&mut self, name: &str, reason: Reason) {
        let Some(d) = self.dataset(name).cloned() else {
            return;
        };
        let started = Instant::now();
        let files = match pipeline::read_inputs(&d) {
            Ok(files) => files,
            Err(e) => {
                let consequence = Self::kept(&d, e.missing_file().is_some());
                self.states.entry(name.to_string()).or_default().fingerprint = None;
                self.problem(name, Status::problem(name, &e, consequence));
                return;
            }
        };
        let fingerprint = fingerprint(&files);
        let troubled = self.troubled.contains_key(name);
        let state = self.states.entry(name.to_string()).or_default();
        let data_only = matches!(reason, Reason::Data(_) | Reason::Reload);
        if data_only
            && state.fingerprint == Some(fingerprint)
            && state.computed.is_some()
            && !troubled
        {
            tracing::debug!(dataset = name, "inputs unchanged; nothing to do");
            return;
        }
        state.fingerprint = Some(fingerprint);
        // Warm from the last good layout in memory; at start, from the one
        // stored beside the outputs (unless --cold).
        let mut request = self.config.request(&d);
        let mut warnings = Vec::new();
        request.previous = match &state.computed {
            Some(computed) => Some(Arc::new(computed.previous())),
            None if reason == Reason::Start && self.options.cold => None,
            None => {
                let stored = pipeline::stored_layout(&d);
                warnings.extend(stored.warning);
                stored.previous
            }
        };
        let style = self.config.style(&d);
        let read_ms = ms_since(started);
        let stop = self.options.stop.clone();
        let stopping = || stop.as_ref().is_some_and(|s| s.load(Ordering::Relaxed));
        // A SIGTERM ends a running layout at its next progress report
        // (between ticks and diagrams), well inside the signal handler's
        // grace period; the abandoned rebuild writes nothing.
        // The first build also feeds the caller's reporter (a terminal bar).
        let shown = match (&self.options.first_build_progress, &reason) {
            (Some(make), Reason::Start) => (make.0)(name),
            _ => None,
        };
        if stop.is_some() || shown.is_some() {
            let flag = stop.clone();
            request.progress = Some(ProgressSink::new(move |p| {
                if flag.as_ref().is_some_and(|f| f.load(Ordering::Relaxed)) {
                    return ControlFlow::Break(());
                }
                match &shown {
                    Some(sink) => (sink.0)(p),
                    None => ControlFlow::Continue(()),
                }
            }));
        }
        let result = pipeline::parse_inputs(&d, &files).and_then(|dataset| {
            let parsed = Instant::now();
            warnings.extend(pipeline::warnings(&files, &dataset));
            if stopping() {
                return Ok(None);
            }
            // A SIGTERM ends the layout itself (see `request.progress`).
            let computed = match pipeline::lay_out(&d, &dataset, &request) {
                Err(BuildError::Layout {
                    source: LayoutError::Cancelled,
                    ..
                }) => return Ok(None),
                other => other?,
            };
            // Done with the reporter: a terminal bar clears before the
            // status line prints.
            request.progress = None;
            let laid_out = Instant::now();
            if stopping() {
                return Ok(None);
            }
            let outputs = pipeline::render_outputs(&computed, &style, &d.outputs)?;
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
            Ok(None) => tracing::debug!(dataset = name, "stopping; rebuild abandoned"),
            Ok(Some((computed, outputs))) => {
                if self.stopping() {
                    return;
                }
                for message in warnings {
                    (self.report)(Status::Warning {
                        subject: name.to_string(),
                        message,
                    });
                }
                let layout = match computed.start {
                    Start::Warm { .. } => LayoutKind::Warm,
                    Start::Cold | Start::Refused(_) => LayoutKind::Cold,
                };
                self.finish(name, reason, layout, started, computed, outputs);
            }
            Err(e) if e.fault() == Fault::Input => {
                tracing::debug!(dataset = name, error = %e, "input refused; reported unless the input changes again");
                self.pending.insert(
                    name.to_string(),
                    (
                        Status::problem(name, &e, Self::kept(&d, false)),
                        Instant::now(),
                    ),
                );
            }
            Err(e) => {
                let consequence = Self::kept(&d, false);
                self.problem(name, Status::problem(name, &e, consequence));
            }
        }
    }

    /// Renders a dataset's stored layout again (a render-only config change).
    fn rerender(&mut self, name: &str) {
        let Some(d) = self.dataset(name).cloned() else {
            return;
        };
        let Some(computed) = self.states.get_mut(name).and_then(|s| s.computed.take()) else {
            // No good layout yet (its last build failed): a full build.
            self.rebuild(name, Reason::Render);
            return;
        };
        let started = Instant::now();
        match pipeline::render_outputs(&computed, &self.config.style(&d), &d.outputs) {
            Ok(outputs) => self.finish(
                name,
                Reason::Render,
                LayoutKind::Reused,
                started,
                computed,
                outputs,
            ),
            Err(e) => {
                let consequence = Self::kept(&d, false);
                self.problem(name, Status::problem(name, &e, consequence));
                if let Some(state) = self.states.get_mut(name) {
                    state.computed = Some(computed);
                }
            }
        }
    }

    /// Writes the outputs that changed (atomically), stores the layout, and
    /// reports the rebuild: failed outputs one line each, saying truly what
    /// happened to the others, then the rebuild's line.
    fn finish(
        &mut self,
        name: &str,
        reason: Reason,
        layout: LayoutKind,
        started: Instant,
        computed: Computed,
        outputs: Vec<Rendered>,
    ) {
        let written = pipeline::write_outputs(&outputs);
        let failed = written.failed.len();
        let others = match (written.written.len(), written.unchanged.len()) {
            (0, 0) => "no output written".to_string(),
            (0, _) => "the other outputs unchanged".to_string(),
            (w, 0) => format!("{w} other output(s) written"),
            (w, u) => format!("{w} other output(s) written, {u} unchanged"),
        };
        self.pending.remove(name);
        let recovered = if failed == 0 {
            self.fixed(name)
        } else {
            for e in &written.failed {
                (self.report)(Status::problem(name, e, others.clone()));
            }
            self.troubled
                .insert(name.to_string(), "outputs not written".to_string());
            false
        };
        (self.report)(Status::Built {
            dataset: name.to_string(),
            reason,
            layout,
            ms: started.elapsed().as_secs_f64() * 1000.0,
            written: written.written,
            unchanged: written.unchanged.len(),
            failed,
            recovered,
        });
        // The pictures are out; what only the next rebuild or a restart needs
        // comes after the status line.
        if let Some(d) = self.dataset(name) {
            if let Err(e) = pipeline::store_layout(d, &computed) {
                tracing::warn!(dataset = name, error = %e, "cannot store the layout for warm starts");
            }
        }
        self.states.entry(name.to_string()).or_default().computed = Some(computed);
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
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for f in files {
        f.role.hash(&mut h);
        f.path.hash(&mut h);
        f.bytes.hash(&mut h);
    }
    h.finish()
}
