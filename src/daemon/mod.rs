//! `nptreemap watch`: the long-running loop that keeps a config's pictures
//! current (issue 6). Orchestration only: wait for a batch of file events
//! ([`watcher`]; links followed to the files they name, [`links`]), sort it
//! into work ([`change`]), queue it per dataset ([`queue`]), hand each
//! dataset's next task to that dataset's own [`worker`] thread (which hands
//! the changed inputs to the dataset's stage graph, [`crate::graph`], kept
//! in memory between rebuilds), and report each outcome as it comes back:
//! one [`event::Rebuilt`] per attempt and its [`status`] lines, both
//! through the one [`event::Report`] callback. No dataset waits for
//! another, and the loop never waits for a rebuild (issue 21 item 3). A bad
//! edit is a reported problem that keeps the last good config and outputs;
//! a panic in a rebuild is that dataset's failure; only a failure to start
//! (no usable config, no watcher) ends the loop with an error.

/// What a batch of changed paths means: relayout, re-render, added, removed.
pub mod change;
/// The typed event of each rebuild attempt, for subscribers.
pub mod event;
/// Inputs behind symbolic links.
pub mod links;
/// Work waiting per dataset, and retries of failed writes.
pub mod queue;
/// The status reporter: lines, events and their de-duplication.
pub mod reporter;
/// The status lines.
pub mod status;
/// notify over directories, and batching of its events.
pub mod watcher;
/// One dataset's rebuilds on a thread of its own.
pub mod worker;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::config::{Config, ConfigFileError, DatasetConfig};
use crate::layout::ProgressSink;
use crate::pipeline::{self, BuildError, Fault};
use change::{ChangeSet, Reason};
use event::Report;
use links::Aliases;
use queue::Queue;
use reporter::{Follow, Reporter};
use status::Status;
use watcher::{Batch, DirWatcher, Message, Timing};
use worker::{Done, Task, Shared, Worker};

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
    /// and the loop ends. The [`Message::Stop`] that goes with it wakes the
    /// loop. The daemon sets it too when it ends otherwise.
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
    /// The config could not be read at start (there is nothing to watch),
    /// or its outputs are unsafe (over an input, the config, another output
    /// or a special file: nothing is built). The build's own error, so that
    /// [`BuildError::fault`] judges it as it judges a build.
    #[error(transparent)]
    Build(#[from] BuildError),
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

impl From<ConfigFileError> for DaemonError {
    fn from(e: ConfigFileError) -> Self {
        DaemonError::Build(e.into())
    }
}

impl DaemonError {
    /// Whose fault it is that the daemon could not start: a build error's
    /// own ([`BuildError::fault`]), else the system's.
    pub fn fault(&self) -> Fault {
        match self {
            DaemonError::Build(e) => e.fault(),
            DaemonError::Path { .. } | DaemonError::Watcher(_) => Fault::System,
        }
    }
}

/// The daemon's state: the last good config, each dataset's worker, the
/// work waiting, and the reporter.
struct Daemon<'a> {
    config_path: PathBuf,
    config: Config,
    timing: Timing,
    stop: Arc<AtomicBool>,
    /// What the workers share; its `done` end is `done`.
    shared: Arc<Shared>,
    done: Receiver<Done>,
    /// Each dataset's worker, started at its first task.
    workers: BTreeMap<String, Worker>,
    /// The work waiting for each dataset's worker.
    queue: Queue,
    /// Every path the daemon reacts to, with the links leading from them.
    aliases: Aliases,
    /// The folders watched (or waited for), as last given to the watcher.
    dirs: BTreeSet<PathBuf>,
    /// Every line and event, and what was said.
    reporter: Reporter<'a>,
    /// When the last batch with relevant paths ended (its debounce over):
    /// the rebuilds it causes are timed from it.
    last_batch: Instant,
    /// Batches with relevant paths so far, numbered in the debug log.
    batches: u64,
    /// Whether the loop was idle (nothing queued, no rebuild running) when
    /// it last looked.
    idle: bool,
}

