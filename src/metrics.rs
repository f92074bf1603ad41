//! Quality figures of a finished layout, computed from the polygons and the
//! dataset's weights the same way `shared/tools/check-layout` does, so the
//! tool's own numbers and the independent checker's agree.

use crate::layout::Layout;
use nptreemap_formats::Dataset;

/// Area and shape figures of a layout.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quality {
    /// Mean over parents with children of Σ|A/A(parent) − w/Σw| (d3's convergence ratio).
    pub area_error_diagram_mean: f64,
    /// Largest per-parent value of the same.
    pub area_error_diagram_max: f64,
    /// Mean over leaves of the bounding box's long side / short side.
    pub aspect_ratio_mean: f64,
}

/// Computes [`Quality`] for `layout`.
pub fn quality(dataset: &Dataset, layout: &Layout) -> Quality {
    let mut sum = 0.0;
    let mut max: f64 = 0.0;
    let mut diagrams = 0usize;
    for (i, node) in dataset.nodes().iter().enumerate() {
        if node.children.is_empty() {
            continue;
        }
        let total: f64 = node.children.iter().map(|c| dataset.node(*c).value).sum();
        let area = layout.cells[i].polygon.area();
        if total <= 0.0 || area <= 0.0 {
            continue;
        }
        let err: f64 = node
            .children
            .iter()
            .map(|c| {
                let share = layout.cells[*c].polygon.area() / area;
                (share - dataset.node(*c).value / total).abs()
            })
            .sum();
        sum += err;
        max = max.max(err);
        diagrams += 1;
    }
    let mut aspect_sum = 0.0;
    let mut leaves = 0usize;
    for i in dataset.leaves() {
        let (lo, hi) = layout.cells[i].polygon.bbox();
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        if w.min(h) > 0.0 {
            aspect_sum += w.max(h) / w.min(h);
            leaves += 1;
        }
    }
    Quality {
        area_error_diagram_mean: if diagrams > 0 {
            sum / diagrams as f64
        } else {
            0.0
        },
        area_error_diagram_max: max,
        aspect_ratio_mean: if leaves > 0 {
            aspect_sum / leaves as f64
        } else {
            0.0
        },
    }
}
