//! The state folder: what a build keeps between runs, where, and in which
//! files. Per dataset, in `<first output's folder>/.nptreemap/` (or the
//! config's `state_dir:`):
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
//!   output's bytes and render settings. A build or `build --check` whose
//!   inputs, settings and outputs match it is done after reading and hashing
//!   them. Small (about 150 bytes per output), deterministic, committed.
//! - `cache/<name>.constraints.bin` ([`constraints`]): the constraints of
//!   the last similarity inputs, so that an edit that leaves them alone (a
//!   weight) recomputes none. Local only: a `.gitignore` in `cache/` says so,
//!   and deleting it costs one computation.
//!
//! Every read goes through [`crate::workspace`], every write through
//! [`crate::store`]. A file that cannot be read or is not ours is never an
//! error: the build recomputes what it would have given (and says so for the
//! stored layout, whose loss makes the picture move).

/// The constraint cache.
pub mod constraints;
/// The stored layout: the warm start of the next build.
pub mod layout;
/// The manifest: what the stored layout and the outputs were made from.
pub mod manifest;

use std::path::{Path, PathBuf};

use crate::config::DatasetConfig;

/// The folder of a dataset's state: the config's `state_dir:` when it has
/// one, else a hidden folder beside its first output, so it travels with the
/// outputs. `None` for a dataset without outputs.
pub fn dir(d: &DatasetConfig) -> Option<PathBuf> {
    let first = d.outputs.first()?;
    Some(match &d.state_dir {
        Some(dir) => dir.clone(),
        None => first
            .path
            .parent()
            .unwrap_or(Path::new("."))
            .join(".nptreemap"),
    })
}

/// The stored layout's path (see [`layout`]).
pub fn layout_path(d: &DatasetConfig) -> Option<PathBuf> {
    Some(dir(d)?.join(file_name(&d.name, "layout.json")))
}

/// The manifest's path (see [`manifest`]).
pub fn manifest_path(d: &DatasetConfig) -> Option<PathBuf> {
    Some(dir(d)?.join(file_name(&d.name, "manifest.json")))
}

/// The constraint cache's path (see [`constraints`]).
pub fn constraints_path(d: &DatasetConfig) -> Option<PathBuf> {
    Some(dir(d)?.join(CACHE).join(file_name(&d.name, "constraints.bin")))
}

/// The sub-folder of what is local only.
pub const CACHE: &str = "cache";

/// The `.gitignore` written into [`CACHE`]: everything in it is local.
pub const CACHE_GITIGNORE: &str = "# Written by nptreemap: local caches, never committed.\n*\n";

/// A state file's name for a dataset name and a suffix: letters and digits
/// of any script, `-` and `_` as they are, every other character
/// percent-encoded (UTF-8 bytes as `%XX`), which is injective (`日本` and
/// `中国` stay themselves; `a b` is `a%20b`, `a/b` is `a%2Fb`, and `..` cannot
/// escape the folder). A name over 200 bytes so encoded keeps its first 200
/// and adds `~` and a 64-bit FNV-1a hash of the whole name (`~` is encoded
/// everywhere else).
pub fn file_name(name: &str, suffix: &str) -> String {
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
    const KEEP: usize = 200;
    if safe.len() > KEEP {
        let mut cut = KEEP;
        while !safe.is_char_boundary(cut) {
            cut -= 1;
        }
        safe.truncate(cut);
        let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        let _ = write!(safe, "~{hash:016x}");
    }
    format!("{safe}.{suffix}")
}