/// How often watched folders (and the links to inputs) are looked at
/// between events: a folder deleted and made again, one missing at start,
/// or a link pointed elsewhere is watched again within this.
const POLL: Duration = Duration::from_millis(500);

/// A channel for [`run`]: give the sender to whatever should stop the daemon
/// (a signal handler sends [`Message::Stop`]) or reload it ([`Message::Reload`]).
pub fn channel() -> (Sender<Message>, Receiver<Message>) {
    std::sync::mpsc::channel()
}

/// Ends the daemon's part in the process, once: whatever calls it first
/// (the loop's end, or the binary's forced exit after a stop signal's grace
/// period) waits until no set of outputs is being written, and from then
/// on no set is written in this process (the lock is never given back), so
/// that the process can exit without leaving a dataset's SVG new and its
/// PNG old. Later calls return at once. This is also the place for whatever
/// else must not outlive the daemon.
pub fn shutdown() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Whatever must end with the daemon ends here, first (what the
        // workers started: adapters' processes), then the writes.
        crate::exec::terminate_all();
        std::mem::forget(crate::store::writing());
        // What the last rebuilds wrote, durable before the process ends.
        if let Err(e) = crate::store::sync_pending() {
            tracing::warn!(error = %e, "cannot sync the files written");
        }
    });
}

/// Runs the daemon on `config_path` until a [`Message::Stop`] arrives on
/// `rx` (whose sender `tx` also feeds the file watcher and the workers).
/// Builds everything once, then rebuilds what each batch of changes
/// affects; a [`Message::Reload`] reads the config and every input again.
/// Every line of output, and the [`event::Rebuilt`] event of every rebuild
/// attempt, goes to `report`.
pub fn run(
    config_path: &Path,
    options: Options,
    tx: Sender<Message>,
    rx: &Receiver<Message>,
    report: &mut dyn FnMut(Report),
) -> Result<(), DaemonError> {
    let config_path = std::path::absolute(config_path).map_err(|source| DaemonError::Path {
        path: config_path.to_path_buf(),
        source,
    })?;
    let config = Config::from_path(&config_path)?;
    let (reads, writes) = pipeline::files_of(&config_path, &config.datasets);
    pipeline::check_outputs(&reads, &writes)?;
    pipeline::remove_stale_temps(&writes);
    // A rebuild's files are in place when it is reported; their fsyncs
    // follow (each worker's, after its report).
    crate::store::sync_later();
    let mut watcher = DirWatcher::new(tx.clone())?;
    let stop = options.stop.clone().unwrap_or_default();
    let (done_tx, done) = std::sync::mpsc::channel();
    let shared = Arc::new(Shared {
        done: done_tx,
        wake: tx,
        stop: stop.clone(),
        cold: options.cold,
        progress: options.first_build_progress.clone(),
        bar: AtomicBool::new(false),
    });
    let mut daemon = Daemon {
        config_path,
        config,
        timing: options.timing,
        stop,
        shared,
        done,
        workers: BTreeMap::new(),
        queue: Queue::default(),
        aliases: Aliases::default(),
        dirs: BTreeSet::new(),
        reporter: Reporter::new(report),
        last_batch: Instant::now(),
        batches: 0,
        idle: false,
    };
    daemon.sync_watches(&mut watcher);
    daemon.reporter.say(Status::Watching {
        config: daemon.config_path.clone(),
        datasets: daemon.config.datasets.len(),
        dirs: watcher.watched().len(),
    });
    let names: Vec<String> = daemon.names();
    for name in names {
        daemon.queue.build(&name, Reason::Start);
    }
    daemon.dispatch();
    daemon.watch(&mut watcher, rx);
    daemon.stop.store(true, Ordering::SeqCst);
    shutdown();
    daemon.reporter.say(Status::Stopped);
    Ok(())
}

