//! Where a point can go inside a convex polygon: a bounded step towards a
//! target, where a segment leaves the polygon, how far a point is from the
//! boundary. The neighbourhood optimiser's attraction moves (paper §5.6–5.7)
//! are made of these; they know nothing of sites or cells.

use super::{cross, ConvexPolygon, Point};

/// The point `step` along the way from `from` to `to` (or `to` itself when it
/// is nearer); `None` when the two coincide.
pub fn step_towards(from: Point, to: Point, step: f64) -> Option<Point> {
    let d = to - from;
    let len = d.length();
    (len > 0.0).then(|| from + d * (step.min(len) / len))
}

impl ConvexPolygon {
    /// Where the segment from `from` (inside) to `to` leaves the polygon: the
    /// distance to the exit point and the edge crossed. When `to` is inside
    /// too, the distance to `to` and no edge.
    pub fn exit_through(&self, from: Point, to: Point) -> (f64, Option<(Point, Point)>) {
        let pts = self.points();
        let dir = to - from;
        let mut best: Option<(f64, (Point, Point))> = None;
        for k in 0..pts.len() {
            let a = pts[k];
            let b = pts[(k + 1) % pts.len()];
            let e = b - a;
            let denom = cross(dir, e);
            if denom == 0.0 {
                continue;
            }
            let t = cross(a - from, e) / denom;
            let u = cross(a - from, dir) / denom;
            if (0.0..=1.0).contains(&t)
                && (0.0..=1.0).contains(&u)
                && best.is_none_or(|(bt, _)| t < bt)
            {
                best = Some((t, (a, b)));
            }
        }
        match best {
            Some((t, edge)) => (dir.length() * t, Some(edge)),
            None => (dir.length(), None),
        }
    }

    /// Distance from a point inside the polygon to its boundary (negative
    /// outside, by how far it is past the nearest edge line).
    pub fn boundary_distance(&self, p: Point) -> f64 {
        let pts = self.points();
        (0..pts.len())
            .map(|k| {
                let a = pts[k];
                let e = pts[(k + 1) % pts.len()] - a;
                cross(e, p - a) / e.length().max(f64::MIN_POSITIVE)
            })
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> ConvexPolygon {
        ConvexPolygon::rectangle(0.0, 0.0, 10.0, 10.0).expect("square")
    }

    #[test]
    fn exit_through_finds_the_crossed_edge() {
        let (d, edge) = square().exit_through(Point::new(5.0, 5.0), Point::new(15.0, 5.0));
        assert!((d - 5.0).abs() < 1e-12);
        let (a, b) = edge.expect("crosses the right edge");
        assert_eq!((a.x, b.x), (10.0, 10.0));
        // A target inside: its distance and no edge.
        let (d, edge) = square().exit_through(Point::new(5.0, 5.0), Point::new(7.0, 5.0));
        assert!((d - 2.0).abs() < 1e-12 && edge.is_none());
    }

    #[test]
    fn boundary_distance_inside_and_outside_a_square() {
        assert!((square().boundary_distance(Point::new(2.0, 5.0)) - 2.0).abs() < 1e-12);
        assert!((square().boundary_distance(Point::new(-1.0, 5.0)) + 1.0).abs() < 1e-12);
    }

    #[test]
    fn step_towards_stops_at_the_target() {
        let a = Point::new(0.0, 0.0);
        let b = Point::new(3.0, 4.0);
        // One unit along (3, 4) is (0.6, 0.8), up to round-off.
        let one = step_towards(a, b, 1.0).expect("a step");
        assert!((one - Point::new(0.6, 0.8)).length() < 1e-12, "{one}");
        assert_eq!(step_towards(a, b, 10.0), Some(b));
        assert_eq!(step_towards(a, a, 1.0), None);
    }
}
