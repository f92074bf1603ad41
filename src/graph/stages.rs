//! The stages of one dataset's build: for each, its memo slot, its key
//! (what its result depends on, as a fingerprint) and one short method, and
//! the chain that runs them ([`DatasetGraph::build_from`]). Each key names
//! exactly the inputs of its stage, so a stage is reused precisely while
//! those are unchanged; adding an input to a stage means adding it to its
//! key here, and adding a stage means a slot, a key and a method here and a
//! [`Stage`] in `report.rs`.
//!
//! Keys feed typed values ([`Fingerprinter::value`], serde), never `Debug`
//! text.

use std::sync::Arc;
use std::time::Instant;

use nptreemap_formats::{Dataset, Features};

use super::memo::{ms_since, Cx, Made, Memo};
use super::start::{self, Chosen, Decision};
use super::{DatasetBuild, DatasetGraph, Job, LayoutStep, OnDisk, OutputBuild, Pending};
use super::{Stage, StageReport};
use crate::config::{DatasetConfig, OutputConfig};
use crate::fingerprint::{Fingerprint, Fingerprinter};
use crate::layout::compute::{lay_out_planned, plan, Plan, Prepared};
use crate::layout::zero::{self, ZeroItems};
use crate::layout::{Computed, LayoutError, Start, ZeroWeights};
use crate::neighborhood::{build_constraints, prepare, reweigh, Constraint, SimilarityKind};
use crate::pipeline::{self, BuildError, InputFile};
use crate::render::{self, Style};
use crate::state::manifest::{self, Manifest, OutputRecord};
use crate::state;

/// The memo slots of the stages.
#[derive(Default)]
pub(super) struct Slots {
    /// Parse: the dataset, by [`inputs`].
    parsed: Memo<Fingerprint, Arc<Dataset>>,
    /// Prepare: virtual nodes and aggregated vectors, by [`prepared`].
    prepared: Memo<Fingerprint, Arc<Dataset>>,
    /// What the prepared dataset in the slot was made from, so that a
    /// weight edit reweighs it instead of preparing again.
    prepared_from: Option<(SimilarityKind, Arc<Dataset>)>,
    /// Constraints, by [`similarity`].
    constraints: Memo<Fingerprint, Arc<Vec<Constraint>>>,
    /// Layout: the last layout, by the inputs and settings it was made
    /// from; also the next warm start ([`start`]).
    pub(super) layout: Memo<LayoutKey, Laid>,
}

/// What a layout was made from.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct LayoutKey {
    /// The inputs' key.
    pub inputs: Fingerprint,
    /// The layout settings' key.
    pub settings: Fingerprint,
}

/// A layout and the fingerprint of its stored text (its identity in the
/// render keys and the page's history).
#[derive(Clone)]
pub(super) struct Laid {
    pub(super) state: Fingerprint,
    pub(super) computed: Arc<Computed>,
}

/// What [`DatasetGraph::ready`] gives a build: the parsed inputs with their
/// warnings, and what a layout is made from when the build lays out.
struct Readied {
    dataset: Arc<Dataset>,
    warnings: Vec<String>,
    input: Option<(Prepared, Plan, Arc<ZeroItems>)>,
}

/// What the layout stage hands on.
struct LayoutOut {
    laid: Laid,
    step: LayoutStep,
    ms: f64,
    started_from: Option<Arc<crate::layout::Previous>>,
}

/// A layout run before its stored text is made.
struct Ran {
    computed: Arc<Computed>,
    step: LayoutStep,
    ms: f64,
    started_from: Option<Arc<crate::layout::Previous>>,
    /// The state of the stored layout the build found.
    stored: Option<Fingerprint>,
}

/// What a build draws for: its job, its layout key, the manifest it found
/// and the output files on disk.
pub(super) struct Target<'a> {
    pub(super) job: &'a Job<'a>,
    pub(super) key: LayoutKey,
    pub(super) manifest: &'a Manifest,
    pub(super) disk: &'a [Option<OnDisk>],
}

/// Each output's manifest record and build, in config order.
pub(super) type Drawn = Vec<(OutputRecord, OutputBuild)>;

