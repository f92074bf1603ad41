//! Pure 2-D geometry: points and convex polygons with their measures. Knows nothing
//! of sites, weights or hierarchies, and does no I/O.

/// Which cells of one level share an edge, and hop distances on that graph.
pub mod adjacency;
/// Convex polygons: construction, area, centroid, containment, clipping, sampling.
pub mod polygon;
/// Bounded steps, segment exits and boundary distances inside a convex polygon.
pub mod reach;
/// The boundary two cells have in common, and the tolerance that decides it.
pub mod shared_edge;

pub use adjacency::{level_adjacency, LevelAdjacency};
pub use glam::DVec2 as Point;
pub use polygon::{ConvexPolygon, GeomError};
pub use reach::step_towards;

/// z-component of the cross product of `a` and `b` (twice the signed triangle area).
#[inline]
pub fn cross(a: Point, b: Point) -> f64 {
    a.x * b.y - a.y * b.x
}
