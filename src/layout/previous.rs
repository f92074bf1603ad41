//! `Previous`: the last layout of a dataset keyed by node id, the input of a
//! warm start (issue 6, "warm start as in stable treemaps"). Owns the model and
//! the decision whether a previous layout fits a new run; may not read files
//! or parse text (the layout-JSON reader is `crate::previous`, at the edge) and
//! does not lay anything out (that is `layout::warm`).
//!
//! Nodes are matched by id, never by index: a new dataset may add, drop or
//! reorder nodes. A node *survives* when the previous layout has its id under
//! the same parent id; the two roots always continue each other, so a renamed
//! root (another file name) does not turn a layout cold.

use std::collections::HashMap;

use super::{Canvas, Layout, Params};
use crate::geom::{ConvexPolygon, LevelAdjacency, Point};
use nptreemap_formats::Dataset;
use std::sync::Arc;

/// One node of a previous layout.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviousNode {
    /// The node's id (stable across runs, taken from the source data).
    pub id: String,
    /// The parent's id; `None` for the root.
    pub parent: Option<String>,
    /// The node's target weight then (leaf value, or the sum of its children).
    pub weight: f64,
    /// Its power-diagram site.
    pub site: Point,
    /// Its site's power weight; `None` when the source did not record it
    /// (layout JSON written before the field existed). Without it the warm start
    /// begins from equal weights at the previous sites, which reaches the same
    /// cells, only in more steps: for fixed sites the weights that give a set of
    /// areas are unique up to a constant (Aurenhammer, Hoffmann and Aronov 1998).
    pub power_weight: Option<f64>,
    /// Its cell.
    pub polygon: ConvexPolygon,
}

impl PreviousNode {
    /// The centroid of its cell.
    pub fn centroid(&self) -> Point {
        self.polygon.centroid()
    }

    /// Whether this node's values are ones a layout of `canvas` can have:
    /// a finite, non-negative target weight, a site and cell within the
    /// canvas (give or take `OUTSIDE_SHARE` of its diagonal), and a power
    /// weight within [`POWER_WEIGHT_BOUND`] squared diagonals. On failure,
    /// the field and what is wrong with it. The one home of these rules: the
    /// layout-JSON reader names the offending field with them, and
    /// [`Previous::fits`] refuses a previous layout built in code with them.
    pub fn check(&self, canvas: Canvas) -> Result<(), (&'static str, String)> {
        let diagonal = Point::new(canvas.width, canvas.height).length();
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err((
                "weight",
                format!("is {}; a weight is a finite number >= 0", self.weight),
            ));
        }
        let margin = OUTSIDE_SHARE * diagonal;
        let inside = |p: Point| {
            p.is_finite()
                && (-margin..=canvas.width + margin).contains(&p.x)
                && (-margin..=canvas.height + margin).contains(&p.y)
        };
        let size = format!("the {}×{} canvas", canvas.width, canvas.height);
        if !inside(self.site) {
            return Err((
                "site",
                format!("[{}, {}] lies outside {size}", self.site.x, self.site.y),
            ));
        }
        if let Some(p) = self.polygon.points().iter().find(|p| !inside(**p)) {
            return Err((
                "polygon",
                format!("has the vertex [{}, {}] outside {size}", p.x, p.y),
            ));
        }
        let bound = POWER_WEIGHT_BOUND * diagonal * diagonal;
        if let Some(w) = self.power_weight.filter(|w| w.is_nan() || w.abs() > bound) {
            return Err((
                "power_weight",
                format!(
                    "is {w:e}, beyond what a layout of {size} has (at most ±{bound:.2e}, \
                     {POWER_WEIGHT_BOUND} squared diagonals); cells started from it collapse"
                ),
            ));
        }
        Ok(())
    }
}

/// Largest power weight, in squared canvas diagonals, that [`PreviousNode::check`]
/// accepts. Finished layouts stay below about 2 (the paper prototype's
/// schedule on the paper's datasets reaches 2.3, ours 0.2): a cell empties
/// once its weight falls a squared distance below a neighbour's, so weights
/// spread over at most a squared diagonal, and the optimiser's steps add no
/// drift. A thousand leaves room for any of that and still keeps the squared
/// distances the power diagram adds to the weights (down to 10⁻⁸ of the
/// canvas for the smallest cells) above their rounding; 1e308 (issue 21)
/// loses every one of them.
pub const POWER_WEIGHT_BOUND: f64 = 1000.0;

/// How far outside the canvas, as a share of its diagonal, a previous site
/// or cell vertex may lie ([`PreviousNode::check`]): layouts keep them inside
/// the outline; this only forgives the rounding of a file's coordinates.
const OUTSIDE_SHARE: f64 = 1e-3;