impl DatasetGraph {
    /// [`DatasetGraph::build`] from files already read: the chain of stages.
    pub fn build_from(
        &mut self,
        job: &Job<'_>,
        files: &[InputFile],
        mut stages: StageReport,
    ) -> Result<DatasetBuild, BuildError> {
        let d = job.dataset;
        let key = LayoutKey {
            inputs: inputs(d, files),
            settings: manifest::settings_key(&job.request.settings()),
        };
        let manifest = self.manifest_of(d);
        // A new render: the labels of the one before last are dropped.
        self.parts.next_render();
        // Each output file is read and hashed on its own thread (tens of
        // megabytes at thousands of leaves).
        let disk: Vec<Option<OnDisk>> = {
            use rayon::prelude::*;
            d.outputs.par_iter().map(|o| super::on_disk(&o.path)).collect()
        };
        // The group colours of the last build are kept (issue 32): they are
        // part of the style every render key names.
        let mut style = job.style.clone();
        style.cells.kept = render::Kept {
            groups: manifest.group_colors(),
            main: manifest.shades.clone(),
        };
        let current = self.current_outputs(job, &style, &manifest, key, &disk);
        let facts = start::Facts {
            refusal: start::refusal(job.cold, self.options.cache),
            inputs: key.inputs,
            settings: key.settings,
            outputs_current: current.is_some(),
            memory: None,
        };
        // Nothing in memory and outputs to make: the decision is to lay out.
        let speculate = current.is_none() && self.slots.layout.last().is_none();
        let decided = (!speculate).then(|| self.decide(d, facts));
        if let (Some(Decision::UpToDate), Some(outputs), Some(record)) =
            (&decided, current, manifest.layout.as_ref())
        {
            return Ok(self.up_to_date(d, record, outputs, stages));
        }
        let mut pending = Pending::default();
        let mut cx = Cx {
            name: &d.name,
            cache: self.options.cache,
            stages: &mut stages,
        };
        let (decision, readied) = if let Some(decision) = decided {
            let lay_out = matches!(decision, Decision::LayOut(_));
            let readied = self.ready(job, files, key, lay_out, &mut cx, &mut pending)?;
            (decision, readied)
        } else {
            self.decide_beside_ready(job, files, key, facts, &mut cx, &mut pending)?
        };
        let Readied {
            dataset,
            mut warnings,
            input,
        } = readied;
        let mut notes = Vec::new();
        let target = Target {
            job,
            key,
            manifest: &manifest,
            disk: &disk,
        };
        let (out, outputs) = match (decision, input) {
            (Decision::LayOut(chosen), Some(input)) => {
                if let Some(warning) = &chosen.warning {
                    // First: it is about the whole run.
                    warnings.insert(0, warning.clone());
                }
                let ran = self.lay_out_from(job, chosen, input, &mut cx, &mut notes)?;
                self.draw_ran(&target, &mut style, ran, &mut cx, &mut pending)?
            }
            _ => {
                let out = self.same(d, &mut cx, &mut pending);
                let past = self.past.iter().cloned().collect::<Vec<_>>();
                let drawn = self.draw(&target, &mut style, &out.laid, &past, &mut cx)?;
                (out, drawn)
            }
        };
        let colors = style.cells.kept;
        let records = outputs.iter().map(|(r, _)| r.clone()).collect();
        let next = Self::next_manifest(key, &out.laid, &dataset, records, &colors);
        let realized = next.layout.as_ref().map_or(0, |r| r.realized);
        pending.manifest = Some(next);
        Ok(DatasetBuild {
            name: d.name.clone(),
            started_from: out.started_from.filter(|_| out.step == LayoutStep::Warm),
            layout: out.step,
            layout_ms: out.ms,
            constraints: out.laid.computed.constraints.len(),
            realized,
            computed: Some(out.laid.computed),
            outputs: outputs.into_iter().map(|(_, o)| o).collect(),
            warnings,
            notes,
            stages,
            pending,
        })
    }

    /// Where the build starts ([`start::decide`]), with the layout in memory
    /// if there is one.
    fn decide(&self, d: &DatasetConfig, facts: start::Facts<'_>) -> Decision {
        let memory = self.slots.layout.last().map(|(k, laid)| start::Memory {
            inputs: k.inputs,
            settings: k.settings,
            computed: &laid.computed,
            previous: self
                .next_previous
                .as_ref()
                .filter(|(state, _)| *state == laid.state)
                .map(|(_, p)| p),
        });
        start::decide(start::Facts { memory, ..facts }, || state::layout::read(d))
    }

