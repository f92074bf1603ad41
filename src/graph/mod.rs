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

/// The keys of the stages.
pub mod keys;
/// What the stages did.
pub mod report;
/// Warm or cold: the one decision.
pub mod start;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use nptreemap_formats::Dataset;

use crate::config::{DatasetConfig, OutputConfig, OutputKind};
use crate::fingerprint::{Fingerprint, Fingerprinter};
use crate::layout::compute::{lay_out_planned, plan, Prepared};
use crate::layout::{zero, Computed, LayoutError, Previous, Request, Start};
use crate::neighborhood::{build_constraints, prepare, Constraint, SimilarityKind};
use crate::pipeline::{self, BuildError, InputFile, Rendered, Written};
use crate::render::{html_page_with_history, Style};
use crate::state::manifest::{self, LayoutRecord, Manifest, OutputRecord};
use crate::state::{self};
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

/// What the state folder gets after the outputs are written.
#[derive(Default)]
struct Pending {
    /// The stored layout's text when it may have changed.
    layout: Option<(String, Fingerprint)>,
    /// Constraints computed this time, for the cache.
    constraints: Option<(Fingerprint, Arc<Dataset>, Arc<Vec<Constraint>>)>,
    /// The new manifest.
    manifest: Option<Manifest>,
}

/// The last layout a graph made, with what it was made from.
struct Last {
    inputs: Fingerprint,
    settings: Fingerprint,
    state: Fingerprint,
    computed: Arc<Computed>,
}