impl Daemon<'_> {
    /// The loop: a batch of events (or an outcome, or the next due time),
    /// what it means, the work handed out, the outcomes reported, until a
    /// stop.
    fn watch(&mut self, watcher: &mut DirWatcher, rx: &Receiver<Message>) {
        while let Some((paths, reload)) = self.next_batch(watcher, rx) {
            let config_changed = reload || paths.contains(&self.config_path);
            let new = config_changed.then(|| self.read_config(reload)).flatten();
            let work = change::classify(&paths, &self.config, new.as_ref(), reload);
            if let Some(new) = new {
                self.config = new;
            }
            // A link pointed elsewhere, a new input: watch where they lead.
            self.sync_watches(watcher);
            self.schedule(work);
            self.collect();
            self.dispatch();
            self.reporter.settle();
            self.note_idle(!paths.is_empty());
        }
    }

    /// Waits for the next batch: its paths (events on a link's target stand
    /// for the configured path; folders made again count for their files)
    /// and whether it asks for a reload; `None` at a stop.
    fn next_batch(
        &mut self,
        watcher: &mut DirWatcher,
        rx: &Receiver<Message>,
    ) -> Option<(BTreeSet<PathBuf>, bool)> {
        if self.stopping() {
            return None;
        }
        let aliases = self.aliases.clone();
        let wait = self.reporter.wait(&self.queue);
        let batch = watcher::next_batch(rx, self.timing, &|p: &Path| aliases.contains(p), Some(wait));
        let (events, reload) = match batch {
            Batch::Stop => return None,
            Batch::Idle => (BTreeSet::new(), false),
            Batch::Paths(paths) => (paths, false),
            Batch::Reload(paths) => (paths, true),
        };
        let mut paths = aliases.watched_of(&events);
        // Folders deleted and made again (or appeared) since the last look:
        // their files may have changed without an event.
        for dir in watcher.check() {
            paths.extend(aliases.watched_in(&dir));
        }
        if !paths.is_empty() {
            self.last_batch = Instant::now();
            self.reporter.events(self.last_batch);
            self.batches += 1;
            tracing::debug!(batch = self.batches, ?paths, "batch");
        }
        Some((paths, reload))
    }

    /// Logs (at debug level) when every change handed to the loop so far
    /// has been handled: nothing queued and no rebuild running, after a
    /// batch or once the last rebuild is done. With the batch numbers of the
    /// `batch` lines, this tells a script (and the tests) that the outputs
    /// now follow from every edit up to that batch.
    fn note_idle(&mut self, batch: bool) {
        let idle = self.queue.is_empty() && !self.workers.values().any(|w| w.busy);
        if idle && (batch || !self.idle) {
            tracing::debug!(after_batch = self.batches, "idle");
        }
        self.idle = idle;
    }

    fn dataset(&self, name: &str) -> Option<&DatasetConfig> {
        self.config.datasets.iter().find(|d| d.name == name)
    }

    fn names(&self) -> Vec<String> {
        self.config.datasets.iter().map(|d| d.name.clone()).collect()
    }

    /// Whether a stop was asked for (see [`Options::stop`]).
    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Watches the folders of the config and of every input, and of the
    /// files their links lead to; reports folders that cannot be watched
    /// (missing ones are polled until they exist).
    fn sync_watches(&mut self, watcher: &mut DirWatcher) {
        self.aliases = Aliases::resolve(&change::inputs_of(&self.config, &self.config_path));
        let dirs = change::dirs_of(&self.aliases.paths());
        if dirs == self.dirs {
            return;
        }
        for (dir, e) in watcher.sync(&dirs) {
            let subject = dir.display().to_string();
            let line = Status::problem(subject, &e, "watched as soon as it exists");
            self.reporter.say(line);
        }
        self.dirs = dirs;
    }

    /// Reads the config again (it changed, or `forced` by SIGHUP). One that
    /// does not parse, or whose outputs are unsafe, is reported and the
    /// previous one kept; otherwise returns what changed.
    fn read_config(&mut self, forced: bool) -> Option<Config> {
        let new = match Config::from_path(&self.config_path) {
            Ok(new) => new,
            Err(e) => {
                let problem = Status::problem("config", &e, "previous config kept");
                self.reporter.problems("config", vec![problem]);
                return None;
            }
        };
        let (reads, writes) = pipeline::files_of(&self.config_path, &new.datasets);
        if let Err(e) = pipeline::check_outputs(&reads, &writes) {
            let problem = Status::problem("config", &e, "previous config kept");
            self.reporter.problems("config", vec![problem]);
            return None;
        }
        pipeline::remove_stale_temps(&writes);
        let again = self.reporter.fixed("config");
        let message = match (again, forced) {
            (true, true) => "ok again; reloaded on SIGHUP",
            (true, false) => "ok again",
            (false, true) => "reloaded on SIGHUP",
            (false, false) => "",
        };
        if !message.is_empty() {
            self.reporter.say(Status::Note {
                subject: "config".to_string(),
                message: message.to_string(),
            });
        }
        Some(new)
    }

    /// Queues the work of a batch; a dataset that left the config is
    /// forgotten (its worker ends once idle).
    fn schedule(&mut self, work: ChangeSet) {
        for name in &work.removed {
            self.queue.forget(name);
            self.reporter.forget(name);
            self.reporter.say(Status::Note {
                subject: name.clone(),
                message: "no longer in the config; its outputs are left as they are".to_string(),
            });
        }
        for (name, reason) in work.relayout {
            self.queue.build(&name, reason);
        }
        for name in work.rerender {
            self.queue.render(&name);
        }
    }

    /// Hands each idle worker its dataset's next task; ends the workers of
    /// datasets that left the config once they are idle.
    fn dispatch(&mut self) {
        if self.stopping() {
            return;
        }
        let now = Instant::now();
        for name in self.queue.ready(now) {
            if self.workers.get(&name).is_some_and(|w| w.busy) {
                continue;
            }
            let Some(d) = self.dataset(&name).cloned() else {
                self.queue.forget(&name);
                continue;
            };
            let Some(next) = self.queue.take(&name, now) else {
                continue;
            };
            // A start build is timed from its dispatch, the rest from the
            // batch that caused them.
            let since = match &next {
                queue::Next::Build(Reason::Start) | queue::Next::Retry => now,
                _ => self.last_batch,
            };
            let job = Task {
                since,
                next,
                request: self.config.request(&d),
                style: self.config.style(&d),
                force: self.reporter.troubled(&name),
                history: self.config.history,
                dataset: d,
            };
            self.send(&name, job);
        }
        let gone: Vec<String> = self
            .workers
            .iter()
            .filter(|(name, w)| !w.busy && self.dataset(name).is_none())
            .map(|(name, _)| name.clone())
            .collect();
        for name in gone {
            // Dropping its end of the channel ends the thread.
            self.workers.remove(&name);
        }
    }

    /// Sends `job` to `name`'s worker, starting one if needed.
    fn send(&mut self, name: &str, job: Task) {
        if !self.workers.contains_key(name) {
            match Worker::spawn(name, self.shared.clone()) {
                Ok(worker) => {
                    self.workers.insert(name.to_string(), worker);
                }
                Err(e) => {
                    let problem = Status::problem(name, &e, "tried again at the next change");
                    self.reporter.problems(name, vec![problem]);
                    return;
                }
            }
        }
        let sent = self.workers.get_mut(name).is_some_and(|w| w.send(job));
        if !sent {
            // The thread is gone (it cannot panic: tasks run under
            // catch_unwind); start another at the next change.
            self.workers.remove(name);
        }
    }

    /// Reports the outcomes the workers sent back, and queues the retries
    /// of what they could not write.
    fn collect(&mut self) {
        while let Ok(done) = self.done.try_recv() {
            // A late word on a reported rebuild: the worker has moved on.
            let late = matches!(done.outcome, worker::Outcome::Unsaved(_));
            if let Some(worker) = self.workers.get_mut(&done.name).filter(|_| !late) {
                worker.busy = false;
            }
            // A dataset that left the config meanwhile: nothing to say.
            let Some(d) = self.dataset(&done.name).cloned() else {
                continue;
            };
            if self.stopping() {
                continue;
            }
            let name = done.name.clone();
            match self.reporter.outcome(&d, done) {
                Follow::Retry => {
                    let wait = self.queue.failed(&name, Instant::now());
                    tracing::debug!(dataset = name, ?wait, "writes retried");
                }
                Follow::Written => self.queue.written(&name),
                Follow::Nothing => {}
            }
        }
    }
}