    /// The decision and the inputs readied at once, for a build with nothing
    /// in memory and outputs to make: the decision is then to lay out, so
    /// reading the stored layout (the warm start's previous, tens of
    /// megabytes at thousands of leaves) and readying the inputs (parse,
    /// prepare, constraints) need not wait for each other.
    fn decide_beside_ready(
        &mut self,
        job: &Job<'_>,
        files: &[InputFile],
        key: LayoutKey,
        facts: start::Facts<'_>,
        cx: &mut Cx<'_>,
        pending: &mut Pending,
    ) -> Result<(Decision, Readied), BuildError> {
        let d = job.dataset;
        let (decision, readied) = rayon::join(
            || start::decide(facts, || state::layout::read(d)),
            || self.ready(job, files, key, true, cx, pending),
        );
        Ok((decision, readied?))
    }

    /// Parse: the input files into a dataset.
    fn parse(
        &mut self,
        d: &DatasetConfig,
        files: &[InputFile],
        key: Fingerprint,
        cx: &mut Cx<'_>,
    ) -> Result<Arc<Dataset>, BuildError> {
        self.slots.parsed.get_or(key, cx, Stage::Parse, "inputs unchanged", || {
            let dataset = pipeline::parse_inputs(d, files)?;
            let note = format!("{} nodes", dataset.len());
            Ok(Made::Ran(Arc::new(dataset), note))
        })
    }

    /// The inputs parsed (with their warnings) and, when the build lays out
    /// (`lay_out`), what the layout is made from: the items of weight 0
    /// hidden or kept (issue 34: everything below works on what is drawn),
    /// the plan, the prepared dataset and its constraints.
    fn ready(
        &mut self,
        job: &Job<'_>,
        files: &[InputFile],
        key: LayoutKey,
        lay_out: bool,
        cx: &mut Cx<'_>,
        pending: &mut Pending,
    ) -> Result<Readied, BuildError> {
        let d = job.dataset;
        let dataset = self.parse(d, files, key.inputs, cx)?;
        let mut warnings = pipeline::warnings(files, &dataset);
        warnings.extend(unknown_pins(&dataset, &job.style));
        if !lay_out {
            return Ok(Readied {
                dataset,
                warnings,
                input: None,
            });
        }
        let mode = job.request.params.zero_weights;
        let (drawn, zero) = zero::apply(&dataset, mode);
        let planned = plan(&drawn, &job.request).map_err(|e| layout_error(d, e))?;
        let source = drawn_key(key.inputs, mode);
        let input = self.similar(Some(d), source, &drawn, &planned, cx, pending);
        Ok(Readied {
            dataset,
            warnings,
            input: Some((input, planned, zero)),
        })
    }

    /// Prepare and constraints for a run (none for a plain treemap, and no
    /// constraints when the plan needs none: `plain`, issue 34). Constraints
    /// computed now go to `pending`, for the state folder's cache.
    pub(super) fn similar(
        &mut self,
        d: Option<&DatasetConfig>,
        source: Fingerprint,
        dataset: &Arc<Dataset>,
        planned: &Plan,
        cx: &mut Cx<'_>,
        pending: &mut Pending,
    ) -> Prepared {
        let Some(kind) = planned.kind else {
            return Prepared::Plain(Arc::clone(dataset));
        };
        let prepared = self.prepare(source, dataset, kind, cx);
        let constraints = if planned.constraints {
            self.constraints(d, dataset, &prepared, kind, cx, pending)
        } else {
            cx.record(Stage::Constraints, false, Instant::now(), "none needed (plain)");
            Arc::new(Vec::new())
        };
        Prepared::Similar(prepared, constraints.as_ref().clone())
    }

    /// Prepare: virtual nodes and aggregated vectors (paper §4).
    fn prepare(
        &mut self,
        source: Fingerprint,
        dataset: &Arc<Dataset>,
        kind: SimilarityKind,
        cx: &mut Cx<'_>,
    ) -> Arc<Dataset> {
        let key = prepared(source, kind);
        let last = self.slots.prepared.last().map(|(_, p)| Arc::clone(p));
        let from = self.slots.prepared_from.replace((kind, Arc::clone(dataset)));
        let made = self.slots.prepared.get_or(key, cx, Stage::Prepare, "dataset unchanged", || {
            // A weight edit: the last prepared tree with the new weights.
            let reweighed = match (&last, &from) {
                (Some(last), Some((k, before))) if *k == kind => reweigh(last, before, dataset),
                _ => None,
            };
            let (prepared, how) = match reweighed {
                Some(p) => (p, "; weights only"),
                None => (prepare(dataset), ""),
            };
            let note = format!("{} nodes{how}", prepared.len());
            Ok::<_, std::convert::Infallible>(Made::Ran(Arc::new(prepared), note))
        });
        match made {
            Ok(prepared) => prepared,
            Err(never) => match never {},
        }
    }

