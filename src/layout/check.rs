//! `sanity_check`: the invariants every finished layout must satisfy, as code
//! (spade's `sanity_check()` idea). Layout tests end with it.

use super::Layout;
use nptreemap_formats::Dataset;

/// Relative tolerance for containment and partition: coordinates come from
/// clipping in f64, so errors are round-off, many orders below this.
const REL_TOL: f64 = 1e-7;

/// A broken layout invariant, naming the node.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SanityError {
    /// The layout has a different number of cells than the dataset has nodes.
    #[error("layout has {cells} cells for {nodes} nodes")]
    CellCount {
        /// Cells in the layout.
        cells: usize,
        /// Nodes in the dataset.
        nodes: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("node {id:?}: non-finite coordinate")]
    NotFinite {
        /// The node's id.
        id: String,
    },
    /// A vertex of a child's cell lies outside its parent's cell.
    #[error("node {id:?}: cell leaves its parent's cell")]
    OutsideParent {
        /// The node's id.
        id: String,
    },
    /// The children's areas do not add up to the parent's.
    #[error("node {id:?}: children cover {ratio} of its area")]
    Partition {
        /// The parent's id.
        id: String,
        /// Σ child area / parent area.
        ratio: f64,
    },
}

/// Checks: one cell per node, finite coordinates, every child inside its parent,
/// children's areas summing to the parent's.
pub fn sanity_check(layout: &Layout, dataset: &Dataset) -> Result<(), SanityError> {
    if layout.cells.len() != dataset.len() {
        return Err(SanityError::CellCount {
            cells: layout.cells.len(),
            nodes: dataset.len(),
        });
    }
    let diag = (layout.canvas.width.powi(2) + layout.canvas.height.powi(2)).sqrt();
    for (i, node) in dataset.nodes().iter().enumerate() {
        let cell = &layout.cells[i];
        let finite = cell.site.is_finite()
            && cell.power_weight.is_finite()
            && cell.polygon.points().iter().all(|p| p.is_finite());
        if !finite {
            return Err(SanityError::NotFinite {
                id: node.id.clone(),
            });
        }
        if let Some(p) = node.parent {
            let parent = &layout.cells[p].polygon;
            let pts = parent.points();
            let m = pts.len();
            let outside = cell.polygon.points().iter().any(|v| {
                (0..m).any(|k| {
                    let a = pts[k];
                    let e = pts[(k + 1) % m] - a;
                    crate::geom::cross(e, *v - a) < -REL_TOL * diag * e.length()
                })
            });
            if outside {
                return Err(SanityError::OutsideParent {
                    id: node.id.clone(),
                });
            }
        }
        if !node.children.is_empty() {
            let total: f64 = node
                .children
                .iter()
                .map(|c| layout.cells[*c].polygon.area())
                .sum();
            let ratio = total / cell.polygon.area();
            if (ratio - 1.0).abs() > 1e-6 {
                return Err(SanityError::Partition {
                    id: node.id.clone(),
                    ratio,
                });
            }
        }
    }
    Ok(())
}
