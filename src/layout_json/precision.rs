//! How precisely the layout-JSON writer spells each cell: the grid its
//! coordinates are rounded to, chosen from the canvas, and the check that the
//! rounded cells still pass the layout checker's rules with a wide margin,
//! refining the cells where they would not. Owns that choice; the writer
//! (`super::write`) spells the numbers.
//!
//! The checker (`check-layout`, and `tests/tools/check_layout.py`) judges a
//! document from its numbers alone: every polygon convex with positive area
//! and winding once, children inside their parent within 1e-5 of the extent
//! diagonal, children covering their parent and overlapping each other within
//! 1e-4 of its area, and every `realized` flag agreeing with a shared boundary
//! of at least 1e-6 of the diagonal. Rounding moves every vertex by up to
//! half a grid step per axis, so a grid that suits big cells can break these
//! rules on tiny ones (a 0.5-px family, a near-straight vertex that turns the
//! wrong way, a contact a few thousandths of a pixel long). So the grid is a
//! start: every rule is checked on the rounded cells with ten times the
//! checker's margin, and the cells of a failing rule get finer grids, up to
//! full precision, until every rule holds. On the 6,000-leaf C-headers tree
//! that refines no cell or a handful; full precision is the layout itself,
//! which passes by construction.

use std::sync::Arc;

use nptreemap_formats::Dataset;

use super::checks::{self, CheckCounts, Checked, Checks, Pass};
use super::spelled::{exact, spell, Spelled};
use crate::geom::{cross, shared_edge, ConvexPolygon, Point};
use crate::layout::{Canvas, Layout};

/// The grid step, as a share of the canvas diagonal: a tenth of the
/// checker's shortest shared boundary (1e-6 of the diagonal) and a hundredth
/// of its containment tolerance (1e-5), so that the rounding of a vertex
/// (at most 0.71 steps) stays well inside both. On a 1000 × 1000 canvas that
/// is 1.4e-4, so coordinates get four decimals: 1/10,000 of a pixel at
/// scale 1, far below anything a picture shows (the SVG has two decimals)
/// yet below a tenth of the checker's 1.4e-3 contact threshold, which three
/// decimals (up to 1.4e-3 of rounding per contact) would not be.
const GRID_SHARE: f64 = 1e-7;

/// Margins of the checks, ten times inside the checker's own tolerances.
/// Partition and sibling overlap, as a share of the parent's area (the
/// checker allows 1e-4).
const AREA_MARGIN: f64 = 1e-5;
/// Containment, as a share of the extent diagonal (the checker allows 1e-5).
const CONTAIN_MARGIN: f64 = 1e-6;
/// A contact's rounded length must stay this far (relative) on its side of
/// the threshold, so that the checker's own arithmetic, which may differ from
/// ours in the last bits, cannot flip it.
const CONTACT_BAND: f64 = 1e-6;

/// Decimals added per refinement before full precision: base, base + 2, full.
const REFINE_STEP: i32 = 2;
const LEVELS: u8 = 3;
/// Passes of check-and-refine before the whole document falls back to full
/// precision. Each pass refines every cell of every failing rule, and full
/// precision passes every rule, so a handful of passes settles any layout;
/// the bound only keeps a pathological one from looping.
const MAX_PASSES: usize = 8;

/// The decimals of the base grid for `canvas`: the fewest with a step of at
/// most [`GRID_SHARE`] of its diagonal.
pub(super) fn base_places(canvas: Canvas) -> i32 {
    let diagonal = Point::new(canvas.width, canvas.height).length();
    let step = GRID_SHARE * diagonal;
    if step.is_finite() && step > 0.0 {
        (-step.log10()).ceil().clamp(0.0, 12.0) as i32
    } else {
        12
    }
}

/// Every cell of `layout` (indexed like `dataset`'s nodes) spelled on the
/// coarsest grid, from [`base_places`], under which the rounded document keeps
/// every rule of the checker with ten times its margin; `pairs` are the
/// constraints `(a, b, realized)` whose flags must survive. With `memo`,
/// the rules of cells spelled as in the last choice are taken over from it
/// (`super::checks`); the choice is the same.
pub(super) fn choose(
    dataset: &Dataset,
    layout: &Layout,
    pairs: &[(usize, usize, bool)],
    memo: Option<&Checks>,
) -> Arc<Vec<Spelled>> {
    let parents: Vec<Option<usize>> = dataset.nodes().iter().map(|n| n.parent).collect();
    let last = memo.and_then(|m| m.take(&parents, pairs));
    let mut checked = Checked {
        parents,
        pairs: pairs.to_vec(),
        passes: Vec::new(),
        counts: CheckCounts::default(),
    };
    let chosen = choose_passes(dataset, layout, pairs, last, &mut checked);
    if let Some(memo) = memo {
        memo.keep(checked);
    }
    chosen
}

