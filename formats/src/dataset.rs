//! The dataset model: a validated tree of [`Node`]s in breadth-first order, built only
//! through [`DatasetBuilder`]. No parsing and no I/O; the readers in this crate (and
//! anything else) describe nodes as [`NodeSpec`]s and let [`DatasetBuilder::build`]
//! check them, so every [`Dataset`] that exists is valid.

use std::collections::HashMap;

use crate::color::Rgb;
use crate::features::Features;
use crate::limits::{Limit, LimitError, Limits};
use crate::warning::{Warning, Warnings};

/// A validated hierarchy. Only [`DatasetBuilder::build`] makes one, so code that
/// receives a `Dataset` can trust its invariants:
///
/// - exactly one root, at index 0; every other node has a parent with a smaller index;
/// - nodes are in breadth-first order (depth never decreases along [`Dataset::nodes`]),
///   children in the order they were added;
/// - ids are unique; weights are finite and `>= 0`; feature values are finite;
///   relations point at existing nodes other than the node itself;
/// - `value` is the node's own weight plus the values of its children.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    nodes: Vec<Node>,
    // Only used for lookups by id, never iterated, so its order cannot leak into results.
    index: HashMap<String, usize>,
    similarity_hint: Option<SimilarityHint>,
    max_depth: usize,
    warnings: Vec<Warning>,
}

/// One node of a [`Dataset`]. Indices (`parent`, `children`, `relations`) point into
/// [`Dataset::nodes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Unique, stable identifier taken from the source data.
    pub id: String,
    /// Text shown to people; the id when the source gives no label.
    pub label: String,
    /// Index of the parent; `None` only for the root.
    pub parent: Option<usize>,
    /// Indices of the children, in input order.
    pub children: Vec<usize>,
    /// Distance from the root (the root has depth 0).
    pub depth: usize,
    /// The node's own weight as given (normally only leaves have one).
    pub weight: Option<f64>,
    /// Own weight (0 when `None`) plus the children's values, as d3's `hierarchy.sum`.
    pub value: f64,
    /// Colour, parsed by the reader from `#rgb` or `#rrggbb`.
    pub color: Option<Rgb>,
    /// What similarity is measured on: a dense vector or a sparse one (a set);
    /// every value is finite. Shared: cloning a node clones a pointer.
    pub features: Option<Features>,
    /// Related nodes (for example countries sharing a border): sorted, without
    /// duplicates and without the node itself.
    pub relations: Vec<usize>,
    /// True for nodes inserted to make leaf depth uniform; readers never set it.
    pub is_virtual: bool,
    /// The source's further columns (or JSON properties) that a caller asked
    /// to carry ([`crate::FormatOptions::carry`]), as (name, text), in the
    /// order asked; a column empty for this node is left out.
    pub fields: Vec<(String, String)>,
}

/// What the source data says about how node similarity should be measured.
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SimilarityHint {
    /// Cosine similarity of the feature vectors, rescaled to [0, 1].
    Cosine,
    /// Jaccard index of the feature vectors' non-zero supports (of two sets:
    /// shared members over all members of the pair).
    Jaccard,
    /// 1 when two feature vectors are identical, else 0.
    Binary,
    /// 1 when the other node is in this node's relation list, else 0.
    NeighborList,
    /// Pearson correlation of the feature vectors (for example the values of a time
    /// series), rescaled from [-1, 1] to [0, 1]; 0 when either vector is constant.
    Pearson,
}

