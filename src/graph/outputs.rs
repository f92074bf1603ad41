//! The outputs of a build: which files already hold what this build would
//! render (their render keys against the manifest, `current_outputs` and
//! `known`), the render stage (`render`: the rest at once, with
//! `render_in_parallel`), and the manifest's record of them
//! (`next_manifest`). Part of the stage graph (`stages.rs` runs the chain).

use std::sync::Arc;
use std::time::Instant;

use nptreemap_formats::Dataset;

use super::memo::{ms_since, Cx};
use super::stages::{output_key, Laid, LayoutKey, Target};
use super::{DatasetGraph, Job, OnDisk, OutputBuild, Stage};
use crate::config::{DatasetConfig, OutputConfig};
use crate::fingerprint::Fingerprint;
use crate::layout::Computed;
use crate::pipeline::{self, BuildError};
use crate::render::{self, Style};
use crate::state::manifest::{self, LayoutRecord, Manifest, OutputRecord};

impl DatasetGraph {
    /// Render: each output whose file does not hold its bytes already, all
    /// of them at once ([`render_in_parallel`]). Without the render `keys`
    /// (the layout's stored text not made yet) none is taken as current.
    pub(super) fn render(
        &self,
        target: &Target<'_>,
        style: &Style,
        computed: &Arc<Computed>,
        keys: Option<&[Fingerprint]>,
        past: &[(Fingerprint, Arc<Computed>)],
        cx: &mut Cx<'_>,
    ) -> Result<Vec<OutputBuild>, BuildError> {
        let Target {
            job,
            manifest,
            disk,
            ..
        } = *target;
        let d = job.dataset;
        let past: Vec<Arc<Computed>> = past.iter().map(|(_, c)| Arc::clone(c)).collect();
        let t = Instant::now();
        let known: Vec<Option<OutputBuild>> = d
            .outputs
            .iter()
            .zip(disk)
            .enumerate()
            .map(|(k, (out, disk))| {
                keys.and_then(|keys| self.known(d, manifest, out, keys[k], *disk))
            })
            .collect();
        let needed: Vec<&OutputConfig> = d
            .outputs
            .iter()
            .zip(&known)
            .filter(|(_, k)| k.is_none())
            .map(|(out, _)| out)
            .collect();
        self.seed_labels(d);
        #[cfg(feature = "png")]
        self.seed_pictures(d, &needed);
        let mut drawn =
            render_in_parallel(computed, style, &needed, &past, &self.parts)?.into_iter();
        let labels = self.parts.counts();
        let mut noted = false;
        #[cfg(feature = "png")]
        let mut bands_noted = false;
        let mut outputs = Vec::with_capacity(d.outputs.len());
        for ((out, disk), known) in d.outputs.iter().zip(disk).zip(known) {
            let shown = super::shown(d, &out.path);
            let built = match known {
                Some(built) => {
                    cx.record_output(Stage::Render, shown, false, t, "file up to date");
                    built
                }
                None => {
                    let (bytes, ms) = drawn.next().expect("one rendering per output needed");
                    let mut note = out.kind().name().to_string();
                    // The labels' counts go with the first output that drew any.
                    if out.kind().styled() && !noted && labels.reused + labels.fitted > 0 {
                        noted = true;
                        note += &format!(
                            "; labels: {} fitted, {} reused",
                            labels.fitted, labels.reused
                        );
                    }
                    // The cell elements of this build's pictures, and the
                    // node lines of its layout JSON (this output's and the
                    // stored layout's), when the memos are in use.
                    if out.kind() == render::OutputKind::Svg && self.parts.cell_lines().is_some() {
                        let c = self.parts.cell_counts();
                        note += &format!("; cells: {} written, {} reused", c.written, c.reused);
                    }
                    if out.kind() == render::OutputKind::Json && self.parts.documents().lines().is_some() {
                        let l = self.parts.line_counts();
                        note += &format!("; node lines: {} written, {} reused", l.written, l.reused);
                    }
                    // The PNGs' bands, summed over this render's PNGs.
                    #[cfg(feature = "png")]
                    if out.kind() == render::OutputKind::Png && !bands_noted {
                        bands_noted = true;
                        let b = self.parts.band_counts();
                        note += &format!(
                            "; bands: {} painted, {} kept; usvg documents: {}",
                            b.painted, b.kept, b.documents
                        );
                    }
                    cx.record_output_ms(Stage::Render, shown, ms, note);
                    OutputBuild::made(out.path.clone(), bytes, *disk)
                }
            };
            outputs.push(built);
        }
        Ok(outputs)
    }

