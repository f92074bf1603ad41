//! Measurement of finished layouts: area error, cell shape, the paper's Table 2
//! figures and the stability of a warm start. Every figure is computed from the
//! polygons and the dataset's weights the same way the independent layout
//! checker does, so the tool's own numbers and the checker's agree. Pure; may
//! not lay anything out (the caller brings finished layouts).

/// Area error: how far each diagram's cell areas are from their targets.
pub mod area;
/// Cell shape: bounding-box aspect ratios.
pub mod shape;
/// Stability between a previous layout and a new one.
pub mod stability;
/// The paper's Table 2 row for one layout.
pub mod table2;

use crate::layout::Layout;
use nptreemap_formats::Dataset;

pub use stability::{stability, Stability};
pub use table2::{table2, EvalMetrics};

/// Area and shape figures of a whole layout, as the layout JSON's `metrics`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quality {
    /// Mean over parents with children of Σ|A/A(parent) − w/Σw| (d3's convergence ratio).
    pub area_error_diagram_mean: f64,
    /// Largest per-parent value of the same.
    pub area_error_diagram_max: f64,
    /// Mean over leaves of the bounding box's long side / short side.
    pub aspect_ratio_mean: f64,
}

/// Computes [`Quality`] for `layout` (cells indexed like `dataset`'s nodes).
pub fn quality(dataset: &Dataset, layout: &Layout) -> Quality {
    let parents = (0..dataset.len()).filter(|&i| !dataset.node(i).children.is_empty());
    let errors = area::diagram_errors(dataset, layout, parents);
    Quality {
        area_error_diagram_mean: errors.mean,
        area_error_diagram_max: errors.max,
        aspect_ratio_mean: shape::leaf_aspect_mean(dataset, layout),
    }
}
