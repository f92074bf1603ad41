//! The state folder: what a build keeps between runs, where, and in which
//! files. Per dataset, in `.nptreemap/` beside its outputs, in the output
//! folder whose path sorts first ([`dir`]; or the config's `state_dir:`),
//! each file named after the config and the dataset ([`key`]; the dataset
//! alone for `nptreemap.yaml`). What an older version left (plain names,
//! beside the first output) is read while these are missing
//! ([`older_paths`]).
//!
//! - `<name>.layout.json`, the stored layout ([`layout`]): the last layout
//!   in full precision with the fingerprint of the layout settings it was
//!   made with, the next build's warm start. Deterministic bytes (no time,
//!   no absolute path); meant to be committed with the outputs, so that a
//!   fresh clone lays an edited dataset out warm from the same layout. A bit
//!   larger than the layout JSON output, whose coordinates are rounded: 3.5 KB
//!   per leaf on a 6,000-leaf tree 10 levels deep (BENCHMARKS.md, "Output
//!   sizes"), 0.7–1.1 KB on two or three levels. Its cells stay in full
//!   precision: a rebuild that reuses every diagram copies them, and must
//!   write the bytes a cold build wrote.
//! - `<name>.manifest.json`, the manifest ([`manifest`]): fingerprints of the
//!   inputs and layout settings the stored layout was made from and of every
//!   output's bytes and render settings, and the colours the picture was
//!   drawn with (each top-level group's, and per parent the child that
//!   wears its colour; kept by the next build). A build or `build --check` whose
//!   inputs, settings and outputs match it is done after reading and hashing
//!   them. Small (about 150 bytes per output and 75 per kept colour: 51 KB
//!   for 6,000 C headers), deterministic, committed.
//! - `cache/<name>.constraints.bin` ([`constraints`]): the constraints of
//!   the last similarity inputs, so that an edit that leaves them alone (a
//!   weight) recomputes none. Local only: a `.gitignore` in `cache/` says so,
//!   and deleting it costs one computation.
//! - `cache/<name>.pictures.bin` ([`pictures`]): for each PNG output, what
//!   its pixels were painted from (band digests), so that a later process
//!   repaints only the bands an edit changed over the file it reads back.
//!   Local only, like the constraints.
//! - `cache/<name>.labels.bin` ([`labels`]): the leaf labels the last
//!   render fitted, by the digest of what decides each, so that a later
//!   process fits only the labels of the cells that moved. Local only.
//!
//! Every read goes through [`crate::workspace`], every write through
//! [`crate::store`]. A file that cannot be read or is not ours is never an
//! error: the build recomputes what it would have given (and says so for the
//! stored layout, whose loss makes the picture move).

/// What the cache's binary files share: a bounded reader, a version stamp.
mod binary;
/// The constraint cache.
pub mod constraints;
/// The leaf labels fitted last, by what decides each.
pub mod labels;
/// The stored layout: the warm start of the next build.
pub mod layout;
/// The stored layout's adjacency per level, for the warm start.
pub mod levels;
/// The manifest: what the stored layout and the outputs were made from.
pub mod manifest;
/// What each PNG output was painted from, to repaint over it.
pub mod pictures;

use std::path::{Path, PathBuf};

use crate::config::DatasetConfig;
use crate::workspace::{self, FileError};

/// The folder of a dataset's state: the config's `state_dir:` when it has
/// one, else a hidden folder beside its outputs, so it travels with them:
/// in the folder of the output whose folder sorts first (by path), so that
/// reordering the outputs never moves it (issue 30 item 8: it sat beside the
/// first output, and a reorder lost the warm start). `None` for a dataset
/// without outputs.
pub fn dir(d: &DatasetConfig) -> Option<PathBuf> {
    let first = d.outputs.iter().map(|o| output_folder(&o.path)).min()?;
    Some(match &d.state_dir {
        Some(dir) => dir.clone(),
        None => first.join(STATE_FOLDER),
    })
}

/// The hidden folder beside the outputs.
const STATE_FOLDER: &str = ".nptreemap";

/// The folder an output is written into.
fn output_folder(path: &Path) -> &Path {
    path.parent().unwrap_or(Path::new("."))
}

/// A kind of file of a dataset's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateKind {
    /// The stored layout ([`layout`]).
    Layout,
    /// The manifest ([`manifest`]).
    Manifest,
    /// The constraint cache ([`constraints`]), in [`CACHE`].
    Constraints,
    /// What the PNG outputs were painted from ([`pictures`]), in [`CACHE`].
    Pictures,
    /// The leaf labels fitted last ([`labels`]), in [`CACHE`].
    Labels,
    /// The stored layout's adjacency per level ([`levels`]), in [`CACHE`].
    Levels,
}