    /// Constraints (method-reference §3): from memory, else from the state
    /// folder's cache (for a configured dataset `d`), else computed.
    fn constraints(
        &mut self,
        d: Option<&DatasetConfig>,
        dataset: &Dataset,
        prepared: &Arc<Dataset>,
        kind: SimilarityKind,
        cx: &mut Cx<'_>,
        pending: &mut Pending,
    ) -> Arc<Vec<Constraint>> {
        let key = similarity(dataset, kind);
        let cache = cx.cache;
        let made = self.slots.constraints.get_or(key, cx, Stage::Constraints, "similarity unchanged", || {
            if let Some(cached) = d
                .filter(|_| cache)
                .and_then(|d| state::constraints::read(d, key, prepared))
            {
                let note = format!("{} from the cache", cached.len());
                return Ok::<_, std::convert::Infallible>(Made::Loaded(Arc::new(cached), note));
            }
            let constraints = Arc::new(build_constraints(prepared, kind));
            pending.constraints = Some((key, Arc::clone(prepared), Arc::clone(&constraints)));
            let note = format!("{} constraints", constraints.len());
            Ok(Made::Ran(constraints, note))
        });
        match made {
            Ok(constraints) => constraints,
            Err(never) => match never {},
        }
    }

    /// The layout in memory, made from the same inputs and settings: the
    /// stages before it are not run. It is stored again when the state
    /// folder moved since (a `state_dir:` edit, another set of outputs), so
    /// that the new folder holds the layout its manifest vouches for.
    fn same(&mut self, d: &DatasetConfig, cx: &mut Cx<'_>, pending: &mut Pending) -> LayoutOut {
        for stage in [Stage::Prepare, Stage::Constraints, Stage::Layout] {
            cx.record(stage, false, Instant::now(), "in memory");
        }
        let (_, laid) = self.slots.layout.last().expect("decided Same: a layout in memory");
        if self.stored_at != state::layout_path(d) {
            let text = state::layout::text(&laid.computed, Some(self.parts.documents()));
            pending.layout = Some((text, laid.state, laid.computed.known_adjacency()));
        }
        LayoutOut {
            laid: laid.clone(),
            step: LayoutStep::Reused,
            ms: 0.0,
            started_from: None,
        }
    }

    /// Layout: a run from the previous layout [`start::decide`] chose.
    fn lay_out_from(
        &mut self,
        job: &Job<'_>,
        chosen: Chosen,
        (input, planned, zero): (Prepared, Plan, Arc<ZeroItems>),
        cx: &mut Cx<'_>,
        notes: &mut Vec<String>,
    ) -> Result<Ran, BuildError> {
        let mut request = job.request.clone();
        request.previous = chosen.previous;
        let started_from = request.previous.clone();
        // Whether the previous layout's adjacency per level comes with it
        // for these nodes (in memory, or beside the stored layout): a warm
        // layout then compares only the pairs of the cells that moved.
        let kept_adjacency = started_from.as_deref().is_some_and(|p| {
            let (Prepared::Plain(d) | Prepared::Similar(d, _)) = &input;
            p.levels_of(d).is_some()
        });
        let t = Instant::now();
        let computed =
            lay_out_planned(input, planned, &request, zero).map_err(|e| layout_error(job.dataset, e))?;
        let ms = ms_since(t);
        let report = &computed.report;
        let step = match &computed.start {
            Start::Warm { .. } if report.iterations == 0 && report.reused == report.diagrams => {
                LayoutStep::Reused
            }
            Start::Warm { .. } => LayoutStep::Warm,
            Start::Refused(why) => {
                notes.push(format!("previous layout not used ({why}); laid out cold"));
                LayoutStep::Cold(why.to_string())
            }
            _ => LayoutStep::Cold(chosen.cold_because.unwrap_or("no previous layout").to_string()),
        };
        let note = match &step {
            LayoutStep::Reused => "every diagram as stored, no tick".to_string(),
            LayoutStep::Warm if kept_adjacency => {
                format!("warm, {} ticks, adjacency kept", report.iterations)
            }
            LayoutStep::Warm => format!("warm, {} ticks", report.iterations),
            LayoutStep::Cold(why) => format!("cold: {why}"),
            LayoutStep::UpToDate => String::new(),
        };
        cx.record(Stage::Layout, step != LayoutStep::Reused, t, note);
        Ok(Ran {
            // Shared from here on: the stored layout's text keeps its
            // extras for the `.json` output of this computation.
            computed: Arc::new(computed),
            step,
            ms,
            started_from,
            stored: chosen.stored,
        })
    }

