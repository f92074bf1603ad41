//! Cell shape as bounding-box aspect ratios: the checker's `aspect_ratio_mean`
//! (long side / short side of each leaf, 1 for a square) and the prototype's
//! figure (width / height of every non-root cell, method-reference §7), which
//! the paper's Table 2 reports.

use crate::layout::Layout;
use nptreemap_formats::Dataset;

/// Mean over leaves of the bounding box's long side / short side; leaves whose
/// box has no width or height are skipped; 0 when none is left.
pub fn leaf_aspect_mean(dataset: &Dataset, layout: &Layout) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for i in dataset.leaves() {
        let Some(cell) = layout.cells.get(i) else {
            continue;
        };
        let (lo, hi) = cell.polygon.bbox();
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        if w.min(h) > 0.0 {
            sum += w.max(h) / w.min(h);
            count += 1;
        }
    }
    mean(sum, count)
}

/// The prototype's aspect figure (`avg_aspect_ratio_proto`): mean bounding-box
/// width / height over every non-root cell of every level, virtual nodes
/// included; cells with zero height are skipped; 0 when none is left.
pub fn proto_aspect_mean(dataset: &Dataset, layout: &Layout) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for (i, node) in dataset.nodes().iter().enumerate() {
        let Some(cell) = layout.cells.get(i) else {
            continue;
        };
        let (lo, hi) = cell.polygon.bbox();
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        if node.parent.is_some() && h > 0.0 {
            sum += w / h;
            count += 1;
        }
    }
    mean(sum, count)
}

/// Mean of the values, 0 when there are none.
fn mean(sum: f64, count: usize) -> f64 {
    if count > 0 {
        sum / count as f64
    } else {
        0.0
    }
}
