//! The map as its reader knows it, for the HTML page: the computed dataset and
//! layout without the virtual single-child copies of method-reference §2.2
//! (a copy has its original's cell, label and colour, so the picture loses
//! nothing and the page's data carries real nodes only; issue 23 item 2).
//! Owns the mapping between computed and real nodes, the deepest level's
//! links and the leaves' neighbours in real terms; may not draw or do I/O.

use std::borrow::Cow;

use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

use crate::layout::{Computed, Layout};
use crate::render::overlay::Link;
use crate::render::picture::deepest_links;

/// The real nodes of a computation, with their cells.
pub(crate) struct RealView<'a> {
    /// The dataset without virtual nodes; a leaf that headed a chain of
    /// copies is a leaf again, with its weight back.
    pub(crate) dataset: Cow<'a, Dataset>,
    /// One cell per node of `dataset`.
    pub(crate) layout: Cow<'a, Layout>,
    /// For every computed node, the real node that stands for it: itself, or
    /// for a virtual copy the real leaf it copies.
    real_of: Vec<usize>,
    /// For every real leaf, the computed leaf at the deepest level that
    /// carries its constraints and neighbours (itself, or its last copy).
    deepest_copy: Vec<usize>,
}

impl<'a> RealView<'a> {
    /// The real view of `computed` (borrowed as it is when it has no copies).
    pub(crate) fn new(computed: &'a Computed) -> RealView<'a> {
        let dataset = &computed.dataset;
        let n = dataset.len().min(computed.layout.cells.len());
        let identity = || RealView {
            dataset: Cow::Borrowed(dataset),
            layout: Cow::Borrowed(&computed.layout),
            real_of: (0..n).collect(),
            deepest_copy: (0..n).collect(),
        };
        if !dataset.nodes().iter().any(|node| node.is_virtual) {
            return identity();
        }
        let mut builder = DatasetBuilder::new();
        for node in dataset.nodes().iter().filter(|node| !node.is_virtual) {
            // A leaf that heads a chain of copies lost its weight to the
            // chain's end (prepare's rule); it gets it back.
            let heads_chain = !node.children.is_empty()
                && node.children.iter().all(|&c| dataset.node(c).is_virtual);
            let mut spec = NodeSpec::new(node.id.clone()).label(node.label.clone());
            spec.parent = node.parent.map(|p| dataset.node(p).id.clone());
            spec.weight = if heads_chain {
                Some(node.value)
            } else {
                node.weight
            };
            spec.color = node.color;
            spec.fields = node.fields.clone();
            builder.add(spec);
        }
        // Every spec comes from a valid dataset, minus nodes that are only
        // ever leaves' descendants: it builds. Should it not, the page
        // shows the computed nodes rather than fail.
        let Ok(real) = builder.build() else {
            return identity();
        };
        let to_computed: Vec<usize> = real
            .nodes()
            .iter()
            .map(|node| dataset.find(&node.id).unwrap_or(0))
            .collect();
        let mut real_of = vec![0; n];
        // Breadth-first order: a parent's entry is set before its children's.
        for (i, node) in dataset.nodes().iter().enumerate().take(n) {
            real_of[i] = if node.is_virtual {
                node.parent.map_or(0, |p| real_of[p])
            } else {
                real.find(&node.id).unwrap_or(0)
            };
        }
        let mut deepest_copy = to_computed.clone();
        for (i, node) in dataset.nodes().iter().enumerate().take(n) {
            if node.is_virtual && node.children.is_empty() {
                deepest_copy[real_of[i]] = i;
            }
        }
        let layout = Layout {
            canvas: computed.layout.canvas,
            cells: to_computed
                .iter()
                .map(|&c| computed.layout.cells[c].clone())
                .collect(),
        };
        RealView {
            dataset: Cow::Owned(real),
            layout: Cow::Owned(layout),
            real_of,
            deepest_copy,
        }
    }

    /// The constraints of the deepest level (where the picture draws them),
    /// between real leaves.
    pub(crate) fn links(&self, computed: &Computed) -> Vec<Link> {
        deepest_links(computed, |i| self.real_of.get(i).copied())
    }

    /// The top-level groups that share an edge (real indices), for colours.
    pub(crate) fn top_pairs(&self, computed: &Computed) -> Vec<(usize, usize)> {
        computed.adjacency().get(1).map_or(Vec::new(), |a| {
            a.pairs()
                .iter()
                .filter(|(x, y)| *x < self.real_of.len() && *y < self.real_of.len())
                .map(|&(x, y)| (self.real_of[x], self.real_of[y]))
                .collect()
        })
    }

    /// The leaves sharing an edge with real leaf `leaf`, as real indices,
    /// sorted, without `leaf` itself.
    pub(crate) fn leaf_neighbors(&self, computed: &Computed, leaf: usize) -> Vec<usize> {
        let Some(&copy) = self.deepest_copy.get(leaf) else {
            return Vec::new();
        };
        let depth = computed.dataset.node(copy).depth;
        let Some(level) = computed.adjacency().get(depth) else {
            return Vec::new();
        };
        let mut out: Vec<usize> = level
            .neighbors(copy)
            .iter()
            .filter(|&&j| j < self.real_of.len())
            .map(|&j| self.real_of[j])
            .filter(|&j| j != leaf)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The real node standing for computed node `i`.
    pub(crate) fn real_of(&self, i: usize) -> usize {
        self.real_of.get(i).copied().unwrap_or(0)
    }
}