/// A previous layout: per node id its site, power weight, cell, target weight
/// and parent, the canvas, and which constraints were realised.
#[derive(Clone, Debug, PartialEq)]
pub struct Previous {
    canvas: Canvas,
    nodes: Vec<PreviousNode>,
    by_id: HashMap<String, usize>,
    /// Number of children per parent id.
    child_counts: HashMap<String, usize>,
    root: Option<usize>,
    realized: Vec<(String, String)>,
    /// The previous layout's adjacency per level, when it came from a
    /// computation in memory (not a file): a warm layout of the same nodes
    /// then compares only the cells that moved (`compute`).
    levels: KeptLevels,
}

/// The adjacency a [`Previous`] carries: what its layout already gives, so
/// not part of what makes two previous layouts equal.
#[derive(Clone, Debug, Default)]
struct KeptLevels(Option<Arc<Vec<LevelAdjacency>>>);

impl PartialEq for KeptLevels {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Why a previous layout was not used; the layout then starts cold. None of
/// these is an error: a layout is always made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WarmRefusal {
    /// The previous layout has no root node.
    #[error("the previous layout has no root")]
    NoRoot,
    /// The canvas changed.
    #[error("the previous layout was made for a {width}×{height} canvas")]
    Canvas {
        /// The previous width.
        width: f64,
        /// The previous height.
        height: f64,
    },
    /// The root outline changed (say a rectangle before, a circle now).
    #[error("the previous layout has another outline")]
    Outline,
    /// A node holds a value no layout of its canvas can have (a power weight
    /// of 1e308, a site far outside the canvas): a warm start from it would
    /// give a degenerate picture (issue 21).
    #[error("node {id:?}: `{field}` {reason}")]
    Unsound {
        /// The node's id.
        id: String,
        /// The field: `power_weight`, `site`, `weight` or `polygon`.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The hierarchy changed too much for old positions to mean anything.
    #[error("only {survivors} of {nodes} nodes survive from the previous layout")]
    TooFewSurvivors {
        /// Nodes found under the same parent.
        survivors: usize,
        /// Non-root nodes of the new dataset.
        nodes: usize,
    },
}

/// Share of the new dataset's non-root nodes that must survive for a warm
/// start. Issue 6 asks to fall back to a cold layout when the hierarchy
/// changed too much; below half, most diagrams would be seeded from scratch
/// anyway and the old arrangement no longer guides the new one.
const MIN_SURVIVING_SHARE: f64 = 0.5;

/// Tolerance, as a share of the canvas diagonal, for "the same outline" (and
/// the same parent cell, in [`super::warm`]): the
/// layout JSON rounds coordinates to 1e-6 canvas units (render/json.rs), far
/// below this, and the checker's shared-edge threshold is the same 1e-6.
const SAME_CELL_TOLERANCE: f64 = 1e-6;

impl Previous {
    /// A previous layout from its parts. Never fails: a repeated id keeps its
    /// last node, a node whose parent id is unknown simply never survives, and
    /// the first node without a parent is the root (the layout-JSON reader
    /// rejects such files with a message; this constructor stays total).
    pub fn new(canvas: Canvas, nodes: Vec<PreviousNode>, realized: Vec<(String, String)>) -> Self {
        let by_id = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| (n.id.clone(), i))
            .collect();
        let root = nodes.iter().position(|n| n.parent.is_none());
        let mut child_counts = HashMap::new();
        for parent in nodes.iter().filter_map(|n| n.parent.as_ref()) {
            *child_counts.entry(parent.clone()).or_insert(0) += 1;
        }
        Self {
            canvas,
            nodes,
            by_id,
            child_counts,
            root,
            realized,
            levels: KeptLevels::default(),
        }
    }

    /// The previous layout that `layout` of `dataset` (cells indexed like its
    /// nodes) becomes, with no realised constraints.
    pub fn from_layout(dataset: &Dataset, layout: &Layout) -> Self {
        let nodes = dataset
            .nodes()
            .iter()
            .zip(&layout.cells)
            .map(|(node, cell)| PreviousNode {
                id: node.id.clone(),
                parent: node.parent.map(|p| dataset.node(p).id.clone()),
                weight: node.value,
                site: cell.site,
                power_weight: Some(cell.power_weight),
                polygon: cell.polygon.clone(),
            })
            .collect();
        Self::new(layout.canvas, nodes, Vec::new())
    }

    /// The same layout with these id pairs as its realised constraints.
    pub fn with_realized(mut self, realized: Vec<(String, String)>) -> Self {
        self.realized = realized;
        self
    }

    /// The same layout with its adjacency per level (index = depth).
    pub fn with_levels(mut self, levels: Arc<Vec<LevelAdjacency>>) -> Self {
        self.levels = KeptLevels(Some(levels));
        self
    }

