//! The stage graph: one dataset's build as a chain of stages, each a pure
//! function of explicit inputs whose result is reused while those inputs
//! are unchanged (by content fingerprint, [`keys`]):
//!
//! ```text
//! read (bytes per file) ─ inputs ─> parse (Dataset) ─> prepare ─┐
//!                                                    similarity ─> constraints
//!   layout settings ─> start (warm or cold: [`start`]) ─> layout <┘
//!   layout + style + output ─> render (per output) ─> write (changed bytes only)
//! ```
//!
//! `build` and `build --check` run [`DatasetGraph::build`] once per dataset
//! and [`DatasetGraph::commit`] (or compare); `layout` and `eval` run
//! [`DatasetGraph::lay_out`]; the watch daemon will keep one graph per
//! dataset and call [`DatasetGraph::build`] on each change. Between
//! processes, what a build needs is in the state folder ([`crate::state`]):
//! the manifest (so that a build that changes nothing stops after reading
//! and hashing inputs and outputs), the stored layout (the warm start) and
//! the constraint cache (so that a weight edit recomputes no constraint).
//!
//! # Why a small typed cache of our own
//!
//! The graph is a fixed chain of seven stages with one result per stage and
//! dataset: each memo is one slot holding the last key and value. salsa
//! (rust-analyzer's incremental engine) would give dependency tracking and
//! early cut-off for query graphs with thousands of dynamic nodes, at the
//! cost of a database type, interned inputs, its macros and a large
//! dependency, and its memos live only in memory, so the state folder would
//! still need the code below. comemo (typst's) memoises function calls by
//! tracked arguments, in memory too, and hashes with a `Hash`
//! implementation that `Dataset` (floats inside) does not have. Here the
//! keys are plain content fingerprints ([`crate::fingerprint`], stable
//! across processes), which serve both the in-memory slots and the files of
//! the state folder; the whole graph is this file and four small ones.
//!
//! Setting `NPTREEMAP_NO_CACHE=1` turns every reuse off (no memo, no
//! manifest, no constraint cache, no stored layout: a cold start), which is
//! how the tests show that each of their assertions depends on a cache.

/// The commit: outputs, then the state folder and the manifest.
mod commit;
/// One stage's memo slot.
pub mod memo;
/// The outputs of a build: render keys, the files on disk, the render stage.
mod outputs;
/// What the stages did.
pub mod report;
/// The stages: slots, keys and methods, and the chain that runs them.
pub mod stages;
/// Where a build starts: nothing to do, the layout in memory, warm or cold.
pub mod start;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use nptreemap_formats::Dataset;

use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::geom::LevelAdjacency;
use crate::layout::compute::{lay_out_planned, plan, Plan, Prepared};
use crate::layout::{zero, Computed, Previous, Request, Start, ZeroItems};
use crate::neighborhood::Constraint;
use crate::pipeline::{self, BuildError};
use crate::render::Style;
use crate::state::manifest::{self, Manifest};
use crate::workspace;
pub use report::{Stage, StageReport};

/// How a graph reuses results.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GraphOptions {
    /// Reuse anything at all (memos, manifest, constraint cache, stored
    /// layout). Off only to show what the caches do.
    pub cache: bool,
}

impl GraphOptions {
    /// Caching on, unless the environment sets `NPTREEMAP_NO_CACHE` (to
    /// anything but `0` or nothing).
    pub fn from_env() -> Self {
        let off = std::env::var_os("NPTREEMAP_NO_CACHE").is_some_and(|v| !v.is_empty() && v != "0");
        GraphOptions { cache: !off }
    }
}

impl Default for GraphOptions {
    fn default() -> Self {
        GraphOptions { cache: true }
    }
}

/// One build of a configured dataset.
pub struct Job<'a> {
    /// The dataset.
    pub dataset: &'a DatasetConfig,
    /// Its layout request ([`crate::config::Config::request`]), perhaps with
    /// a progress sink; any `previous` in it is ignored ([`start`] decides).
    pub request: Request,
    /// Its picture style.
    pub style: Style,
    /// Lay out from scratch (`--cold`).
    pub cold: bool,
}