/// Why a set of [`NodeSpec`]s does not form a valid [`Dataset`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// No node was added.
    #[error("the dataset has no nodes")]
    Empty,
    /// Two nodes share an id.
    #[error("node {id:?}: the id is used by more than one node")]
    DuplicateId {
        /// The repeated id.
        id: String,
    },
    /// A node names a parent that was never added.
    #[error("node {id:?}: parent {parent:?} does not exist")]
    MissingParent {
        /// The node naming the parent.
        id: String,
        /// The id it names.
        parent: String,
    },
    /// Following parents from this node never reaches the root.
    #[error("node {id:?}: its chain of parents forms a cycle")]
    Cycle {
        /// A node on the cycle.
        id: String,
    },
    /// Every node has a parent (so the parents must form a cycle).
    #[error("no root: every node has a parent")]
    NoRoot,
    /// More than one node has no parent.
    #[error("more than one root: nodes {first:?} and {second:?} both have no parent")]
    MultipleRoots {
        /// The first parentless node, in the order added.
        first: String,
        /// The second parentless node.
        second: String,
    },
    /// A weight is negative, infinite or NaN.
    #[error("node {id:?}: weight {value} {}", weight_problem(*.value))]
    InvalidWeight {
        /// The node.
        id: String,
        /// The offending weight.
        value: f64,
    },
    /// A feature value is infinite or NaN.
    #[error("node {id:?}: feature {index} is {value}, not a finite number")]
    InvalidFeature {
        /// The node.
        id: String,
        /// Position of the value in the feature vector (0-based).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A relation names a node that does not exist.
    #[error("node {id:?}: related node {target:?} does not exist")]
    UnknownRelation {
        /// The node with the relation.
        id: String,
        /// The id it names.
        target: String,
    },
    /// The weights of a node and everything below it add up to more than
    /// the largest finite number (the sum would be written as infinity).
    #[error(
        "node {id:?}: its weight and those below it sum to more than 1.8e308, not a finite number"
    )]
    WeightOverflow {
        /// The node whose sum overflows (the lowest such node).
        id: String,
    },
    /// A feature value so large that the sums of squares and products the
    /// similarities and projections take would overflow.
    #[error(
        "node {id:?}: feature {index} is {value:e}; feature values must lie within ±{FEATURE_BOUND:e} (sums of their squares would overflow)"
    )]
    FeatureTooLarge {
        /// The node.
        id: String,
        /// Position of the value (0-based).
        index: usize,
        /// The value.
        value: f64,
    },
    /// The dataset is larger than the [`Limits`] allow (too many nodes, too deep).
    #[error(transparent)]
    TooLarge(#[from] LimitError),
}

/// The largest feature magnitude accepted. Similarities, the mean aggregation
/// of vectors (paper §4) and the projections sum squares and products of
/// feature values over all dimensions and nodes; within ±1e100 those sums stay
/// below 1e210 for any input within the limits, far from f64's 1.8e308, so no
/// similarity silently becomes 0 (values near 1e308 used to give 0
/// constraints). Real embeddings are O(1).
pub const FEATURE_BOUND: f64 = 1e100;

/// Words for what is wrong with a weight that failed [`is_valid_weight`].
fn weight_problem(value: f64) -> &'static str {
    if value.is_nan() || value.is_infinite() {
        "is not a finite number"
    } else {
        "is negative"
    }
}

impl ModelError {
    /// The id of the node the error is about, when there is one (readers use it to
    /// point at the node's position in the input).
    pub fn node_id(&self) -> Option<&str> {
        match self {
            ModelError::Empty | ModelError::NoRoot => None,
            ModelError::DuplicateId { id }
            | ModelError::MissingParent { id, .. }
            | ModelError::Cycle { id }
            | ModelError::InvalidWeight { id, .. }
            | ModelError::InvalidFeature { id, .. }
            | ModelError::UnknownRelation { id, .. }
            | ModelError::WeightOverflow { id }
            | ModelError::FeatureTooLarge { id, .. } => Some(id),
            ModelError::TooLarge(_) => None,
            ModelError::MultipleRoots { second, .. } => Some(second),
        }
    }
}

/// True when `value` can be a node weight: finite and not negative.
pub(crate) fn is_valid_weight(value: f64) -> bool {
    value.is_finite() && value >= 0.0
}

impl Dataset {
    /// All nodes in breadth-first order: the root first, then depth 1, and so on;
    /// siblings in input order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The node at `index`. Panics if `index >= self.len()`, like slice indexing:
    /// indices come from this dataset, never from user data.
    pub fn node(&self, index: usize) -> &Node {
        &self.nodes[index]
    }

    /// Index of the root, which is always 0.
    pub fn root(&self) -> usize {
        0
    }

