//! Start policies for one diagram: where the sites begin. One function each
//! (style principle 4); the optimiser does not care which was used.

use super::rng::Rng;
use crate::geom::{ConvexPolygon, Point};

/// `n` positions uniformly at random inside `clip` (d3-voronoi-map's default
/// `initialPosition` policy), reproducible from `rng`.
pub fn random_positions(clip: &ConvexPolygon, n: usize, rng: &mut Rng) -> Vec<Point> {
    (0..n)
        .map(|_| clip.sample(rng.next_f64(), rng.next_f64()))
        .collect()
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
