//! A node's similarity bins (method-reference §3.1–3.2): the d3.bin thresholds
//! over a row's scores, each bin's size and best entries, from a full row
//! ([`bin_row`]) or a sparse one ([`bin_sparse`]), and the strength a link
//! taken from a bin carries.

use super::similarity::{score, SimilarityKind};
use super::sparse_rows::SparseRow;

/// Number of bins before empty thresholds are dropped (§3.2).
const BIN_COUNT: usize = 5;
/// How many of each bin's best entries are kept. Stage A reads at most
/// `TOP_BIN_CAP` (6); Stage C enters a bin only while the node holds at most
/// `STAGE_C_STOP_ABOVE` (3) links, so among a bin's first 4 entries one is new.
pub(super) const BIN_HEAD: usize = super::sparse_rows::HEAD;

/// The similarity bins of one node, top bin first, each with its best entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Bins {
    pub(super) bins: Vec<Bin>,
}

/// One bin: how many entries it has and the first [`BIN_HEAD`] of them in list
/// order (similarity descending, ties in breadth-first order).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Bin {
    pub(super) len: usize,
    pub(super) head: Vec<Candidate>,
}

/// A node of the level with its raw similarity and score.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Candidate {
    pub(super) similarity: f64,
    pub(super) node: usize,
    pub(super) score: u8,
}

/// The d3.bin thresholds of §3.2 for scores in `lo..=hi`: the candidates
/// `lo + (t/5)·(hi − lo)` for t = 0..4, without those `<= lo` (d3 drops
/// thresholds at or below the domain's start) or `> hi`.
fn thresholds(lo: u8, hi: u8) -> Vec<f64> {
    let (lo, hi) = (f64::from(lo), f64::from(hi));
    (0..BIN_COUNT)
        .map(|t| lo + (t as f64 / BIN_COUNT as f64) * (hi - lo))
        .filter(|&x| x > lo && x <= hi)
        .collect()
}

/// The bin of `score`, counted from the top bin (0), for these thresholds. A value
/// equal to a threshold belongs to the upper bin (bisect-right, as d3.bin).
fn bin_from_top(score: u8, thresholds: &[f64]) -> usize {
    let value = f64::from(score);
    let ascending = thresholds.iter().take_while(|&&x| x <= value).count();
    thresholds.len() - ascending
}

/// Keeps `head` as the first [`BIN_HEAD`] candidates by (similarity descending,
/// node ascending). Candidates arrive in breadth-first order, so on equal
/// similarity the one already present stays ahead: the stable sort of §3.1.
fn push_head(head: &mut Vec<Candidate>, candidate: Candidate) {
    if head.len() == BIN_HEAD
        && head
            .last()
            .is_some_and(|last| last.similarity >= candidate.similarity)
    {
        return;
    }
    let position = head.partition_point(|c| c.similarity >= candidate.similarity);
    head.insert(position, candidate);
    head.truncate(BIN_HEAD);
}

/// The bins of node `level[i]` (§3.1–3.2; the neighbour-list variant has one bin,
/// the nodes it lists, all at score 100) from its filled similarity `row`.
pub(super) fn bin_row(
    kind: SimilarityKind,
    level: &[usize],
    i: usize,
    row: &[f64],
    scores: &mut Vec<u8>,
) -> Bins {
    if level.len() < 2 {
        return Bins::default();
    }
    // Scores once per pair; `u8::MAX` marks the node itself.
    scores.clear();
    scores.extend(row.iter().map(|&s| score(s)));
    scores[i] = u8::MAX;
    let candidate = |j: usize| Candidate {
        similarity: row[j],
        node: level[j],
        score: scores[j],
    };
    if kind == SimilarityKind::NeighborList {
        let mut bin = Bin::default();
        for j in (0..level.len()).filter(|&j| j != i && scores[j] > 0) {
            bin.len += 1;
            push_head(&mut bin.head, candidate(j));
        }
        return Bins { bins: vec![bin] };
    }
    let (mut lo, mut hi) = (u8::MAX, 0u8);
    for (j, &s) in scores.iter().enumerate() {
        if j != i {
            lo = lo.min(s);
            hi = hi.max(s);
        }
    }
    let bin_of = bin_table(lo, hi);
    let mut bins = vec![Bin::default(); usize::from(bin_of[usize::from(lo)]) + 1];
    for (j, &s) in scores.iter().enumerate() {
        if j != i {
            let bin = &mut bins[usize::from(bin_of[usize::from(s)])];
            bin.len += 1;
            push_head(&mut bin.head, candidate(j));
        }
    }
    Bins { bins }
}

/// What Stages A and C (method-reference §3.3, §3.5) read of a node's bins,
/// and nothing more: none when the best score is 0 (no link is ever made);
/// the top bin alone when it holds at least [`STAGE_VIEW_FULL_TOP`] entries
/// (Stage A then gives the node 4 or more links and Stage C stops before its
/// first bin); else every bin up to and including the first empty one (Stage
/// C stops there). Each bin counted and listed up to its first [`BIN_HEAD`]
/// entries: Stage A reads at most 6, Stage C at most 4, and only whether a
/// bin is empty. Two rows with the same view give the same lists; the
/// nearest-neighbour rows (`knn_rows`) produce views only.
pub(super) fn stage_view(bins: &Bins) -> Bins {
    let Some(top) = bins.bins.first() else {
        return Bins::default();
    };
    if top.head.first().is_none_or(|c| c.score == 0) {
        return Bins::default();
    }
    let capped = |bin: &Bin| Bin {
        len: bin.len.min(BIN_HEAD),
        head: bin.head.iter().take(BIN_HEAD).copied().collect(),
    };
    if top.len >= STAGE_VIEW_FULL_TOP {
        return Bins {
            bins: vec![capped(top)],
        };
    }
    let reach = bins
        .bins
        .iter()
        .position(|b| b.len == 0)
        .map_or(bins.bins.len(), |empty| empty + 1);
    Bins {
        bins: bins.bins[..reach].iter().map(capped).collect(),
    }
}

