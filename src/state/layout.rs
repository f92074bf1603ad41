//! The stored layout of a dataset (`<name>.layout.json`): the last layout in
//! full precision (layout JSON written by [`layout_json::state`]), from which
//! the next build or a restarted `watch` starts warm, with the fingerprint
//! of the layout settings it was made with in its second line
//! (`"nptreemap_settings"`, a field readers of the format ignore). The
//! settings travel inside the file, so no interrupted write can pair a
//! layout with another layout's settings. Whether a build starts from it is
//! decided in one place, `graph::start`.

use std::sync::Arc;

use super::{manifest, StateKind};
use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::layout::{Computed, Previous};
use crate::{layout_json, store};

/// A dataset's stored layout, as [`read`] found it.
#[derive(Debug, Default)]
pub struct StoredLayout {
    /// The layout to start warm from, if there is a readable one.
    pub previous: Option<Arc<Previous>>,
    /// The fingerprint of the file's bytes, when it was read.
    pub fingerprint: Option<Fingerprint>,
    /// The fingerprint of the layout settings it was made with, when it
    /// records them (files of older versions do not).
    pub settings: Option<Fingerprint>,
    /// Why a stored layout that is there could not be used (truncated by a
    /// full disk, edited by hand): the layout starts cold, so the picture
    /// jumps; the user should hear of it. One line, naming the file.
    pub warning: Option<String>,
    /// Read from where an older version left it ([`super::older_paths`]):
    /// not yet where this version keeps it.
    pub older: bool,
}

/// The layout stored for a dataset, if there is one. One that cannot be
/// read is not an error (the next build replaces it): it comes back as a
/// warning and the layout starts cold.
pub fn read(d: &DatasetConfig) -> StoredLayout {
    let unusable = |path: &std::path::Path, why: String| StoredLayout {
        warning: Some(format!(
            "{}: the stored layout cannot be used ({why}); laid out cold, so the picture may move",
            path.display()
        )),
        ..StoredLayout::default()
    };
    let found = match super::read(d, StateKind::Layout) {
        Ok(Some(found)) => found,
        Ok(None) => return StoredLayout::default(),
        Err(e) => return unusable(e.path(), e.to_string()),
    };
    match layout_json::read(&found.text) {
        Ok(previous) => {
            let fingerprint = Fingerprint::of_bytes(found.text.as_bytes());
            // The adjacency the build that wrote this very text found.
            let previous = match super::levels::read(d, fingerprint, previous.nodes().len()) {
                Some(levels) => previous.with_levels(Arc::new(levels)),
                None => previous,
            };
            StoredLayout {
                previous: Some(Arc::new(previous)),
                fingerprint: Some(fingerprint),
                settings: settings_of(&found.text),
                warning: None,
                older: found.older,
            }
        }
        Err(e) => unusable(&found.path, e.to_string()),
    }
}

/// The field holding the settings' fingerprint.
const SETTINGS_FIELD: &str = "\"nptreemap_settings\": \"";

/// The stored layout's text for a computation: layout JSON in full
/// precision, with the fingerprint of its layout settings as the first field.
pub fn text(computed: &Arc<Computed>, memo: Option<&layout_json::DocumentMemo>) -> String {
    let doc = layout_json::state_with(computed, memo);
    let key = manifest::settings_key(&computed.settings);
    match doc.strip_prefix("{\n") {
        Some(rest) => format!("{{\n  {SETTINGS_FIELD}{key}\",\n{rest}"),
        None => doc,
    }
}

/// The settings' fingerprint a stored layout's text records, if any.
fn settings_of(text: &str) -> Option<Fingerprint> {
    let head = text.get(..text.len().min(200))?;
    let at = head.find(SETTINGS_FIELD)? + SETTINGS_FIELD.len();
    Fingerprint::parse(head.get(at..at + 32)?)
}

/// Writes a stored layout's text (atomically; unchanged bytes are not
/// rewritten). Returns whether it wrote.
pub fn write(d: &DatasetConfig, text: &str) -> std::io::Result<bool> {
    match super::layout_path(d) {
        Some(path) => store::write_if_changed(&path, text.as_bytes()),
        None => Ok(false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{compute, Request};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    #[test]
    fn the_stored_layout_carries_its_settings_and_stays_layout_json() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for (id, w) in [("a", 1.0), ("b", 2.0)] {
            b.add(NodeSpec::new(id).parent("r").weight(w));
        }
        let computed = Arc::new(compute(&b.build().expect("valid"), &Request::default()).expect("layout"));
        let text = text(&computed, None);
        assert_eq!(
            settings_of(&text),
            Some(manifest::settings_key(&computed.settings))
        );
        assert!(layout_json::read(&text).is_ok());
        assert_eq!(settings_of(&layout_json::state(&computed)), None);
    }
}
