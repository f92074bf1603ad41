//! Start policies for one diagram: where the sites begin. One function each
//! (style principle 4); the optimiser does not care which was used.

use crate::geom::{ConvexPolygon, Point};
use crate::rng::Rng;

/// `n` positions uniformly at random inside `clip` (d3-voronoi-map's default
/// `initialPosition` policy), reproducible from `rng`.
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
}