    /// Its adjacency per level and each node's cell, when it carries them
    /// and its nodes are `dataset`'s, one for one in the same order (so its
    /// node indices are `dataset`'s).
    pub(crate) fn levels_of(
        &self,
        dataset: &Dataset,
    ) -> Option<(&[LevelAdjacency], Vec<&ConvexPolygon>)> {
        let levels = self.levels.0.as_deref()?;
        let same = self.nodes.len() == dataset.len()
            && self
                .nodes
                .iter()
                .zip(dataset.nodes())
                .all(|(p, n)| p.id == n.id);
        same.then(|| (&levels[..], self.nodes.iter().map(|n| &n.polygon).collect()))
    }

    /// The canvas the previous layout was made for.
    pub fn canvas(&self) -> Canvas {
        self.canvas
    }

    /// Every node, in the source's order.
    pub fn nodes(&self) -> &[PreviousNode] {
        &self.nodes
    }

    /// The node with this id.
    pub fn get(&self, id: &str) -> Option<&PreviousNode> {
        self.by_id.get(id).map(|&i| &self.nodes[i])
    }

    /// The root node.
    pub fn root(&self) -> Option<&PreviousNode> {
        self.root.map(|i| &self.nodes[i])
    }

    /// How many children the node with this id had.
    pub fn child_count(&self, id: &str) -> usize {
        self.child_counts.get(id).copied().unwrap_or(0)
    }

    /// Id pairs of the constraints realised in the previous layout.
    pub fn realized(&self) -> &[(String, String)] {
        &self.realized
    }

    /// The previous cell of node `index` of `dataset` in its role as a parent:
    /// the previous root for the root, else the node with the same id wherever
    /// it was (a subtree moved under another parent keeps its inner arrangement).
    pub fn cell_of(&self, dataset: &Dataset, index: usize) -> Option<&PreviousNode> {
        if index == dataset.root() {
            self.root()
        } else {
            self.get(&dataset.node(index).id)
        }
    }

    /// The previous node that node `index` of `dataset` continues: same id and
    /// same parent (see the module doc); `None` for a new or moved node and
    /// for the root.
    pub fn survivor(&self, dataset: &Dataset, index: usize) -> Option<&PreviousNode> {
        let node = dataset.node(index);
        let parent = node.parent?;
        let old = self.get(&node.id)?;
        let old_parent = old.parent.as_deref()?;
        let same_parent = if parent == dataset.root() {
            self.root().is_some_and(|r| r.id == old_parent)
        } else {
            dataset.node(parent).id == old_parent
        };
        same_parent.then_some(old)
    }

    /// How many non-root nodes of `dataset` survive.
    pub fn survivors(&self, dataset: &Dataset) -> usize {
        (0..dataset.len())
            .filter(|&i| self.survivor(dataset, i).is_some())
            .count()
    }

    /// Whether a run with `params` on `dataset` may start from this layout:
    /// the same canvas and outline, every node's values ones a layout can
    /// have ([`PreviousNode::check`]), and at least half of the nodes surviving.
    /// A previous layout for another canvas or outline is not rescaled: it is
    /// simply not used, and the layout starts cold.
    pub fn fits(&self, dataset: &Dataset, params: &Params) -> Result<(), WarmRefusal> {
        let root = self.root().ok_or(WarmRefusal::NoRoot)?;
        let (c, p) = (self.canvas, params.canvas);
        let tol = same_cell_tolerance(p);
        if (c.width - p.width).abs() > tol || (c.height - p.height).abs() > tol {
            return Err(WarmRefusal::Canvas {
                width: c.width,
                height: c.height,
            });
        }
        match params.outline.polygon(params.canvas) {
            Ok(outline) if same_polygon(&outline, &root.polygon, tol) => {}
            _ => return Err(WarmRefusal::Outline),
        }
        for n in &self.nodes {
            n.check(self.canvas)
                .map_err(|(field, reason)| WarmRefusal::Unsound {
                    id: n.id.clone(),
                    field,
                    reason,
                })?;
        }
        let nodes = dataset.len().saturating_sub(1);
        let survivors = self.survivors(dataset);
        if (survivors as f64) < MIN_SURVIVING_SHARE * nodes as f64 {
            return Err(WarmRefusal::TooFewSurvivors { survivors, nodes });
        }
        Ok(())
    }
}

/// The distance under which two vertices count as the same (see
/// `SAME_CELL_TOLERANCE`).
pub(super) fn same_cell_tolerance(canvas: Canvas) -> f64 {
    SAME_CELL_TOLERANCE * Point::new(canvas.width, canvas.height).length()
}

