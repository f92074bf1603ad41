//! What of a level's adjacency across diagrams cannot change while the level
//! is laid out ([`CrossPlan`], kept by [`CrossCache`] and built once per
//! level), and the cross-diagram pairs of a snapshot from it.
//!
//! Every parent's cell is fixed for the whole level, so an only child's cell
//! (a [`Diagram::Single`](super::level::Diagram::Single): mostly a virtual
//! copy of a leaf, paper §4) is too. On deep levels of a tree with copies
//! most cells are such, and the pairs between two of them were compared anew
//! every tick; they are compared once here. A snapshot then compares only
//! pairs with a cell of a moving diagram
//! ([`Diagram::Sim`](super::level::Diagram::Sim)), and only against cells that
//! can reach that diagram's parent cell. The pairs are exactly those of
//! comparing every boundary cell with every other
//! ([`level_adjacency`](crate::geom::level_adjacency), as the snapshot did
//! before): the same [`shared_length`](crate::geom::shared_edge::shared_length)
//! calls on the pairs that can count, none on pairs that cannot.

use std::sync::{Arc, Mutex, PoisonError};

use super::links::{LevelLinks, LIFTED_WEIGHT};
use crate::geom::adjacency::{adjacent_pairs, box_pad, overlapping_boxes};
use crate::geom::shared_edge::PERPENDICULAR_TOL;
use crate::geom::{ConvexPolygon, LevelAdjacency, Point};

/// The [`CrossPlan`] of the level's diagrams, made on the first snapshot and
/// kept while the diagrams' parents and only children stay the same (they do
/// for a whole level; a snapshot of other diagrams makes a new plan).
#[derive(Default)]
pub(super) struct CrossCache {
    plan: Mutex<Option<Arc<CrossPlan>>>,
}

impl CrossCache {
    /// The plan for `diagrams`: the kept one when it fits them, else a new
    /// one, with `aspect` the shape measure of an only child's cell.
    pub(super) fn plan(
        &self,
        diagrams: &[Part<'_>],
        links: &LevelLinks,
        scale: f64,
        aspect: fn(&ConvexPolygon) -> f64,
    ) -> Arc<CrossPlan> {
        // A panic elsewhere while the lock was held leaves a plan that was
        // either complete or absent, so a poisoned lock is still usable.
        let mut kept = self.plan.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(plan) = kept.as_ref().filter(|p| p.fits(diagrams, scale)) {
            return Arc::clone(plan);
        }
        let plan = Arc::new(CrossPlan::new(diagrams, links, scale, aspect));
        *kept = Some(Arc::clone(&plan));
        plan
    }
}

/// What the plan reads of one of the level's diagrams: an only child (its
/// node and cell, the parent's), or the parent's cell of a diagram whose
/// cells move.
pub(super) enum Part<'a> {
    Single {
        child: usize,
        polygon: &'a ConvexPolygon,
    },
    Sim {
        clip: &'a ConvexPolygon,
    },
}

/// What one diagram was when the plan was made.
enum Shape {
    /// An only child (level-local index) and its cell, with the cell's
    /// centroid and bounding-box aspect, which every snapshot reads.
    Single {
        local: usize,
        polygon: ConvexPolygon,
        centroid: Point,
        aspect: f64,
    },
    /// A diagram whose cells move, its parent's cell, and the box every one
    /// of its cells' padded boxes lies in (the parent's box widened by the
    /// pad and a margin for round-off).
    Sim {
        clip: ConvexPolygon,
        reach: (Point, Point),
    },
}

/// A level's fixed cross-diagram geometry: the adjacent pairs of only
/// children, and which only children a moving diagram's cell can reach.
pub(super) struct CrossPlan {
    scale: f64,
    shapes: Vec<Shape>,
    /// Adjacent pairs `(a, b)`, `a < b`, of only children (level-local).
    fixed_pairs: Vec<(usize, usize)>,
    /// Only children (level-local, sorted) whose padded cell box meets some
    /// moving diagram's reach box: the only ones a moving cell can touch.
    near_singles: Vec<usize>,
    /// Per level-local index `a`, the partners `b > a` it has constraints
    /// with and what their adjacency is worth ([`LevelLinks::worth`]),
    /// sorted by `b`.
    worth: Vec<Vec<(usize, usize)>>,
    /// What [`fixed_pairs`](Self::fixed_pairs) are worth together.
    fixed_worth: usize,
}