    /// Number of nodes, the root included.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false: a dataset has at least its root.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Index of the node with this id.
    pub fn find(&self, id: &str) -> Option<usize> {
        self.index.get(id).copied()
    }

    /// Indices of the nodes without children, in breadth-first order.
    pub fn leaves(&self) -> impl Iterator<Item = usize> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, node)| node.children.is_empty())
            .map(|(index, _)| index)
    }

    /// True when node `index` has no children. Panics if `index >= self.len()`.
    pub fn is_leaf(&self, index: usize) -> bool {
        self.nodes[index].children.is_empty()
    }

    /// The nodes from the root down to `index`, both included.
    pub fn path(&self, index: usize) -> Vec<usize> {
        let mut path = Vec::new();
        let mut at = Some(index);
        while let Some(k) = at {
            path.push(k);
            at = self.nodes[k].parent;
        }
        path.reverse();
        path
    }

    /// The largest depth of any node (0 when the root is the only node).
    pub fn max_depth(&self) -> usize {
        self.max_depth
    }

    /// What the source says about measuring similarity, if anything.
    pub fn similarity_hint(&self) -> Option<SimilarityHint> {
        self.similarity_hint
    }

    /// This dataset with each node's own weight replaced by `weights`
    /// (indexed like [`Dataset::nodes`]) and every value summed again, as
    /// [`DatasetBuilder::build`] sums them: for a caller that changes weights
    /// only (a warm rebuild after a weight edit), without building the tree
    /// again. Errors as `build` would on the same weights.
    pub fn with_weights(&self, weights: &[Option<f64>]) -> Result<Dataset, ModelError> {
        let mut out = self.clone();
        for (node, &weight) in out.nodes.iter_mut().zip(weights) {
            if let Some(w) = weight.filter(|w| !is_valid_weight(*w)) {
                return Err(ModelError::InvalidWeight {
                    id: node.id.clone(),
                    value: w,
                });
            }
            node.weight = weight;
        }
        sum_values(&mut out.nodes)?;
        Ok(out)
    }

    /// What the reader found suspicious but read anyway, in input order: the
    /// first [`Warnings::KEPT`] of each kind and input, then a line "and N
    /// more ..." for each kind and input that had more.
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }
}

/// The description of one node handed to [`DatasetBuilder::add`]. Parents and
/// relations are named by id, so nodes can be added in any order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeSpec {
    /// Unique id.
    pub id: String,
    /// Display label; the id when `None`.
    pub label: Option<String>,
    /// Id of the parent; `None` for the root.
    pub parent: Option<String>,
    /// The node's own weight.
    pub weight: Option<f64>,
    /// Colour.
    pub color: Option<Rgb>,
    /// What similarity is measured on (a dense vector, or a set).
    pub features: Option<Features>,
    /// Ids of related nodes; a relation to the node itself is dropped.
    pub relations: Vec<String>,
    /// Further (name, text) pairs the node carries unchanged ([`Node::fields`]).
    pub fields: Vec<(String, String)>,
}

impl NodeSpec {
    /// A node with this id and nothing else (a root, until [`NodeSpec::parent`] is set).
    pub fn new(id: impl Into<String>) -> Self {
        NodeSpec {
            id: id.into(),
            ..NodeSpec::default()
        }
    }

    /// Sets the parent's id.
    pub fn parent(mut self, parent: impl Into<String>) -> Self {
        self.parent = Some(parent.into());
        self
    }

    /// Sets the node's own weight.
    pub fn weight(mut self, weight: f64) -> Self {
        self.weight = Some(weight);
        self
    }

    /// Sets the display label.
    pub fn label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    /// Sets the colour.
    pub fn color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }

    /// Sets the features: a dense vector (`Vec<f64>`) or a
    /// [`crate::SparseVector`] (a set).
    pub fn features(mut self, features: impl Into<Features>) -> Self {
        self.features = Some(features.into());
        self
    }

    /// Adds a related node by id.
    pub fn relation(mut self, target: impl Into<String>) -> Self {
        self.relations.push(target.into());
        self
    }
}

