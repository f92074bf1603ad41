//! The commit of a build: its stale outputs written (atomically, all or
//! none of a set under way at a forced exit), then the state folder beside
//! or after them (the labels, the PNG's bands, the stored layout, the
//! constraint cache) and last the manifest, which vouches for the outputs
//! and may only follow them; and the state a commit could not write, kept
//! for a retry.

use std::path::Path;
use std::time::Instant;

use crate::config::DatasetConfig;
use crate::pipeline::{self, Written};
use crate::state::{self, manifest};

use super::memo;
use super::{shown, DatasetBuild, DatasetGraph, Job, Pending, Stage};

/// What a commit writes to the state folder beside its outputs (or after
/// them: [`DatasetGraph::commit_outputs`]).
pub(super) struct Beside {
    pending: Pending,
    labels: Option<Vec<state::labels::Entry>>,
    #[cfg(feature = "png")]
    pictures: Option<Vec<state::pictures::Record>>,
}

/// What [`DatasetGraph::commit_outputs`] left for
/// [`DatasetGraph::finish_commit`].
pub(super) struct Later {
    dataset: DatasetConfig,
    state: Beside,
    /// Whether every output was written (else the manifest waits).
    complete: bool,
}

impl DatasetGraph {
    /// Writes a build's stale outputs (atomically, all or none of a set
    /// being under way at a forced exit) and, beside them, its stored layout
    /// and constraint cache (a warm start and a cache: neither vouches for
    /// an output, so neither waits for them); then the manifest, which
    /// vouches for the outputs and may only follow them. A state file that
    /// cannot be written only costs the next build its reuse (logged, and
    /// kept for [`DatasetGraph::store_again`]).
    pub fn commit(&mut self, job: &Job<'_>, build: &mut DatasetBuild) -> Written {
        self.commit_now_or_later(job, build, false)
    }

    /// [`DatasetGraph::commit`] for the watch daemon: the outputs now; the
    /// state folder (the labels, the PNG's bands, the stored layout, the
    /// constraint cache and, last, the manifest) by
    /// [`DatasetGraph::finish_commit`], once the rebuild is reported. At
    /// 6,000 leaves the stored layout alone is 21 MB, written beside 29 MB
    /// of outputs; the outputs are what a reader waits for. Until then the
    /// manifest on disk is the last one, which vouches for nothing these
    /// outputs replaced (each output is checked against its digest), and a
    /// process that ends before the finish starts from the last stored
    /// layout, as after a failed write.
    pub fn commit_outputs(&mut self, job: &Job<'_>, build: &mut DatasetBuild) -> Written {
        self.commit_now_or_later(job, build, true)
    }

    /// Writes what [`DatasetGraph::commit_outputs`] left to write, if any,
    /// under the write lock (a forced exit waits for it): the error of the
    /// stored layout, whose state is then kept for
    /// [`DatasetGraph::store_again`].
    pub fn finish_commit(&mut self) -> std::io::Result<()> {
        let Some(later) = self.later.take() else {
            return Ok(());
        };
        let _writing = crate::store::writing();
        let stored = store_beside(&later.dataset, &later.state);
        self.settle_store(&later.dataset, later.state.pending, stored, later.complete)
    }

    fn commit_now_or_later(
        &mut self,
        job: &Job<'_>,
        build: &mut DatasetBuild,
        later: bool,
    ) -> Written {
        let d = job.dataset;
        let t = Instant::now();
        let cache = self.options.cache;
        let pending = if cache {
            std::mem::take(&mut build.pending)
        } else {
            Pending::default()
        };
        let stale: Vec<(&Path, &[u8])> = build
            .outputs
            .iter()
            .filter(|o| o.stale())
            .filter_map(|o| o.bytes.as_deref().map(|bytes| (o.path.as_path(), bytes)))
            .collect();
        #[cfg(feature = "png")]
        let pictures = cache
            .then(|| self.picture_records(d, &build.outputs))
            .flatten();
        let labels = cache.then(|| self.parts.kept_labels()).flatten();
        let state = Beside {
            pending,
            labels,
            #[cfg(feature = "png")]
            pictures,
        };
        let (mut written, stored) = if later {
            (pipeline::write_files_beside(&stale, || ()).0, Ok(()))
        } else {
            pipeline::write_files_beside(&stale, || store_beside(d, &state))
        };
        for o in build.outputs.iter().filter(|o| !o.stale()) {
            written.unchanged.push(o.path.clone());
        }
        // One pass writes the set (under one lock): each output gets its
        // share of the time.
        let ms = memo::ms_since(t) / build.outputs.len().max(1) as f64;
        for o in &build.outputs {
            let wrote = written.written.contains(&o.path);
            let note = if wrote { "written" } else { "file unchanged" };
            let output = shown(d, &o.path);
            build
                .stages
                .record_output(&d.name, Stage::Write, output, wrote, ms, note);
        }
        if !cache {
            return written;
        }
        let complete = written.failed.is_empty();
        if later {
            self.later = Some(Later {
                dataset: d.clone(),
                state,
                complete,
            });
        } else {
            // Errors are logged; a retry comes of `unstored`.
            let _ = self.settle_store(d, state.pending, stored, complete);
        }
        written
    }

