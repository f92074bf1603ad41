//! `ConvexPolygon`, the only polygon type of the crate: positive orientation (positive
//! shoelace area), at least three vertices, no repeated or collinear vertices.

use super::{cross, Point};

/// Why a point list is not a usable convex polygon.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeomError {
    /// Fewer than three distinct, non-collinear vertices.
    #[error("a polygon needs at least three distinct, non-collinear vertices")]
    TooFewPoints,
    /// A coordinate is NaN or infinite.
    #[error("a polygon vertex has a non-finite coordinate")]
    NotFinite,
    /// The vertices do not turn the same way.
    #[error("the polygon is not convex")]
    NotConvex,
}

/// A convex polygon with positive orientation.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct ConvexPolygon {
    points: Vec<Point>,
}

/// Relative tolerance for "the same point" and "collinear": far below any
/// visible size, far above f64 round-off on canvas-sized coordinates.
const REL_EPS: f64 = 1e-12;

impl ConvexPolygon {
    /// Builds a polygon from vertices in either orientation. Repeated and
    /// collinear vertices are dropped; the rest must turn one way.
    pub fn new(points: Vec<Point>) -> Result<Self, GeomError> {
        if points.iter().any(|p| !p.is_finite()) {
            return Err(GeomError::NotFinite);
        }
        let mut points = clean(points);
        if points.len() < 3 {
            return Err(GeomError::TooFewPoints);
        }
        if signed_area(&points) < 0.0 {
            points.reverse();
        }
        let n = points.len();
        let scale = scale_of(&points);
        for i in 0..n {
            let a = points[i];
            let b = points[(i + 1) % n];
            let c = points[(i + 2) % n];
            if cross(b - a, c - b) < -REL_EPS * scale * scale {
                return Err(GeomError::NotConvex);
            }
        }
        Ok(Self { points })
    }

    /// Builds a polygon from vertices known to be convex and positively oriented
    /// (the output of clipping a convex polygon); only cleans them. `None` when
    /// fewer than three vertices remain.
    pub fn from_convex(points: Vec<Point>) -> Option<Self> {
        let points = clean(points);
        (points.len() >= 3 && signed_area(&points) > 0.0).then_some(Self { points })
    }

    /// Axis-aligned rectangle with corner `(x, y)`, width `w` and height `h`.
    pub fn rectangle(x: f64, y: f64, w: f64, h: f64) -> Result<Self, GeomError> {
        Self::new(vec![
            Point::new(x, y),
            Point::new(x + w, y),
            Point::new(x + w, y + h),
            Point::new(x, y + h),
        ])
    }

    /// Regular polygon with `sides` vertices on a circle of `radius` around
    /// `center`, the first vertex straight above the centre (y grows downwards on
    /// screen, so "above" is −y).
    pub fn regular(center: Point, radius: f64, sides: usize) -> Result<Self, GeomError> {
        let sides = sides.max(3);
        let pts = (0..sides)
            .map(|k| {
                let t =
                    -std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU * k as f64 / sides as f64;
                center + radius * Point::new(t.cos(), t.sin())
            })
            .collect();
        Self::new(pts)
    }

    /// The vertices, positively oriented.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false: a polygon has at least three vertices.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Area (positive).
    pub fn area(&self) -> f64 {
        signed_area(&self.points)
    }

    /// Area centroid.
    pub fn centroid(&self) -> Point {
        // Relative to the first vertex, so large offsets do not cost precision.
        let o = self.points[0];
        let mut acc = Point::ZERO;
        let mut twice_area = 0.0;
        for w in self.points[1..].windows(2) {
            let (a, b) = (w[0] - o, w[1] - o);
            let c = cross(a, b);
            twice_area += c;
            acc += (a + b) * c;
        }
        if twice_area <= 0.0 {
            return self.vertex_mean();
        }
        o + acc / (3.0 * twice_area)
    }

    /// Mean of the vertices (a fallback centre for degenerate slivers).
    pub fn vertex_mean(&self) -> Point {
        self.points.iter().copied().sum::<Point>() / self.points.len() as f64
    }