    /// Gives the label memo, when it holds none (a one-shot build, a
    /// daemon's first render) and an output draws labels, the labels the
    /// state folder kept (`state::labels`): the render then fits only
    /// those of the cells that moved.
    pub(super) fn seed_labels(&self, d: &DatasetConfig) {
        if self.options.cache
            && self.parts.no_labels()
            && d.outputs.iter().any(|o| o.kind().styled())
        {
            self.parts.seed_labels(crate::state::labels::read(d));
        }
    }

    /// Gives the render, for each PNG output of `needed` it has no picture
    /// of (a one-shot build, a daemon's first render), the picture its
    /// file holds when the state folder says what it was painted from and
    /// the file still holds those bytes (`state::pictures`): the render then
    /// repaints only the bands that changed. Anything missing, changed or
    /// not exactly readable costs only the reuse (a whole paint).
    #[cfg(feature = "png")]
    fn seed_pictures(&self, d: &DatasetConfig, needed: &[&OutputConfig]) {
        let wanted: Vec<&&OutputConfig> = needed
            .iter()
            .filter(|o| o.kind() == render::OutputKind::Png && !self.parts.has_png(o.scale))
            .collect();
        if wanted.is_empty() || !self.options.cache {
            return;
        }
        let records = crate::state::pictures::read(d);
        for out in wanted {
            let name = manifest::relative(d, &out.path);
            let Some(r) = records
                .iter()
                .find(|r| r.path == name && r.scale == out.scale)
            else {
                continue;
            };
            let Ok(bytes) = crate::workspace::read_input(&out.path, &d.fields.limits) else {
                continue;
            };
            if xxhash_rust::xxh3::xxh3_128(&bytes) != r.png {
                continue;
            }
            match render::png::read_back(bytes, out.scale, r.svg, r.bands.clone()) {
                Some(painted) => self.parts.seed_png(painted),
                None => tracing::debug!(output = %name, "the PNG cannot be read back exactly"),
            }
        }
    }

    /// What the state folder keeps of this build's PNG outputs: for each
    /// rendered now, what it was painted from (`state::pictures`); `None`
    /// when no PNG was rendered (the records on disk still hold).
    #[cfg(feature = "png")]
    pub(super) fn picture_records(
        &self,
        d: &DatasetConfig,
        outputs: &[OutputBuild],
    ) -> Option<Vec<crate::state::pictures::Record>> {
        let pngs: Vec<(&OutputConfig, &[u8])> = d
            .outputs
            .iter()
            .filter(|o| o.kind() == render::OutputKind::Png)
            .filter_map(|o| {
                let built = outputs.iter().find(|b| b.path == o.path)?;
                Some((o, built.bytes.as_deref()?))
            })
            .collect();
        if pngs.is_empty() {
            return None;
        }
        Some(
            pngs.into_iter()
                .filter_map(|(o, bytes)| {
                    let (bands, svg) = self.parts.painted(o.scale, bytes)?;
                    Some(crate::state::pictures::Record {
                        path: manifest::relative(d, &o.path),
                        scale: o.scale,
                        png: xxhash_rust::xxh3::xxh3_128(bytes),
                        svg,
                        bands,
                    })
                })
                .collect(),
        )
    }

    /// The output as its file holds it, when the manifest vouches that the
    /// file holds what `render_key` renders.
    fn known(
        &self,
        d: &DatasetConfig,
        manifest: &Manifest,
        out: &OutputConfig,
        render_key: Fingerprint,
        disk: Option<OnDisk>,
    ) -> Option<OutputBuild> {
        let record = manifest
            .output(d, &out.path)
            .filter(|r| self.options.cache && r.render == render_key)?;
        let disk = disk.filter(|f| f.fingerprint == record.bytes)?;
        Some(OutputBuild::on_disk(out.path.clone(), disk))
    }