    /// The outputs of a run and its stored layout's text, whose fingerprint
    /// (the layout's state) names the layout in every render key and in
    /// the page's history. A run whose cells moved has a new text, so its
    /// outputs are drawn beside the text (on the other cores) and keyed
    /// once it is known; should the text be the last layout's after all,
    /// the page's history is not the one drawn, and they are drawn again.
    fn draw_ran(
        &mut self,
        target: &Target<'_>,
        style: &mut Style,
        ran: Ran,
        cx: &mut Cx<'_>,
        pending: &mut Pending,
    ) -> Result<(LayoutOut, Drawn), BuildError> {
        let computed = Arc::clone(&ran.computed);
        self.seed_labels(target.job.dataset);
        if ran.step == LayoutStep::Reused {
            // The labels the pictures will draw (every core) beside the
            // text (one thread), which decides whether anything is drawn.
            let pictured = target.job.dataset.outputs.iter().any(|o| o.kind().styled());
            let (text, ()) = rayon::join(
                || state::layout::text(&computed, Some(self.parts.documents())),
                || {
                    if pictured {
                        render::fit_labels(&computed, &target.job.style, &self.parts);
                    }
                },
            );
            let out = self.settle(target.key, ran, text, pending);
            let past = self.past.iter().cloned().collect::<Vec<_>>();
            let drawn = self.draw(target, style, &out.laid, &past, cx)?;
            return Ok((out, drawn));
        }
        let last = self.slots.layout.last().map(|(_, l)| l.state);
        let past = self.past_beside_new();
        let mut colored = style.clone();
        let recorded = cx.stages.runs.len();
        let this = &*self;
        let (text, drawn) = rayon::join(
            || state::layout::text(&computed, Some(this.parts.documents())),
            || {
                colored.cells.kept = render::group_colors(&computed, &colored);
                this.render(target, &colored, &computed, None, &past, cx)
            },
        );
        let out = self.settle(target.key, ran, text, pending);
        if last == Some(out.laid.state) {
            // The report keeps the drawing that counts.
            cx.stages.runs.truncate(recorded);
            let past = self.past.iter().cloned().collect::<Vec<_>>();
            let drawn = self.draw(target, style, &out.laid, &past, cx)?;
            return Ok((out, drawn));
        }
        let builds = drawn?;
        *style = colored;
        let keys = render_keys(target, style, out.laid.state, &past);
        Ok((out, records(target, keys, builds)))
    }

    /// The colours a build draws with, every group's fixed (recorded, so
    /// the next build keeps them and finds its render keys unchanged), and
    /// its outputs, each drawn or found by its render key.
    fn draw(
        &self,
        target: &Target<'_>,
        style: &mut Style,
        laid: &Laid,
        past: &[(Fingerprint, Arc<Computed>)],
        cx: &mut Cx<'_>,
    ) -> Result<Drawn, BuildError> {
        style.cells.kept = render::group_colors(&laid.computed, style);
        let keys = render_keys(target, style, laid.state, past);
        let builds = self.render(target, style, &laid.computed, Some(&keys), past, cx)?;
        Ok(records(target, keys, builds))
    }

