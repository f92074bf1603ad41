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

use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::Instant;

use crate::config::{Config, ConfigFileError, DatasetConfig};
use crate::layout::{Computed, Start};
use crate::pipeline::{self, Fault, Rendered};
use change::{ChangeSet, Reason};
use status::{LayoutKind, Status};
use watcher::{Batch, DirWatcher, Message, Timing};

/// How the daemon runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Lay every dataset out from scratch at start instead of warm from the
    /// layout stored beside its outputs. Later rebuilds start warm from the
    /// last good layout either way.
    pub cold: bool,
    /// Event batching windows.
    pub timing: Timing,
}

/// Why the daemon could not start (or had to stop).
#[derive(Debug, thiserror::Error)]
pub enum DaemonError {
    /// The config could not be read at start: there is nothing to watch.
    #[error(transparent)]
    Config(#[from] ConfigFileError),
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
            DaemonError::Config(_) => Fault::Input,
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
    /// Parse failures not reported yet, by dataset: a file read while a
    /// writer is still at it (editors and scripts writing in place truncate
    /// first) fails to parse, and the write's own events bring a rebuild that
    /// succeeds. A failure is reported only when the inputs then stay quiet
    /// for [`SETTLE`]; a good rebuild forgets it.
    pending: BTreeMap<String, Status>,
}

/// How long the inputs must stay unchanged after a parse failure before it
/// is reported (see `Daemon::pending`): long enough for a writer descheduled
/// mid-write on a busy machine, short for a person fixing a typo.
const SETTLE: std::time::Duration = std::time::Duration::from_millis(1000);

/// A channel for [`run`]: give the sender to whatever should stop the daemon
/// (a signal handler sends [`Message::Stop`]).
pub fn channel() -> (Sender<Message>, Receiver<Message>) {
    std::sync::mpsc::channel()
}

/// Runs the daemon on `config_path` until a [`Message::Stop`] arrives on
/// `rx` (whose sender `tx` also feeds the file watcher). Builds everything
/// once, then rebuilds what each batch of changes affects. Every line of
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
    let mut watcher = DirWatcher::new(tx)?;
    let mut daemon = Daemon {
        config_path,
        config,
        options,
        states: BTreeMap::new(),
        report,
        pending: BTreeMap::new(),
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
        daemon.rebuild(&name, Reason::Start);
    }
    loop {
        let inputs = change::inputs_of(&daemon.config, &daemon.config_path);
        let idle = (!daemon.pending.is_empty()).then_some(SETTLE);
        let batch = watcher::next_batch(
            rx,
            daemon.options.timing,
            &|p: &Path| inputs.contains(p),
            idle,
        );
        let paths = match batch {
            Batch::Stop => break,
            Batch::Idle => {
                for (_, problem) in std::mem::take(&mut daemon.pending) {
                    (daemon.report)(problem);
                }
                continue;
            }
            Batch::Paths(paths) => paths,
        };
        tracing::debug!(?paths, "batch");
        let mut work = ChangeSet::default();
        if paths.contains(&daemon.config_path) {
            if let Some(set) = daemon.reload_config() {
                work = set;
                daemon.sync_watches(&mut watcher);
            }
        }
        for (name, reason) in change::touched(&daemon.config, &paths).relayout {
            work.relayout.entry(name).or_insert(reason);
        }
        daemon.apply(work);
    }
    (daemon.report)(Status::Stopped);
    Ok(())
}