/// How a build got its layout.
#[derive(Clone, Debug, PartialEq)]
pub enum LayoutStep {
    /// Nothing changed since the stored layout and the outputs were made:
    /// not even parsed.
    UpToDate,
    /// The layout of the same inputs and settings, taken over: from memory,
    /// or from the stored layout with every diagram as it was (no tick).
    Reused,
    /// Laid out warm from the previous layout.
    Warm,
    /// Laid out from scratch, and why.
    Cold(String),
}

/// One output of a build.
#[derive(Clone, Debug)]
pub struct OutputBuild {
    /// Where it goes.
    pub path: PathBuf,
    /// Its new bytes when it was rendered; `None` when the file on disk is
    /// known to hold them already (not rendered).
    pub bytes: Option<Vec<u8>>,
    /// The fingerprint of its bytes.
    pub fingerprint: Fingerprint,
    /// Its size in bytes.
    pub len: u64,
    /// The fingerprint of the file on disk before the build (`None`: none).
    pub on_disk: Option<Fingerprint>,
}

impl OutputBuild {
    /// An output rendered now, to go where `disk` was found.
    fn made(path: PathBuf, bytes: Vec<u8>, disk: Option<OnDisk>) -> Self {
        OutputBuild {
            path,
            fingerprint: Fingerprint::of_bytes(&bytes),
            len: bytes.len() as u64,
            bytes: Some(bytes),
            on_disk: disk.map(|f| f.fingerprint),
        }
    }

    /// An output its file holds already.
    fn on_disk(path: PathBuf, disk: OnDisk) -> Self {
        OutputBuild {
            path,
            bytes: None,
            fingerprint: disk.fingerprint,
            len: disk.len,
            on_disk: Some(disk.fingerprint),
        }
    }

    /// Whether writing it would change the file.
    pub fn stale(&self) -> bool {
        self.on_disk != Some(self.fingerprint)
    }
}

/// What a build of one dataset made, not written yet.
pub struct DatasetBuild {
    /// The dataset's name.
    pub name: String,
    /// How the layout was got.
    pub layout: LayoutStep,
    /// Milliseconds spent in the layout stage (0 when reused).
    pub layout_ms: f64,
    /// Constraints of the layout.
    pub constraints: usize,
    /// How many of them it realises.
    pub realized: usize,
    /// The layout, unless nothing needed it.
    pub computed: Option<Arc<Computed>>,
    /// Every output, in config order.
    pub outputs: Vec<OutputBuild>,
    /// Input warnings and an unreadable stored layout, one line each.
    pub warnings: Vec<String>,
    /// Facts worth a `note:` line (a previous layout that did not fit).
    pub notes: Vec<String>,
    /// What each stage did.
    pub stages: StageReport,
    /// The previous layout the layout started from, when it ran warm (for
    /// stability figures: how far the cells moved).
    pub started_from: Option<Arc<Previous>>,
    pending: Pending,
}

impl DatasetBuild {
    /// The outputs whose files a write would change.
    pub fn stale(&self) -> impl Iterator<Item = &OutputBuild> {
        self.outputs.iter().filter(|o| o.stale())
    }
}

/// A layout's adjacency per level, as `Computed` shares it.
type KeptLevels = Arc<Vec<LevelAdjacency>>;

/// What the state folder gets after the outputs are written.
#[derive(Default)]
struct Pending {
    /// The stored layout's text when it may have changed, its fingerprint
    /// and the layout's adjacency per level when known (`state::levels`).
    layout: Option<(String, Fingerprint, Option<KeptLevels>)>,
    /// Constraints computed this time, for the cache.
    constraints: Option<(Fingerprint, Arc<Dataset>, Arc<Vec<Constraint>>)>,
    /// The new manifest.
    manifest: Option<Manifest>,
}

