//! The stored layout of a dataset (`<name>.layout.json`): the last layout in
//! full precision (layout JSON written by [`layout_json::state`]), from which
//! the next build or a restarted `watch` starts warm. Reading it, writing it,
//! and recording in the manifest which settings it was made with. Whether a
//! build starts from it is decided in one place, `graph::start`.

use std::sync::Arc;

use super::manifest::{self, LayoutRecord};
use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::layout::{Computed, Previous};
use crate::{layout_json, store, workspace};

/// A dataset's stored layout, as [`read`] found it.
#[derive(Debug, Default)]
pub struct StoredLayout {
    /// The layout to start warm from, if there is a readable one.
    pub previous: Option<Arc<Previous>>,
    /// The fingerprint of the file's bytes, when it was read.
    pub fingerprint: Option<Fingerprint>,
    /// Why a stored layout that is there could not be used (truncated by a
    /// full disk, edited by hand): the layout starts cold, so the picture
    /// jumps; the user should hear of it. One line, naming the file.
    pub warning: Option<String>,
}

/// The layout stored for a dataset, if there is one. One that cannot be
/// read is not an error (the next build replaces it): it comes back as a
/// warning and the layout starts cold.
pub fn read(d: &DatasetConfig) -> StoredLayout {
    let Some(path) = super::layout_path(d) else {
        return StoredLayout::default();
    };
    let unusable = |why: String| StoredLayout {
        warning: Some(format!(
            "{}: the stored layout cannot be used ({why}); laid out cold, so the picture may move",
            path.display()
        )),
        ..StoredLayout::default()
    };
    let text = match workspace::read_state(&path, &d.fields.limits) {
        Ok(Some(text)) => text,
        Ok(None) => return StoredLayout::default(),
        Err(e) => return unusable(e.to_string()),
    };
    match layout_json::read(&text) {
        Ok(previous) => StoredLayout {
            previous: Some(Arc::new(previous)),
            fingerprint: Some(Fingerprint::of_bytes(text.as_bytes())),
            warning: None,
        },
        Err(e) => unusable(e.to_string()),
    }
}

/// The stored layout's text for a computation (full precision).
pub fn text(computed: &Computed) -> String {
    layout_json::state(computed)
}

/// Writes a stored layout's text (atomically; unchanged bytes are not
/// rewritten). Returns whether it wrote.
pub fn write(d: &DatasetConfig, text: &str) -> std::io::Result<bool> {
    match super::layout_path(d) {
        Some(path) => store::write_if_changed(&path, text.as_bytes()),
        None => Ok(false),
    }
}

/// Stores a dataset's layout and records in the manifest the settings it
/// was made with, without its inputs (which this caller, `nptreemap watch`,
/// does not fingerprint yet): the next build starts warm from it but
/// renders its outputs to compare them. The build itself writes the
/// complete record (`graph`).
pub fn store(d: &DatasetConfig, computed: &Computed) -> std::io::Result<()> {
    let text = text(computed);
    write(d, &text)?;
    let mut m = manifest::read(d);
    m.layout = Some(LayoutRecord {
        inputs: None,
        settings: manifest::settings_key(&computed.settings),
        state: Fingerprint::of_bytes(text.as_bytes()),
        constraints: computed.constraints.len(),
        realized: computed.realized.iter().filter(|r| **r).count(),
        warnings: Vec::new(),
    });
    manifest::write(d, &m).map(|_| ())
}