/// The passes of [`choose`], each kept in `checked`.
fn choose_passes(
    dataset: &Dataset,
    layout: &Layout,
    pairs: &[(usize, usize, bool)],
    last: Option<Checked>,
    checked: &mut Checked,
) -> Arc<Vec<Spelled>> {
    let base = base_places(layout.canvas);
    let n = layout.cells.len();
    let mut level = vec![0u8; n];
    let chain = chain_tops(dataset);
    let places_of = |l: u8| (l + 1 < LEVELS).then(|| base + REFINE_STEP * i32::from(l));
    for k in 0..MAX_PASSES {
        let cells: Arc<Vec<Spelled>> = Arc::new(
            layout
                .cells
                .iter()
                .zip(&level)
                .map(|(c, &l)| spell(&c.polygon, c.site, places_of(l)))
                .collect(),
        );
        let before = last.as_ref().and_then(|l| l.passes.get(k));
        let pass = check(dataset, cells, pairs, before, &mut checked.counts);
        let failing = failing(dataset, &pass, pairs);
        let cells = Arc::clone(&pass.cells);
        checked.passes.push(pass);
        if failing.is_empty() {
            return cells;
        }
        let mut raised = false;
        for i in failing {
            if level[i] + 1 < LEVELS {
                level[i] += 1;
                raised = true;
            }
        }
        // An only child has its parent's cell: the whole chain takes one
        // grid, or each refinement would only move the mismatch a level up
        // (a pass per level of a chain of virtual copies).
        let mut top_level = vec![0u8; n];
        for (i, &t) in chain.iter().enumerate() {
            top_level[t] = top_level[t].max(level[i]);
        }
        for (i, &t) in chain.iter().enumerate() {
            level[i] = top_level[t];
        }
        if !raised {
            // Only cells already in full precision fail: the layout itself
            // breaks a margin. Nothing finer exists; write it as it is.
            return cells;
        }
    }
    Arc::new(exact(layout))
}

/// Per node, the highest node of the chain of only children it belongs to
/// (itself when it is not an only child). A dataset lists its nodes
/// breadth-first, parents first, so one pass suffices.
fn chain_tops(dataset: &Dataset) -> Vec<usize> {
    let mut top: Vec<usize> = (0..dataset.len()).collect();
    for (i, node) in dataset.nodes().iter().enumerate() {
        if let Some(p) = node.parent {
            if dataset.node(p).children.len() == 1 {
                top[i] = top[p];
            }
        }
    }
    top
}

/// Every rule's outcome on the rounded `cells`: those of `last` (the same
/// pass of the last choice) where the rule names no cell spelled
/// differently and the diagonal is the same, the others checked.
fn check(
    dataset: &Dataset,
    cells: Arc<Vec<Spelled>>,
    pairs: &[(usize, usize, bool)],
    last: Option<&Pass>,
    counts: &mut CheckCounts,
) -> Pass {
    let n = cells.len();
    let mut changed = checks::changed(&cells, last);
    // Rule 1 and the boxes: each changed cell's rounded polygon.
    let mut polygons: Vec<Option<Option<ConvexPolygon>>> = vec![None; n];
    let mut boxes: Vec<Option<(Point, Point)>> = Vec::with_capacity(n);
    for i in 0..n {
        boxes.push(match last {
            Some(l) if !changed[i] => l.boxes[i],
            _ => {
                let p = polygon(&cells[i]);
                let b = p.as_ref().map(|p| p.bbox());
                polygons[i] = Some(p);
                b
            }
        });
    }
    let diagonal = checks::diagonal(&boxes);
    let last = last.filter(|l| l.diagonal.to_bits() == diagonal.to_bits());
    if last.is_none() {
        changed.fill(true);
    }
    let family_again: Vec<bool> = dataset
        .nodes()
        .iter()
        .enumerate()
        .map(|(p, node)| {
            !node.children.is_empty() && (changed[p] || node.children.iter().any(|&c| changed[c]))
        })
        .collect();
    let pair_again: Vec<bool> = pairs
        .iter()
        .map(|&(a, b, _)| changed[a] || changed[b])
        .collect();
    // Every polygon those rules name (an unchanged member of a family or
    // pair checked again too).
    for (p, node) in dataset.nodes().iter().enumerate() {
        if family_again[p] {
            for i in std::iter::once(p).chain(node.children.iter().copied()) {
                polygons[i].get_or_insert_with(|| polygon(&cells[i]));
            }
        }
    }
    for (&(a, b, _), &again) in pairs.iter().zip(&pair_again) {
        if again {
            for i in [a, b] {
                polygons[i].get_or_insert_with(|| polygon(&cells[i]));
            }
        }
    }
    let polygons: Vec<Option<&ConvexPolygon>> = polygons
        .iter()
        .map(|p| p.as_ref().and_then(|p| p.as_ref()))
        .collect();
    let mut rounded = Rounded {
        polygons: &polygons,
        diagonal,
        last,
        counts,
    };
    let family_bad = rounded.families(dataset, &family_again);
    let pair_bad = rounded.contacts(pairs, &pair_again);
    Pass {
        cells,
        boxes,
        diagonal,
        family_bad,
        pair_bad,
    }
}

