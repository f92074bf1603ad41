//! Lines of text written before, kept by a digest of everything they spell
//! (issue 32, item 2: draw what moved): a layout JSON node's line (its
//! ids, weights and coordinates as spelled), an SVG cell's element. After a
//! weight edit the cells are bit for bit those of the build before except in
//! the diagrams the edit moved, so a writer that asks here first formats
//! only the lines of what moved. Each writer keys its own lines (the stored
//! layout's full precision and the `.json` output's rounding differ, and so
//! their lines).
//!
//! Two generations, as the labels' memo (`render::parts`): what the current
//! build wrote and what the one before did; [`LineMemo::next_build`] drops
//! the older, so the memo holds at most two builds' lines however long a
//! `watch` runs, each generation bounded by `MAX_HELD` (some 23 MB at 6,000
//! C headers). Digests of 128 bits (xxh3), as the state folder's
//! fingerprints.
//!
//! Hand-written rather than a caching crate: the generations are the
//! eviction rule a rebuild needs, and it is one map of our own keys.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::{Arc, Mutex};

/// A line, shared between the memo and the document being written.
pub(crate) type Line = Arc<str>;

/// The memo's map: its keys are digests already, so the hasher takes their
/// low bits instead of hashing them again (SipHash over 38,000 keys was a
/// tenth of a document's node lines).
type ByDigest = HashMap<u128, Line, BuildHasherDefault<DigestBits>>;

/// The [`Hasher`] of [`ByDigest`]: the last 64 bits written.
#[derive(Default)]
struct DigestBits(u64);

impl Hasher for DigestBits {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.0 ^= u64::from_le_bytes(b);
        }
    }

    fn write_u128(&mut self, v: u128) {
        self.0 = v as u64;
    }
}

/// The lines of the last two builds (see the module docs).
#[derive(Debug, Default)]
pub struct LineMemo {
    inner: Mutex<Generations>,
}

#[derive(Debug, Default)]
struct Generations {
    current: ByDigest,
    previous: ByDigest,
    /// Bytes of the lines the current generation holds.
    held: usize,
    counts: LineCounts,
}

/// Most bytes of lines one generation keeps (the memo holds two): a
/// document of 6,000 C headers and its stored layout keep some 23 MB; a
/// hundred times that keeps lines until the bound and writes the rest
/// anew each build, with the same bytes.
const MAX_HELD: usize = 64 << 20;

/// How many lines a build found and wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineCounts {
    /// Found in the memo.
    pub reused: usize,
    /// Formatted anew.
    pub written: usize,
}

impl LineMemo {
    /// An empty memo.
    pub fn new() -> LineMemo {
        LineMemo::default()
    }

    /// Starts the next build: the lines of the build before last are
    /// dropped. Returns the last build's counts.
    pub fn next_build(&self) -> LineCounts {
        let mut g = self.lock();
        // Sized for what the last build held: the lines found move over one
        // by one, and growing the map on the way rehashed it a dozen times.
        let capacity = g.current.len();
        g.previous = std::mem::replace(
            &mut g.current,
            ByDigest::with_capacity_and_hasher(capacity, Default::default()),
        );
        g.held = 0;
        std::mem::take(&mut g.counts)
    }

    /// The counts of the build under way.
    pub fn counts(&self) -> LineCounts {
        self.lock().counts
    }

    /// The lines of `keys`, in order: `None` for those not in the memo
    /// (found ones move to the current generation).
    pub(crate) fn find(&self, keys: &[u128]) -> Vec<Option<Line>> {
        let mut g = self.lock();
        let found: Vec<Option<Line>> = keys.iter().map(|k| g.take(*k)).collect();
        let reused = found.iter().filter(|f| f.is_some()).count();
        g.counts.reused += reused;
        g.counts.written += keys.len() - reused;
        found
    }

    /// Keeps the lines just written, by key, up to [`MAX_HELD`] bytes.
    pub(crate) fn keep(&self, lines: Vec<(u128, Line)>) {
        let mut g = self.lock();
        for (key, line) in lines {
            if g.held + line.len() > MAX_HELD {
                break;
            }
            g.held += line.len();
            g.current.insert(key, line);
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Generations> {
        // A panic while the lock was held leaves whole entries only.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Generations {
    /// The line of `key` from either generation, kept in the current one.
    fn take(&mut self, key: u128) -> Option<Line> {
        if let Some(line) = self.current.get(&key) {
            return Some(line.clone());
        }
        let line = self.previous.remove(&key)?;
        if self.held + line.len() <= MAX_HELD {
            self.held += line.len();
            self.current.insert(key, line.clone());
        }
        Some(line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A generation keeps lines up to its bound and no further; the lines
    /// beyond it are written again next time (the bytes do not change).
    #[test]
    fn a_generation_keeps_lines_up_to_its_bound() {
        let lines = LineMemo::new();
        let mb: Line = Line::from("x".repeat(1 << 20));
        let count = MAX_HELD / mb.len() + 6;
        let keys: Vec<u128> = (0..count as u128).collect();
        lines.keep(keys.iter().map(|&k| (k, Line::clone(&mb))).collect());
        lines.next_build();
        let found = lines.find(&keys);
        let kept = found.iter().filter(|f| f.is_some()).count();
        assert_eq!(kept, MAX_HELD / mb.len());
        assert!(found[..kept].iter().all(Option::is_some));
        assert!(found[kept..].iter().all(Option::is_none));
        assert_eq!(
            lines.counts(),
            LineCounts {
                reused: kept,
                written: count - kept
            }
        );
    }
}