/// One dataset's stage graph: the last result of each stage with its key.
#[derive(Default)]
pub struct DatasetGraph {
    options: GraphOptions,
    /// The manifest as last read or written (loaded at the first build).
    manifest: Option<Manifest>,
    /// Each stage's last result with its key.
    slots: stages::Slots,
    /// The layouts before the last one this graph made, oldest first, at most
    /// `history` of them: the HTML page's past layouts (`history:`, issue
    /// 25). In memory only: a session's history, not the state folder's.
    past: VecDeque<(Fingerprint, Arc<Computed>)>,
    /// How many past layouts the HTML page carries ([`DatasetGraph::keep_history`]).
    history: usize,
    /// State a commit could not write (a full disk, a read-only folder),
    /// kept for [`DatasetGraph::store_again`].
    unstored: Option<Pending>,
    /// Layouts no longer held, freed by [`DatasetGraph::ready_next`]: in
    /// `watch` after the rebuild is reported (a 6,000-leaf layout took 7 ms
    /// to free, on the rebuild's way to its outputs).
    retired: Vec<Arc<Computed>>,
    /// What [`DatasetGraph::commit_outputs`] left for
    /// [`DatasetGraph::finish_commit`].
    later: Option<commit::Later>,
    /// Where the last commit stored the layout: a rebuild that takes the
    /// layout over from memory writes it again when the state folder has
    /// moved since (a `state_dir:` edit, another set of outputs), so that the
    /// new folder holds the layout its manifest vouches for.
    stored_at: Option<PathBuf>,
    /// The labels of the last render, for the next (issue 32: an edit fits
    /// only the labels of the cells it moved).
    parts: crate::render::Parts,
    /// The last layout as the next warm start's previous one, made ahead
    /// ([`DatasetGraph::ready_next`]), by the layout's state fingerprint.
    /// One only: the past layouts kept for the page's history hold none.
    next_previous: Option<(Fingerprint, Arc<Previous>)>,
}

/// An output's file as the build found it.
#[derive(Clone, Copy)]
struct OnDisk {
    fingerprint: Fingerprint,
    len: u64,
}

/// The fingerprint and size of the file at `path`, if it is there and
/// readable.
fn on_disk(path: &Path) -> Option<OnDisk> {
    workspace::read_bytes(path).ok().map(|bytes| OnDisk {
        fingerprint: Fingerprint::of_bytes(&bytes),
        len: bytes.len() as u64,
    })
}

impl DatasetGraph {
    /// An empty graph.
    pub fn new(options: GraphOptions) -> Self {
        DatasetGraph {
            options,
            ..DatasetGraph::default()
        }
    }

    /// Makes now what the next warm start begins from (the last layout as a
    /// previous one, tens of milliseconds at thousands of leaves), so that
    /// a daemon's next rebuild does not wait for it: the daemon calls this
    /// while it waits for the next batch of events.
    pub fn ready_next(&mut self) {
        self.retired.clear();
        let Some((_, laid)) = self.slots.layout.last() else {
            return;
        };
        if self.next_previous.as_ref().is_none_or(|(s, _)| *s != laid.state) {
            self.next_previous = Some((laid.state, laid.computed.previous()));
        }
    }

    /// Keeps the last `n` layouts it made before the current one for the
    /// HTML page's steps back (the watch daemon's `history:`; `build` keeps
    /// none, so its page has no history and stays a function of the inputs).
    pub fn keep_history(&mut self, n: usize) {
        self.history = n;
        while self.past.len() > n {
            self.past.pop_front();
        }
    }

    /// Builds a configured dataset: reads its files and runs the stages
    /// that their changes (and the settings') call for. Writes nothing
    /// ([`DatasetGraph::commit`] does).
    pub fn build(&mut self, job: &Job<'_>) -> Result<DatasetBuild, BuildError> {
        let t = Instant::now();
        let files = pipeline::read_inputs(job.dataset)?;
        let mut stages = StageReport::default();
        let size: usize = files.iter().map(|f| f.bytes.len()).sum();
        stages.record(
            &job.dataset.name,
            Stage::Read,
            true,
            memo::ms_since(t),
            format!("{} file(s), {size} bytes", files.len()),
        );
        self.build_from(job, &files, stages)
    }

    /// The manifest as last read or written (read at the first build).
    fn manifest_of(&mut self, d: &DatasetConfig) -> Manifest {
        let cache = self.options.cache;
        self.manifest
            .get_or_insert_with(|| {
                if cache {
                    manifest::read(d)
                } else {
                    Manifest::default()
                }
            })
            .clone()
    }