/// The rounded cells a pass checks its rules on, with the last choice's
/// same pass to take outcomes over from.
struct Rounded<'a> {
    /// Per cell, its rounded polygon where a rule to check names it (`None`
    /// also when the ring breaks rule 1).
    polygons: &'a [Option<&'a ConvexPolygon>],
    diagonal: f64,
    last: Option<&'a Pass>,
    counts: &'a mut CheckCounts,
}

impl Rounded<'_> {
    /// Rules 2-4 per family (containment, partition, overlap): checked where
    /// `again`, else the outcome of `last`.
    fn families(&mut self, dataset: &Dataset, again: &[bool]) -> Vec<bool> {
        dataset
            .nodes()
            .iter()
            .enumerate()
            .map(|(parent, node)| {
                if node.children.is_empty() {
                    return false;
                }
                let kept = |l: &Pass| l.family_bad[parent];
                self.outcome(again[parent], kept, |polygons, diagonal| {
                    let children: Option<Vec<&ConvexPolygon>> =
                        node.children.iter().map(|&c| polygons[c]).collect();
                    match (polygons[parent], children) {
                        (Some(outer), Some(children)) => !family_ok(outer, &children, diagonal),
                        _ => true,
                    }
                })
            })
            .collect()
    }

    /// A rule's outcome: `kept` of the last choice's pass unless `again`,
    /// else `check`ed on the rounded polygons and diagonal; counted.
    fn outcome(
        &mut self,
        again: bool,
        kept: impl FnOnce(&Pass) -> bool,
        check: impl FnOnce(&[Option<&ConvexPolygon>], f64) -> bool,
    ) -> bool {
        if again {
            self.counts.checked += 1;
            check(self.polygons, self.diagonal)
        } else {
            self.counts.kept += 1;
            self.last.is_some_and(kept)
        }
    }

    /// Rule 5 per constraint pair: whether its `realized` flag disagrees with
    /// the rounded cells; checked where `again`, else the outcome of `last`.
    fn contacts(&mut self, pairs: &[(usize, usize, bool)], again: &[bool]) -> Vec<bool> {
        let tol = shared_edge::PERPENDICULAR_TOL * self.diagonal;
        let threshold = shared_edge::MIN_SHARED * self.diagonal;
        pairs
            .iter()
            .zip(again)
            .enumerate()
            .map(|(k, (&(a, b, realized), &again))| {
                self.outcome(
                    again,
                    |l| l.pair_bad[k],
                    |polygons, _| {
                        let agrees = match (polygons[a], polygons[b]) {
                            (Some(pa), Some(pb)) => {
                                let shared = shared_edge::shared_length(pa, pb, tol);
                                if realized {
                                    shared >= threshold * (1.0 + CONTACT_BAND)
                                } else {
                                    shared < threshold * (1.0 - CONTACT_BAND)
                                }
                            }
                            _ => false,
                        };
                        !agrees
                    },
                )
            })
            .collect()
    }
}

