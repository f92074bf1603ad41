//! A similarity row restricted to a set of columns, reduced to what the
//! binning of method-reference §3.2 can read from it: how many columns hold
//! each score, and per score the first [`BIN_HEAD`] columns in list order
//! (similarity descending, ties by column order). Two such summaries over
//! disjoint column sets merge into the summary over their union, and a
//! summary over a whole row gives the row's bins bit for bit as `bin_row`
//! does: a bin's count is the sum of its scores' counts, and its head comes
//! from its highest scores, whose first entries are all it can hold. This is
//! what lets a virtual copy's row be assembled from parts (`copies`).

use std::cmp::Ordering;

use super::bins::{bin_table, Bin, Bins, Candidate, BIN_HEAD};
use super::similarity::score;

/// Possible scores, 0..=100 (§3.2).
const SCORES: usize = 101;

/// One kept entry: a column's id (a level position or a leaf's rank, as the
/// owner of the summary says) with its exact similarity and score.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Entry {
    pub(super) score: u8,
    pub(super) similarity: f64,
    pub(super) id: u32,
}

/// List order within one score: similarity descending (−0 and 0 equal, as
/// `push_head`'s `>=` has them), then column order.
fn list_order(a: &Entry, b: &Entry) -> Ordering {
    b.similarity
        .partial_cmp(&a.similarity)
        .unwrap_or(Ordering::Equal)
        .then(a.id.cmp(&b.id))
}

/// A row over a set of columns: counts per score and each score's first
/// [`BIN_HEAD`] entries, sorted by score descending, then list order.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct ScoreTops {
    counts: Vec<u32>,
    tops: Vec<Entry>,
}

impl ScoreTops {
    /// The summary of no column.
    #[cfg(test)]
    pub(super) fn empty() -> Self {
        ScoreTops {
            counts: vec![0; SCORES],
            tops: Vec::new(),
        }
    }

    /// The ids renamed by `rename`, which must keep their order (a level's
    /// positions and the leaves' ranks order the leaves alike).
    pub(super) fn renamed(mut self, rename: impl Fn(u32) -> u32) -> Self {
        for e in &mut self.tops {
            e.id = rename(e.id);
        }
        self
    }

    /// The summary over the union of both column sets (disjoint, ids in one
    /// order).
    pub(super) fn merge(&mut self, other: &ScoreTops) {
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        if other.tops.is_empty() {
            return;
        }
        // Both lists are sorted: one linear merge, then each score cut to
        // its first entries.
        let order = |a: &Entry, b: &Entry| b.score.cmp(&a.score).then_with(|| list_order(a, b));
        let (mut x, mut y) = (self.tops.iter().peekable(), other.tops.iter().peekable());
        let mut kept: Vec<Entry> = Vec::with_capacity(self.tops.len() + other.tops.len());
        let (mut run, mut current) = (0, None);
        loop {
            let e = match (x.peek(), y.peek()) {
                (Some(a), Some(b)) if order(a, b) != Ordering::Greater => x.next(),
                (Some(_), Some(_)) | (None, Some(_)) => y.next(),
                (Some(_), None) => x.next(),
                (None, None) => break,
            };
            let Some(&e) = e else { break };
            if current == Some(e.score) {
                run += 1;
            } else {
                (run, current) = (0, Some(e.score));
            }
            if run < BIN_HEAD {
                kept.push(e);
            }
        }
        self.tops = kept;
    }

    /// The bins of a row whose summary over every other node of its level is
    /// `self` (ids are level positions; `level[id]` is the node), as
    /// `bin_row` gives them from the full row. `level_len` is the level's size.
    pub(super) fn bins(&self, level_len: usize, level: &[usize]) -> Bins {
        if level_len < 2 {
            return Bins::default();
        }
        let present = || (0..SCORES).filter(|&s| self.counts[s] > 0);
        let (Some(lo), Some(hi)) = (present().next(), present().next_back()) else {
            return Bins::default();
        };
        let bin_of = bin_table(lo as u8, hi as u8);
        let mut bins = vec![Bin::default(); usize::from(bin_of[lo]) + 1];
        let mut tops = self.tops.iter().peekable();
        for s in present().rev() {
            let bin = &mut bins[usize::from(bin_of[s])];
            let needed = bin.len < BIN_HEAD;
            bin.len += self.counts[s] as usize;
            while let Some(e) = tops.next_if(|e| usize::from(e.score) >= s) {
                if needed && usize::from(e.score) == s {
                    bin.head.push(Candidate {
                        similarity: e.similarity,
                        node: level[e.id as usize],
                        score: e.score,
                    });
                }
            }
        }
        for bin in &mut bins {
            // Scores arrive highest first, each in list order: the head is
            // already in `push_head`'s order.
            bin.head.truncate(BIN_HEAD);
        }
        Bins { bins }
    }
}