impl StateKind {
    /// The end of its name, after the dataset's key.
    fn suffix(self) -> &'static str {
        match self {
            StateKind::Layout => "layout.json",
            StateKind::Manifest => "manifest.json",
            StateKind::Constraints => "constraints.bin",
            StateKind::Pictures => "pictures.bin",
            StateKind::Labels => "labels.bin",
            StateKind::Levels => "levels.bin",
        }
    }

    /// Its path in the state folder `dir`, for a key.
    fn in_dir(self, dir: &Path, key: &str) -> PathBuf {
        let name = format!("{key}.{}", self.suffix());
        match self {
            StateKind::Constraints
            | StateKind::Pictures
            | StateKind::Labels
            | StateKind::Levels => {
                dir.join(CACHE).join(name)
            }
            _ => dir.join(name),
        }
    }
}

/// Where this version keeps a state file of `d`.
pub fn path(d: &DatasetConfig, file: StateKind) -> Option<PathBuf> {
    Some(file.in_dir(&dir(d)?, &key(d)))
}

/// The stored layout's path (see [`layout`]).
pub fn layout_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Layout)
}

/// The manifest's path (see [`manifest`]).
pub fn manifest_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Manifest)
}

/// The constraint cache's path (see [`constraints`]).
pub fn constraints_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Constraints)
}

/// The PNG outputs' picture records' path (see [`pictures`]).
pub fn pictures_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Pictures)
}

/// The leaf labels' path (see [`labels`]).
pub fn labels_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Labels)
}

/// The stored layout's adjacency's path (see [`levels`]).
pub fn levels_path(d: &DatasetConfig) -> Option<PathBuf> {
    path(d, StateKind::Levels)
}

/// Where an older version may have left a state file of `d`, most likely
/// first: under the dataset's plain name (before the config's name was part
/// of it) in the state folder, then, without `state_dir:`, beside each
/// output's folder in config order (an older version kept it beside the
/// first output), under either name. Read only while the file is missing
/// where this version keeps it; the next commit writes it there. The
/// constraint cache, local only, is not looked for.
pub fn older_paths(d: &DatasetConfig, file: StateKind) -> Vec<PathBuf> {
    let Some(here) = dir(d) else {
        return Vec::new();
    };
    let mut keys = vec![key(d)];
    let plain = plain_key(&d.name);
    if keys[0] != plain {
        keys.push(plain);
    }
    let mut dirs = vec![here.clone()];
    if d.state_dir.is_none() {
        for o in &d.outputs {
            let there = output_folder(&o.path).join(STATE_FOLDER);
            if !dirs.contains(&there) {
                dirs.push(there);
            }
        }
    }
    let mut out = Vec::new();
    for dir in &dirs {
        for key in &keys {
            let path = file.in_dir(dir, key);
            if *dir != here || *key != keys[0] {
                out.push(path);
            }
        }
    }
    out
}

/// A state file's text as found: where it was read from, and whether that
/// is where an older version left it rather than where this one keeps it.
#[derive(Debug)]
pub struct Found {
    /// The file read.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// Read from one of [`older_paths`].
    pub older: bool,
}

/// Reads a state file of `d` through the one reader: where this version
/// keeps it, else, while that is missing, the first of [`older_paths`] that
/// is there. `Ok(None)` when there is none; the error when one is there but
/// cannot be read.
pub fn read(d: &DatasetConfig, file: StateKind) -> Result<Option<Found>, FileError> {
    let Some(primary) = path(d, file) else {
        return Ok(None);
    };
    if let Some(text) = workspace::read_state(&primary, &d.fields.limits)? {
        return Ok(Some(Found {
            path: primary,
            text,
            older: false,
        }));
    }
    for path in older_paths(d, file) {
        if let Some(text) = workspace::read_state(&path, &d.fields.limits)? {
            tracing::info!(path = %path.display(), "state left by an older version");
            return Ok(Some(Found {
                path,
                text,
                older: true,
            }));
        }
    }
    Ok(None)
}

/// The sub-folder of what is local only.
pub const CACHE: &str = "cache";

/// The `.gitignore` written into [`CACHE`]: everything in it is local.
pub const CACHE_GITIGNORE: &str = "# Written by nptreemap: local caches, never committed.\n*\n";

/// The stem of the default config file (`nptreemap.yaml`): its datasets'
/// state keeps the plain names older versions gave it.
pub const DEFAULT_CONFIG_STEM: &str = "nptreemap";

/// What the names of a dataset's state files start with: the name of the
/// config it belongs to and the dataset's own (`site.countries`), so that two
/// configs that write into one output folder keep their own state (issue 30
/// item 9: building one made the other's pictures redraw); the dataset's
/// name alone for the default config. Both parts are encoded as
/// [`plain_key`] encodes a name, so `.` never occurs in either and the pair
/// is told apart from any other; deterministic, no absolute path, so the
/// state can be committed. Over 200 bytes, the first 200, `~` and a 64-bit
/// FNV-1a hash of the whole.
pub fn key(d: &DatasetConfig) -> String {
    match d
        .config_stem
        .as_deref()
        .filter(|stem| *stem != DEFAULT_CONFIG_STEM)
    {
        None => plain_key(&d.name),
        Some(stem) => {
            let joined = format!("{}.{}", encode(stem), encode(&d.name));
            let hash = fnv(joined.as_bytes());
            capped(joined, hash)
        }
    }
}

