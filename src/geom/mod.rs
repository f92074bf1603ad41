//! Pure 2-D geometry: points and convex polygons with their measures. Knows nothing
//! of sites, weights or hierarchies, and does no I/O.

/// Convex polygons: construction, area, centroid, containment, clipping, sampling.
pub mod polygon;

pub use glam::DVec2 as Point;
pub use polygon::{ConvexPolygon, GeomError};

/// z-component of the cross product of `a` and `b` (twice the signed triangle area).
#[inline]
pub fn cross(a: Point, b: Point) -> f64 {
    a.x * b.y - a.y * b.x
}
