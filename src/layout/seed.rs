//! Start policies for one diagram: where the sites begin. One function each
//! (style principle 4); the optimiser does not care which was used. The warm
//! start's pieces ([`CellMap`](crate::layout::seed::CellMap),
//! [`clamp_inside`](crate::layout::seed::clamp_inside),
//! [`beside`](crate::layout::seed::beside)) are here too;
//! [`crate::layout::warm`] puts them together.

use crate::geom::{ConvexPolygon, Point};
use crate::rng::Rng;

/// `n` positions uniformly at random inside `clip` (d3-voronoi-map's default
/// `initialPosition` policy), reproducible from `rng`.
#[cfg(any(test, feature = "internals"))]
pub fn random_positions(clip: &ConvexPolygon, n: usize, rng: &mut Rng) -> Vec<Point> {
    (0..n)
        .map(|_| clip.sample(rng.next_f64(), rng.next_f64()))
        .collect()
}

/// `n` well-spread positions inside `clip`: the Halton sequence (bases 2 and 3)
/// over the bounding box, shifted by a random offset (Cranley–Patterson
/// rotation) so seeds differ, keeping the points that fall inside. Evenly spread
/// starts need fewer Lloyd steps to reach round cells than uniform random ones.
pub fn halton_positions(clip: &ConvexPolygon, n: usize, rng: &mut Rng) -> Vec<Point> {
    let (lo, hi) = clip.bbox();
    let size = hi - lo;
    let (du, dv) = (rng.next_f64(), rng.next_f64());
    let mut out = Vec::with_capacity(n);
    // A convex polygon fills at least half of... not necessarily its box (a thin
    // diagonal sliver), so cap the attempts and fill up with area sampling.
    let max_attempts = 64 * n + 64;
    let mut k = 1u64;
    while out.len() < n && (k as usize) <= max_attempts {
        let u = (radical_inverse(k, 2) + du).fract();
        let v = (radical_inverse(k, 3) + dv).fract();
        let p = lo + Point::new(u * size.x, v * size.y);
        if clip.contains(p) {
            out.push(p);
        }
        k += 1;
    }
    while out.len() < n {
        out.push(clip.sample(rng.next_f64(), rng.next_f64()));
    }
    out
}

/// The map that carries a site from a parent's previous cell into its new
/// one: the affine map between the two cells' bounding boxes (stable treemaps'
/// rescaling of surviving nodes into their new parent, issue 6), and the
/// matching rescale of power weights, which are squared lengths, by the area
/// ratio. Two boxes equal within a tolerance give the identity, bit for bit,
/// so an unchanged diagram starts exactly where it ended, also when the old
/// cell was read back from layout JSON with its coordinates rounded.
#[derive(Clone, Copy, Debug)]
pub struct CellMap {
    from: (Point, Point),
    to: (Point, Point),
    weight_scale: f64,
    identity: bool,
}

impl CellMap {
    /// The map from cell `old` to cell `new`; the identity when their boxes'
    /// corners are within `tol` of each other.
    pub fn between(old: &ConvexPolygon, new: &ConvexPolygon, tol: f64) -> Self {
        let (from, to) = (old.bbox(), new.bbox());
        let identity = from.0.distance(to.0) <= tol && from.1.distance(to.1) <= tol;
        let ratio = new.area() / old.area();
        Self {
            from,
            to,
            weight_scale: if identity { 1.0 } else { ratio },
            identity,
        }
    }

    /// Where `p` (in the old cell) lands in the new cell's box. A degenerate
    /// old box (a hostile previous layout) sends every point to the new box's
    /// centre; the caller clamps into the cell anyway.
    pub fn point(&self, p: Point) -> Point {
        if self.identity {
            return p;
        }
        let (lo, hi) = self.from;
        let (nlo, nhi) = self.to;
        let u = (p - lo) / (hi - lo);
        if u.is_finite() {
            nlo + u * (nhi - nlo)
        } else {
            (nlo + nhi) * 0.5
        }
    }