/// A top bin this large gives Stage A more than `STAGE_C_STOP_ABOVE` (3)
/// links, so Stage C reads no bin of the node.
pub(super) const STAGE_VIEW_FULL_TOP: usize = 4;

/// The bins of a node from its sparse row (the measures of [`SparseLevel`]): the same
/// bins as [`bin_row`] gives from the full row, bit for bit. Entries go in level order,
/// shown ones before the zeros; they never tie (shown similarities are non-zero), so
/// every head gets the order of the full scan.
pub(super) fn bin_sparse(kind: SimilarityKind, row: &SparseRow, level: &[usize]) -> Bins {
    if level.len() < 2 {
        return Bins::default();
    }
    let candidate = |j: usize, similarity: f64| Candidate {
        similarity,
        node: level[j],
        score: score(similarity),
    };
    if kind == SimilarityKind::NeighborList {
        let mut bin = Bin::default();
        for &(j, s) in row.shown.iter().filter(|&&(_, s)| score(s) > 0) {
            bin.len += 1;
            push_head(&mut bin.head, candidate(j, s));
        }
        return Bins { bins: vec![bin] };
    }
    let (mut lo, mut hi) = (u8::MAX, 0u8);
    let scores = row
        .shown
        .iter()
        .map(|&(_, s)| score(s))
        .chain(row.hidden.filter(|h| h.1 > 0).map(|h| score(h.0)))
        .chain((row.zeros > 0).then_some(0));
    for s in scores {
        lo = lo.min(s);
        hi = hi.max(s);
    }
    let bin_of = bin_table(lo, hi);
    let mut bins = vec![Bin::default(); usize::from(bin_of[usize::from(lo)]) + 1];
    for &(j, s) in &row.shown {
        let bin = &mut bins[usize::from(bin_of[usize::from(score(s))])];
        bin.len += 1;
        push_head(&mut bin.head, candidate(j, s));
    }
    if let Some((s, count)) = row.hidden {
        bins[usize::from(bin_of[usize::from(score(s))])].len += count;
    }
    if row.zeros > 0 {
        let bin = &mut bins[usize::from(bin_of[0])];
        bin.len += row.zeros;
        for &j in &row.zero_head {
            push_head(&mut bin.head, candidate(j, 0.0));
        }
    }
    Bins { bins }
}

/// The bin (from the top) of every possible score for a row with scores in `lo..=hi`,
/// so the per-pair work is a table lookup.
pub(super) fn bin_table(lo: u8, hi: u8) -> [u8; 101] {
    let thresholds = thresholds(lo, hi);
    let mut bin_of = [0u8; 101];
    for (s, slot) in bin_of.iter_mut().enumerate() {
        *slot = bin_from_top(s as u8, &thresholds) as u8;
    }
    bin_of
}

/// Strength of a link taken from bin `bin` (0 = top) with this score.
pub(super) fn strength_for(bin: usize, score: u8) -> u8 {
    if score == 100 || bin == 0 {
        3
    } else if bin == 1 {
        2
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_follows_d3_bin() {
        // lo = 20, hi = 100: bins [84,100], [68,84), [52,68), [36,52), [20,36).
        let t = thresholds(20, 100);
        assert_eq!(t, [36.0, 52.0, 68.0, 84.0]);
        let bin = |s| bin_from_top(s, &t);
        assert_eq!(bin(100), 0);
        assert_eq!(bin(84), 0);
        assert_eq!(bin(83), 1);
        assert_eq!(bin(68), 1);
        assert_eq!(bin(67), 2);
        assert_eq!(bin(52), 2);
        assert_eq!(bin(51), 3);
        assert_eq!(bin(36), 3);
        assert_eq!(bin(35), 4);
        assert_eq!(bin(20), 4);
        // hi == lo: one bin with everything.
        assert!(thresholds(40, 40).is_empty());
        assert_eq!(bin_from_top(40, &thresholds(40, 40)), 0);
        assert!(thresholds(0, 0).is_empty());
        // Fractional thresholds: lo = 0, hi = 7 gives 1.4, 2.8, 4.2, 5.6.
        let t = thresholds(0, 7);
        assert_eq!(t.len(), 4);
        assert_eq!(bin_from_top(7, &t), 0);
        assert_eq!(bin_from_top(6, &t), 0);
        assert_eq!(bin_from_top(5, &t), 1);
        assert_eq!(bin_from_top(1, &t), 4);
    }

    #[test]
    fn head_keeps_stable_descending_order() {
        let mut head = Vec::new();
        for (node, s) in [(0, 0.5), (1, 0.7), (2, 0.5), (3, 0.7), (4, 0.9)] {
            push_head(
                &mut head,
                Candidate {
                    similarity: s,
                    node,
                    score: score(s),
                },
            );
        }
        let order: Vec<usize> = head.iter().map(|c| c.node).collect();
        assert_eq!(order, [4, 1, 3, 0, 2]);
        for node in 10..20 {
            push_head(
                &mut head,
                Candidate {
                    similarity: 0.7,
                    node,
                    score: 70,
                },
            );
        }
        let order: Vec<usize> = head.iter().map(|c| c.node).collect();
        assert_eq!(order, [4, 1, 3, 10, 11, 12, 13, 14]);
    }
}