/// The cells that take part in a rule the rounded cells of `pass` break.
fn failing(dataset: &Dataset, pass: &Pass, pairs: &[(usize, usize, bool)]) -> Vec<usize> {
    let mut bad: Vec<bool> = pass
        .boxes
        .iter()
        .zip(pass.cells.iter())
        .map(|(b, c)| b.is_none() && c.places.is_some())
        .collect();
    for (parent, node) in dataset.nodes().iter().enumerate() {
        if pass.family_bad[parent] {
            bad[parent] = true;
            for &c in &node.children {
                bad[c] = true;
            }
        }
    }
    for (&(a, b, _), &pair_bad) in pairs.iter().zip(&pass.pair_bad) {
        if pair_bad {
            bad[a] = true;
            bad[b] = true;
        }
    }
    bad.iter()
        .enumerate()
        .filter(|(_, b)| **b)
        .map(|(i, _)| i)
        .collect()
}

/// The rounded polygon of a spelled cell, `None` when its ring breaks
/// rule 1 (see [`ring_ok`]).
fn polygon(cell: &Spelled) -> Option<ConvexPolygon> {
    ring_ok(&cell.polygon)
        .then(|| ConvexPolygon::new(cell.polygon.clone()).ok())
        .flatten()
}

/// A ring both checkers take as convex: at least three vertices, every turn
/// to the left or straight ahead (never back), winding once, positive area.
pub(super) fn ring_ok(points: &[Point]) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let mut winding = 0.0;
    let mut twice_area = 0.0;
    for i in 0..n {
        let (a, b, c) = (points[i], points[(i + 1) % n], points[(i + 2) % n]);
        let (u, v) = (b - a, c - b);
        let turn = cross(u, v);
        if turn < 0.0 || (turn == 0.0 && u.dot(v) <= 0.0) {
            return false;
        }
        winding += turn.atan2(u.dot(v));
        twice_area += cross(a, b);
    }
    twice_area > 0.0 && (winding - std::f64::consts::TAU).abs() < 1e-6
}

/// Containment, partition and sibling overlap of one family, with the margins.
fn family_ok(outer: &ConvexPolygon, children: &[&ConvexPolygon], diagonal: f64) -> bool {
    let area = outer.area();
    let slack = CONTAIN_MARGIN * diagonal;
    let ring = outer.points();
    let inside = |p: &Point| {
        (0..ring.len()).all(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let e = b - a;
            let length = e.length();
            length == 0.0 || cross(e, *p - a) / length >= -slack
        })
    };
    if !children.iter().all(|c| c.points().iter().all(inside)) {
        return false;
    }
    let covered: f64 = children.iter().map(|c| c.area()).sum();
    if (covered - area).abs() > AREA_MARGIN * area {
        return false;
    }
    sibling_overlap(children) <= AREA_MARGIN * area
}

/// Summed area in which siblings overlap: pairs whose boxes meet, swept by x.
fn sibling_overlap(children: &[&ConvexPolygon]) -> f64 {
    let mut boxes: Vec<(Point, Point, usize)> = children
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (lo, hi) = c.bbox();
            (lo, hi, i)
        })
        .collect();
    boxes.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
    let mut total = 0.0;
    for (k, &(lo, hi, i)) in boxes.iter().enumerate() {
        for &(lo2, hi2, j) in &boxes[k + 1..] {
            if lo2.x >= hi.x {
                break;
            }
            if lo2.y >= hi.y || lo.y >= hi2.y {
                continue;
            }
            total += overlap(children[i], children[j]);
        }
    }
    total
}