/// True when the two polygons have the same vertices within `tol` (in any
/// starting position: the JSON reader may rotate the vertex list).
pub(super) fn same_polygon(a: &ConvexPolygon, b: &ConvexPolygon, tol: f64) -> bool {
    a.len() == b.len()
        && a.points()
            .iter()
            .all(|p| b.points().iter().any(|q| p.distance(*q) <= tol))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{layout, Outline};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn tree(leaves: &[(&str, &str, f64)]) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        let mut groups: Vec<&str> = Vec::new();
        for (g, _, _) in leaves {
            if !groups.contains(g) {
                groups.push(g);
                b.add(NodeSpec::new(*g).parent("root"));
            }
        }
        for (g, id, w) in leaves {
            b.add(NodeSpec::new(*id).parent(*g).weight(*w));
        }
        b.build().expect("valid")
    }

    #[test]
    fn survivors_need_the_same_parent_and_roots_continue_each_other() {
        let old = tree(&[("A", "a1", 1.0), ("A", "a2", 2.0), ("B", "b1", 3.0)]);
        let (l, _) = layout(&old, &Params::default()).expect("layout");
        let prev = Previous::from_layout(&old, &l);
        // b1 moved to A, a3 is new, the root is renamed.
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("other-root"));
        b.add(NodeSpec::new("A").parent("other-root"));
        b.add(NodeSpec::new("B").parent("other-root"));
        for (id, g) in [("a1", "A"), ("a2", "A"), ("b1", "A"), ("a3", "B")] {
            b.add(NodeSpec::new(id).parent(g).weight(1.0));
        }
        let new = b.build().expect("valid");
        let alive: Vec<&str> = (0..new.len())
            .filter(|&i| prev.survivor(&new, i).is_some())
            .map(|i| new.node(i).id.as_str())
            .collect();
        assert_eq!(alive, ["A", "B", "a1", "a2"]);
        assert_eq!(
            prev.cell_of(&new, new.root()).map(|n| n.id.as_str()),
            Some("root")
        );
        assert_eq!(prev.fits(&new, &Params::default()), Ok(()));
    }

    #[test]
    fn another_canvas_outline_or_hierarchy_is_refused() {
        let ds = tree(&[("A", "a1", 1.0), ("A", "a2", 2.0), ("B", "b1", 3.0)]);
        let (l, _) = layout(&ds, &Params::default()).expect("layout");
        let prev = Previous::from_layout(&ds, &l);
        let mut wide = Params::default();
        wide.canvas.width = 1200.0;
        assert!(matches!(
            prev.fits(&ds, &wide),
            Err(WarmRefusal::Canvas { .. })
        ));
        let round = Params {
            outline: Outline::Circle,
            ..Params::default()
        };
        assert_eq!(prev.fits(&ds, &round), Err(WarmRefusal::Outline));
        let other = tree(&[("X", "x1", 1.0), ("Y", "y1", 2.0), ("A", "a1", 3.0)]);
        assert_eq!(
            prev.fits(&other, &Params::default()),
            Err(WarmRefusal::TooFewSurvivors {
                survivors: 2,
                nodes: 6
            })
        );
        let empty = Previous::new(Canvas::default(), Vec::new(), Vec::new());
        assert_eq!(
            empty.fits(&ds, &Params::default()),
            Err(WarmRefusal::NoRoot)
        );
    }
    /// A previous layout built in code (not read from a file, which the
    /// reader checks) with values no layout can have is refused, naming the
    /// node and the field: the run starts cold (issue 21, item 8).
    #[test]
    fn values_no_layout_can_have_are_refused() {
        let ds = tree(&[("A", "a1", 1.0), ("A", "a2", 2.0), ("B", "b1", 3.0)]);
        let (l, _) = layout(&ds, &Params::default()).expect("layout");
        let prev = Previous::from_layout(&ds, &l);
        let hostile = |change: &dyn Fn(&mut PreviousNode)| {
            let mut nodes = prev.nodes().to_vec();
            let i = nodes.iter().position(|n| n.id == "a2").expect("a2");
            change(&mut nodes[i]);
            Previous::new(prev.canvas(), nodes, Vec::new()).fits(&ds, &Params::default())
        };
        let refused = |r: Result<(), WarmRefusal>, field: &str| match r {
            Err(WarmRefusal::Unsound { id, field: f, .. }) => {
                assert_eq!((id.as_str(), f), ("a2", field));
            }
            other => panic!("{field}: {other:?}"),
        };
        refused(hostile(&|n| n.power_weight = Some(1e308)), "power_weight");
        refused(
            hostile(&|n| n.power_weight = Some(f64::NAN)),
            "power_weight",
        );
        refused(hostile(&|n| n.site = Point::new(-1e6, 3.0)), "site");
        refused(hostile(&|n| n.weight = f64::INFINITY), "weight");
        assert_eq!(hostile(&|n| n.power_weight = None), Ok(()));
    }
}
