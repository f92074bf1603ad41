//! The manifest of a dataset's state (`<name>.manifest.json`): what the
//! stored layout was made from and what every output was rendered from, as
//! fingerprints. It is what lets a build that changes nothing stop after
//! reading and hashing the inputs and the outputs, and what tells which
//! outputs a changed build need not render again.
//!
//! Deterministic JSON (no times, no absolute paths: outputs are named
//! relative to the config's folder), so it can be committed; about 150 bytes
//! plus 150 per output and about 75 per kept colour (a top-level group, or a
//! parent of two children or more: 51 KB for 6,000 C headers in 191 folders). One that is missing, unreadable or of another
//! format reads as empty: the build then recomputes and writes it anew.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::config::DatasetConfig;
use crate::fingerprint::{Fingerprint, Fingerprinter};
use crate::layout::LayoutSettings;
use crate::store;

use super::StateKind;

/// The value of the manifest's `format` field.
pub const FORMAT: &str = "nptreemap-state/1";

/// A dataset's manifest.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: String,
    /// What the stored layout was made from; `None` when there is no stored
    /// layout this manifest vouches for.
    pub layout: Option<LayoutRecord>,
    /// Every output last written, in config order.
    pub outputs: Vec<OutputRecord>,
    /// The colour every top-level group was drawn with (`#rrggbb`, by group
    /// id): the next build keeps them, so no edit recolours a group
    /// (`render::group_colors`). Committed with the rest: a fresh clone
    /// draws the groups in the colours of the committed pictures.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub colors: BTreeMap<String, String>,
    /// Per parent (by id), the child that wore the parent's colour, so the
    /// next build shades the siblings from the same child.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub shades: BTreeMap<String, String>,
}

/// What the stored layout was made from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayoutRecord {
    /// The inputs (bytes and reading settings, see `graph::keys::inputs`);
    /// `None` when the writer did not know them (`nptreemap watch`, which
    /// does not run on the stage graph yet): the layout then still starts
    /// warm, but nothing is taken as up to date.
    pub inputs: Option<Fingerprint>,
    /// The layout settings ([`settings_key`]).
    pub settings: Fingerprint,
    /// The stored layout file's bytes (what the outputs' render keys name).
    pub state: Fingerprint,
    /// Its constraints, for the build's status line.
    pub constraints: usize,
    /// How many of them it realises.
    pub realized: usize,
    /// The input warnings of those inputs, `(role, message)`, printed again
    /// by a build that does not read them.
    pub warnings: Vec<(String, String)>,
}

/// One output as last written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputRecord {
    /// The output's path relative to the config's folder (as configured).
    pub path: String,
    /// What it was rendered from: the layout and the style (`graph::keys::render`).
    pub render: Fingerprint,
    /// Its bytes.
    pub bytes: Fingerprint,
}

impl Manifest {
    /// The recorded group colours that parse (an entry edited into
    /// something else is left out: that group is coloured afresh).
    pub fn group_colors(&self) -> BTreeMap<String, nptreemap_formats::Rgb> {
        self.colors
            .iter()
            .filter_map(|(id, c)| Some((id.clone(), c.parse().ok()?)))
            .collect()
    }

    /// The record of the output at `path`, if any.
    pub fn output(&self, d: &DatasetConfig, path: &Path) -> Option<&OutputRecord> {
        let name = relative(d, path);
        self.outputs.iter().find(|o| o.path == name)
    }
}

/// An output's name in the manifest: its path relative to the config's
/// folder (`out/a.svg`, `../site/a.svg`), or as given when it is absolute.
pub fn relative(d: &DatasetConfig, path: &Path) -> String {
    let rel = path.strip_prefix(&d.base).unwrap_or(path);
    // Forward slashes on every platform, so a committed manifest is the same
    // everywhere.
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy())
        .collect::<Vec<_>>()
        .join("/")
}

/// The fingerprint of the layout settings that shape the picture: the
/// canvas, outline, seed, method, similarity, convergence and iteration
/// settings, and those of the similarity-driven methods: every field of
/// [`LayoutSettings`], by its serialisation, so a field added later is never
/// left out.
pub fn settings_key(settings: &LayoutSettings) -> Fingerprint {
    Fingerprinter::new("settings").value(settings).finish()
}

/// Reads a dataset's manifest; empty when there is none or it cannot be used.
pub fn read(d: &DatasetConfig) -> Manifest {
    let found = match super::read(d, StateKind::Manifest) {
        Ok(Some(found)) => found,
        Ok(None) => return Manifest::default(),
        Err(e) => {
            tracing::info!(error = %e, "manifest not readable; rebuilding it");
            return Manifest::default();
        }
    };
    match serde_json::from_str::<Manifest>(&found.text) {
        Ok(m) if m.format == FORMAT => m,
        Ok(_) | Err(_) => {
            tracing::info!(path = %found.path.display(), "manifest of another format; rebuilding it");
            Manifest::default()
        }
    }
}

/// Writes a dataset's manifest (only when its bytes change). Returns where.
pub fn write(d: &DatasetConfig, manifest: &Manifest) -> std::io::Result<Option<PathBuf>> {
    let Some(path) = super::manifest_path(d) else {
        return Ok(None);
    };
    let mut m = manifest.clone();
    m.format = FORMAT.to_string();
    let mut text = serde_json::to_string_pretty(&m).map_err(std::io::Error::other)?;
    text.push('\n');
    store::write_if_changed(&path, text.as_bytes())?;
    Ok(Some(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_seed_and_every_setting_change_the_key() {
        let base = LayoutSettings::default();
        let mut seed = base.clone();
        seed.params.seed = 2;
        let mut frames = base.clone();
        frames.neighbor.frames = 3;
        assert_eq!(settings_key(&base), settings_key(&base.clone()));
        assert_ne!(settings_key(&base), settings_key(&seed));
        assert_ne!(settings_key(&base), settings_key(&frames));
    }

    #[test]
    fn a_manifest_round_trips_and_names_outputs_relatively() {
        let mut d = DatasetConfig::hierarchy_file(Path::new("data.json"), None);
        d.base = PathBuf::from("docs");
        assert_eq!(relative(&d, Path::new("docs/out/a.svg")), "out/a.svg");
        assert_eq!(relative(&d, Path::new("docs/../site/a.svg")), "../site/a.svg");
        let f = Fingerprint::of_bytes(b"x");
        let m = Manifest {
            format: FORMAT.to_string(),
            layout: Some(LayoutRecord {
                inputs: None,
                settings: f,
                state: f,
                constraints: 3,
                realized: 2,
                warnings: vec![("nodes".into(), "line 2: a self pair".into())],
            }),
            outputs: vec![OutputRecord {
                path: "out/a.svg".into(),
                render: f,
                bytes: f,
            }],
            colors: BTreeMap::from([
                ("group:a".into(), "#4e79a7".into()),
                ("group:b".into(), "not a colour".into()),
            ]),
            shades: BTreeMap::from([("group:a".into(), "a1".into())]),
        };
        let text = serde_json::to_string(&m).expect("json");
        assert_eq!(serde_json::from_str::<Manifest>(&text).expect("back"), m);
        // A colour edited into something else is left out, not an error.
        let kept = m.group_colors();
        assert_eq!(kept.keys().collect::<Vec<_>>(), ["group:a"]);
        assert!(m.output(&d, Path::new("docs/out/a.svg")).is_some());
    }
}