/// A dataset name as a file name: letters and digits of any script, `-`
/// and `_` as they are, every other character percent-encoded (UTF-8 bytes
/// as `%XX`), which is injective (`日本` and `中国` stay themselves; `a b` is
/// `a%20b`, `a/b` is `a%2Fb`, and `..` cannot escape the folder). A name
/// over 200 bytes so encoded keeps its first 200 and adds `~` and a 64-bit
/// FNV-1a hash of the whole name (`~` is encoded everywhere else).
pub fn plain_key(name: &str) -> String {
    capped(encode(name), fnv(name.as_bytes()))
}

fn encode(name: &str) -> String {
    use std::fmt::Write;
    let mut safe = String::new();
    for c in name.chars() {
        if c.is_alphanumeric() || c == '-' || c == '_' {
            safe.push(c);
        } else {
            for b in c.encode_utf8(&mut [0; 4]).bytes() {
                let _ = write!(safe, "%{b:02X}");
            }
        }
    }
    safe
}

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `safe` cut to 200 bytes with `~` and `hash` added when it is longer.
fn capped(mut safe: String, hash: u64) -> String {
    use std::fmt::Write;
    const KEEP: usize = 200;
    if safe.len() > KEEP {
        let mut cut = KEEP;
        while !safe.is_char_boundary(cut) {
            cut -= 1;
        }
        safe.truncate(cut);
        let _ = write!(safe, "~{hash:016x}");
    }
    safe
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    fn dataset(config: &str, stem: Option<&str>) -> DatasetConfig {
        let mut d = Config::from_str(config, Path::new("/w"))
            .expect("config")
            .datasets
            .remove(0);
        d.config_stem = stem.map(str::to_string);
        d
    }

    const TWO_FOLDERS: &str = "datasets:\n  - {name: c, format: f, files: {}, outputs: [out/c.svg, json/c.json]}\n";

    /// Issue 30 item 8: the state folder is the same whatever the order of
    /// the outputs.
    #[test]
    fn the_state_folder_does_not_depend_on_the_order_of_the_outputs() {
        let d = dataset(TWO_FOLDERS, None);
        let mut reversed = d.clone();
        reversed.outputs.reverse();
        assert_eq!(dir(&d), Some(PathBuf::from("/w/json/.nptreemap")));
        assert_eq!(dir(&d), dir(&reversed));
        // Where an older version kept it (beside the first output) is looked at.
        assert_eq!(
            older_paths(&d, StateKind::Layout),
            [PathBuf::from("/w/out/.nptreemap/c.layout.json")]
        );
    }

    /// Issue 30 item 9: the state of a config other than the default one is
    /// named after it too, and the pair (config, dataset) is told apart from
    /// any other, whatever the names hold.
    #[test]
    fn state_names_are_keyed_by_config_and_dataset() {
        let d = dataset(TWO_FOLDERS, Some("site"));
        assert_eq!(
            layout_path(&d),
            Some(PathBuf::from("/w/json/.nptreemap/site.c.layout.json"))
        );
        assert_eq!(key(&dataset(TWO_FOLDERS, Some("nptreemap"))), "c");
        assert_eq!(
            older_paths(&d, StateKind::Manifest),
            [
                "/w/json/.nptreemap/c.manifest.json",
                "/w/out/.nptreemap/site.c.manifest.json",
                "/w/out/.nptreemap/c.manifest.json"
            ]
            .map(PathBuf::from)
        );
        let named = |stem: &str, name: &str| {
            let mut d = dataset(TWO_FOLDERS, Some(stem));
            d.name = name.to_string();
            key(&d)
        };
        let pairs = [("a.b", "c"), ("a", "b.c"), ("a", "b%2Ec"), ("a.b.c", "d"), ("日本", "x y")];
        let keys: std::collections::BTreeSet<String> =
            pairs.iter().map(|(s, n)| named(s, n)).collect();
        assert_eq!(keys.len(), pairs.len(), "{keys:?}");
        assert_eq!(named("日本", "x y"), "日本.x%20y");
        let long = named(&"s".repeat(150), &"n".repeat(150));
        assert!(long.len() < 230 && long.contains('~'), "{long}");
        assert_ne!(long, named(&"s".repeat(151), &"n".repeat(149)));
        // The default config's names are what older versions wrote.
        assert_eq!(plain_key("a/b"), "a%2Fb");
    }
}