    /// What the stored layout's text settles: the layout's state, the text
    /// to store unless it is stored already, the last layout become history
    /// when it differs, and the layout slot.
    fn settle(&mut self, key: LayoutKey, ran: Ran, text: String, pending: &mut Pending) -> LayoutOut {
        let state = Fingerprint::of_bytes(text.as_bytes());
        if ran.stored != Some(state) {
            pending.layout = Some((text, state, ran.computed.known_adjacency()));
        }
        let laid = Laid {
            state,
            computed: ran.computed,
        };
        if let Some((_, last)) = self.slots.layout.take() {
            match last.state != state {
                true => self.past.push_back((last.state, last.computed)),
                false => self.retired.push(last.computed),
            }
        }
        while self.past.len() > self.history {
            if let Some((_, old)) = self.past.pop_front() {
                self.retired.push(old);
            }
        }
        self.slots.layout.set(key, laid.clone());
        LayoutOut {
            laid,
            step: ran.step,
            ms: ran.ms,
            started_from: ran.started_from,
        }
    }

    /// The past layouts as [`DatasetGraph::settle`] leaves them for a
    /// layout unlike the last one.
    fn past_beside_new(&self) -> Vec<(Fingerprint, Arc<Computed>)> {
        let mut past: Vec<_> = self.past.iter().cloned().collect();
        if let Some((_, last)) = self.slots.layout.last() {
            past.push((last.state, Arc::clone(&last.computed)));
        }
        let over = past.len().saturating_sub(self.history);
        past.drain(..over);
        past
    }
}

/// Each output's render key for the layout of `state` drawn with `style`.
/// The past layouts are one more input of the HTML page's render, keyed by
/// their stored layouts' fingerprints (as the current one is): a page is
/// rendered again when its history changed, and the other outputs, which do
/// not show it, are not.
fn render_keys(
    target: &Target<'_>,
    style: &Style,
    state: Fingerprint,
    past: &[(Fingerprint, Arc<Computed>)],
) -> Vec<Fingerprint> {
    let past_states: Vec<Fingerprint> = past.iter().map(|(s, _)| *s).collect();
    target
        .job
        .dataset
        .outputs
        .iter()
        .map(|out| output_key(target.key, state, style, out, &past_states))
        .collect()
}

/// The manifest's record of each output (its render key and bytes) beside
/// its build, in config order.
fn records(target: &Target<'_>, keys: Vec<Fingerprint>, builds: Vec<OutputBuild>) -> Drawn {
    let d = target.job.dataset;
    d.outputs
        .iter()
        .zip(keys)
        .zip(builds)
        .map(|((out, render), built)| {
            let record = OutputRecord {
                path: manifest::relative(d, &out.path),
                render,
                bytes: built.fingerprint,
            };
            (record, built)
        })
        .collect()
}

/// A warning per `render.colors` entry that names no top-level group: a
/// typo must not pass as a pinned colour silently.
fn unknown_pins(dataset: &Dataset, style: &Style) -> Vec<String> {
    let groups = &dataset.node(dataset.root()).children;
    let known = |key: &str| {
        groups.iter().any(|&g| {
            let node = dataset.node(g);
            node.id == key || node.label == key
        })
    };
    style
        .cells
        .group_colors
        .keys()
        .filter(|key| !known(key))
        .map(|key| {
            format!("render.colors: no top-level group has the id or label {key:?}; that colour is not used")
        })
        .collect()
}

/// A layout error of dataset `d`.
pub(super) fn layout_error(d: &DatasetConfig, source: LayoutError) -> BuildError {
    BuildError::Layout {
        dataset: d.name.clone(),
        source,
    }
}

/// Read and parse: the input bytes by role and everything that decides how
/// they are read (format, field mapping, limits, an exec command). Not the
/// paths: a moved file with the same bytes gives the same dataset.
pub fn inputs(d: &DatasetConfig, files: &[InputFile]) -> Fingerprint {
    let mut f = Fingerprinter::new("inputs");
    f.str(&d.format).value(&d.fields).value(&d.command);
    for file in files {
        f.str(&file.role).bytes(&file.bytes);
    }
    f.finish()
}

/// What is drawn of the parsed inputs: the inputs' key and whether items of
/// weight 0 are hidden (`layout.zero_weights`), which decides the nodes
/// that are prepared. The source of the prepared dataset's key in a build.
pub fn drawn_key(inputs: Fingerprint, zero_weights: ZeroWeights) -> Fingerprint {
    Fingerprinter::new("drawn")
        .fingerprint(inputs)
        .str(zero_weights.name())
        .finish()
}

/// Prepare: the dataset it starts from (its `source` key: [`drawn_key`] in
/// a build, [`dataset`] for one given in memory) and the similarity.
pub fn prepared(source: Fingerprint, kind: SimilarityKind) -> Fingerprint {
    Fingerprinter::new("prepared")
        .fingerprint(source)
        .value(&kind)
        .finish()
}