/// Area of the intersection of two convex polygons: `a` clipped by every
/// edge of `b` (both positively oriented, so `b` lies left of its edges).
fn overlap(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    let ring = b.points();
    let mut part = Some(a.clone());
    for i in 0..ring.len() {
        let Some(p) = part else { return 0.0 };
        let (s, e) = (ring[i], ring[(i + 1) % ring.len()]);
        let normal = Point::new(e.y - s.y, s.x - e.x);
        part = p.clip_halfplane(normal, normal.dot(s));
    }
    part.map_or(0.0, |p| p.area())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::LayoutCell;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// A 1000 × 1000 canvas: `A` below (`A1` left of `split`, `A2` right),
    /// `B` a strip `h` tall along the top (`B1`, `B2` its halves). A strip
    /// thinner than the base grid's step rounds flat, so its family needs
    /// a second pass on a finer grid.
    fn strips(split: f64, h: f64) -> (Dataset, Layout) {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for (id, parent) in [("A", "root"), ("B", "root"), ("A1", "A"), ("A2", "A")] {
            b.add(NodeSpec::new(id).parent(parent));
        }
        for id in ["B1", "B2"] {
            b.add(NodeSpec::new(id).parent("B").weight(1.0));
        }
        let dataset = b.build().expect("valid");
        let top = 1000.0 - h;
        let rect = |id: &str| match id {
            "root" => (0.0, 0.0, 1000.0, 1000.0),
            "A" => (0.0, 0.0, 1000.0, top),
            "A1" => (0.0, 0.0, split, top),
            "A2" => (split, 0.0, 1000.0 - split, top),
            "B" => (0.0, top, 1000.0, h),
            "B1" => (0.0, top, 500.0, h),
            _ => (500.0, top, 500.0, h),
        };
        let cells = dataset
            .nodes()
            .iter()
            .map(|node| {
                let (x, y, w, h) = rect(&node.id);
                LayoutCell::rectangle(x, y, w, h)
            })
            .collect();
        let canvas = Canvas {
            width: 1000.0,
            height: 1000.0,
        };
        (dataset, Layout { canvas, cells })
    }

    /// Issue 32, item 2: a choice that takes over the last choice's checks
    /// spells every cell as a fresh choice does, across edits that move a
    /// cell, that make a strip need the finer grid and that undo it, and
    /// checks again only the rules of the cells that moved.
    #[test]
    fn kept_checks_choose_as_a_fresh_check() {
        let memo = Checks::default();
        let pairs_of = |d: &Dataset| {
            let f = |id: &str| d.find(id).expect("node");
            vec![
                (f("A1"), f("A2"), true),
                (f("A1"), f("B1"), true),
                (f("A2"), f("B1"), true),
                (f("A1"), f("B2"), false),
            ]
        };
        let mut kept_any = false;
        for (split, h) in [
            (400.0, 3e-5),
            (400.5, 3e-5),
            (400.5, 0.25),
            (400.5, 3e-5),
            (400.5, 3e-5),
        ] {
            let (dataset, layout) = strips(split, h);
            let pairs = pairs_of(&dataset);
            let fresh = choose(&dataset, &layout, &pairs, None);
            let kept = choose(&dataset, &layout, &pairs, Some(&memo));
            assert_eq!(kept, fresh, "split {split}, h {h}");
            let refined = fresh.iter().filter(|c| c.places != Some(4)).count();
            assert_eq!(
                refined > 0,
                h < 1e-4,
                "a strip under the grid step is refined"
            );
            let counts = memo.counts();
            kept_any |= counts.kept > 0;
        }
        assert!(kept_any);
        // The last two choices are of the same layout: nothing is checked.
        assert_eq!(memo.counts().checked, 0);
        assert!(
            memo.counts().kept >= 2 * 2 + 2 * 4,
            "two passes of 2 families and 4 pairs"
        );
        // One moved cell: only the rules naming it are checked again.
        let (dataset, layout) = strips(401.0, 3e-5);
        choose(&dataset, &layout, &pairs_of(&dataset), Some(&memo));
        let counts = memo.counts();
        assert!(counts.checked > 0 && counts.kept > 0, "{counts:?}");
    }

    #[test]
    fn the_grid_follows_the_canvas() {
        let c = |w, h| Canvas {
            width: w,
            height: h,
        };
        // 1000 × 1000: diagonal 1414, a tenth of 1.4e-3 is 1.4e-4: 1e-4.
        assert_eq!(base_places(c(1000.0, 1000.0)), 4);
        assert_eq!(base_places(c(400.0, 200.0)), 5);
        assert_eq!(base_places(c(20000.0, 20000.0)), 3);
        for (w, h) in [(1000.0, 1000.0), (400.0, 200.0), (7.0, 3.0), (1e5, 1.0)] {
            let step = 10f64.powi(-base_places(c(w, h)));
            let diagonal = Point::new(w, h).length();
            assert!(step <= 1e-7 * diagonal && step * 10.0 > 1e-7 * diagonal);
        }
    }

    #[test]
    fn a_ring_that_rounding_bends_backwards_is_refused() {
        let p = |x, y| Point::new(x, y);
        assert!(ring_ok(&[p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]));
        // A vertex a hair inside the straight bottom edge: a reflex turn.
        let square = [p(0.0, 0.0), p(2.0, 0.0), p(2.0, 2.0), p(0.0, 2.0)];
        assert!(ring_ok(&square));
        let mut bent = square.to_vec();
        bent.insert(1, p(1.0, 0.0001));
        assert!(!ring_ok(&bent));
        bent[1] = p(1.0, 0.0);
        assert!(ring_ok(&bent), "straight ahead is fine");
        // Clockwise, or flat.
        assert!(!ring_ok(&[p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0)]));
        assert!(!ring_ok(&[p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0)]));
    }
}