impl Daemon<'_> {
    fn dataset(&self, name: &str) -> Option<&DatasetConfig> {
        self.config.datasets.iter().find(|d| d.name == name)
    }

    /// Watches the folders of the config and of every input; reports folders
    /// that cannot be watched (they are retried at the next config change).
    fn sync_watches(&mut self, watcher: &mut DirWatcher) {
        let dirs = change::dirs_of(&change::inputs_of(&self.config, &self.config_path));
        for (dir, e) in watcher.sync(&dirs) {
            (self.report)(Status::problem(
                dir.display().to_string(),
                &e,
                "its files are not watched",
            ));
        }
    }

    /// Reads the changed config. A config that does not parse is reported and
    /// the previous one kept; otherwise returns what changed.
    fn reload_config(&mut self) -> Option<ChangeSet> {
        match Config::from_path(&self.config_path) {
            Ok(new) => {
                let set = change::diff(&self.config, &new);
                self.config = new;
                Some(set)
            }
            Err(e) => {
                (self.report)(Status::problem("config", &e, "previous config kept"));
                None
            }
        }
    }

    fn apply(&mut self, work: ChangeSet) {
        for name in &work.removed {
            self.states.remove(name);
            (self.report)(Status::Note {
                subject: name.clone(),
                message: "no longer in the config; its outputs are left as they are".to_string(),
            });
        }
        for (name, reason) in work.relayout {
            self.rebuild(&name, reason);
        }
        for name in work.rerender {
            self.rerender(&name);
        }
    }

    /// Reads, lays out (warm when a previous layout exists), renders and
    /// writes one dataset; reports one line.
    fn rebuild(&mut self, name: &str, reason: Reason) {
        let Some(d) = self.dataset(name).cloned() else {
            return;
        };
        let started = Instant::now();
        let files = match pipeline::read_inputs(&d) {
            Ok(files) => files,
            Err(e) => {
                let consequence = if e.missing_file().is_some() {
                    "last outputs kept; rebuilt when the file is back"
                } else {
                    "last good outputs kept"
                };
                (self.report)(Status::problem(name, &e, consequence));
                return;
            }
        };
        let fingerprint = fingerprint(&files);
        let state = self.states.entry(name.to_string()).or_default();
        let data_only = matches!(reason, Reason::Data(_));
        if data_only && state.fingerprint == Some(fingerprint) && state.computed.is_some() {
            tracing::debug!(dataset = name, "inputs unchanged; nothing to do");
            return;
        }
        state.fingerprint = Some(fingerprint);
        // Warm from the last good layout in memory; at start, from the one
        // stored beside the outputs (unless --cold).
        let mut request = self.config.request(&d);
        request.previous = match &state.computed {
            Some(computed) => Some(Arc::new(computed.previous())),
            None if reason == Reason::Start && self.options.cold => None,
            None => pipeline::stored_layout(&d).previous,
        };
        let style = self.config.style(&d);
        let read_ms = ms_since(started);
        let result = pipeline::parse_inputs(&d, &files).and_then(|dataset| {
            let parsed = Instant::now();
            let computed = pipeline::lay_out(&d, &dataset, &request)?;
            let laid_out = Instant::now();
            let outputs = pipeline::render_outputs(&computed, &style, &d.outputs)?;
            tracing::debug!(
                dataset = name,
                read_ms,
                parse_ms = ms_between(started, parsed) - read_ms,
                layout_ms = ms_between(parsed, laid_out),
                render_ms = ms_since(laid_out),
                "rebuilt in memory"
            );
            Ok((computed, outputs))
        });
        match result {
            Ok((computed, outputs)) => {
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
                    Status::problem(name, &e, "last good outputs kept"),
                );
            }
            Err(e) => (self.report)(Status::problem(name, &e, "last good outputs kept")),
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
                (self.report)(Status::problem(name, &e, "last good outputs kept"));
                if let Some(state) = self.states.get_mut(name) {
                    state.computed = Some(computed);
                }
            }
        }
    }

    /// Writes the outputs that changed (atomically), stores the layout, and
    /// reports the rebuild.
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
        for e in &written.failed {
            (self.report)(Status::problem(name, e, "other outputs written"));
        }
        self.pending.remove(name);
        (self.report)(Status::Built {
            dataset: name.to_string(),
            reason,
            layout,
            ms: started.elapsed().as_secs_f64() * 1000.0,
            written: written.written,
            unchanged: written.unchanged.len(),
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
