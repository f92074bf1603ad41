//! Rows of identical vectors binned once (cosine and Pearson levels): a
//! level where many nodes share one vector (the same text embedded twice, a
//! generated table) made every path slow, since all of a row's entries tie
//! and each is then compared exactly and sorted (15,000 identical 8-d
//! vectors: 6.8 s in the constraint stage; BENCHMARKS.md, issue 34 item 4).
//!
//! Why it is exact: two nodes `r` and `m` of identical vectors have the same
//! similarity to every other node, and to each other in both directions
//! (the measure reads only the two vectors). So the row of `m` is the row of
//! `r` with the entry of `m` replaced by one of `r`, of the same similarity
//! and score: the same thresholds, the same bin sizes, and heads that differ
//! at most by that one entry ([`derive`]).

use std::collections::HashMap;

use xxhash_rust::xxh3::Xxh3;

use super::bins::{Bins, Candidate, BIN_HEAD};
use super::similarity::{pair_similarity, score, NodeFeatures, SimilarityKind};

/// For each of `rows` (level positions), the index into `rows` of the first
/// row with a bit-identical vector (itself for the first), or `None` when
/// no two rows share a vector or the measure is not cosine or Pearson.
pub(super) fn firsts(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    rows: &[usize],
) -> Option<Vec<usize>> {
    if !matches!(kind, SimilarityKind::Cosine | SimilarityKind::Pearson) {
        return None;
    }
    // Rows by a digest of their vector's bits (16 bytes a row, not a copy
    // of the vector); a digest seen before is confirmed bit for bit.
    let mut seen: HashMap<u128, Vec<usize>> = HashMap::with_capacity(rows.len());
    let mut firsts = Vec::with_capacity(rows.len());
    let mut shared = false;
    for (k, &i) in rows.iter().enumerate() {
        let values = features[i].values()?;
        let mut h = Xxh3::new();
        for x in values {
            h.update(&x.to_bits().to_le_bytes());
        }
        let same = |f: &usize| {
            let other = features[rows[*f]].values().unwrap_or_default();
            other.len() == values.len()
                && other.iter().zip(values).all(|(a, b)| a.to_bits() == b.to_bits())
        };
        let firsts_of_digest = seen.entry(h.digest128()).or_default();
        let first = match firsts_of_digest.iter().find(|f| same(f)) {
            Some(&f) => f,
            None => {
                firsts_of_digest.push(k);
                k
            }
        };
        shared |= first != k;
        firsts.push(first);
    }
    shared.then_some(firsts)
}

/// The bins of row `m` from `bins_r`, those of row `r` whose vector is
/// bit-identical to `m`'s (full bins or a stage view: both keep each bin's
/// first [`BIN_HEAD`] entries in head order).
pub(super) fn derive(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    (r, bins_r): (usize, &Bins),
    m: usize,
) -> Bins {
    let s = pair_similarity(kind, &features[m], &features[r], level[r]);
    let entry_r = Candidate {
        similarity: s,
        node: level[r],
        score: score(s),
    };
    // Head order: similarity descending (−0 as 0, as `bins::push_head`),
    // then level order.
    let before = |a: &Candidate, b: &Candidate| {
        b.similarity
            .partial_cmp(&a.similarity)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.node.cmp(&b.node))
    };
    let mut bins = bins_r.clone();
    // `m` in a head: `r` takes its place there.
    for bin in &mut bins.bins {
        if let Some(p) = bin.head.iter().position(|c| c.node == level[m]) {
            bin.head[p] = entry_r;
            bin.head.sort_by(before);
            return bins;
        }
    }
    // `m` beyond its bin's head (so the head is full, and every entry in it
    // precedes `m`): `r`, which precedes `m`, enters only ahead of an entry
    // of its own score that it precedes.
    for bin in &mut bins.bins {
        if bin.head.iter().any(|c| c.score == entry_r.score) {
            if bin.head.iter().any(|c| before(&entry_r, c).is_lt()) {
                bin.head.push(entry_r);
                bin.head.sort_by(before);
                bin.head.truncate(BIN_HEAD);
            }
            break;
        }
    }
    bins
}

#[cfg(test)]
mod tests {
    use super::super::bins::stage_view;
    use super::super::rows::{exact_bins, level_bins};
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// Groups of 2, 12 and 40 identical vectors (more than a bin's head)
    /// among distinct ones, in 3 and 8 dimensions, interleaved in level
    /// order: every row's stage view equals that of its own exact row, bit
    /// for bit, for cosine and for Pearson.
    #[test]
    fn identical_vectors_get_the_bins_of_their_own_rows() {
        for (d, kind) in [(3, SimilarityKind::Cosine), (8, SimilarityKind::Pearson)] {
            let mut builder = DatasetBuilder::new();
            builder.add(NodeSpec::new("r"));
            let shared: Vec<Vec<f64>> = (0..3)
                .map(|g| (0..d).map(|k| ((g * 7 + k * 3) % 5) as f64 - 1.5).collect())
                .collect();
            let mut left = [2usize, 12, 40];
            for i in 0..300usize {
                let g = i % 5;
                let v: Vec<f64> = if g < 3 && left[g] > 0 {
                    left[g] -= 1;
                    shared[g].clone()
                } else {
                    (0..d).map(|k| (i as f64 * 1.37 + (k * k) as f64 * 0.61).sin()).collect()
                };
                builder.add(NodeSpec::new(format!("n{i}")).parent("r").weight(1.0).features(v));
            }
            let p = super::super::prepare::prepare(&builder.build().expect("valid"));
            let level: Vec<usize> = (1..p.len()).collect();
            let features: Vec<NodeFeatures<'_>> =
                level.iter().map(|&n| NodeFeatures::new(kind, &p, n)).collect();
            let all: Vec<usize> = (0..level.len()).collect();
            let firsts = firsts(kind, &features, &all).expect("shared vectors");
            assert_eq!(firsts.iter().enumerate().filter(|&(k, &f)| f != k).count(), 1 + 11 + 39);
            let binned = level_bins(&p, kind, &level, true);
            for (i, bins) in binned.iter().enumerate() {
                // What the stages read of both (the filter gives only that).
                let want = stage_view(&exact_bins(kind, &features, &level, i));
                assert_eq!(stage_view(bins), want, "{kind:?}: row {i}");
            }
        }
    }
}