/// Constraints: what the constraints of a dataset depend on, and nothing
/// else: the measure, and per node (in order) its id, parent, vector and
/// relations. Weights, labels and colours are left out, so a weight edit
/// keeps the constraints (vectors of inner nodes are plain means of their
/// children's, never weighted: `neighborhood::prepare`).
pub fn similarity(dataset: &Dataset, kind: SimilarityKind) -> Fingerprint {
    Fingerprinter::new("similarity")
        .value(&kind)
        .fingerprint(similarity_of_nodes(dataset))
        .finish()
}

/// The per-node part of [`similarity`].
fn similarity_of_nodes(dataset: &Dataset) -> Fingerprint {
    let mut f = Fingerprinter::new("nodes");
    f.u64(dataset.len() as u64);
    for node in dataset.nodes() {
        f.str(&node.id)
            .u64(node.parent.map_or(u64::MAX, |p| p as u64));
        match &node.features {
            Some(Features::Dense(values)) => {
                f.u64(values.len() as u64);
                for &v in values.iter() {
                    f.f64(v);
                }
            }
            Some(Features::Sparse(sparse)) => {
                // Marked apart from a dense vector of the same length.
                f.u64(u64::MAX - 1).u64(sparse.len() as u64);
                f.u64(sparse.indices().len() as u64);
                for (k, v) in sparse.entries() {
                    f.u64(u64::from(k)).f64(v);
                }
            }
            None => {
                f.u64(u64::MAX);
            }
        }
        f.u64(node.relations.len() as u64);
        for &r in &node.relations {
            f.u64(r as u64);
        }
    }
    f.finish()
}

/// A dataset given in memory (`layout`, `eval`): all of it (what the
/// similarity key covers, and weights, labels, colours, virtual flags and
/// the similarity hint), for the memo of its prepared form.
pub fn dataset(dataset: &Dataset) -> Fingerprint {
    let mut f = Fingerprinter::new("dataset");
    f.value(&dataset.similarity_hint());
    for node in dataset.nodes() {
        f.str(&node.label)
            .f64(node.weight.unwrap_or(f64::NAN))
            .f64(node.value)
            .value(&node.color)
            .u64(u64::from(node.is_virtual));
    }
    f.fingerprint(similarity_of_nodes(dataset));
    f.finish()
}

/// Render: one output's bytes depend on the renderers themselves (a
/// fingerprint of their sources, made at compile time: outputs of another
/// version are made again), the layout (the inputs and settings
/// it was made from and the stored layout's bytes, which hold every cell and
/// constraint), the style (unless its kind shows none), the output's kind
/// and scale, and the past layouts of a kind that shows them (their stored
/// layouts' fingerprints, oldest first).
pub fn output_key(
    key: LayoutKey,
    layout: Fingerprint,
    style: &Style,
    output: &OutputConfig,
    past: &[Fingerprint],
) -> Fingerprint {
    let kind = output.kind();
    let mut f = Fingerprinter::new("render");
    f.str(env!("NPTREEMAP_RENDER_SOURCE"))
        .fingerprint(key.inputs)
        .fingerprint(key.settings)
        .fingerprint(layout)
        .value(&kind)
        .f64(output.scale);
    if kind.styled() {
        f.value(style);
    }
    if kind.shows_history() && !past.is_empty() {
        f.str("history");
        for state in past {
            f.fingerprint(*state);
        }
    }
    f.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn data(weight: f64, features: Vec<f64>) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        b.add(NodeSpec::new("a").parent("r").weight(weight).features(features));
        b.add(NodeSpec::new("b").parent("r").weight(1.0).features(vec![1.0, 0.0]));
        b.build().expect("valid")
    }

    #[test]
    fn the_similarity_key_ignores_weights_only() {
        let k = |d: &Dataset| similarity(d, SimilarityKind::Cosine);
        let base = data(1.0, vec![0.0, 1.0]);
        assert_eq!(k(&base), k(&data(7.0, vec![0.0, 1.0])));
        assert_ne!(k(&base), k(&data(1.0, vec![1.0, 1.0])));
        assert_ne!(k(&base), similarity(&base, SimilarityKind::Jaccard));
    }
}