impl CrossPlan {
    fn new(
        diagrams: &[Part<'_>],
        links: &LevelLinks,
        scale: f64,
        aspect: fn(&ConvexPolygon) -> f64,
    ) -> Self {
        let pad = box_pad(scale);
        // Cells are clipped to their parent's cell, so their boxes lie in its
        // box up to round-off; the margin keeps round-off from sending a
        // snapshot to the full comparison (`holds`).
        let widen = Point::splat(pad + PERPENDICULAR_TOL * scale);
        let shapes: Vec<Shape> = diagrams
            .iter()
            .map(|d| match d {
                Part::Single { child, polygon } => Shape::Single {
                    local: links.local[*child],
                    polygon: (*polygon).clone(),
                    centroid: polygon.centroid(),
                    aspect: aspect(polygon),
                },
                Part::Sim { clip } => {
                    let (lo, hi) = clip.bbox();
                    Shape::Sim {
                        clip: (*clip).clone(),
                        reach: (lo - widen, hi + widen),
                    }
                }
            })
            .collect();
        let mut plan = Self {
            scale,
            shapes,
            fixed_pairs: Vec::new(),
            near_singles: Vec::new(),
            worth: pair_worth(links),
            fixed_worth: 0,
        };
        if diagrams.len() < 2 {
            return plan;
        }
        let mut single_cell: Vec<Option<&ConvexPolygon>> = vec![None; links.nodes.len()];
        let mut singles = Vec::new();
        for s in &plan.shapes {
            if let Shape::Single { local, polygon, .. } = s {
                single_cell[*local] = Some(polygon);
                singles.push(*local);
            }
        }
        plan.fixed_pairs = adjacent_pairs(|k| single_cell[k], &singles, scale, |_, _| true);
        plan.fixed_worth = plan.fixed_pairs.iter().map(|&(a, b)| plan.pair_worth(a, b)).sum();
        // Reach boxes of moving diagrams first, then padded boxes of only
        // children; a pair of one of each that overlaps names a near one.
        let mut boxes: Vec<(Point, Point)> = plan
            .shapes
            .iter()
            .filter_map(|s| match s {
                Shape::Sim { reach, .. } => Some(*reach),
                Shape::Single { .. } => None,
            })
            .collect();
        let moving = boxes.len();
        boxes.extend(singles.iter().map(|&k| {
            let (lo, hi) = single_cell[k].expect("an only child's cell").bbox();
            (lo - Point::splat(pad), hi + Point::splat(pad))
        }));
        let mut near: Vec<usize> = overlapping_boxes(&boxes, scale, |a, b| a < moving && b >= moving)
            .into_iter()
            .map(|(_, b)| singles[b - moving])
            .collect();
        near.sort_unstable();
        near.dedup();
        plan.near_singles = near;
        plan
    }

    /// True when `diagrams` are the ones the plan was made for: the same
    /// parents' cells and the same only children with the same cells.
    fn fits(&self, diagrams: &[Part<'_>], scale: f64) -> bool {
        self.scale == scale
            && self.shapes.len() == diagrams.len()
            && self.shapes.iter().zip(diagrams).all(|(s, d)| match (s, d) {
                (Shape::Single { polygon: p, .. }, Part::Single { polygon, .. }) => p == *polygon,
                (Shape::Sim { clip: c, .. }, Part::Sim { clip }) => c == *clip,
                _ => false,
            })
    }

    /// The centroid and bounding-box aspect of diagram `d`'s cell when it is
    /// an only child.
    pub(super) fn single(&self, d: usize) -> Option<(Point, f64)> {
        match &self.shapes[d] {
            Shape::Single {
                centroid, aspect, ..
            } => Some((*centroid, *aspect)),
            Shape::Sim { .. } => None,
        }
    }

    /// True when `cell`, a cell of moving diagram `d`, lies (padded) in `d`'s
    /// reach box, as every cell clipped to its parent does: then only the
    /// near only children can touch it. False sends the snapshot to the
    /// full comparison, so the pairs stay exact whatever the cell.
    pub(super) fn holds(&self, d: usize, cell: &ConvexPolygon) -> bool {
        let Shape::Sim { reach, .. } = &self.shapes[d] else {
            return false;
        };
        let pad = Point::splat(box_pad(self.scale));
        let (lo, hi) = cell.bbox();
        let (lo, hi) = (lo - pad, hi + pad);
        lo.x >= reach.0.x && lo.y >= reach.0.y && hi.x <= reach.1.x && hi.y <= reach.1.y
    }

    /// What the adjacency of `a` and `b` (level-local, `a < b`) is worth.
    fn pair_worth(&self, a: usize, b: usize) -> usize {
        let partners = &self.worth[a];
        partners
            .binary_search_by_key(&b, |p| p.0)
            .map_or(0, |i| partners[i].1)
    }

    /// [`LevelLinks::realized`] for `adjacency`, whose pairs of only
    /// children are the plan's [`fixed_pairs`](Self::fixed_pairs) (`diagram[k]`
    /// is node `k`'s diagram): their worth is summed once per level, and only
    /// the pairs with a moving cell are looked up.
    pub(super) fn realized(&self, adjacency: &LevelAdjacency, diagram: &[usize]) -> usize {
        let fixed = |k: usize| self.is_single(diagram[k]);
        let moving: usize = adjacency
            .pairs()
            .iter()
            .filter(|&&(a, b)| !(fixed(a) && fixed(b)))
            .map(|&(a, b)| self.pair_worth(a, b))
            .sum();
        self.fixed_worth + moving
    }

    /// True when diagram `d` is an only child.
    fn is_single(&self, d: usize) -> bool {
        matches!(self.shapes[d], Shape::Single { .. })
    }

    /// The level's adjacent pairs across diagrams (level-local, `a < b`,
    /// unsorted): the fixed pairs of only children, plus those with a cell
    /// of a moving diagram, compared among `moving` (the moving diagrams'
    /// cells on their parent's boundary, each of which [`holds`](Self::holds))
    /// and the near only children. `cell(k)` is cell `k`'s polygon and
    /// `diagram[k]` its diagram.
    pub(super) fn cross_pairs<'a>(
        &self,
        cell: impl Fn(usize) -> Option<&'a ConvexPolygon>,
        moving: &[usize],
        diagram: &[usize],
    ) -> Vec<(usize, usize)> {
        let mut nodes = Vec::with_capacity(moving.len() + self.near_singles.len());
        nodes.extend_from_slice(moving);
        nodes.extend_from_slice(&self.near_singles);
        let fixed = |k: usize| self.is_single(diagram[k]);
        let mut pairs = adjacent_pairs(cell, &nodes, self.scale, |a, b| {
            diagram[a] != diagram[b] && !(fixed(a) && fixed(b))
        });
        pairs.extend_from_slice(&self.fixed_pairs);
        pairs
    }
}

/// Per level-local index `a`, its partners `b > a` and what their adjacency
/// is worth: 1 per own constraint and [`LIFTED_WEIGHT`] per lifted one, as
/// [`LevelLinks::worth`] counts them.
fn pair_worth(links: &LevelLinks) -> Vec<Vec<(usize, usize)>> {
    (0..links.nodes.len())
        .map(|a| {
            let own = links.links[a].iter().map(|&(b, _)| (b, 1));
            let lifted = links.lifted[a].iter().map(|&(b, n)| (b, LIFTED_WEIGHT * n));
            let mut partners: Vec<(usize, usize)> = own.chain(lifted).filter(|p| p.0 > a).collect();
            partners.sort_unstable();
            // One entry per partner, its worth summed.
            let mut merged: Vec<(usize, usize)> = Vec::with_capacity(partners.len());
            for (b, w) in partners {
                match merged.last_mut() {
                    Some(last) if last.0 == b => last.1 += w,
                    _ => merged.push((b, w)),
                }
            }
            merged
        })
        .collect()
}
