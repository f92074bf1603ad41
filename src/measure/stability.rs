//! Stability figures between a previous layout and a new one (issue 6): how far
//! the leaves that are in both moved, and how many of the previously realised
//! constraints are still realised. Owns these two figures only and may not lay
//! anything out (the caller brings both layouts).

use std::collections::BTreeMap;

use crate::geom::Point;
use crate::layout::{Computed, Previous};

/// How much a layout changed against the previous one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stability {
    /// Leaves of the new layout whose id the previous layout has (wherever it
    /// sat there).
    pub leaves: usize,
    /// Of those, leaves whose target weight is unchanged.
    pub unchanged: usize,
    /// Mean centroid displacement of those leaves, as a share of the canvas
    /// diagonal (0 when there are none).
    pub displacement_mean: f64,
    /// The same over the unchanged leaves only: issue 6's "unchanged leaves
    /// move on average at most 1%".
    pub displacement_unchanged_mean: f64,
    /// Largest displacement of any of those leaves, same unit.
    pub displacement_max: f64,
    /// Constraints realised in the previous layout whose two nodes are both
    /// still there, on one depth.
    pub realized_before: usize,
    /// Of those, how many share an edge in the new layout (checker semantics).
    pub kept: usize,
}

impl Stability {
    /// `kept / realized_before`, or `None` when nothing was realised before.
    pub fn kept_share(&self) -> Option<f64> {
        (self.realized_before > 0).then(|| self.kept as f64 / self.realized_before as f64)
    }
}

/// Compares a finished computation with `previous`. Nodes are matched by id;
/// centroids are the cells' area centroids; "still realised" reads the
/// computation's own adjacency.
pub fn stability(previous: &Previous, computed: &Computed) -> Stability {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    let diagonal = Point::new(layout.canvas.width, layout.canvas.height).length();
    let mut out = Stability::default();
    let (mut sum, mut sum_unchanged) = (0.0, 0.0);
    for i in dataset.leaves() {
        let node = dataset.node(i);
        let Some(old) = previous.get(&node.id) else {
            continue;
        };
        let moved = old.centroid().distance(layout.cells[i].polygon.centroid()) / diagonal;
        out.leaves += 1;
        sum += moved;
        out.displacement_max = out.displacement_max.max(moved);
        if old.weight == node.value {
            out.unchanged += 1;
            sum_unchanged += moved;
        }
    }
    if out.leaves > 0 {
        out.displacement_mean = sum / out.leaves as f64;
    }
    if out.unchanged > 0 {
        out.displacement_unchanged_mean = sum_unchanged / out.unchanged as f64;
    }

    // Realised pairs whose nodes both survive, grouped by depth.
    let mut by_depth: BTreeMap<usize, Vec<(usize, usize)>> = BTreeMap::new();
    for (a, b) in previous.realized() {
        if let (Some(a), Some(b)) = (dataset.find(a), dataset.find(b)) {
            let depth = dataset.node(a).depth;
            if depth == dataset.node(b).depth && a != b {
                by_depth.entry(depth).or_default().push((a, b));
            }
        }
    }
    let adjacency = computed.adjacency();
    for (depth, pairs) in by_depth {
        let adjacency = &adjacency[depth];
        out.realized_before += pairs.len();
        out.kept += pairs
            .iter()
            .filter(|(a, b)| adjacency.are_adjacent(*a, *b))
            .count();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{compute, Request};
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec, SimilarityHint};

    fn dataset(scale_first: f64) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for g in 0..3 {
            b.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for k in 0..5 {
                let w = if g == 0 && k == 0 {
                    scale_first
                } else {
                    1.0 + k as f64
                };
                let angle = (g * 5 + k) as f64;
                b.add(
                    NodeSpec::new(format!("g{g}l{k}"))
                        .parent(format!("g{g}"))
                        .weight(w)
                        .features(vec![angle.cos(), angle.sin(), 1.0]),
                );
            }
        }
        b.similarity_hint(SimilarityHint::Cosine);
        b.build().expect("valid")
    }

    #[test]
    fn the_same_layout_is_perfectly_stable() {
        let c = compute(&dataset(1.0), &Request::default()).expect("layout");
        let s = stability(&c.previous(), &c);
        assert_eq!(s.leaves, 15);
        assert_eq!(s.unchanged, 15);
        assert_eq!(s.displacement_max, 0.0);
        assert!(s.realized_before > 0);
        assert_eq!(s.kept_share(), Some(1.0));
    }

    #[test]
    fn a_weight_change_is_seen() {
        let before = compute(&dataset(1.0), &Request::default()).expect("layout");
        let after = compute(&dataset(3.0), &Request::default()).expect("layout");
        let s = stability(&before.previous(), &after);
        assert_eq!((s.leaves, s.unchanged), (15, 14));
        assert!(s.displacement_max > 0.0);
        assert!(s.kept <= s.realized_before);
    }
}
