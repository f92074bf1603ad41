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

use nptreemap_formats::Dataset;

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

/// One cell as the writer spells it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Spelled {
    /// Decimals of its numbers; `None` for full precision.
    pub(super) places: Option<i32>,
    /// Its polygon's vertices, rounded (repeated vertices dropped).
    pub(super) polygon: Vec<Point>,
    /// Its site, rounded.
    pub(super) site: Point,
}

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

/// `v` rounded to `places` decimals (`None`: as is), never `-0.0`.
///
/// Dividing the rounded integer by the power of ten gives the double nearest
/// to the decimal, so a shortest round-trip printer writes exactly that
/// decimal (no `0.30000000000000004` tails).
pub(super) fn round(v: f64, places: Option<i32>) -> f64 {
    let Some(places) = places else {
        return v + 0.0;
    };
    let scale = 10f64.powi(places);
    let r = (v * scale).round() / scale;
    // `+ 0.0` turns -0.0 into 0.0 (IEEE: -0 + +0 = +0).
    if r.is_finite() {
        r + 0.0
    } else {
        v + 0.0
    }
}

/// Every cell of `layout` spelled in full precision (the stored state).
pub(super) fn exact(layout: &Layout) -> Vec<Spelled> {
    layout
        .cells
        .iter()
        .map(|c| spell(&c.polygon, c.site, None))
        .collect()
}

/// Every cell of `layout` (indexed like `dataset`'s nodes) spelled on the
/// coarsest grid, from [`base_places`], under which the rounded document keeps
/// every rule of the checker with ten times its margin; `pairs` are the
/// constraints `(a, b, realized)` whose flags must survive.
pub(super) fn choose(
    dataset: &Dataset,
    layout: &Layout,
    pairs: &[(usize, usize, bool)],
) -> Vec<Spelled> {
    let base = base_places(layout.canvas);
    let n = layout.cells.len();
    let mut level = vec![0u8; n];
    let chain = chain_tops(dataset);
    let places_of = |l: u8| (l + 1 < LEVELS).then(|| base + REFINE_STEP * i32::from(l));
    for _ in 0..MAX_PASSES {
        let cells: Vec<Spelled> = layout
            .cells
            .iter()
            .zip(&level)
            .map(|(c, &l)| spell(&c.polygon, c.site, places_of(l)))
            .collect();
        let failing = failing(dataset, &cells, pairs);
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
    exact(layout)
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

fn spell(polygon: &ConvexPolygon, site: Point, places: Option<i32>) -> Spelled {
    let r = |p: Point| Point::new(round(p.x, places), round(p.y, places));
    let mut points: Vec<Point> = Vec::with_capacity(polygon.len());
    for p in polygon.points() {
        let q = r(*p);
        if points.last() != Some(&q) {
            points.push(q);
        }
    }
    while points.len() > 1 && points.first() == points.last() {
        points.pop();
    }
    Spelled {
        places,
        polygon: points,
        site: r(site),
    }
}

/// The cells that take part in a rule the rounded `cells` break.
fn failing(dataset: &Dataset, cells: &[Spelled], pairs: &[(usize, usize, bool)]) -> Vec<usize> {
    let mut bad = vec![false; cells.len()];
    // Rule 1: each ring turns one way, once, with positive area.
    let polygons: Vec<Option<ConvexPolygon>> = cells
        .iter()
        .map(|c| {
            ring_ok(&c.polygon)
                .then(|| ConvexPolygon::new(c.polygon.clone()).ok())
                .flatten()
        })
        .collect();
    for (i, p) in polygons.iter().enumerate() {
        if p.is_none() && cells[i].places.is_some() {
            bad[i] = true;
        }
    }
    let diagonal = shared_edge::extent_diagonal(polygons.iter().flatten()).unwrap_or(1.0);
    // Rules 2-4, per family: containment, partition, overlap.
    for (parent, node) in dataset.nodes().iter().enumerate() {
        if node.children.is_empty() {
            continue;
        }
        let family_bad = match (
            &polygons[parent],
            node.children
                .iter()
                .map(|&c| polygons[c].as_ref())
                .collect::<Option<Vec<_>>>(),
        ) {
            (Some(outer), Some(children)) => !family_ok(outer, &children, diagonal),
            _ => true,
        };
        if family_bad {
            bad[parent] = true;
            for &c in &node.children {
                bad[c] = true;
            }
        }
    }
    // Rule 5: every `realized` flag agrees with the rounded cells.
    let tol = shared_edge::PERPENDICULAR_TOL * diagonal;
    let threshold = shared_edge::MIN_SHARED * diagonal;
    for &(a, b, realized) in pairs {
        let agrees = match (&polygons[a], &polygons[b]) {
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
        if !agrees {
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

/// A ring both checkers take as convex: at least three vertices, every turn
/// to the left or straight ahead (never back), winding once, positive area.
fn ring_ok(points: &[Point]) -> bool {
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
    fn rounding_is_to_decimals_and_never_negative_zero() {
        assert_eq!(round(1.0 / 3.0, Some(4)), 0.3333);
        assert_eq!(round(-1e-9, Some(4)).to_string(), "0");
        assert_eq!(round(-0.0, None).to_string(), "0");
        assert_eq!(round(0.1 + 0.2, Some(4)), 0.3);
        assert_eq!(round(1.0 / 3.0, None), 1.0 / 3.0);
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