/// Collects [`NodeSpec`]s and turns them into a validated [`Dataset`].
#[derive(Clone, Debug, Default)]
pub struct DatasetBuilder {
    specs: Vec<NodeSpec>,
    // Parallel to `specs`: true for nodes added with `add_virtual`. Kept outside
    // `NodeSpec` so readers that build specs field by field are unaffected.
    virtual_flags: Vec<bool>,
    similarity_hint: Option<SimilarityHint>,
    // `None`: no limits (the layout's own rebuild with virtual nodes, tests).
    limits: Option<Limits>,
    warnings: Warnings,
}

impl DatasetBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        DatasetBuilder::default()
    }

    /// Adds a node. Siblings keep the order in which they are added.
    pub fn add(&mut self, spec: NodeSpec) -> &mut Self {
        self.specs.push(spec);
        self.virtual_flags.push(false);
        self
    }

    /// Adds a node marked [`Node::is_virtual`]: one inserted to make leaf depth
    /// uniform (method-reference §2.2), not taken from the source data. Otherwise
    /// the same as [`DatasetBuilder::add`].
    pub fn add_virtual(&mut self, spec: NodeSpec) -> &mut Self {
        self.specs.push(spec);
        self.virtual_flags.push(true);
        self
    }

    /// Records what the source says about measuring similarity.
    pub fn similarity_hint(&mut self, hint: SimilarityHint) -> &mut Self {
        self.similarity_hint = Some(hint);
        self
    }

    /// Checks the node count and depth against `limits` in [`DatasetBuilder::build`]
    /// (without, there are none).
    pub fn limits(&mut self, limits: Limits) -> &mut Self {
        self.limits = Some(limits);
        self
    }

    /// Adds a warning for the dataset to carry (the first few of a kind are
    /// kept, the rest counted: see [`Warnings`]).
    pub fn warn(&mut self, warning: Warning) -> &mut Self {
        self.warnings.push(warning);
        self
    }

    /// Adds warnings a reader collected, with the ones it only counted.
    pub fn warnings(&mut self, warnings: Warnings) -> &mut Self {
        self.warnings.append(warnings);
        self
    }

    /// Checks the nodes and builds the dataset in breadth-first order.
    ///
    /// Checks run in a fixed order, so the same input always reports the same error:
    /// per node in the order added (id unique, weight, features, colour), then
    /// parents exist, one root, relations exist, and finally that every node is
    /// reachable from the root (anything else sits on or under a cycle).
    pub fn build(self) -> Result<Dataset, ModelError> {
        let DatasetBuilder {
            specs,
            virtual_flags,
            similarity_hint,
            limits,
            warnings,
        } = self;
        let warnings = warnings.into_vec();
        if specs.is_empty() {
            return Err(ModelError::Empty);
        }
        if let Some(limits) = &limits {
            limits.check_nodes(specs.len())?;
        }
        let links = Links::resolve(&specs)?;
        let (order, new_index) = breadth_first(&specs, &links)?;
        let (mut nodes, index) =
            place_nodes(specs, &links, &order, &new_index, &virtual_flags, limits)?;
        sum_values(&mut nodes)?;
        let max_depth = nodes.last().map_or(0, |node| node.depth);
        Ok(Dataset {
            nodes,
            index,
            similarity_hint,
            max_depth,
            warnings,
        })
    }
}

/// The specs' parents, children and relations as spec indices.
struct Links {
    root: usize,
    parent_of: Vec<Option<usize>>,
    /// In the order added.
    children_of: Vec<Vec<usize>>,
    relations_of: Vec<Vec<usize>>,
}

