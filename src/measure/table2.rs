//! The paper's Table 2 row for one layout (method-reference §7): constraints
//! realised at the deepest level, the area error of the leaf diagrams, the
//! graph distance between constrained cells and the aspect ratios. Realised
//! means adjacent in the deepest level's adjacency, which the caller computed
//! once (`Computed::adjacency`).

use super::area::{diagram_errors, diagram_errors_by};
use super::shape::{leaf_aspect_mean, proto_aspect_mean};
use crate::geom::adjacency::{hop_distances, LevelAdjacency};
use crate::layout::{Computed, Layout};
use nptreemap_formats::Dataset;

/// The paper's Table 2 figures for one layout (method-reference §7).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalMetrics {
    /// Depth levels, the root level included (max depth + 1).
    pub levels: usize,
    /// Nodes, the root and virtual nodes included.
    pub nodes: usize,
    /// Nodes without children.
    pub leaves: usize,
    /// Constraint pairs at the deepest level (as given, duplicates included).
    pub leaf_constraints: usize,
    /// Constraint pairs whose cells share an edge.
    pub realized: usize,
    /// `100 × realized / leaf_constraints`; 0 when there are no constraints.
    pub realized_pct: f64,
    /// Mean over the leaf level's diagrams (the parents of the deepest nodes,
    /// single-child diagrams included) of Σ|A* − A| / A(parent), A* the target
    /// area from node values. Diagrams whose parent has no area or whose children
    /// have no value are skipped, as the checker does; 0 when none is left.
    pub area_error: f64,
    /// Median hop distance over the constraint pairs joined by a path (the mean of
    /// the middle two for an even count); `None` when no pair is joined.
    pub graph_distance_median: Option<f64>,
    /// Largest hop distance over the constraint pairs joined by a path.
    pub graph_distance_max: Option<usize>,
    /// Mean over leaves of the bounding box's long side / short side (§10 row 17,
    /// `avg_aspect_ratio`); leaves with a zero-width box are skipped; 0 when none.
    pub aspect_ratio: f64,
    /// The prototype's figure (§7, `avg_aspect_ratio_proto`): mean bounding-box
    /// width / height over every non-root cell of every level, virtual nodes
    /// included; cells with zero height are skipped; 0 when none.
    pub aspect_ratio_proto: f64,
}

/// The Table 2 row of a finished computation: its deepest level's constraints
/// against its deepest level's adjacency.
pub fn table2(computed: &Computed) -> EvalMetrics {
    let dataset = &computed.dataset;
    let deepest = dataset.max_depth();
    let leaf_pairs: Vec<(usize, usize)> = computed
        .constraints
        .iter()
        .filter(|c| dataset.node(c.a).depth == deepest)
        .map(|c| (c.a, c.b))
        .collect();
    let adjacency = &computed.adjacency()[deepest];
    let mut m = eval_metrics(dataset, &computed.layout, adjacency, &leaf_pairs);
    // Against what the picture promises (issue 34): with `zero_weights:
    // floor`, items of weight 0 at the weight they are drawn at.
    if let Some(drawn) = computed.drawn_weights() {
        let parents = leaf_parents(dataset);
        m.area_error = diagram_errors_by(dataset, &computed.layout, parents, |i| drawn[i]).mean;
    }
    m
}

/// The leaf level's diagrams: the distinct parents of the deepest nodes, in
/// node order.
fn leaf_parents(dataset: &Dataset) -> Vec<usize> {
    let nodes = dataset.nodes();
    let mut parents: Vec<usize> = (0..nodes.len())
        .filter(|&i| nodes[i].depth == dataset.max_depth())
        .filter_map(|i| nodes[i].parent)
        .collect();
    parents.sort_unstable();
    parents.dedup();
    parents
}

