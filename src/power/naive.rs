//! The reference path, [`power_diagram_naive`]: every cell clipped by every other
//! site, O(n²). Used by tests to check the fast path; may not be used for real
//! layouts and may not diverge from the fast path's conventions.

use super::assemble::{symmetrize, CellBuilder, Prepared};
use super::clip::LabeledPolygon;
use super::{Cell, PowerDiagram, Site};
use crate::geom::ConvexPolygon;

/// The same diagram as [`power_diagram`](super::power_diagram), by clipping each
/// cell with all other sites in index order. Quadratic: a reference for tests,
/// not for production use. Same conventions for ignored (non-finite) sites,
/// coincident sites and `dominated_by`.
pub(crate) fn power_diagram_naive(sites: &[Site], clip: &ConvexPolygon) -> PowerDiagram {
    let input = Prepared::new(sites, clip);
    let mut builder = CellBuilder::new(LabeledPolygon::default());
    let mut cells: Vec<Cell> = (0..input.len())
        .map(|i| {
            if !input.active[i] {
                return super::assemble::empty_cell(input.pos[i], input.shadow[i]);
            }
            builder.start(&input, i);
            for j in (0..input.len()).filter(|&j| j != i && input.active[j]) {
                builder.visit(j, input.pos[j], input.w[j], false);
            }
            builder.finish(input.clip, input.edge_tol)
        })
        .collect();
    symmetrize(&mut cells, false);
    PowerDiagram { cells }
}
