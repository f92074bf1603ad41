//! Keeping every cell of a `MapSimulation` non-empty: the guard before a new
//! diagram (`prevent_domination`), the repair of empty cells after one, and the
//! restart of a site that the repair could not keep.

use super::MapSimulation;
use crate::geom::Point;
use crate::power::{power_diagram, Site};

/// Repair rounds per diagram evaluation. One round fixes every empty cell seen;
/// more than a handful means pathological input, where the next tick goes on.
const REPAIR_ROUNDS: usize = 4;

/// Rounds of the quick repair (a dominated site's weight raised just below its
/// dominator's) before empty cells get [`MapSimulation::restart_site`]. The
/// quick fix is local but can cascade through chains of tiny cells beside huge
/// ones (weights 1:85,000 in the Debian packages of `tests/data/real`).
const QUICK_REPAIR_ROUNDS: usize = 2;

/// Rounds of [`MapSimulation::restart_empty`].
const RESTART_ROUNDS: usize = 3;

/// Random points tried by [`MapSimulation::restart_site`] after the site's own
/// position and its dominator's centroid.
const RESTART_TRIES: usize = 8;

/// A weight gap (upper minus lower bound, a squared length) wide enough to
/// stop [`MapSimulation::restart_site`]'s search, as a share of the clip's area.
const RESTART_MIN_GAP: f64 = 1e-9;

/// A dominated site's weight is raised to leave this share of the squared site
/// distance as margin, so the repaired site lies strictly inside its cell
/// (d3-voronoi-map's `handleOverweighted` uses the full distance plus epsilon).
const REPAIR_MARGIN: f64 = 0.9;

/// [`MapSimulation::prevent_domination`] keeps `w_j − w_i` below this share of
/// `d²`, so the bisector stays at least `(1 − margin)·d/2` from the site. A
/// small cell next to a big one needs its bisector close to its site (a 1:10⁴
/// area ratio needs about d/300), so the margin is thin; a wider one pinned
/// small corner cells above their target area.
const PREVENT_MARGIN: f64 = 0.999;

/// Passes of [`MapSimulation::prevent_domination`]; raising one weight can make
/// that site dominate another, which the next pass catches.
const PREVENT_PASSES: usize = 3;

impl MapSimulation {
    /// Gives every site with an empty cell a new start (`restart_site`)
    /// and recomputes the diagram, a few rounds at most; returns how many
    /// sites were restarted. For the end of an optimisation, where a cell left
    /// empty would make the layout fail.
    pub fn restart_empty(&mut self) -> usize {
        let mut restarted = 0;
        for _ in 0..RESTART_ROUNDS {
            let empty: Vec<usize> = (0..self.sites.len())
                .filter(|&i| self.diagram.cells[i].polygon.is_none())
                .collect();
            if empty.is_empty() {
                break;
            }
            for &i in &empty {
                self.restart_site(i);
            }
            restarted += empty.len();
            self.diagram = power_diagram(&self.sites, &self.clip);
        }
        self.error = self.area_error();
        restarted
    }


    /// Before a new diagram: raise the weight of any site that a neighbour or
    /// its dominator in the previous diagram would swallow at the current
    /// positions. A cheap local version of d3-voronoi-map's all-pairs
    /// `handleOverweighted` (O(n²)); what it misses, [`Self::repair`] catches.
    pub(super) fn prevent_domination(&mut self) {
        for _ in 0..PREVENT_PASSES {
            let mut changed = false;
            for i in 0..self.sites.len() {
                let cell = &self.diagram.cells[i];
                let others = cell
                    .neighbors
                    .iter()
                    .map(|nb| nb.site)
                    .chain(cell.dominated_by);
                for j in others {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    let floor = self.sites[j].weight - PREVENT_MARGIN * d2;
                    if self.sites[i].weight < floor {
                        self.sites[i].weight = floor;
                        changed = true;
                    }
                }
            }
            if !changed {
                return;
            }
        }
    }