impl Links {
    /// Resolves the ids, checking in a fixed order: per spec (id unique, its
    /// values), then parents exist and there is one root, then relations exist.
    fn resolve(specs: &[NodeSpec]) -> Result<Links, ModelError> {
        let mut index_of: HashMap<&str, usize> = HashMap::with_capacity(specs.len());
        for (i, spec) in specs.iter().enumerate() {
            if index_of.insert(spec.id.as_str(), i).is_some() {
                return Err(ModelError::DuplicateId {
                    id: spec.id.clone(),
                });
            }
            check_values(spec)?;
        }

        let mut parent_of: Vec<Option<usize>> = Vec::with_capacity(specs.len());
        let mut root: Option<usize> = None;
        for (i, spec) in specs.iter().enumerate() {
            match &spec.parent {
                Some(parent) => match index_of.get(parent.as_str()) {
                    Some(&p) => parent_of.push(Some(p)),
                    None => {
                        return Err(ModelError::MissingParent {
                            id: spec.id.clone(),
                            parent: parent.clone(),
                        })
                    }
                },
                None => {
                    if let Some(first) = root {
                        return Err(ModelError::MultipleRoots {
                            first: specs[first].id.clone(),
                            second: spec.id.clone(),
                        });
                    }
                    root = Some(i);
                    parent_of.push(None);
                }
            }
        }
        let root = root.ok_or(ModelError::NoRoot)?;

        for spec in specs {
            if let Some(target) = spec
                .relations
                .iter()
                .find(|target| !index_of.contains_key(target.as_str()))
            {
                return Err(ModelError::UnknownRelation {
                    id: spec.id.clone(),
                    target: target.clone(),
                });
            }
        }
        let relations_of: Vec<Vec<usize>> = specs
            .iter()
            .map(|spec| {
                spec.relations
                    .iter()
                    .filter_map(|target| index_of.get(target.as_str()).copied())
                    .collect()
            })
            .collect();

        let mut children_of: Vec<Vec<usize>> = vec![Vec::new(); specs.len()];
        for (i, parent) in parent_of.iter().enumerate() {
            if let Some(p) = parent {
                children_of[*p].push(i);
            }
        }
        Ok(Links {
            root,
            parent_of,
            children_of,
            relations_of,
        })
    }
}

/// The specs in breadth-first order from the root, and each spec's position
/// in it. A node never reached has a parent chain that does not end at the
/// root, which (as every parent exists) means a cycle: an error naming a node
/// on it.
fn breadth_first(
    specs: &[NodeSpec],
    links: &Links,
) -> Result<(Vec<usize>, Vec<usize>), ModelError> {
    let mut order: Vec<usize> = Vec::with_capacity(specs.len());
    let mut new_index: Vec<Option<usize>> = vec![None; specs.len()];
    order.push(links.root);
    new_index[links.root] = Some(0);
    let mut head = 0;
    while head < order.len() {
        let current = order[head];
        head += 1;
        for &child in &links.children_of[current] {
            new_index[child] = Some(order.len());
            order.push(child);
        }
    }
    if order.len() < specs.len() {
        let unreached = new_index.iter().position(Option::is_none).unwrap_or(0);
        return Err(ModelError::Cycle {
            id: specs[node_on_cycle(unreached, &links.parent_of)].id.clone(),
        });
    }
    // Every spec was reached, so every entry is set.
    let new_index: Vec<usize> = new_index.into_iter().map(|i| i.unwrap_or(0)).collect();
    Ok((order, new_index))
}

/// The nodes in breadth-first `order` (`new_index`: each spec's place in
/// it; `virtual_flags` by spec), with their depth checked against `limits`, relations sorted and
/// without repeats or the node itself, and values still 0; and the index by id.
fn place_nodes(
    mut specs: Vec<NodeSpec>,
    links: &Links,
    order: &[usize],
    new_index: &[usize],
    virtual_flags: &[bool],
    limits: Option<Limits>,
) -> Result<(Vec<Node>, HashMap<String, usize>), ModelError> {
    let mut nodes: Vec<Node> = Vec::with_capacity(order.len());
    let mut index: HashMap<String, usize> = HashMap::with_capacity(order.len());
    for (position, &old) in order.iter().enumerate() {
        // `order` visits each spec exactly once, so taking it leaves nothing behind
        // that is read later.
        let spec = std::mem::take(&mut specs[old]);
        let parent = links.parent_of[old].map(|p| new_index[p]);
        let depth = parent.map_or(0, |p| nodes[p].depth + 1);
        if let Some(limits) = limits.filter(|l| depth > l.max_depth) {
            return Err(limits
                .exceeded(
                    Limit::Depth,
                    format_args!("node {:?} is at depth {depth}", spec.id),
                )
                .into());
        }
        let mut relations: Vec<usize> = links.relations_of[old]
            .iter()
            .map(|&target| new_index[target])
            .filter(|&target| target != position)
            .collect();
        relations.sort_unstable();
        relations.dedup();
        index.insert(spec.id.clone(), position);
        nodes.push(Node {
            label: spec.label.unwrap_or_else(|| spec.id.clone()),
            id: spec.id,
            parent,
            children: links.children_of[old]
                .iter()
                .map(|&c| new_index[c])
                .collect(),
            depth,
            weight: spec.weight,
            value: 0.0,
            color: spec.color,
            features: spec.features,
            relations,
            is_virtual: virtual_flags.get(old).copied().unwrap_or(false),
            fields: spec.fields,
        });
    }
    Ok((nodes, index))
}