    /// Lower and upper corners of the bounding box.
    pub fn bbox(&self) -> (Point, Point) {
        let mut lo = self.points[0];
        let mut hi = self.points[0];
        for p in &self.points[1..] {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }

    /// Length of the bounding-box diagonal: a size scale for tolerances.
    pub fn diameter_bound(&self) -> f64 {
        let (lo, hi) = self.bbox();
        (hi - lo).length()
    }

    /// True when `p` is inside or on the boundary (within round-off).
    pub fn contains(&self, p: Point) -> bool {
        let n = self.points.len();
        let tol = REL_EPS * self.diameter_bound();
        (0..n).all(|i| {
            let a = self.points[i];
            let b = self.points[(i + 1) % n];
            let e = b - a;
            cross(e, p - a) >= -tol * e.length()
        })
    }

    /// The part of the polygon where `normal · x <= offset`, or `None` when that
    /// part has no area.
    pub fn clip_halfplane(&self, normal: Point, offset: f64) -> Option<Self> {
        let n = self.points.len();
        let side: Vec<f64> = self
            .points
            .iter()
            .map(|p| normal.dot(*p) - offset)
            .collect();
        if side.iter().all(|s| *s <= 0.0) {
            return Some(self.clone());
        }
        if side.iter().all(|s| *s >= 0.0) {
            return None;
        }
        let mut out = Vec::with_capacity(n + 1);
        for i in 0..n {
            let j = (i + 1) % n;
            let (p, q) = (self.points[i], self.points[j]);
            let (sp, sq) = (side[i], side[j]);
            if sp <= 0.0 {
                out.push(p);
            }
            if (sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0) {
                out.push(p + (q - p) * (sp / (sp - sq)));
            }
        }
        Self::from_convex(out)
    }

    /// A point inside the polygon from two numbers in `[0, 1)`; uniform over the
    /// area when `u` and `v` are. Used for seeded initial positions.
    pub fn sample(&self, u: f64, v: f64) -> Point {
        let o = self.points[0];
        let total = self.area();
        let mut target = u.clamp(0.0, 1.0) * total;
        let last = self.points.len() - 2;
        for (k, w) in self.points[1..].windows(2).enumerate() {
            let tri = 0.5 * cross(w[0] - o, w[1] - o);
            if target <= tri || k + 1 == last {
                let t = if tri > 0.0 {
                    (target / tri).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                // Square-root warp: uniform in the triangle (o, w0, w1).
                let s = t.sqrt();
                let v = v.clamp(0.0, 1.0);
                return o * (1.0 - s) + w[0] * (s * (1.0 - v)) + w[1] * (s * v);
            }
            target -= tri;
        }
        self.centroid()
    }
}

/// Shoelace signed area (positive for our orientation).
pub(crate) fn signed_area(points: &[Point]) -> f64 {
    let n = points.len();
    if n < 3 {
        return 0.0;
    }
    let o = points[0];
    let mut s = 0.0;
    for i in 1..n - 1 {
        s += cross(points[i] - o, points[i + 1] - o);
    }
    0.5 * s
}

fn scale_of(points: &[Point]) -> f64 {
    let mut lo = points[0];
    let mut hi = points[0];
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).length().max(f64::MIN_POSITIVE)
}

/// Drops repeated vertices and vertices on the line through their neighbours.
fn clean(mut points: Vec<Point>) -> Vec<Point> {
    if points.len() < 2 {
        return points;
    }
    let scale = scale_of(&points);
    let same = REL_EPS * scale;
    points.dedup_by(|a, b| a.distance(*b) <= same);
    while points.len() > 1 && points[0].distance(points[points.len() - 1]) <= same {
        points.pop();
    }
    // Collinear removal: repeat until stable, since removing one vertex can make
    // its neighbour collinear in turn only in degenerate inputs.
    let mut changed = true;
    while changed && points.len() >= 3 {
        changed = false;
        let n = points.len();
        let mut keep = Vec::with_capacity(n);
        for i in 0..n {
            let a = points[(i + n - 1) % n];
            let b = points[i];
            let c = points[(i + 1) % n];
            let area2 = cross(b - a, c - a).abs();
            if area2 <= REL_EPS * scale * (c - a).length() {
                changed = true;
            } else {
                keep.push(b);
            }
        }
        if changed {
            points = keep;
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> ConvexPolygon {
        ConvexPolygon::rectangle(0.0, 0.0, 2.0, 2.0).unwrap()
    }

    #[test]
    fn square_measures() {
        let s = square();
        assert_eq!(s.area(), 4.0);
        assert!((s.centroid() - Point::new(1.0, 1.0)).length() < 1e-12);
        assert!(s.contains(Point::new(1.0, 1.0)));
        assert!(s.contains(Point::new(0.0, 1.0)));
        assert!(!s.contains(Point::new(-0.1, 1.0)));
    }

    #[test]
    fn orientation_is_normalized_and_collinear_points_dropped() {
        let p = ConvexPolygon::new(vec![
            Point::new(0.0, 0.0),
            Point::new(0.0, 1.0),
            Point::new(0.0, 2.0),
            Point::new(2.0, 2.0),
            Point::new(2.0, 2.0),
            Point::new(2.0, 0.0),
        ])
        .unwrap();
        assert_eq!(p.len(), 4);
        assert!(p.area() > 0.0);
    }

    #[test]
    fn rejects_bad_input() {
        assert_eq!(
            ConvexPolygon::new(vec![Point::ZERO, Point::X, Point::X * 2.0]),
            Err(GeomError::TooFewPoints)
        );
        assert_eq!(
            ConvexPolygon::new(vec![Point::ZERO, Point::X, Point::new(f64::NAN, 1.0)]),
            Err(GeomError::NotFinite)
        );
        let dart = vec![
            Point::new(0.0, 0.0),
            Point::new(2.0, 1.0),
            Point::new(4.0, 0.0),
            Point::new(2.0, 4.0),
        ];
        assert_eq!(ConvexPolygon::new(dart), Err(GeomError::NotConvex));
    }

    #[test]
    fn clipping_halves_the_square() {
        let s = square();
        let left = s.clip_halfplane(Point::X, 1.0).unwrap();
        assert!((left.area() - 2.0).abs() < 1e-12);
        assert!(s.clip_halfplane(Point::X, -1.0).is_none());
        assert_eq!(s.clip_halfplane(Point::X, 5.0).unwrap(), s);
    }

    #[test]
    fn regular_polygon_area_approaches_circle() {
        let c = ConvexPolygon::regular(Point::new(5.0, 5.0), 1.0, 256).unwrap();
        assert!((c.area() - std::f64::consts::PI).abs() < 1e-3);
        assert!((c.centroid() - Point::new(5.0, 5.0)).length() < 1e-9);
    }

    #[test]
    fn samples_fall_inside() {
        let c = ConvexPolygon::regular(Point::ZERO, 3.0, 7).unwrap();
        for i in 0..50 {
            for j in 0..7 {
                let p = c.sample(i as f64 / 50.0, j as f64 / 7.0);
                assert!(c.contains(p), "{p:?}");
            }
        }
    }
}