    /// The build when nothing changed since the manifest was written
    /// ([`start::decide`]): every output as its file holds it, and the
    /// warnings the manifest recorded.
    fn up_to_date(
        &self,
        d: &DatasetConfig,
        record: &manifest::LayoutRecord,
        outputs: Vec<OutputBuild>,
        mut stages: StageReport,
    ) -> DatasetBuild {
        let name = d.name.as_str();
        for stage in [Stage::Parse, Stage::Prepare, Stage::Constraints, Stage::Layout] {
            stages.record(name, stage, false, 0.0, "nothing changed");
        }
        for o in &outputs {
            let output = shown(d, &o.path);
            stages.record_output(name, Stage::Render, output, false, 0.0, "nothing changed");
        }
        let warnings = record
            .warnings
            .iter()
            .map(|(role, message)| {
                let file = d
                    .files
                    .iter()
                    .find(|(r, _)| *r == role)
                    .map_or_else(|| role.clone(), |(_, p)| p.display().to_string());
                format!("{file}: {message}")
            })
            .collect();
        DatasetBuild {
            name: d.name.clone(),
            layout: LayoutStep::UpToDate,
            layout_ms: 0.0,
            constraints: record.constraints,
            realized: record.realized,
            computed: None,
            outputs,
            warnings,
            notes: Vec::new(),
            stages,
            started_from: None,
            pending: Pending::default(),
        }
    }

    /// Runs the stages before the layout (prepare and constraints) for a
    /// dataset [`DatasetGraph::lay_out`] will lay out, so that timing the
    /// layouts measures the layout stage alone.
    pub fn prepare_for(
        &mut self,
        d: &DatasetConfig,
        dataset: &Dataset,
        request: &Request,
    ) -> Result<(), BuildError> {
        self.prepared_run(d, dataset, request, &mut StageReport::default())?;
        Ok(())
    }

    /// Lays out a dataset that is not configured for a build (`layout`,
    /// `eval`): prepare and constraints through the graph's memos, so that
    /// several methods or starts on one dataset compute them once.
    pub fn lay_out(
        &mut self,
        d: &DatasetConfig,
        dataset: &Dataset,
        request: &Request,
        stages: &mut StageReport,
    ) -> Result<Computed, BuildError> {
        let (input, planned, zero) = self.prepared_run(d, dataset, request, stages)?;
        let t = Instant::now();
        let computed = lay_out_planned(input, planned, request, zero)
            .map_err(|e| stages::layout_error(d, e))?;
        let note = match &computed.start {
            Start::Warm { .. } => "warm",
            _ => "cold",
        };
        stages.record(&d.name, Stage::Layout, true, memo::ms_since(t), note);
        Ok(computed)
    }

    /// The input of a run on a dataset given in memory, its plan and what
    /// was hidden of it, through the prepare and constraints slots.
    fn prepared_run(
        &mut self,
        d: &DatasetConfig,
        dataset: &Dataset,
        request: &Request,
        stages: &mut StageReport,
    ) -> Result<(Prepared, Plan, Arc<ZeroItems>), BuildError> {
        let (dataset, zero) = zero::apply(&Arc::new(dataset.clone()), request.params.zero_weights);
        let planned = plan(&dataset, request).map_err(|e| stages::layout_error(d, e))?;
        let mut cx = memo::Cx {
            name: &d.name,
            cache: self.options.cache,
            stages,
        };
        let source = stages::dataset(&dataset);
        let input = self.similar(None, source, &dataset, &planned, &mut cx, &mut Pending::default());
        Ok((input, planned, zero))
    }
}

/// An output's path as `-v` names it: relative to the config's folder, as
/// the config wrote it, control characters escaped (a newline in a name
/// must not forge a log line).
pub(crate) fn shown(d: &DatasetConfig, path: &Path) -> String {
    let text = path.strip_prefix(&d.base).unwrap_or(path).display().to_string();
    text.chars()
        .flat_map(|c| {
            let escaped: Vec<char> = if c.is_control() {
                c.escape_default().collect()
            } else {
                vec![c]
            };
            escaped
        })
        .collect()
}
