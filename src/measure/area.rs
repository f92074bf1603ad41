//! Area error of diagrams: for a parent, Σ over its children of
//! |A(child) / A(parent) − w(child) / Σw|, d3-voronoi-map's convergence ratio
//! and the checker's `area_error` (the paper's Table 2 "area error", §6).

use crate::layout::Layout;
use nptreemap_formats::Dataset;

/// Mean and largest area error over a set of diagrams.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AreaErrors {
    /// Mean over the diagrams measured; 0 when none was.
    pub mean: f64,
    /// The largest; 0 when none was measured.
    pub max: f64,
    /// How many diagrams were measured.
    pub diagrams: usize,
}

/// The area error of the diagram of `parent`: `None` when its cell has no area
/// or its children have no weight (nothing to compare with, as the checker
/// skips them). Children without a cell in `layout` add nothing.
pub fn diagram_error(dataset: &Dataset, layout: &Layout, parent: usize) -> Option<f64> {
    diagram_error_by(dataset, layout, parent, |i| dataset.node(i).value)
}

/// [`diagram_error`] against `weight(node)` instead of the nodes' values
/// (the weights a picture promises: `Computed::drawn_weights`).
pub fn diagram_error_by(
    dataset: &Dataset,
    layout: &Layout,
    parent: usize,
    weight: impl Fn(usize) -> f64,
) -> Option<f64> {
    let nodes = dataset.nodes();
    let cells = &layout.cells;
    let kids = &nodes.get(parent)?.children;
    let kids = || kids.iter().copied().filter(|&c| c < nodes.len());
    let total: f64 = kids().map(&weight).sum();
    let area = cells.get(parent)?.polygon.area();
    if !(total > 0.0 && area > 0.0) {
        return None;
    }
    let mut err = 0.0;
    for c in kids() {
        if let Some(cell) = cells.get(c) {
            // |A* − A| / A(parent) with A* = weight / total × A(parent).
            err += (weight(c) / total - cell.polygon.area() / area).abs();
        }
    }
    Some(err)
}

/// [`diagram_error`] over the diagrams of `parents`, in the order given.
pub fn diagram_errors(
    dataset: &Dataset,
    layout: &Layout,
    parents: impl IntoIterator<Item = usize>,
) -> AreaErrors {
    diagram_errors_by(dataset, layout, parents, |i| dataset.node(i).value)
}

/// [`diagram_errors`] against `weight(node)` ([`diagram_error_by`]).
pub fn diagram_errors_by(
    dataset: &Dataset,
    layout: &Layout,
    parents: impl IntoIterator<Item = usize>,
    weight: impl Fn(usize) -> f64,
) -> AreaErrors {
    let mut out = AreaErrors::default();
    let mut sum = 0.0;
    for err in parents
        .into_iter()
        .filter_map(|p| diagram_error_by(dataset, layout, p, &weight))
    {
        sum += err;
        out.max = out.max.max(err);
        out.diagrams += 1;
    }
    if out.diagrams > 0 {
        out.mean = sum / out.diagrams as f64;
    }
    out
}