    /// A power weight rescaled by the area ratio; `None` when that is not a
    /// finite number.
    pub fn weight(&self, w: f64) -> Option<f64> {
        let scaled = w * self.weight_scale;
        scaled.is_finite().then_some(scaled)
    }
}

/// `p` if it lies inside `clip`, else the point on the segment from the
/// centroid to `p` just inside the boundary (at 99% of the way to it, so the
/// site is not on an edge).
pub fn clamp_inside(clip: &ConvexPolygon, p: Point) -> Point {
    if clip.contains(p) {
        return p;
    }
    let c = clip.centroid();
    if !p.is_finite() {
        return c;
    }
    // Bisection on t in p(t) = c + t (p - c): t = 0 is inside, t = 1 outside.
    let (mut inside, mut outside) = (0.0, 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (inside + outside);
        if clip.contains(c + (p - c) * mid) {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    c + (p - c) * (0.99 * inside)
}

/// A point at about `radius` from `at` in a direction drawn from `rng`,
/// inside `clip`: where a new node starts beside a sibling (issue 6: "new
/// nodes start beside their most similar sibling"). The radius is halved
/// until the point is inside; if it never is, the point halfway to the
/// centroid is used.
pub fn beside(clip: &ConvexPolygon, at: Point, radius: f64, rng: &mut Rng) -> Point {
    let angle = std::f64::consts::TAU * rng.next_f64();
    let dir = Point::new(angle.cos(), angle.sin());
    let mut r = radius;
    for _ in 0..20 {
        let p = at + dir * r;
        if p.is_finite() && clip.contains(p) {
            return p;
        }
        r *= 0.5;
    }
    clamp_inside(clip, at + (clip.centroid() - at) * 0.5)
}

/// The van der Corput radical inverse of `k` in `base`.
fn radical_inverse(mut k: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut r = 0.0;
    while k > 0 {
        r += f * (k % base) as f64;
        k /= base;
        f *= inv;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_positions_are_inside_and_reproducible() {
        let clip = ConvexPolygon::regular(Point::new(50.0, 50.0), 40.0, 5).unwrap();
        let a = random_positions(&clip, 200, &mut Rng::new(3));
        let b = random_positions(&clip, 200, &mut Rng::new(3));
        assert_eq!(a, b);
        assert!(a.iter().all(|p| clip.contains(*p)));
    }

    #[test]
    fn cell_map_is_the_identity_on_the_same_cell_and_scales_weights() {
        let old = ConvexPolygon::rectangle(0.0, 0.0, 10.0, 10.0).unwrap();
        let same = CellMap::between(&old, &old.clone(), 0.0);
        let p = Point::new(1.0 / 3.0, 7.1);
        assert_eq!(same.point(p), p);
        assert_eq!(same.weight(2.5), Some(2.5));
        let new = ConvexPolygon::rectangle(10.0, 0.0, 20.0, 10.0).unwrap();
        let map = CellMap::between(&old, &new, 1e-9);
        assert_eq!(map.point(Point::new(5.0, 5.0)), Point::new(20.0, 5.0));
        assert_eq!(map.weight(4.0), Some(8.0));
        assert_eq!(map.weight(f64::MAX), None);
        let near = ConvexPolygon::rectangle(0.0, 0.0, 10.0 + 1e-7, 10.0).unwrap();
        assert_eq!(CellMap::between(&old, &near, 1e-6).point(p), p);
    }

    #[test]
    fn clamp_and_beside_stay_inside() {
        let clip = ConvexPolygon::regular(Point::new(0.0, 0.0), 10.0, 7).unwrap();
        let far = clamp_inside(&clip, Point::new(100.0, 3.0));
        assert!(clip.contains(far) && far.x > 8.0, "{far:?}");
        assert_eq!(
            clamp_inside(&clip, Point::new(1.0, 1.0)),
            Point::new(1.0, 1.0)
        );
        let mut rng = Rng::new(4);
        for _ in 0..50 {
            let p = beside(&clip, Point::new(9.0, 0.0), 5.0, &mut rng);
            assert!(clip.contains(p));
        }
    }
}