/// One dataset's stage graph: the last result of each stage with its key.
#[derive(Default)]
pub struct DatasetGraph {
    options: GraphOptions,
    /// The manifest as last read or written (loaded at the first build).
    manifest: Option<Manifest>,
    parsed: Option<(Fingerprint, Arc<Dataset>)>,
    prepared: Option<(Fingerprint, Arc<Dataset>)>,
    constraints: Option<(Fingerprint, Arc<Vec<Constraint>>)>,
    last: Option<Last>,
    /// The layouts before `last` this graph made, oldest first, at most
    /// `history` of them: the HTML page's past layouts (`history:`, issue
    /// 25). In memory only: a session's history, not the state folder's.
    past: VecDeque<(Fingerprint, Arc<Computed>)>,
    /// How many past layouts the HTML page carries ([`DatasetGraph::keep_history`]).
    history: usize,
    /// State a commit could not write (a full disk, a read-only folder),
    /// kept for [`DatasetGraph::store_again`].
    unstored: Option<Pending>,
    /// Where the last commit stored the layout: a rebuild that takes the
    /// layout over from memory writes it again when the state folder has
    /// moved since (a `state_dir:` edit, another set of outputs), so that the
    /// new folder holds the layout its manifest vouches for.
    stored_at: Option<PathBuf>,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1000.0
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
            ms_since(t),
            format!("{} file(s), {size} bytes", files.len()),
        );
        self.build_from(job, &files, stages)
    }

    /// [`DatasetGraph::build`] from files already read.
    pub fn build_from(
        &mut self,
        job: &Job<'_>,
        files: &[InputFile],
        mut stages: StageReport,
    ) -> Result<DatasetBuild, BuildError> {
        let d = job.dataset;
        let name = d.name.as_str();
        let cache = self.options.cache;
        let inputs = keys::inputs(d, files);
        let settings = manifest::settings_key(&job.request.settings());
        let manifest = self
            .manifest
            .get_or_insert_with(|| {
                if cache {
                    manifest::read(d)
                } else {
                    Manifest::default()
                }
            })
            .clone();
        let disk: Vec<Option<OnDisk>> = d.outputs.iter().map(|o| on_disk(&o.path)).collect();

        if let Some(done) = self.up_to_date(job, &manifest, inputs, settings, &disk, &mut stages) {
            return Ok(done);
        }

        // Parse.
        let t = Instant::now();
        let dataset = match &self.parsed {
            Some((key, dataset)) if cache && *key == inputs => {
                stages.record(name, Stage::Parse, false, ms_since(t), "inputs unchanged");
                Arc::clone(dataset)
            }
            _ => {
                let dataset = Arc::new(pipeline::parse_inputs(d, files)?);
                stages.record(
                    name,
                    Stage::Parse,
                    true,
                    ms_since(t),
                    format!("{} nodes", dataset.len()),
                );
                self.parsed = Some((inputs, Arc::clone(&dataset)));
                dataset
            }
        };
        let mut warnings = pipeline::warnings(files, &dataset);
        let warning_record: Vec<(String, String)> = dataset
            .warnings()
            .iter()
            .map(|w| (w.role.clone(), w.to_string()))
            .collect();
        let layout_error = |source: LayoutError| BuildError::Layout {
            dataset: d.name.clone(),
            source,
        };
        // Items of weight 0 hidden or kept (issue 34): everything below
        // works on what is drawn.
        let mode = job.request.params.zero_weights;
        let (dataset, zero) = zero::apply(&dataset, mode);
        let planned = plan(&dataset, &job.request).map_err(layout_error)?;

        // Layout: the last one in memory when it was made from these inputs
        // and settings, else prepare, constraints and a run from the start
        // the one decision picks.
        let mut notes = Vec::new();
        let mut pending = Pending::default();
        let mut started_from = None;
        let (computed, state, step, layout_ms) = match &self.last {
            Some(last)
                if cache && !job.cold && last.inputs == inputs && last.settings == settings =>
            {
                for stage in [Stage::Prepare, Stage::Constraints, Stage::Layout] {
                    stages.record(name, stage, false, 0.0, "in memory");
                }
                if self.stored_at != state::layout_path(d) {
                    pending.layout = Some((state::layout::text(&last.computed), last.state));
                }
                (Arc::clone(&last.computed), last.state, LayoutStep::Reused, 0.0)
            }
            _ => {
                let input = match planned.kind {
                    None => Prepared::Plain(Arc::clone(&dataset)),
                    Some(kind) => {
                        let kind = (kind, planned.constraints);
                        let source = keys::drawn(inputs, mode);
                        let (prepared, constraints, fresh) =
                            self.similar(Some(d), source, &dataset, kind, name, &mut stages);
                        if let Some(key) = fresh {
                            pending.constraints =
                                Some((key, Arc::clone(&prepared), Arc::clone(&constraints)));
                        }
                        Prepared::Similar(prepared, constraints.as_ref().clone())
                    }
                };
                let memory = self.last.as_ref().map(|last| start::Memory {
                    settings: last.settings,
                    computed: &last.computed,
                });
                let chosen = start::choose(d, cold_because(job.cold, cache), memory, settings);
                // The stored layout's warning first: it is about the whole run.
                if let Some(warning) = chosen.warning {
                    warnings.insert(0, warning);
                }
                let mut request = job.request.clone();
                request.previous = chosen.previous;
                started_from = request.previous.clone();
                let t = Instant::now();
                let computed =
                    lay_out_planned(input, planned, &request, zero).map_err(layout_error)?;
                let layout_ms = ms_since(t);
                let report = &computed.report;
                let step = match (&computed.start, chosen.cold_because) {
                    (Start::Warm { .. }, _)
                        if report.iterations == 0 && report.reused == report.diagrams =>
                    {
                        LayoutStep::Reused
                    }
                    (Start::Warm { .. }, _) => LayoutStep::Warm,
                    (Start::Refused(why), _) => {
                        notes.push(format!("previous layout not used ({why}); laid out cold"));
                        LayoutStep::Cold(why.to_string())
                    }
                    (_, why) => LayoutStep::Cold(why.unwrap_or("no previous layout").to_string()),
                };
                let note = match &step {
                    LayoutStep::Reused => "every diagram as stored, no tick".to_string(),
                    LayoutStep::Warm => format!("warm, {} ticks", report.iterations),
                    LayoutStep::Cold(why) => format!("cold: {why}"),
                    LayoutStep::UpToDate => String::new(),
                };
                stages.record(name, Stage::Layout, step != LayoutStep::Reused, layout_ms, note);
                let text = state::layout::text(&computed);
                let state = Fingerprint::of_bytes(text.as_bytes());
                if chosen.stored != Some(state) {
                    pending.layout = Some((text, state));
                }
                let computed = Arc::new(computed);
                // The layout it replaces becomes history when it differs.
                if let Some(last) = self.last.take().filter(|l| l.state != state) {
                    self.past.push_back((last.state, last.computed));
                }
                while self.past.len() > self.history {
                    self.past.pop_front();
                }
                self.last = Some(Last {
                    inputs,
                    settings,
                    state,
                    computed: Arc::clone(&computed),
                });
                (computed, state, step, layout_ms)
            }
        };

        // Render the outputs whose files do not hold their bytes already.
        let mut svg_text = None;
        let mut outputs = Vec::with_capacity(d.outputs.len());
        let mut records = Vec::with_capacity(d.outputs.len());
        // The past layouts are one more input of the HTML page's render,
        // keyed by their stored layouts' fingerprints (as the current one
        // is): a page is rendered again when its history changed, and the
        // other outputs, which do not show it, are not.
        let past: Vec<Arc<Computed>> = self.past.iter().map(|(_, c)| Arc::clone(c)).collect();
        let past_states: Vec<Fingerprint> = self.past.iter().map(|(s, _)| *s).collect();
        for (out, disk) in d.outputs.iter().zip(&disk) {
            let html = out.kind == Some(OutputKind::Html) && !past.is_empty();
            let mut key = keys::render(inputs, settings, state, &job.style, out);
            if html {
                key = keys::history(key, &past_states);
            }
            let t = Instant::now();
            let known = manifest
                .output(d, &out.path)
                .filter(|r| cache && r.render == key && disk.map(|f| f.fingerprint) == Some(r.bytes));
            let built = match known {
                Some(record) => {
                    stages.record_output(
                        name,
                        Stage::Render,
                        shown(d, &out.path),
                        false,
                        ms_since(t),
                        "file up to date",
                    );
                    OutputBuild {
                        path: out.path.clone(),
                        bytes: None,
                        fingerprint: record.bytes,
                        len: disk.map_or(0, |f| f.len),
                        on_disk: disk.map(|f| f.fingerprint),
                    }
                }
                None => {
                    let Rendered { path, bytes } = if html {
                        Rendered {
                            path: out.path.clone(),
                            bytes: html_page_with_history(&computed, &job.style, &past).into_bytes(),
                        }
                    } else {
                        pipeline::render_output(&computed, &job.style, out, &mut svg_text)?
                    };
                    stages.record_output(
                        name,
                        Stage::Render,
                        shown(d, &out.path),
                        true,
                        ms_since(t),
                        kind_name(out),
                    );
                    OutputBuild {
                        path,
                        fingerprint: Fingerprint::of_bytes(&bytes),
                        len: bytes.len() as u64,
                        bytes: Some(bytes),
                        on_disk: disk.map(|f| f.fingerprint),
                    }
                }
            };
            records.push(OutputRecord {
                path: manifest::relative(d, &out.path),
                render: key,
                bytes: built.fingerprint,
            });
            outputs.push(built);
        }
        let realized = computed.realized.iter().filter(|r| **r).count();
        pending.manifest = Some(Manifest {
            format: manifest::FORMAT.to_string(),
            layout: Some(LayoutRecord {
                inputs: Some(inputs),
                settings,
                state,
                constraints: computed.constraints.len(),
                realized,
                warnings: warning_record,
            }),
            outputs: records,
        });
        let started_from = started_from.filter(|_| step == LayoutStep::Warm);
        Ok(DatasetBuild {
            name: d.name.clone(),
            layout: step,
            layout_ms,
            constraints: computed.constraints.len(),
            realized,
            computed: Some(computed),
            outputs,
            warnings,
            notes,
            stages,
            started_from,
            pending,
        })
    }

    /// The build when nothing changed since the manifest was written: the
    /// same inputs and layout settings as the stored layout, and every
    /// output's file holding what the same layout and style rendered.
    fn up_to_date(
        &self,
        job: &Job<'_>,
        manifest: &Manifest,
        inputs: Fingerprint,
        settings: Fingerprint,
        disk: &[Option<OnDisk>],
        stages: &mut StageReport,
    ) -> Option<DatasetBuild> {
        let d = job.dataset;
        if !self.options.cache || job.cold {
            return None;
        }
        let record = manifest
            .layout
            .as_ref()
            .filter(|r| r.inputs == Some(inputs) && r.settings == settings)?;
        let mut outputs = Vec::with_capacity(d.outputs.len());
        for (out, disk) in d.outputs.iter().zip(disk) {
            let key = keys::render(inputs, settings, record.state, &job.style, out);
            let r = manifest
                .output(d, &out.path)
                .filter(|r| r.render == key && disk.map(|f| f.fingerprint) == Some(r.bytes))?;
            outputs.push(OutputBuild {
                path: out.path.clone(),
                bytes: None,
                fingerprint: r.bytes,
                len: disk.map_or(0, |f| f.len),
                on_disk: disk.map(|f| f.fingerprint),
            });
        }
        let name = d.name.as_str();
        for stage in [Stage::Parse, Stage::Prepare, Stage::Constraints, Stage::Layout] {
            stages.record(name, stage, false, 0.0, "nothing changed");
        }
        for o in &outputs {
            let output = shown(d, &o.path);
            stages.record_output(name, Stage::Render, output, false, 0.0, "nothing changed");
        }
        let files: Vec<(String, PathBuf)> =
            d.files.iter().map(|(r, p)| (r.clone(), p.clone())).collect();
        let warnings = record
            .warnings
            .iter()
            .map(|(role, message)| {
                let file = files
                    .iter()
                    .find(|(r, _)| r == role)
                    .map_or_else(|| role.clone(), |(_, p)| p.display().to_string());
                format!("{file}: {message}")
            })
            .collect();
        Some(DatasetBuild {
            name: d.name.clone(),
            layout: LayoutStep::UpToDate,
            layout_ms: 0.0,
            constraints: record.constraints,
            realized: record.realized,
            computed: None,
            outputs,
            warnings,
            notes: Vec::new(),
            stages: std::mem::take(stages),
            started_from: None,
            pending: Pending::default(),
        })
    }

    /// Prepare and constraints for a similarity run: from memory when their
    /// keys match, the constraints else from the state folder's cache (for a
    /// configured dataset `d`), else computed; none when the plan needs none
    /// (`needed` false: `plain`, issue 34). The third value is the
    /// constraints' key when they were computed (for the cache).
    fn similar(
        &mut self,
        d: Option<&DatasetConfig>,
        source: Fingerprint,
        dataset: &Dataset,
        (kind, needed): (SimilarityKind, bool),
        name: &str,
        stages: &mut StageReport,
    ) -> (Arc<Dataset>, Arc<Vec<Constraint>>, Option<Fingerprint>) {
        let cache = self.options.cache;
        let t = Instant::now();
        let prepared_key = Fingerprinter::new("prepared")
            .fingerprint(source)
            .debug(&kind)
            .finish();
        let prepared = match &self.prepared {
            Some((key, prepared)) if cache && *key == prepared_key => {
                stages.record(name, Stage::Prepare, false, ms_since(t), "dataset unchanged");
                Arc::clone(prepared)
            }
            _ => {
                let prepared = Arc::new(prepare(dataset));
                stages.record(
                    name,
                    Stage::Prepare,
                    true,
                    ms_since(t),
                    format!("{} nodes", prepared.len()),
                );
                self.prepared = Some((prepared_key, Arc::clone(&prepared)));
                prepared
            }
        };
        let t = Instant::now();
        if !needed {
            stages.record(name, Stage::Constraints, false, 0.0, "none needed (plain)");
            return (prepared, Arc::new(Vec::new()), None);
        }
        let key = keys::similarity(dataset, kind);
        if let Some((k, constraints)) = &self.constraints {
            if cache && *k == key {
                stages.record(name, Stage::Constraints, false, ms_since(t), "similarity unchanged");
                return (prepared, Arc::clone(constraints), None);
            }
        }
        if let Some(cached) = d
            .filter(|_| cache)
            .and_then(|d| state::constraints::read(d, key, &prepared))
        {
            let constraints = Arc::new(cached);
            stages.record(
                name,
                Stage::Constraints,
                false,
                ms_since(t),
                format!("{} from the cache", constraints.len()),
            );
            self.constraints = Some((key, Arc::clone(&constraints)));
            return (prepared, constraints, None);
        }
        let constraints = Arc::new(build_constraints(&prepared, kind));
        stages.record(
            name,
            Stage::Constraints,
            true,
            ms_since(t),
            format!("{} constraints", constraints.len()),
        );
        self.constraints = Some((key, Arc::clone(&constraints)));
        (prepared, constraints, Some(key))
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
        let (dataset, _) = zero::apply(&Arc::new(dataset.clone()), request.params.zero_weights);
        let planned = plan(&dataset, request).map_err(|source| BuildError::Layout {
            dataset: d.name.clone(),
            source,
        })?;
        if let Some(kind) = planned.kind {
            let source = keys::dataset(&dataset);
            let kind = (kind, planned.constraints);
            self.similar(None, source, &dataset, kind, &d.name, &mut StageReport::default());
        }
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
        let layout_error = |source| BuildError::Layout {
            dataset: d.name.clone(),
            source,
        };
        let (dataset, zero) = zero::apply(&Arc::new(dataset.clone()), request.params.zero_weights);
        let planned = plan(&dataset, request).map_err(layout_error)?;
        let input = match planned.kind {
            None => Prepared::Plain(dataset),
            Some(kind) => {
                let source = keys::dataset(&dataset);
                let kind = (kind, planned.constraints);
                let (prepared, constraints, _) =
                    self.similar(None, source, &dataset, kind, &d.name, stages);
                Prepared::Similar(prepared, constraints.as_ref().clone())
            }
        };
        let t = Instant::now();
        let computed = lay_out_planned(input, planned, request, zero).map_err(layout_error)?;
        let note = match &computed.start {
            Start::Warm { .. } => "warm",
            _ => "cold",
        };
        stages.record(&d.name, Stage::Layout, true, ms_since(t), note);
        Ok(computed)
    }

    /// Writes a build's stale outputs (atomically, all or none of a set
    /// being under way at a forced exit), then its state: the stored layout,
    /// the constraint cache and the manifest. A state file that cannot be
    /// written only costs the next build its reuse (logged, and kept for
    /// [`DatasetGraph::store_again`]).
    pub fn commit(&mut self, job: &Job<'_>, build: &mut DatasetBuild) -> Written {
        let d = job.dataset;
        let t = Instant::now();
        let stale: Vec<Rendered> = build
            .outputs
            .iter()
            .filter(|o| o.stale())
            .filter_map(|o| {
                o.bytes.as_ref().map(|bytes| Rendered {
                    path: o.path.clone(),
                    bytes: bytes.clone(),
                })
            })
            .collect();
        let mut written = pipeline::write_outputs(&stale);
        for o in build.outputs.iter().filter(|o| !o.stale()) {
            written.unchanged.push(o.path.clone());
        }
        // One pass writes the set (under one lock): each output gets its
        // share of the time.
        let ms = ms_since(t) / build.outputs.len().max(1) as f64;
        for o in &build.outputs {
            let wrote = written.written.contains(&o.path);
            let note = if wrote { "written" } else { "file unchanged" };
            let output = shown(d, &o.path);
            build
                .stages
                .record_output(&d.name, Stage::Write, output, wrote, ms, note);
        }
        if !self.options.cache {
            return written;
        }
        let pending = std::mem::take(&mut build.pending);
        if written.failed.is_empty() {
            self.unstored = None;
            if let Err(e) = self.store(d, pending) {
                tracing::warn!(dataset = %d.name, error = %e, "cannot write the state folder");
            }
        } else {
            // The outputs come first: the manifest may not vouch for files
            // that were not written. Kept for the retry that writes them.
            self.unstored = Some(pending);
        }
        written
    }

    /// Writes the state a commit could not write (after its outputs could
    /// not be written, or the state itself could not be): `Ok` when there
    /// is none left to write.
    pub fn store_again(&mut self, d: &DatasetConfig) -> std::io::Result<()> {
        match self.unstored.take() {
            Some(pending) => self.store(d, pending),
            None => Ok(()),
        }
    }

    /// Whether state is waiting for [`DatasetGraph::store_again`].
    pub fn unstored(&self) -> bool {
        self.unstored.is_some()
    }

    /// Writes a build's state: the stored layout, the constraint cache and
    /// the manifest. A constraint cache that cannot be written only costs
    /// the next process its reuse (logged); a stored layout that cannot be
    /// is kept for a retry with the manifest (which must not vouch for it).
    fn store(&mut self, d: &DatasetConfig, pending: Pending) -> std::io::Result<()> {
        if let Some((key, prepared, constraints)) = &pending.constraints {
            if let Err(e) = state::constraints::write(d, *key, prepared, constraints) {
                tracing::warn!(dataset = %d.name, error = %e, "cannot cache the constraints");
            }
        }
        if let Some((text, _)) = &pending.layout {
            if let Err(e) = state::layout::write(d, text) {
                self.unstored = Some(Pending {
                    constraints: None,
                    ..pending
                });
                return Err(e);
            }
        }
        if let Some(m) = pending.manifest {
            if let Err(e) = manifest::write(d, &m) {
                tracing::warn!(dataset = %d.name, error = %e, "cannot write the state manifest");
            }
            self.manifest = Some(m);
        }
        self.stored_at = state::layout_path(d);
        Ok(())
    }
}

/// Why a build may not start warm, if it may not.
fn cold_because(cold: bool, cache: bool) -> Option<&'static str> {
    if cold {
        Some("--cold")
    } else if !cache {
        Some("caching off: NPTREEMAP_NO_CACHE")
    } else {
        None
    }
}

/// An output's path as `-v` names it: relative to the config's folder, as
/// the config wrote it, control characters escaped (a newline in a name
/// must not forge a log line).
fn shown(d: &DatasetConfig, path: &Path) -> String {
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

fn kind_name(out: &OutputConfig) -> String {
    out.path
        .extension()
        .map_or_else(String::new, |e| e.to_string_lossy().into_owned())
}
