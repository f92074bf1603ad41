//! What the cache's binary files share (`pictures`, `labels`): a reader
//! that never reads past the bytes it was given, and the renderers' version
//! that files holding a renderer's results are stamped with, and their
//! reading and writing (in `cache/`, beside its `.gitignore`).

use std::path::{Path, PathBuf};

use crate::config::DatasetConfig;
use crate::{store, workspace};

/// The items of the file at `path` by `decode`; none when there is no such
/// file or `decode` refuses it (a cache's loss only costs its reuse).
pub(super) fn read<T>(
    d: &DatasetConfig,
    path: Option<PathBuf>,
    decode: impl FnOnce(&[u8]) -> Option<Vec<T>>,
) -> Vec<T> {
    let Some(path) = path else {
        return Vec::new();
    };
    match workspace::read_input(&path, &d.fields.limits) {
        Ok(bytes) => decode(&bytes).unwrap_or_default(),
        Err(e) => {
            tracing::debug!(error = %e, path = %path.display(), "no cache file");
            Vec::new()
        }
    }
}

/// Writes `bytes` to the cache file at `path` (and the cache folder's
/// `.gitignore`) unless it holds them already.
pub(super) fn write(path: Option<PathBuf>, bytes: &[u8]) -> std::io::Result<()> {
    let Some(path) = path else {
        return Ok(());
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    store::write_if_changed(&dir.join(".gitignore"), super::CACHE_GITIGNORE.as_bytes())?;
    store::write_if_changed(&path, bytes).map(|_| ())
}

/// The renderers' version: the digest of their sources (made at compile
/// time, as the render keys' `NPTREEMAP_RENDER_SOURCE`), so that results of
/// another version are never trusted.
pub(super) fn renderers() -> u128 {
    xxhash_rust::xxh3::xxh3_128(env!("NPTREEMAP_RENDER_SOURCE").as_bytes())
}

/// A reader over a file's bytes, little-endian: every count is checked
/// against what is left before anything is allocated.
pub(super) struct Bytes<'a>(pub(super) &'a [u8]);

impl<'a> Bytes<'a> {
    /// The next `n` bytes.
    pub(super) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, rest) = self.0.split_at_checked(n)?;
        self.0 = rest;
        Some(head)
    }

    pub(super) fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    pub(super) fn f64(&mut self) -> Option<f64> {
        Some(f64::from_bits(self.u64()?))
    }

    pub(super) fn u128(&mut self) -> Option<u128> {
        Some(u128::from_le_bytes(self.take(16)?.try_into().ok()?))
    }

    /// A count (u64) of items of at least `size` bytes each, when the rest
    /// can hold that many.
    pub(super) fn count(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size)? <= self.0.len()).then_some(n)
    }

    /// Whether every byte was read.
    pub(super) fn is_done(&self) -> bool {
        self.0.is_empty()
    }
}
