//! The stored layout's adjacency per level (`cache/<name>.levels.bin`,
//! issue 32 item 2: a one-shot `build` reuses what the state folder
//! allows): which cells of each level share an edge, as the build that
//! wrote the stored layout found them. A later process that starts warm
//! from that layout takes them over, so its layout compares only the pairs
//! of the cells that moved instead of every level's (35 ms of a 6,000-header
//! rebuild), as a `watch` does with the layout in memory.
//!
//! Exact by its key: the file names the fingerprint of the stored layout's
//! text it belongs to, and is used only beside that very text, whose cells
//! (full precision) are the ones the adjacency was found on. A small binary
//! file: `NPTA`, version, the text's fingerprint (16 bytes), a level count,
//! then per level its node count and node indices, its pair count and
//! pairs (u64 each), little-endian. Local only: a file that does not match
//! (another text, truncated, an index past the layout's nodes) is ignored,
//! and the layout then finds the adjacency itself.

use super::binary::{self, Bytes};
use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::geom::LevelAdjacency;

const MAGIC: &[u8; 4] = b"NPTA";
const VERSION: u32 = 1;

/// The adjacency kept beside the stored layout whose text has
/// fingerprint `text`, of a layout of `nodes` nodes; `None` when there is
/// none for that text.
pub fn read(d: &DatasetConfig, text: Fingerprint, nodes: usize) -> Option<Vec<LevelAdjacency>> {
    let levels = binary::read(d, super::levels_path(d), |bytes| decode(bytes, text, nodes));
    (!levels.is_empty()).then_some(levels)
}

/// Writes `levels` as the adjacency of the stored layout whose text has
/// fingerprint `text` (and the cache folder's `.gitignore`).
pub fn write(d: &DatasetConfig, text: Fingerprint, levels: &[LevelAdjacency]) -> std::io::Result<()> {
    binary::write(super::levels_path(d), &encode(text, levels))
}

fn encode(text: Fingerprint, levels: &[LevelAdjacency]) -> Vec<u8> {
    let size: usize = levels
        .iter()
        .map(|l| 16 + 8 * l.nodes().len() + 16 * l.pairs().len())
        .sum();
    let mut out = Vec::with_capacity(40 + size);
    let u = |out: &mut Vec<u8>, v: usize| out.extend_from_slice(&(v as u64).to_le_bytes());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&text.to_bytes());
    u(&mut out, levels.len());
    for level in levels {
        u(&mut out, level.nodes().len());
        for &n in level.nodes() {
            u(&mut out, n);
        }
        u(&mut out, level.pairs().len());
        for &(a, b) in level.pairs() {
            u(&mut out, a);
            u(&mut out, b);
        }
    }
    out
}

/// The levels of `bytes` when they belong to the text `text` and every
/// index is one of the layout's `nodes` (each list is bounded by the bytes
/// left before it is allocated, and the adjacency's tables by `nodes`).
fn decode(bytes: &[u8], text: Fingerprint, nodes: usize) -> Option<Vec<LevelAdjacency>> {
    let mut r = Bytes(bytes);
    if r.take(4)? != MAGIC
        || r.take(4)? != VERSION.to_le_bytes()
        || r.take(16)? != text.to_bytes()
    {
        return None;
    }
    let index = |r: &mut Bytes<'_>| {
        let i = usize::try_from(r.u64()?).ok()?;
        (i < nodes).then_some(i)
    };
    // The smallest level: two empty lists.
    let count = r.count(16)?;
    let mut levels = Vec::with_capacity(count);
    for _ in 0..count {
        let n = r.count(8)?;
        let members = (0..n).map(|_| index(&mut r)).collect::<Option<Vec<_>>>()?;
        let p = r.count(16)?;
        let pairs = (0..p)
            .map(|_| Some((index(&mut r)?, index(&mut r)?)))
            .collect::<Option<Vec<_>>>()?;
        levels.push(LevelAdjacency::from_pairs(members, pairs));
    }
    r.is_done().then_some(levels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<LevelAdjacency> {
        vec![
            LevelAdjacency::from_pairs(vec![0], Vec::new()),
            LevelAdjacency::from_pairs(vec![1, 2, 3], vec![(1, 2), (2, 3)]),
            LevelAdjacency::from_pairs(vec![4, 5, 6, 7], vec![(4, 5), (4, 7), (5, 6), (6, 7)]),
        ]
    }

    #[test]
    fn levels_come_back_only_for_their_text_and_within_the_layout() {
        let text = Fingerprint::of_bytes(b"a stored layout");
        let bytes = encode(text, &sample());
        assert_eq!(decode(&bytes, text, 8), Some(sample()));
        let other = Fingerprint::of_bytes(b"another stored layout");
        assert_eq!(decode(&bytes, other, 8), None, "another text");
        assert_eq!(decode(&bytes, text, 7), None, "node 7 past a layout of 7 nodes");
        for cut in [0, 3, 20, bytes.len() / 2, bytes.len() - 1] {
            assert_eq!(decode(&bytes[..cut], text, 8), None, "cut at {cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(decode(&longer, text, 8), None, "bytes past the end");
        // A count the rest cannot hold is refused before anything is
        // allocated for it.
        let mut huge = bytes[..24].to_vec();
        huge.extend_from_slice(&u64::MAX.to_le_bytes());
        assert_eq!(decode(&huge, text, 8), None);
        // Any byte changed: refused, or levels within the layout's nodes.
        for at in 0..bytes.len() {
            let mut changed = bytes.clone();
            changed[at] ^= 0x5a;
            for level in decode(&changed, text, 8).into_iter().flatten() {
                assert!(level.nodes().iter().all(|&n| n < 8), "byte {at}");
                assert!(level.pairs().iter().all(|&(a, b)| a < 8 && b < 8), "byte {at}");
            }
        }
    }
}