    /// Every output as its file holds it, when the manifest records these
    /// inputs and settings and vouches for every file: the facts of the
    /// "nothing changed" decision.
    pub(super) fn current_outputs(
        &self,
        job: &Job<'_>,
        style: &Style,
        manifest: &Manifest,
        key: LayoutKey,
        disk: &[Option<OnDisk>],
    ) -> Option<Vec<OutputBuild>> {
        let d = job.dataset;
        let record = manifest
            .layout
            .as_ref()
            .filter(|r| r.inputs == Some(key.inputs) && r.settings == key.settings)?;
        let past: Vec<Fingerprint> = self.past.iter().map(|(s, _)| *s).collect();
        d.outputs
            .iter()
            .zip(disk)
            .map(|(out, disk)| {
                let render_key = output_key(key, record.state, style, out, &past);
                self.known(d, manifest, out, render_key, *disk)
            })
            .collect()
    }

    /// The manifest a build leaves for the next: what the layout was made from,
    /// each output's render key and bytes, and the colours drawn (kept next).
    pub(super) fn next_manifest(
        key: LayoutKey,
        laid: &Laid,
        dataset: &Dataset,
        outputs: Vec<OutputRecord>,
        colors: &render::Kept,
    ) -> Manifest {
        let record = LayoutRecord {
            inputs: Some(key.inputs),
            settings: key.settings,
            state: laid.state,
            constraints: laid.computed.constraints.len(),
            realized: laid.computed.realized.iter().filter(|r| **r).count(),
            warnings: dataset
                .warnings()
                .iter()
                .map(|w| (w.role.clone(), w.to_string()))
                .collect(),
        };
        Manifest {
            format: manifest::FORMAT.to_string(),
            layout: Some(record),
            outputs,
            colors: colors.groups.iter().map(|(id, c)| (id.clone(), c.to_hex())).collect(),
            shades: colors.main.clone(),
        }
    }
}

/// Renders `outputs` of one layout at once, each with the milliseconds it
/// took: the picture's SVG text and then the outputs that draw it (the SVG,
/// the PNG) beside the outputs that do not show it (the page, the layout
/// JSON), so a picture's painting never waits for the page or the JSON. The
/// bytes are those of rendering them one by one; only the order of the work
/// changes. The SVG text's time counts towards the first picture.
fn render_in_parallel(
    computed: &Computed,
    style: &Style,
    outputs: &[&OutputConfig],
    past: &[Arc<Computed>],
    parts: &render::Parts,
) -> Result<Vec<(Vec<u8>, f64)>, BuildError> {
    use rayon::prelude::*;
    type Drawn = Result<Vec<(usize, (Vec<u8>, f64))>, BuildError>;
    let pictured = |out: &OutputConfig| out.kind().draws_picture();
    let styled = outputs.iter().position(|o| o.kind().styled());
    let t = Instant::now();
    // Fitted ahead unless the layout step already did it for this render
    // (beside the stored layout's text): a second pass would only find them.
    if styled.is_some() && parts.counts() == render::LabelCounts::default() {
        render::fit_labels(computed, style, parts);
    }
    // The labels' time counts towards the first output that draws them.
    let labels_ms = ms_since(t);
    let timed = |out: &OutputConfig, picture: Option<Arc<render::Picture>>| {
        let t = Instant::now();
        let mut picture = picture;
        pipeline::render_output(computed, style, out, past, &mut picture, parts)
            .map(|b| (b, ms_since(t)))
    };
    let first = outputs.iter().position(|o| pictured(o));
    let (drawn, plain): (Drawn, Drawn) = rayon::join(
        || {
            let Some(first) = first else {
                return Ok(Vec::new());
            };
            let t = Instant::now();
            let picture = Arc::new(render::picture_with(computed, style, parts));
            let picture_ms = ms_since(t);
            outputs
                .par_iter()
                .enumerate()
                .filter(|(_, out)| pictured(out))
                .map(|(k, out)| {
                    let (bytes, ms) = timed(out, Some(Arc::clone(&picture)))?;
                    Ok((k, (bytes, ms + if k == first { picture_ms } else { 0.0 })))
                })
                .collect()
        },
        || {
            outputs
                .par_iter()
                .enumerate()
                .filter(|(_, out)| !pictured(out))
                .map(|(k, out)| Ok((k, timed(out, None)?)))
                .collect()
        },
    );
    let mut all: Vec<(usize, (Vec<u8>, f64))> = drawn?;
    all.extend(plain?);
    all.sort_by_key(|(k, _)| *k);
    Ok(all
        .into_iter()
        .map(|(k, (bytes, ms))| (bytes, ms + if Some(k) == styled { labels_ms } else { 0.0 }))
        .collect())
}
