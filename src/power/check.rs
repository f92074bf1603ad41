//! [`PowerDiagram::sanity_check`] and [`DiagramError`]: the invariants every
//! diagram must meet. Reads diagrams only; may not build or repair them.

use super::clip::dominates;
use super::{PowerDiagram, Site};
use crate::geom::{cross, ConvexPolygon, Point};

/// Positions are compared with this tolerance relative to the clip's diameter:
/// generous against round-off, tiny against anything visible.
const POS_TOL_REL: f64 = 1e-8;
/// Relative tolerance on the total area.
const AREA_TOL_REL: f64 = 1e-9;

/// An invariant a [`PowerDiagram`] violates.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagramError {
    /// The diagram has a different number of cells than there are sites.
    #[error("{cells} cells for {sites} sites")]
    CellCount {
        /// Number of cells.
        cells: usize,
        /// Number of sites.
        sites: usize,
    },
    /// A cell's polygon turns the wrong way somewhere.
    #[error("cell {cell} is not convex")]
    NotConvex {
        /// The offending cell.
        cell: usize,
    },
    /// A cell's vertex lies outside the clip polygon.
    #[error("cell {cell} reaches outside the clip polygon")]
    OutsideClip {
        /// The offending cell.
        cell: usize,
    },
    /// The stored area or centroid does not match the polygon (or the empty state).
    #[error("cell {cell}: stored area or centroid disagrees with its polygon")]
    Measures {
        /// The offending cell.
        cell: usize,
    },
    /// The cells do not tile the clip polygon.
    #[error("cell areas sum to {sum}, the clip's area is {expected}")]
    AreaSum {
        /// Sum of the cell areas.
        sum: f64,
        /// Area of the clip polygon.
        expected: f64,
    },
    /// A neighbour list is unsorted, lists the cell itself, an unknown index or
    /// an empty cell, or belongs to an empty cell.
    #[error("cell {cell}: malformed neighbour list")]
    NeighborList {
        /// The offending cell.
        cell: usize,
    },
    /// `a` lists `b` but `b` does not list `a`.
    #[error("cell {a} lists {b} as neighbour but not the other way round")]
    Asymmetric {
        /// The cell listing the neighbour.
        a: usize,
        /// The listed cell.
        b: usize,
    },
    /// A shared edge does not lie on the boundaries of both cells.
    #[error("the edge cell {a} shares with {b} is not on both boundaries")]
    EdgeOffBoundary {
        /// The cell listing the edge.
        a: usize,
        /// The neighbour.
        b: usize,
    },
    /// `dominated_by` contradicts the weights or the cell.
    #[error("cell {cell}: dominated_by is inconsistent")]
    Dominance {
        /// The offending cell.
        cell: usize,
    },
}

impl PowerDiagram {
    /// Checks the invariants: one cell per site; every cell convex and inside
    /// `clip`; stored area and centroid match the polygon; areas sum to the
    /// clip's area (when at least one site has finite position and weight);
    /// neighbour lists sorted, symmetric, with each shared edge on both cells'
    /// boundaries; `dominated_by` consistent with the weights, and a site with
    /// `dominated_by: None` inside the clip lies in its own cell.
    ///
    /// Positions are checked to 1e-8 × the clip's diameter, the area sum to
    /// 1e-9 relative. In exactly degenerate inputs (a site whose cell shrinks to
    /// the single point it sits on) the last rule can report a false alarm.
    pub fn sanity_check(&self, sites: &[Site], clip: &ConvexPolygon) -> Result<(), DiagramError> {
        if self.cells.len() != sites.len() {
            return Err(DiagramError::CellCount {
                cells: self.cells.len(),
                sites: sites.len(),
            });
        }
        let tol = POS_TOL_REL * clip.diameter_bound();
        let mut sum = 0.0;
        for (i, cell) in self.cells.iter().enumerate() {
            let Some(poly) = &cell.polygon else {
                if cell.area != 0.0
                    || cell.centroid != sites[i].position && sites[i].position.is_finite()
                {
                    return Err(DiagramError::Measures { cell: i });
                }
                if !cell.neighbors.is_empty() {
                    return Err(DiagramError::NeighborList { cell: i });
                }
                continue;
            };
            let scale = poly.area().abs().max(f64::MIN_POSITIVE);
            if (cell.area - poly.area()).abs() > 1e-12 * scale
                || (cell.centroid - poly.centroid()).length() > tol
            {
                return Err(DiagramError::Measures { cell: i });
            }
            sum += cell.area;
            if !is_convex(poly.points(), tol) {
                return Err(DiagramError::NotConvex { cell: i });
            }
            if poly
                .points()
                .iter()
                .any(|v| signed_inside(clip.points(), *v) < -tol)
            {
                return Err(DiagramError::OutsideClip { cell: i });
            }
            let list = &cell.neighbors;
            if list.windows(2).any(|w| w[0].site >= w[1].site) {
                return Err(DiagramError::NeighborList { cell: i });
            }
            for nb in list {
                let j = nb.site;
                let Some(other) = self
                    .cells
                    .get(j)
                    .filter(|_| j != i)
                    .and_then(|c| c.polygon.as_ref())
                else {
                    return Err(DiagramError::NeighborList { cell: i });
                };
                if self.cells[j]
                    .neighbors
                    .binary_search_by_key(&i, |x| x.site)
                    .is_err()
                {
                    return Err(DiagramError::Asymmetric { a: i, b: j });
                }
                let [a, b] = nb.edge;
                let on_both = [a, b, 0.5 * (a + b)].iter().all(|x| {
                    boundary_distance(poly.points(), *x) <= tol
                        && boundary_distance(other.points(), *x) <= tol
                });
                if !on_both {
                    return Err(DiagramError::EdgeOffBoundary { a: i, b: j });
                }
            }
        }
        let any_site = sites
            .iter()
            .any(|s| s.position.is_finite() && s.weight.is_finite());
        let expected = clip.area();
        if any_site && (sum - expected).abs() > AREA_TOL_REL * expected {
            return Err(DiagramError::AreaSum { sum, expected });
        }
        if let Some(i) = (0..sites.len()).find(|&i| !self.dominance_ok(i, sites, clip, tol)) {
            return Err(DiagramError::Dominance { cell: i });
        }
        Ok(())
    }

