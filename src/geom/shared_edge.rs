//! Shared-edge geometry: which stretches of boundary two convex cells have in
//! common, with the one tolerance that decides it. "Share an edge" is defined
//! exactly as in the independent layout checker (`check-layout`), so every
//! `realized` flag, tab and adjacency this crate computes agrees with it. Owns
//! the tolerances and the edge overlap; may not know about layouts, levels or
//! hierarchies (those pass polygons in).

use super::{cross, ConvexPolygon, Point};

/// Shortest shared boundary, as a fraction of the layout's length scale
/// ([`extent_diagonal`]), for two cells to count as adjacent: the checker's
/// `--min-shared` default. The paper counts a constraint as realised when the
/// two cells "share an edge" (§6); a shorter overlap is round-off, not an edge.
pub const MIN_SHARED: f64 = 1e-6;

/// Perpendicular tolerance, as a fraction of the same length scale, within
/// which an edge of one cell lies on an edge of the other (the checker's
/// `tol_d`).
pub const PERPENDICULAR_TOL: f64 = 1e-5;

/// Calls `f(p1, u, lo, hi)` for every overlap of an edge of `a` (from `p1` along
/// the unit direction `u`) with an edge of `b` lying within `tol` of its line; the
/// overlap is the parameter interval `[lo, hi]` along `u`, with `hi > lo`.
///
/// This is the checker's `shared_length` loop verbatim (same edge order, same
/// tests), so the sums agree with it to round-off.
fn for_each_overlap(
    a: &ConvexPolygon,
    b: &ConvexPolygon,
    tol: f64,
    mut f: impl FnMut(Point, Point, f64, f64),
) {
    let pa = a.points();
    let pb = b.points();
    let (na, nb) = (pa.len(), pb.len());
    for i in 0..na {
        let p1 = pa[i];
        let e = pa[(i + 1) % na] - p1;
        let length = e.length();
        // Not `== 0.0` alone: a non-finite length would poison every overlap.
        if length <= 0.0 || !length.is_finite() {
            continue;
        }
        let u = e / length;
        for j in 0..nb {
            let q1 = pb[j];
            let q2 = pb[(j + 1) % nb];
            // Both end points of b's edge must lie on a's edge line (within tol):
            // then the edges are collinear and only the overlap along u is left.
            if cross(u, q1 - p1).abs() > tol || cross(u, q2 - p1).abs() > tol {
                continue;
            }
            let t1 = u.dot(q1 - p1);
            let t2 = u.dot(q2 - p1);
            let lo = t1.min(t2).max(0.0);
            let hi = t1.max(t2).min(length);
            if hi > lo {
                f(p1, u, lo, hi);
            }
        }
    }
}

/// Total length of boundary that `a` and `b` have in common: the summed overlap
/// of collinear edges, an edge of `b` counting as on an edge of `a` when both its
/// end points are within `tol` of that edge's line. Touching at a vertex gives 0.
/// Same definition and edge order as the checker's `shared_length`.
pub fn shared_length(a: &ConvexPolygon, b: &ConvexPolygon, tol: f64) -> f64 {
    #[cfg(test)]
    {
        CALLS.with(|c| c.set(c.get() + 1));
    }
    let mut total = 0.0;
    for_each_overlap(a, b, tol, |_, _, lo, hi| total += hi - lo);
    total
}

/// The pieces of boundary that `a` and `b` have in common (see [`shared_length`]),
/// as segments on `a`'s edges, in `a`'s edge order, each running in `a`'s
/// direction. Their lengths sum to [`shared_length`].
pub fn shared_segments(a: &ConvexPolygon, b: &ConvexPolygon, tol: f64) -> Vec<[Point; 2]> {
    let mut out = Vec::new();
    for_each_overlap(a, b, tol, |p1, u, lo, hi| {
        out.push([p1 + u * lo, p1 + u * hi]);
    });
    out
}

/// The length scale of a set of cells used for adjacency thresholds: the
/// diagonal of the bounding box of all their vertices, exactly as the checker
/// computes it (for a rectangle outline, the canvas diagonal). `None` when there
/// are no polygons.
pub fn extent_diagonal<'a>(polygons: impl IntoIterator<Item = &'a ConvexPolygon>) -> Option<f64> {
    let mut bounds: Option<(Point, Point)> = None;
    for polygon in polygons {
        let (lo, hi) = polygon.bbox();
        bounds = Some(match bounds {
            None => (lo, hi),
            Some((l, h)) => (l.min(lo), h.max(hi)),
        });
    }
    bounds.map(|(lo, hi)| (hi - lo).length())
}

#[cfg(test)]
thread_local! {
    /// [`shared_length`] calls on this thread, so that tests can bound how
    /// many polygon pairs a computation compares.
    static CALLS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// [`shared_length`] calls made on this thread so far (test builds).
#[cfg(test)]
pub(crate) fn shared_length_calls() -> usize {
    CALLS.with(std::cell::Cell::get)
}

/// Sets the count of [`shared_length_calls`] (test builds), for a check that
/// compares polygons without counting against the code it checks.
#[cfg(test)]
pub(crate) fn set_shared_length_calls(to: usize) {
    CALLS.with(|c| c.set(to));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: f64, y: f64, w: f64, h: f64) -> ConvexPolygon {
        ConvexPolygon::rectangle(x, y, w, h).expect("valid rectangle")
    }

    #[test]
    fn squares_sharing_a_side() {
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 0.0, 1.0, 1.0);
        assert!((shared_length(&a, &b, 1e-9) - 1.0).abs() < 1e-12);
        assert!((shared_length(&b, &a, 1e-9) - 1.0).abs() < 1e-12);
        let segs = shared_segments(&a, &b, 1e-9);
        assert_eq!(segs.len(), 1);
        assert!((segs[0][0] - segs[0][1]).length() - 1.0 < 1e-12);
        assert!(segs[0].iter().all(|p| (p.x - 1.0).abs() < 1e-12));
    }

    #[test]
    fn squares_touching_at_a_corner_share_nothing() {
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 1.0, 1.0, 1.0);
        assert_eq!(shared_length(&a, &b, 1e-9), 0.0);
        assert!(shared_segments(&a, &b, 1e-9).is_empty());
    }

    #[test]
    fn partial_overlap_of_collinear_edges() {
        // a's right side is x = 1, y in [0, 1]; b's left side is x = 1, y in
        // [0.5, 1.5]: they overlap on y in [0.5, 1], length 0.5.
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 0.5, 1.0, 1.0);
        assert!((shared_length(&a, &b, 1e-9) - 0.5).abs() < 1e-12);
        let segs = shared_segments(&a, &b, 1e-9);
        assert_eq!(segs.len(), 1);
        let ys = [
            segs[0][0].y.min(segs[0][1].y),
            segs[0][0].y.max(segs[0][1].y),
        ];
        assert!((ys[0] - 0.5).abs() < 1e-12 && (ys[1] - 1.0).abs() < 1e-12);
        // Within the perpendicular tolerance a small gap still counts as shared.
        let c = rect(1.0 + 1e-7, 0.0, 1.0, 1.0);
        assert!((shared_length(&a, &c, 1e-6) - 1.0).abs() < 1e-9);
        assert_eq!(shared_length(&a, &c, 1e-8), 0.0);
    }

    #[test]
    fn extent_diagonal_spans_every_vertex() {
        let cells = [rect(0.0, 0.0, 3.0, 1.0), rect(0.0, 1.0, 1.0, 3.0)];
        assert_eq!(extent_diagonal(&cells), Some(5.0));
        assert_eq!(extent_diagonal(&[]), None);
    }
}