    /// What becomes of a build's state once its outputs (`complete`: all of
    /// them) and its state folder (`stored`) were written.
    fn settle_store(
        &mut self,
        d: &DatasetConfig,
        mut pending: Pending,
        stored: std::io::Result<()>,
        complete: bool,
    ) -> std::io::Result<()> {
        // Written now: a retry need not write the cache again.
        pending.constraints = None;
        match stored {
            Err(e) => {
                // The manifest may not vouch for a stored layout that is not
                // there: both wait for the retry.
                tracing::warn!(dataset = %d.name, error = %e, "cannot write the state folder");
                self.unstored = Some(pending);
                return Err(e);
            }
            Ok(()) if complete => {
                self.unstored = None;
                pending.layout = None;
                self.store_manifest(d, pending);
            }
            // The outputs come first: the manifest may not vouch for files
            // that were not written. Kept for the retry that writes them.
            Ok(()) => self.unstored = Some(pending),
        }
        Ok(())
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
    /// the manifest (the manifest only once the stored layout is written).
    fn store(&mut self, d: &DatasetConfig, mut pending: Pending) -> std::io::Result<()> {
        if let Err(e) = store_warm_start(d, &pending) {
            pending.constraints = None;
            self.unstored = Some(pending);
            return Err(e);
        }
        self.store_manifest(d, pending);
        Ok(())
    }

    /// Writes the manifest of `pending`, if any (a manifest that cannot be
    /// written only costs the next build its reuse: logged).
    fn store_manifest(&mut self, d: &DatasetConfig, pending: Pending) {
        if let Some(m) = pending.manifest {
            if let Err(e) = manifest::write(d, &m) {
                tracing::warn!(dataset = %d.name, error = %e, "cannot write the state manifest");
            }
            self.manifest = Some(m);
        }
        self.stored_at = state::layout_path(d);
    }
}

/// Writes `state` but the manifest: the labels and the PNG's bands (a
/// failure only costs the next build their reuse: logged), then
/// [`store_warm_start`].
fn store_beside(d: &DatasetConfig, state: &Beside) -> std::io::Result<()> {
    if let Some(entries) = &state.labels {
        if let Err(e) = state::labels::write(d, entries) {
            tracing::warn!(dataset = %d.name, error = %e, "cannot keep the labels");
        }
    }
    #[cfg(feature = "png")]
    if let Some(records) = &state.pictures {
        if let Err(e) = state::pictures::write(d, records) {
            tracing::warn!(dataset = %d.name, error = %e, "cannot keep the PNG's bands");
        }
    }
    store_warm_start(d, &state.pending)
}

/// Writes the state a next build starts from: the constraint cache (a
/// failure only costs the next process its reuse: logged) and the stored
/// layout (a failure is returned: the manifest must wait for it).
fn store_warm_start(d: &DatasetConfig, pending: &Pending) -> std::io::Result<()> {
    if let Some((key, prepared, constraints)) = &pending.constraints {
        if let Err(e) = state::constraints::write(d, *key, prepared, constraints) {
            tracing::warn!(dataset = %d.name, error = %e, "cannot cache the constraints");
        }
    }
    if let Some((text, fingerprint, levels)) = &pending.layout {
        state::layout::write(d, text)?;
        // Only a cache: its loss costs the next process the comparisons.
        if let Some(levels) = levels {
            if let Err(e) = state::levels::write(d, *fingerprint, levels) {
                tracing::warn!(dataset = %d.name, error = %e, "cannot keep the adjacency");
            }
        }
    }
    Ok(())
}