/// Computes [`EvalMetrics`]. `leaf_pairs` are the constraint pairs (node
/// indices) at the deepest level and `adjacency` that level's adjacency in
/// `layout`. Nodes without a cell in `layout` are skipped rather than trusted.
pub fn eval_metrics(
    dataset: &Dataset,
    layout: &Layout,
    adjacency: &LevelAdjacency,
    leaf_pairs: &[(usize, usize)],
) -> EvalMetrics {
    let nodes = dataset.nodes();
    let max_depth = dataset.max_depth();
    let realized = leaf_pairs
        .iter()
        .filter(|&&(a, b)| adjacency.are_adjacent(a, b))
        .count();
    let mut hops: Vec<usize> = hop_distances(adjacency, leaf_pairs)
        .into_iter()
        .flatten()
        .collect();
    hops.sort_unstable();
    let graph_distance_median = match hops.len() {
        0 => None,
        n if n % 2 == 1 => Some(hops[n / 2] as f64),
        n => Some((hops[n / 2 - 1] + hops[n / 2]) as f64 / 2.0),
    };

    let parents = leaf_parents(dataset);

    EvalMetrics {
        levels: max_depth + 1,
        nodes: nodes.len(),
        leaves: dataset.leaves().count(),
        leaf_constraints: leaf_pairs.len(),
        realized,
        realized_pct: if leaf_pairs.is_empty() {
            0.0
        } else {
            100.0 * realized as f64 / leaf_pairs.len() as f64
        },
        area_error: diagram_errors(dataset, layout, parents).mean,
        graph_distance_median,
        graph_distance_max: hops.last().copied(),
        aspect_ratio: leaf_aspect_mean(dataset, layout),
        aspect_ratio_proto: proto_aspect_mean(dataset, layout),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::ConvexPolygon;
    use crate::layout::{Canvas, LayoutCell};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// The deepest level's adjacency in `layout`.
    fn deepest(ds: &Dataset, layout: &Layout) -> LevelAdjacency {
        let nodes: Vec<usize> = (0..ds.len())
            .filter(|&i| ds.node(i).depth == ds.max_depth())
            .collect();
        layout.level_adjacency(&nodes)
    }

    fn rect(x: f64, y: f64, w: f64, h: f64) -> ConvexPolygon {
        ConvexPolygon::rectangle(x, y, w, h).expect("valid rectangle")
    }

    fn layout_of(canvas: Canvas, polys: Vec<ConvexPolygon>) -> Layout {
        Layout {
            canvas,
            cells: polys
                .into_iter()
                .map(|polygon| LayoutCell {
                    site: polygon.centroid(),
                    power_weight: 0.0,
                    polygon,
                })
                .collect(),
        }
    }

    #[test]
    fn eval_metrics_by_hand() -> Result<(), nptreemap_formats::ModelError> {
        // Nodes in BFS order: 0 root, 1 A, 2 B, 3 a1 (1), 4 a2 (2), 5 b1 (1).
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        b.add(NodeSpec::new("A").parent("root"));
        b.add(NodeSpec::new("B").parent("root"));
        b.add(NodeSpec::new("a1").parent("A").weight(1.0));
        b.add(NodeSpec::new("a2").parent("A").weight(2.0));
        b.add(NodeSpec::new("b1").parent("B").weight(1.0));
        let ds = b.build()?;
        assert_eq!(ds.node(3).id, "a1");
        // Canvas 4 × 2: A = [0,3]×[0,2], B = [3,4]×[0,2]; a1 and a2 halve A
        // (1.5 × 2 each), b1 fills B.
        let layout = layout_of(
            Canvas {
                width: 4.0,
                height: 2.0,
            },
            vec![
                rect(0.0, 0.0, 4.0, 2.0),
                rect(0.0, 0.0, 3.0, 2.0),
                rect(3.0, 0.0, 1.0, 2.0),
                rect(0.0, 0.0, 1.5, 2.0),
                rect(1.5, 0.0, 1.5, 2.0),
                rect(3.0, 0.0, 1.0, 2.0),
            ],
        );
        // Leaf adjacency: a1–a2 (x = 1.5) and a2–b1 (x = 3); a1–b1 apart.
        // Constraints (a1, b1) and (a1, a2): one realized (50 %); hops 2 and 1,
        // so median 1.5 and max 2.
        // Area error: diagram A has targets 2 and 4 (A = 6, values 1 : 2) against
        // areas 3 and 3, so (1 + 1) / 6 = 1/3; diagram B (single child) 0;
        // mean 1/6.
        // Aspect (leaves, long/short): a1 2/1.5 = 4/3, a2 4/3, b1 2; mean 14/9.
        // Aspect (proto, w/h of non-root cells): A 1.5, B 0.5, a1 0.75, a2 0.75,
        // b1 0.5; sum 4, mean 0.8.
        let m = eval_metrics(&ds, &layout, &deepest(&ds, &layout), &[(3, 5), (3, 4)]);
        assert_eq!(m.levels, 3);
        assert_eq!(m.nodes, 6);
        assert_eq!(m.leaves, 3);
        assert_eq!(m.leaf_constraints, 2);
        assert_eq!(m.realized, 1);
        assert!((m.realized_pct - 50.0).abs() < 1e-12);
        assert!((m.area_error - 1.0 / 6.0).abs() < 1e-12);
        assert_eq!(m.graph_distance_median, Some(1.5));
        assert_eq!(m.graph_distance_max, Some(2));
        assert!((m.aspect_ratio - 14.0 / 9.0).abs() < 1e-12);
        assert!((m.aspect_ratio_proto - 0.8).abs() < 1e-12);

        // A layout missing cells and pairs naming no node must not panic.
        let short = Layout {
            canvas: layout.canvas,
            cells: layout.cells[..2].to_vec(),
        };
        let m = eval_metrics(&ds, &short, &deepest(&ds, &short), &[(3, 5), (100, 200)]);
        assert_eq!(m.realized, 0);
        assert_eq!(m.graph_distance_median, None);
        Ok(())
    }
}