/// Each node's value: its own weight plus its children's values. Children
/// come after their parent in BFS order, so a reverse sweep sees every
/// child's value before its parent's. Children are summed last to first
/// because d3's `hierarchy.sum` does, which keeps floating-point totals equal
/// to the prototype's.
fn sum_values(nodes: &mut [Node]) -> Result<(), ModelError> {
    for i in (0..nodes.len()).rev() {
        let mut value = nodes[i].weight.unwrap_or(0.0);
        for &child in nodes[i].children.iter().rev() {
            value += nodes[child].value;
        }
        if !value.is_finite() {
            return Err(ModelError::WeightOverflow {
                id: nodes[i].id.clone(),
            });
        }
        nodes[i].value = value;
    }
    Ok(())
}

/// Checks the per-node values that do not depend on other nodes.
fn check_values(spec: &NodeSpec) -> Result<(), ModelError> {
    if let Some(weight) = spec.weight {
        if !is_valid_weight(weight) {
            return Err(ModelError::InvalidWeight {
                id: spec.id.clone(),
                value: weight,
            });
        }
    }
    if let Some(features) = &spec.features {
        // Non-finite values first, then magnitudes: the same input always
        // reports the same error.
        let entries = || -> Box<dyn Iterator<Item = (usize, f64)> + '_> {
            match features {
                Features::Dense(values) => Box::new(values.iter().copied().enumerate()),
                Features::Sparse(sparse) => {
                    Box::new(sparse.entries().map(|(k, v)| (k as usize, v)))
                }
            }
        };
        if let Some((index, value)) = entries().find(|(_, v)| !v.is_finite()) {
            return Err(ModelError::InvalidFeature {
                id: spec.id.clone(),
                index,
                value,
            });
        }
        if let Some((index, value)) = entries().find(|(_, v)| v.abs() > FEATURE_BOUND) {
            return Err(ModelError::FeatureTooLarge {
                id: spec.id.clone(),
                index,
                value,
            });
        }
    }
    Ok(())
}

/// Follows parents from `start` (a node not reachable from the root) until a node
/// repeats; that node lies on the cycle, which makes a clearer report than `start`,
/// which may merely hang below the cycle. Terminates within `parent_of.len()` steps.
fn node_on_cycle(start: usize, parent_of: &[Option<usize>]) -> usize {
    let mut seen = vec![false; parent_of.len()];
    let mut current = start;
    while !seen[current] {
        seen[current] = true;
        match parent_of[current] {
            Some(parent) => current = parent,
            // Unreachable for an unreached node (only the root has no parent); stop anyway.
            None => return start,
        }
    }
    current
}

#[cfg(test)]
mod tests {

