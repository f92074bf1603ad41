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

use crate::layout::{Computed, Layout};
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
    quality_by(dataset, layout, |i| dataset.node(i).value)
}

/// [`Quality`] of a finished computation against what its picture promises
/// (issue 34): the nodes' values, except that with `zero_weights: floor` an
/// item of weight 0 counts at the weight it is drawn at
/// ([`Computed::drawn_weights`], which the layout JSON states per node as
/// `drawn_weight`). Hidden items have no cell and are not in the dataset.
pub fn drawn_quality(computed: &Computed) -> Quality {
    let ds = &computed.dataset;
    match computed.drawn_weights() {
        Some(drawn) => quality_by(ds, &computed.layout, |i| drawn[i]),
        None => quality(ds, &computed.layout),
    }
}

fn quality_by(dataset: &Dataset, layout: &Layout, weight: impl Fn(usize) -> f64) -> Quality {
    let parents = (0..dataset.len()).filter(|&i| !dataset.node(i).children.is_empty());
    let errors = area::diagram_errors_by(dataset, layout, parents, weight);
    Quality {
        area_error_diagram_mean: errors.mean,
        area_error_diagram_max: errors.max,
        aspect_ratio_mean: shape::leaf_aspect_mean(dataset, layout),
    }
}
