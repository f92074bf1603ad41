//! The precision choice's checks, kept from one document to the next
//! (issue 32, item 2: draw what moved). `precision::choose` spells every
//! cell on a grid and checks the checker's rules on the rounded cells, pass
//! by pass; after a weight edit almost every cell is spelled as before, so a
//! pass here checks again only the rules that name a cell spelled
//! differently from the same pass of the last choice, and takes the other
//! outcomes over.
//!
//! Exact, not a heuristic: a rule's outcome depends only on the spelled
//! cells it names, the family structure and the extent diagonal (the
//! tolerances' scale), so it is taken over only when all of those are the
//! same; a different tree, constraint list or diagonal checks everything.
//! The choice, and so the document's bytes, are those of a fresh check
//! (test `precision::tests::kept_checks_choose_as_a_fresh_check`).
//!
//! Hand-written: the memo is the last choice's passes, replaced each time,
//! bounded by [`MAX_HELD`] bytes.

use std::sync::{Arc, Mutex};

use crate::geom::Point;

use super::spelled::Spelled;

/// Most bytes of spelled cells the memo keeps (some 7 MB at 6,000 C
/// headers): a hundred times that checks every rule each document, as a
/// first document does, with the same choice.
const MAX_HELD: usize = 64 << 20;

/// The passes of the last choice, for the next (see the module docs).
#[derive(Debug, Default)]
pub struct Checks {
    last: Mutex<Option<Checked>>,
}

/// What one choice checked: the tree and constraint pairs it checked them
/// on, and its passes in order.
#[derive(Debug)]
pub(super) struct Checked {
    pub(super) parents: Vec<Option<usize>>,
    pub(super) pairs: Vec<(usize, usize, bool)>,
    pub(super) passes: Vec<Pass>,
    pub(super) counts: CheckCounts,
}

/// One pass: its spelled cells and every rule's outcome on them.
#[derive(Debug)]
pub(super) struct Pass {
    pub(super) cells: Arc<Vec<Spelled>>,
    /// Per cell, the bounding box of its rounded polygon; `None` when the
    /// rounded ring is not a convex polygon (rule 1).
    pub(super) boxes: Vec<Option<(Point, Point)>>,
    /// The extent diagonal the tolerances were scaled by.
    pub(super) diagonal: f64,
    /// Per node, whether its family (it and its children) breaks rules 2-4.
    pub(super) family_bad: Vec<bool>,
    /// Per constraint pair, whether its `realized` flag disagrees (rule 5).
    pub(super) pair_bad: Vec<bool>,
}

/// How many rules a document checked and how many it took over.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CheckCounts {
    /// Checked on the rounded cells.
    pub checked: usize,
    /// Taken over from the last choice.
    pub kept: usize,
}

impl Checks {
    /// The last choice's passes when they were checked on the same tree and
    /// pairs, taken out (the choice under way puts its own back).
    pub(super) fn take(
        &self,
        parents: &[Option<usize>],
        pairs: &[(usize, usize, bool)],
    ) -> Option<Checked> {
        self.lock()
            .take()
            .filter(|c| c.parents == parents && c.pairs == pairs)
    }

    /// How many rules the last choice checked and took over, over all its
    /// passes.
    pub fn counts(&self) -> CheckCounts {
        self.lock().as_ref().map(|c| c.counts).unwrap_or_default()
    }

    /// Keeps `checked` for the next choice, unless it is above the bound.
    pub(super) fn keep(&self, checked: Checked) {
        let held: usize = checked
            .passes
            .iter()
            .map(|p| {
                p.cells
                    .iter()
                    .map(|c| 64 + 16 * c.polygon.len())
                    .sum::<usize>()
                    + 40 * p.boxes.len()
            })
            .sum();
        if held <= MAX_HELD {
            *self.lock() = Some(checked);
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Option<Checked>> {
        // A panic while the lock was held leaves a whole entry or none.
        self.last.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Which rules of a pass must be checked again against `last`, the same
/// pass of the last choice: per cell whether it is spelled differently.
pub(super) fn changed(cells: &[Spelled], last: Option<&Pass>) -> Vec<bool> {
    match last {
        Some(l) if l.cells.len() == cells.len() => cells
            .iter()
            .zip(l.cells.iter())
            .map(|(a, b)| a != b)
            .collect(),
        _ => vec![true; cells.len()],
    }
}

/// The diagonal of the boxes' extent, as `shared_edge::extent_diagonal` of
/// the polygons (1 when there are none).
pub(super) fn diagonal(boxes: &[Option<(Point, Point)>]) -> f64 {
    let mut bounds: Option<(Point, Point)> = None;
    for &(lo, hi) in boxes.iter().flatten() {
        bounds = Some(match bounds {
            None => (lo, hi),
            Some((l, h)) => (l.min(lo), h.max(hi)),
        });
    }
    bounds.map_or(1.0, |(lo, hi)| (hi - lo).length())
}