    fn dominance_ok(&self, i: usize, sites: &[Site], clip: &ConvexPolygon, tol: f64) -> bool {
        let cell = &self.cells[i];
        let s = sites[i];
        match cell.dominated_by {
            Some(j) => {
                let Some(o) = sites.get(j).filter(|_| j != i) else {
                    return false;
                };
                let d2 = (o.position - s.position).length_squared();
                // Dominated: the site may not sit in the interior of its cell.
                dominates(j, o.weight, i, s.weight, d2)
                    && cell
                        .polygon
                        .as_ref()
                        .is_none_or(|p| signed_inside(p.points(), s.position) <= tol)
            }
            None => {
                let usable = s.position.is_finite() && s.weight.is_finite();
                if !usable || signed_inside(clip.points(), s.position) <= tol {
                    return true;
                }
                cell.polygon
                    .as_ref()
                    .is_some_and(|p| signed_inside(p.points(), s.position) >= -tol)
            }
        }
    }
}

/// Whether each vertex lies on the inner side of every edge, to within `tol`.
fn is_convex(points: &[Point], tol: f64) -> bool {
    let n = points.len();
    (0..n).all(|k| {
        let (a, b) = (points[k], points[(k + 1) % n]);
        let len = (b - a).length();
        points.iter().all(|v| cross(b - a, *v - a) >= -tol * len)
    })
}

/// Signed distance of `x` inside the convex polygon (negative outside): the
/// smallest signed distance to an edge's line.
fn signed_inside(points: &[Point], x: Point) -> f64 {
    let n = points.len();
    (0..n)
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let len = (b - a).length();
            if len > 0.0 {
                cross(b - a, x - a) / len
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `x` to the polygon's boundary.
fn boundary_distance(points: &[Point], x: Point) -> f64 {
    let n = points.len();
    (0..n)
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let e = b - a;
            let t = if e.length_squared() > 0.0 {
                ((x - a).dot(e) / e.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + e * t - x).length()
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::power::power_diagram;

    #[test]
    fn detects_tampering() {
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 2.0, 2.0).expect("clip");
        let sites = [
            Site {
                position: Point::new(0.5, 1.0),
                weight: 0.0,
            },
            Site {
                position: Point::new(1.5, 1.0),
                weight: 0.0,
            },
        ];
        let good = power_diagram(&sites, &clip);
        good.sanity_check(&sites, &clip).expect("sane");

        let mut d = good.clone();
        d.cells[1].neighbors.clear();
        assert_eq!(
            d.sanity_check(&sites, &clip),
            Err(DiagramError::Asymmetric { a: 0, b: 1 })
        );

        let mut d = good.clone();
        d.cells[0].neighbors[0].edge[0].x += 0.1;
        assert!(matches!(
            d.sanity_check(&sites, &clip),
            Err(DiagramError::EdgeOffBoundary { .. })
        ));

        let mut d = good.clone();
        d.cells[1].polygon = None;
        d.cells[1].area = 0.0;
        d.cells[1].centroid = sites[1].position;
        d.cells[1].neighbors.clear();
        d.cells[0].neighbors.clear();
        assert!(matches!(
            d.sanity_check(&sites, &clip),
            Err(DiagramError::AreaSum { .. })
        ));

        let mut d = good.clone();
        d.cells[0].dominated_by = Some(1);
        assert_eq!(
            d.sanity_check(&sites, &clip),
            Err(DiagramError::Dominance { cell: 0 })
        );

        assert!(matches!(
            good.sanity_check(&sites[..1], &clip),
            Err(DiagramError::CellCount { .. })
        ));
    }
}