    #[test]
    fn path_runs_from_the_root_to_the_node() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        b.add(NodeSpec::new("a").parent("r"));
        b.add(NodeSpec::new("a1").parent("a").weight(1.0));
        b.add(NodeSpec::new("b").parent("r").weight(1.0));
        let ds = b.build().expect("valid");
        let ids = |i: usize| -> Vec<String> {
            ds.path(i).iter().map(|k| ds.node(*k).id.clone()).collect()
        };
        assert_eq!(ids(ds.find("a1").expect("a1")), ["r", "a", "a1"]);
        assert_eq!(ids(ds.root()), ["r"]);
    }

    use super::*;

    fn build(specs: Vec<NodeSpec>) -> Result<Dataset, ModelError> {
        let mut builder = DatasetBuilder::new();
        for spec in specs {
            builder.add(spec);
        }
        builder.build()
    }

    #[test]
    fn nodes_added_in_any_order_come_out_breadth_first() {
        let dataset = build(vec![
            NodeSpec::new("a1").parent("a").weight(2.0),
            NodeSpec::new("b").parent("r").weight(5.0),
            NodeSpec::new("a").parent("r"),
            NodeSpec::new("r"),
            NodeSpec::new("a2").parent("a").weight(3.0),
        ])
        .expect("valid");
        let ids: Vec<&str> = dataset.nodes().iter().map(|n| n.id.as_str()).collect();
        // Siblings keep the order they were added: b before a, a1 before a2.
        assert_eq!(ids, ["r", "b", "a", "a1", "a2"]);
        assert_eq!(dataset.root(), 0);
        assert_eq!(dataset.node(0).parent, None);
        assert_eq!(dataset.node(0).children, vec![1, 2]);
        assert_eq!(dataset.node(2).children, vec![3, 4]);
        assert_eq!(dataset.node(3).parent, Some(2));
        let depths: Vec<usize> = dataset.nodes().iter().map(|n| n.depth).collect();
        assert_eq!(depths, [0, 1, 1, 2, 2]);
        assert_eq!(dataset.max_depth(), 2);
        assert_eq!(dataset.leaves().collect::<Vec<_>>(), vec![1, 3, 4]);
        assert!(dataset.is_leaf(1));
        assert!(!dataset.is_leaf(2));
        assert_eq!(dataset.find("a2"), Some(4));
        assert_eq!(dataset.find("zz"), None);
        assert_eq!(dataset.len(), 5);
        assert!(!dataset.is_empty());
    }

    #[test]
    fn value_is_own_weight_plus_children() {
        let dataset = build(vec![
            NodeSpec::new("r").weight(1.0),
            NodeSpec::new("a").parent("r"),
            NodeSpec::new("a1").parent("a").weight(2.0),
            NodeSpec::new("a2").parent("a").weight(3.5),
            NodeSpec::new("b").parent("r"),
        ])
        .expect("valid");
        let values: Vec<f64> = dataset.nodes().iter().map(|n| n.value).collect();
        // r, a, b, a1, a2: b has no weight, so 0; the root counts its own 1.
        assert_eq!(values, [6.5, 5.5, 0.0, 2.0, 3.5]);
    }

    #[test]
    fn labels_default_to_ids_and_relations_are_resolved() {
        let dataset = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("x")
                .parent("r")
                .label("Ex")
                .relation("z")
                .relation("y")
                .relation("z")
                .relation("x"),
            NodeSpec::new("y")
                .parent("r")
                .color(Rgb::new(0xaa, 0xbb, 0xcc)),
            NodeSpec::new("z")
                .parent("r")
                .features(vec![1.0, 0.5])
                .color(Rgb::new(0x00, 0xff, 0x7f)),
        ])
        .expect("valid");
        let x = dataset.node(1);
        assert_eq!(x.label, "Ex");
        assert_eq!(dataset.node(2).label, "y");
        // Sorted, deduplicated, self dropped.
        assert_eq!(x.relations, vec![2, 3]);
        assert_eq!(dataset.node(2).color, Some(Rgb::new(0xaa, 0xbb, 0xcc)));
        assert_eq!(
            dataset.node(3).features.as_ref().map(Features::to_dense),
            Some(vec![1.0, 0.5])
        );
        assert!(dataset.nodes().iter().all(|n| !n.is_virtual));
        assert_eq!(dataset.similarity_hint(), None);
    }

    #[test]
    fn virtual_nodes_are_marked() {
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add_virtual(NodeSpec::new("v").parent("a"))
            .add(NodeSpec::new("a").parent("r"));
        let dataset = builder.build().expect("valid");
        let flags: Vec<(&str, bool)> = dataset
            .nodes()
            .iter()
            .map(|n| (n.id.as_str(), n.is_virtual))
            .collect();
        assert_eq!(flags, [("r", false), ("a", false), ("v", true)]);
    }

    #[test]
    fn similarity_hint_is_kept() {
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .similarity_hint(SimilarityHint::Jaccard);
        let dataset = builder.build().expect("valid");
        assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Jaccard));
        assert_eq!(dataset.max_depth(), 0);
        assert_eq!(dataset.leaves().collect::<Vec<_>>(), vec![0]);
    }

    #[test]
    fn empty_is_an_error() {
        let error = build(vec![]).expect_err("empty");
        assert_eq!(error, ModelError::Empty);
        assert_eq!(error.to_string(), "the dataset has no nodes");
    }

    #[test]
    fn duplicate_id() {
        let error = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("CN").parent("r"),
            NodeSpec::new("CN").parent("r"),
        ])
        .expect_err("duplicate");
        assert_eq!(error, ModelError::DuplicateId { id: "CN".into() });
        assert_eq!(
            error.to_string(),
            "node \"CN\": the id is used by more than one node"
        );
        assert_eq!(error.node_id(), Some("CN"));
    }

    #[test]
    fn missing_parent() {
        let error = build(vec![NodeSpec::new("r"), NodeSpec::new("CN").parent("Asia")])
            .expect_err("missing parent");
        assert_eq!(
            error.to_string(),
            "node \"CN\": parent \"Asia\" does not exist"
        );
    }

    #[test]
    fn cycle_below_a_valid_root_is_reported_not_looped() {
        let error = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("hang").parent("b"),
            NodeSpec::new("a").parent("b"),
            NodeSpec::new("b").parent("a"),
        ])
        .expect_err("cycle");
        // "hang" is the first unreached node, but it only hangs below the cycle a <-> b.
        assert_eq!(error, ModelError::Cycle { id: "b".into() });
        assert_eq!(
            error.to_string(),
            "node \"b\": its chain of parents forms a cycle"
        );
    }

    #[test]
    fn self_parent_is_a_cycle() {
        let error =
            build(vec![NodeSpec::new("r"), NodeSpec::new("s").parent("s")]).expect_err("cycle");
        assert_eq!(error, ModelError::Cycle { id: "s".into() });
    }

    #[test]
    fn no_root() {
        let error = build(vec![
            NodeSpec::new("a").parent("b"),
            NodeSpec::new("b").parent("a"),
        ])
        .expect_err("no root");
        assert_eq!(error, ModelError::NoRoot);
        assert_eq!(error.to_string(), "no root: every node has a parent");
    }

    #[test]
    fn multiple_roots() {
        let error = build(vec![NodeSpec::new("r"), NodeSpec::new("s")]).expect_err("two roots");
        assert_eq!(
            error.to_string(),
            "more than one root: nodes \"r\" and \"s\" both have no parent"
        );
    }

    #[test]
    fn invalid_weights() {
        let negative = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("CN").parent("r").weight(-3.0),
        ])
        .expect_err("negative");
        assert_eq!(negative.to_string(), "node \"CN\": weight -3 is negative");
        let nan = build(vec![NodeSpec::new("r").weight(f64::NAN)]).expect_err("nan");
        assert_eq!(
            nan.to_string(),
            "node \"r\": weight NaN is not a finite number"
        );
        let inf = build(vec![NodeSpec::new("r").weight(f64::INFINITY)]).expect_err("inf");
        assert_eq!(
            inf.to_string(),
            "node \"r\": weight inf is not a finite number"
        );
    }

    #[test]
    fn invalid_feature() {
        let error = build(vec![NodeSpec::new("r").features(vec![0.0, 1.0, f64::NAN])])
            .expect_err("nan feature");
        // NaN != NaN, so match the variant instead of comparing with `==`.
        assert!(matches!(
            &error,
            ModelError::InvalidFeature { id, index: 2, value } if id == "r" && value.is_nan()
        ));
        assert_eq!(
            error.to_string(),
            "node \"r\": feature 2 is NaN, not a finite number"
        );
    }

    #[test]
    fn unknown_relation() {
        let error = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("CN").parent("r").relation("AF"),
        ])
        .expect_err("unknown relation");
        assert_eq!(
            error.to_string(),
            "node \"CN\": related node \"AF\" does not exist"
        );
    }
}