    /// Gives every site a non-empty cell, recomputing the diagram while any cell
    /// is empty: a dominated site's weight is raised to just below the level at
    /// which its dominator swallows it; an empty cell that is not dominated
    /// (coincident sites) gets a fresh random position. Sites that are dominated
    /// but still have a cell are left to [`Self::prevent_domination`] before the
    /// next diagram: fixing them here cascades (a raised site dominates the
    /// next), costing a full diagram per round.
    pub(super) fn repair(&mut self) {
        for round in 0..REPAIR_ROUNDS {
            let mut changed = false;
            for i in 0..self.sites.len() {
                let cell = &self.diagram.cells[i];
                if cell.polygon.is_some() {
                    continue;
                }
                if round >= QUICK_REPAIR_ROUNDS {
                    // The quick fix cascades (a raised site swallows the
                    // next); give what is still empty a start that provably
                    // has a cell.
                    self.restart_site(i);
                    changed = true;
                    continue;
                }
                let dominator = cell.dominated_by.map(|j| {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    (j, d2)
                });
                match dominator {
                    // A dominator on the very same spot (coincident sites) cannot
                    // be escaped through weights.
                    Some((j, d2)) if d2 > 0.0 => {
                        self.sites[i].weight = self.sites[j].weight - REPAIR_MARGIN * d2;
                    }
                    _ => {
                        self.sites[i].position =
                            self.clip.sample(self.rng.next_f64(), self.rng.next_f64());
                    }
                }
                changed = true;
            }
            if !changed {
                return;
            }
            self.diagram = power_diagram(&self.sites, &self.clip);
        }
    }

    /// Gives site `i` a weight, and if need be a position, at which it owns a
    /// cell without swallowing any other site. At a point `p`, site `i` holds
    /// `p` against every other site `k` when `w_i > max_k (w_k − |p − p_k|²)`
    /// (the lower bound `lo`) and takes no other site's own point when `w_i <
    /// min_k (w_k + |p − p_k|²)` (the upper bound `hi`). The site stays where
    /// it is when the bounds leave room there; else it moves to the first of
    /// its dominator's centroid and a few seeded random points where they do
    /// (the widest gap if none is wide). O(n) per site, and only for sites
    /// whose cell the quick repair could not keep.
    pub(super) fn restart_site(&mut self, i: usize) {
        let bounds = |sites: &[Site], p: Point| -> (f64, f64) {
            let mut lo = f64::NEG_INFINITY;
            let mut hi = f64::INFINITY;
            for (k, s) in sites.iter().enumerate() {
                if k == i || !(s.weight.is_finite() && s.position.is_finite()) {
                    continue;
                }
                let d2 = p.distance_squared(s.position);
                lo = lo.max(s.weight - d2);
                hi = hi.min(s.weight + d2);
            }
            (lo, hi)
        };
        let wide = RESTART_MIN_GAP * self.clip_area;
        let mut candidates = Vec::with_capacity(2);
        let here = self.sites[i].position;
        if here.is_finite() && self.clip.contains(here) {
            candidates.push(here);
        }
        if let Some(j) = self.diagram.cells[i].dominated_by {
            if self.diagram.cells[j].polygon.is_some() {
                candidates.push(self.diagram.cells[j].centroid);
            }
        }
        let mut best: Option<(f64, Point, f64)> = None;
        for k in 0..candidates.len() + RESTART_TRIES {
            let p = match candidates.get(k) {
                Some(p) => *p,
                None => self.clip.sample(self.rng.next_f64(), self.rng.next_f64()),
            };
            let (lo, hi) = bounds(&self.sites, p);
            // Infinite when there is no other site: any weight will do.
            let gap = hi - lo;
            if best.is_none_or(|b| gap > b.0) {
                best = Some((gap, p, lo));
            }
            if gap > wide {
                break;
            }
        }
        let Some((gap, p, lo)) = best else {
            return;
        };
        // Above the lower bound by what a free disc of the target area needs
        // (|x − p|² < w_i − lo), and never past half the gap.
        let weight = if gap.is_infinite() {
            0.0
        } else {
            lo + (self.targets[i] / std::f64::consts::PI).min(0.5 * gap.max(0.0))
        };
        self.sites[i] = Site {
            position: p,
            weight,
        };
    }
}
