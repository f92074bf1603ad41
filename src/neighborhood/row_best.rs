//! A row's best entries, kept while the row is scanned (all of it, or the part a
//! nearest-neighbour search visits), and the stage view (`bins::stage_view`)
//! they settle once the row's lowest and highest scores are known.
//!
//! What a row's stages read (method-reference §3.2–3.5): the thresholds, from
//! the row's lowest and highest score; the top bin's first 6 entries; and, only
//! when the top bin holds fewer than 4, the first entries of each following
//! bin up to the first empty one. So a row needs its best entries in exact
//! order and its two extreme scores; not a histogram of every score nor the
//! best entries of every score. [`RowBest`] keeps every entry that may be
//! among the [`WANTED`] best, from values within `eps` of the exact
//! similarities (the f32 filter's), and [`view_from_best`] builds the view from
//! them, or says that the view needs an entry beyond them (a small top bin over
//! crowded following bins): then the caller bins that row another way.

use super::bins::{bin_table, stage_view, Bin, Bins, Candidate, BIN_HEAD, STAGE_VIEW_FULL_TOP};
use super::similarity::score;

/// Entries a row keeps: the top bin's first [`BIN_HEAD`] and room for a second
/// bin's head behind a small top bin.
pub(super) const WANTED: usize = BIN_HEAD + STAGE_VIEW_FULL_TOP;

/// One row's best entries so far.
pub(super) struct RowBest {
    /// Entries that may be among the [`WANTED`] best: (similarity within `eps`
    /// of the exact one, level position).
    kept: Vec<(f64, usize)>,
    /// A lower bound on the [`WANTED`]-th best exact similarity.
    pub(super) floor: f64,
    /// Kept entries at which `kept` is pruned next.
    prune_at: usize,
    /// An upper bound on the row's lowest similarity (of the entries taken).
    pub(super) lowest: f64,
}

impl RowBest {
    pub(super) fn new() -> Self {
        RowBest {
            kept: Vec::new(),
            floor: f64::NEG_INFINITY,
            prune_at: 2 * WANTED,
            lowest: f64::INFINITY,
        }
    }

    /// Takes entry `j` with similarity `s`, within `eps` of the exact one.
    #[inline]
    pub(super) fn take(&mut self, s: f64, j: usize, eps: f64) {
        self.lowest = self.lowest.min(s + eps);
        if s + eps < self.floor {
            return;
        }
        self.kept.push((s, j));
        if self.kept.len() >= self.prune_at {
            self.prune(eps);
        }
    }

    /// Raises `floor` to the [`WANTED`]-th best kept value less `eps` (that
    /// many entries are at least that good) and drops what is below it.
    pub(super) fn prune(&mut self, eps: f64) {
        if self.kept.len() < WANTED {
            return;
        }
        let (_, &mut (nth, _), _) = self
            .kept
            .select_nth_unstable_by(WANTED - 1, |a, b| b.0.total_cmp(&a.0));
        self.floor = self.floor.max(nth - eps);
        let floor = self.floor;
        self.kept.retain(|&(s, _)| s + eps >= floor);
        self.prune_at = (2 * self.kept.len()).max(2 * WANTED);
    }

    /// Every entry whose exact similarity (`exact(j)`) is at least `floor`, in
    /// head order (similarity descending, level order): all such entries were
    /// kept, since a kept value is within `eps` of the exact one and `floor`
    /// only rose. Of a score's entries only the first [`BIN_HEAD`] are given:
    /// entries of one score share a bin whatever the thresholds, and a view
    /// reads a bin's first [`BIN_HEAD`] entries and its size up to
    /// [`BIN_HEAD`], which the first [`BIN_HEAD`] of each of its scores give.
    /// Why: where a row's entries all but tie (near-identical vectors) every
    /// one of them is kept, and sorting them all was most of the row's cost.
    pub(super) fn exact_best(&self, eps: f64, exact: impl Fn(usize) -> f64) -> Vec<(f64, usize)> {
        let floor = self.floor;
        let mut best: Vec<(f64, usize)> = self
            .kept
            .iter()
            .filter(|&&(s, _)| s + eps >= floor)
            .map(|&(_, j)| (exact(j), j))
            .filter(|&(s, _)| s >= floor)
            .collect();
        // `partial_cmp` treats −0 and 0 as equal, as `bins::push_head` does.
        let before = |a: &(f64, usize), b: &(f64, usize)| {
            b.0.partial_cmp(&a.0)
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(a.1.cmp(&b.1))
        };
        if best.len() > 4 * WANTED {
            let mut by_score: Vec<Vec<(f64, usize)>> = vec![Vec::new(); usize::from(u8::MAX) + 1];
            for entry in best.drain(..) {
                by_score[usize::from(score(entry.0))].push(entry);
            }
            for mut entries in by_score.into_iter().rev() {
                if entries.len() > BIN_HEAD {
                    entries.select_nth_unstable_by(BIN_HEAD - 1, before);
                    entries.truncate(BIN_HEAD);
                }
                best.extend(entries);
            }
        }
        best.sort_by(before);
        best
    }
}

/// The stage view of a row whose lowest score is `lo` and highest `hi`, from
/// `best`: every entry of similarity at least `floor` (or, per score, the
/// first [`BIN_HEAD`] of them: [`RowBest::exact_best`]), in head order. `None`
/// when the view needs an entry or a count beyond `best`.
pub(super) fn view_from_best(
    best: &[(f64, usize)],
    floor: f64,
    lo: u8,
    hi: u8,
    level: &[usize],
) -> Option<Bins> {
    if hi == 0 {
        return Some(Bins::default());
    }
    let bin_of = bin_table(lo, hi);
    let count = usize::from(bin_of[usize::from(lo)]) + 1;
    // Entries not in `best` are below `floor`, so score at most score(floor):
    // bins above that score's bin are complete in `best`.
    let complete_below = if floor == f64::NEG_INFINITY {
        count
    } else {
        usize::from(bin_of[usize::from(score(floor))])
    };
    let mut bins = vec![Bin::default(); count];
    for &(s, j) in best {
        let sc = score(s);
        let bin = &mut bins[usize::from(bin_of[usize::from(sc)])];
        bin.len += 1;
        if bin.head.len() < BIN_HEAD {
            bin.head.push(Candidate {
                similarity: s,
                node: level[j],
                score: sc,
            });
        }
    }
    let known = |b: usize, bins: &[Bin]| b < complete_below || bins[b].len >= BIN_HEAD;
    // The top bin's size decides how far the stages read: certain when `best`
    // holds enough of it, or all of it.
    if bins[0].len < STAGE_VIEW_FULL_TOP && complete_below == 0 {
        return None;
    }
    let view = stage_view(&Bins { bins: bins.clone() });
    (0..view.bins.len())
        .all(|b| known(b, &bins))
        .then_some(view)
}