/// Builds a [`ScoreTops`] from columns offered in ascending id order (so ties
/// keep the first offered ahead, the stable order of §3.1). Scratch space
/// reused between rows.
#[derive(Default)]
pub(super) struct TopsBuilder {
    counts: Vec<u32>,
    kept: Vec<Vec<(f64, u32)>>,
}

impl TopsBuilder {
    /// Starts a new row.
    pub(super) fn reset(&mut self) {
        self.counts.clear();
        self.counts.resize(SCORES, 0);
        self.kept.resize_with(SCORES, Vec::new);
        for k in &mut self.kept {
            k.clear();
        }
    }

    /// Counts column `id` with this similarity and keeps it while it is among
    /// its score's first [`BIN_HEAD`].
    #[inline]
    pub(super) fn take(&mut self, similarity: f64, id: u32) {
        let s = usize::from(score(similarity));
        self.counts[s] += 1;
        self.keep(s, similarity, id);
    }

    /// Counts `n` columns of similarity exactly 0 without offering them
    /// (offer the first ones with [`TopsBuilder::keep_zero`]).
    pub(super) fn count_zeros(&mut self, n: usize) {
        self.counts[0] += u32::try_from(n).unwrap_or(u32::MAX);
    }

    /// Offers a column of similarity exactly 0 already counted.
    pub(super) fn keep_zero(&mut self, id: u32) {
        self.keep(0, 0.0, id);
    }

    #[inline]
    fn keep(&mut self, s: usize, similarity: f64, id: u32) {
        let kept = &mut self.kept[s];
        if kept.len() == BIN_HEAD && kept.last().is_some_and(|last| last.0 >= similarity) {
            return;
        }
        let position = kept.partition_point(|c| c.0 >= similarity);
        kept.insert(position, (similarity, id));
        kept.truncate(BIN_HEAD);
    }

    /// The summary of the row offered since [`TopsBuilder::reset`].
    pub(super) fn finish(&self) -> ScoreTops {
        let mut tops = Vec::new();
        for s in (0..SCORES).rev() {
            tops.extend(self.kept[s].iter().map(|&(similarity, id)| Entry {
                score: s as u8,
                similarity,
                id,
            }));
        }
        ScoreTops {
            counts: self.counts.clone(),
            tops,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::bins::bin_row;
    use super::super::similarity::SimilarityKind;
    use super::*;

    /// A pseudo-random row with many ties, split into parts in any way, gives
    /// `bin_row`'s bins once merged.
    #[test]
    fn merged_parts_bin_as_the_whole_row() {
        let mut state = 7u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        for round in 0..200 {
            let n = 2 + next(300) as usize;
            let spread = 1 + next(100);
            let row: Vec<f64> = (0..n)
                .map(|_| (next(spread) as f64 + [0.0, 0.25, 0.5][next(3) as usize]) / 100.0)
                .collect();
            let i = next(n as u64) as usize;
            let level: Vec<usize> = (0..n).map(|j| 10 + 2 * j).collect();
            let want = bin_row(SimilarityKind::Cosine, &level, i, &row, &mut Vec::new());
            let parts = 1 + next(4);
            let mut builders: Vec<TopsBuilder> = (0..parts).map(|_| TopsBuilder::default()).collect();
            for b in &mut builders {
                b.reset();
            }
            for (j, &s) in row.iter().enumerate() {
                if j != i {
                    builders[next(parts) as usize].take(s, j as u32);
                }
            }
            let mut merged = ScoreTops::empty();
            for b in &builders {
                merged.merge(&b.finish());
            }
            assert_eq!(merged.bins(n, &level), want, "round {round}");
        }
    }
}
