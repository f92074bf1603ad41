//! Items of weight zero (issue 34 item 2): `layout.zero_weights` says what
//! becomes of them, and [`apply`](crate::layout::zero::apply) is the pure step on a validated dataset,
//! before preparation and layout, that does it. With
//! [`ZeroWeights::Hide`] every non-root node of value 0 (an empty file; a
//! folder of nothing but empty files) leaves the dataset and so has no cell,
//! no constraint and no label, as in d3's treemaps, which draw nothing for a
//! zero value; what was hidden is kept ([`ZeroItems`]) for the legend, the
//! page's tooltips and the layout JSON's `hidden` list. With
//! [`ZeroWeights::Floor`] the dataset is unchanged and the layout draws them
//! at the floor of `min_weight_ratio` (`treemap::floored_targets`); the
//! record then only counts them, so that every output can say so.

use std::sync::Arc;

use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

/// What becomes of items of weight 0. Named in configs
/// (`layout.zero_weights`) and on the command line (`--zero-weights`).
#[derive(
    serde::Serialize, Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize,
)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum ZeroWeights {
    /// No cell: the picture shows only what has a size, and says how many
    /// items it left out (the default: an empty file has no size to draw).
    #[default]
    Hide,
    /// A cell at the floor of `min_weight_ratio`, as small as the area
    /// target allows; the picture says how many are drawn so.
    Floor,
}

impl ZeroWeights {
    /// Both settings, the default first.
    pub const ALL: [ZeroWeights; 2] = [ZeroWeights::Hide, ZeroWeights::Floor];

    /// The name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ZeroWeights::Hide => "hide",
            ZeroWeights::Floor => "floor",
        }
    }
}

/// A node left out of the layout, as the layout JSON lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct HiddenNode {
    /// Its id.
    pub id: String,
    /// Its label.
    pub label: String,
    /// Its parent's id (a drawn node, or another hidden one).
    pub parent: String,
    /// Its depth in the input.
    pub depth: usize,
    /// True when it has no children in the input (an item, not a group).
    pub leaf: bool,
}

/// What a drawn node holds that is not drawn: for its tooltip.
#[derive(Clone, Debug, PartialEq)]
pub struct HiddenUnder {
    /// The drawn node's id.
    pub parent: String,
    /// Items (leaves) of weight 0 below it, through its hidden children.
    pub items: usize,
    /// The labels of its first hidden children (at most [`NAMES_KEPT`]).
    pub names: Vec<String>,
    /// Its hidden children whose labels were not kept.
    pub more: usize,
}

/// Labels of hidden children kept per drawn node: a tooltip names a few
/// and counts the rest (a folder may hold thousands of empty files).
pub const NAMES_KEPT: usize = 5;

/// What became of a dataset's items of weight 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ZeroItems {
    /// The setting that applied.
    pub mode: ZeroWeights,
    /// Leaves of weight 0 (the root aside): hidden with `hide`, drawn at the
    /// floor with `floor`.
    pub items: usize,
    /// Whether every item weighs 0 (the root's value is 0): `hide` then
    /// draws the root alone, `floor` draws them all at equal sizes.
    pub all: bool,
    /// With `hide`, every node left out, in breadth-first order (parents
    /// before their children); empty with `floor`.
    pub hidden: Vec<HiddenNode>,
    /// With `hide`, per drawn node with hidden children, in breadth-first
    /// order of those nodes.
    pub under: Vec<HiddenUnder>,
}

impl ZeroItems {
    /// The line outputs say about them (legend, status lines), `None` when
    /// there are none: "12 items of weight 0 not drawn".
    pub fn summary(&self) -> Option<String> {
        if self.items == 0 {
            return None;
        }
        let n = items(self.items);
        Some(match (self.mode, self.all) {
            (ZeroWeights::Hide, false) => format!("{n} of weight 0 not drawn"),
            (ZeroWeights::Floor, false) => format!("{n} of weight 0 drawn at a minimum size"),
            (ZeroWeights::Hide, true) => format!("all {n} weigh 0: none drawn"),
            (ZeroWeights::Floor, true) => format!("all {n} weigh 0: drawn at equal sizes"),
        })
    }

    /// What of the drawn node `id` is hidden, if anything.
    pub fn under(&self, id: &str) -> Option<&HiddenUnder> {
        self.under.iter().find(|u| u.parent == id)
    }
}

/// "1 item", "12 items".
pub fn items(n: usize) -> String {
    format!("{n} item{}", if n == 1 { "" } else { "s" })
}

/// What `mode` does to the items of weight 0 of `dataset` (the leaves of
/// weight 0 other than the root), counted, without the list of what it
/// hides: O(n), no copy (`check` says it without a layout).
pub fn counted(dataset: &Dataset, mode: ZeroWeights) -> ZeroItems {
    let items = dataset
        .nodes()
        .iter()
        .filter(|n| n.parent.is_some() && n.children.is_empty() && n.value == 0.0)
        .count();
    ZeroItems {
        mode,
        items,
        all: items > 0 && dataset.node(dataset.root()).value == 0.0,
        ..ZeroItems::default()
    }
}

/// The dataset to prepare and lay out under `mode`, and what became of its
/// items of weight 0. Without any (or with `floor`) the dataset comes back
/// as it is, shared, not copied. A dataset of nothing but empty items keeps
/// its root alone: one cell, which the legend says holds them all.
pub fn apply(dataset: &Arc<Dataset>, mode: ZeroWeights) -> (Arc<Dataset>, Arc<ZeroItems>) {
    let record = counted(dataset, mode);
    if record.items == 0 || mode == ZeroWeights::Floor {
        return (Arc::clone(dataset), Arc::new(record));
    }
    let (visible, hidden, under) = hide(dataset);
    let record = ZeroItems {
        hidden,
        under,
        ..record
    };
    (Arc::new(visible), Arc::new(record))
}

/// Whether node `i` is left out: not the root, and nothing of weight below it.
fn hidden(dataset: &Dataset, i: usize) -> bool {
    let node = dataset.node(i);
    node.parent.is_some() && node.value == 0.0
}

/// The dataset without its nodes of value 0 (the root kept), the nodes left
/// out and, per drawn node, what of it was.
fn hide(dataset: &Dataset) -> (Dataset, Vec<HiddenNode>, Vec<HiddenUnder>) {
    let nodes = dataset.nodes();
    // Hidden leaves below each node, children before parents (BFS reversed).
    let mut below = vec![0usize; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        if n.children.is_empty() && hidden(dataset, i) {
            below[i] = 1;
        }
        if let Some(p) = n.parent {
            if hidden(dataset, i) {
                below[p] += below[i];
            }
        }
    }
    let mut builder = DatasetBuilder::new();
    if let Some(hint) = dataset.similarity_hint() {
        builder.similarity_hint(hint);
    }
    let mut gone = Vec::new();
    let mut under: Vec<HiddenUnder> = Vec::new();
    for (i, node) in nodes.iter().enumerate() {
        let parent_id = node.parent.map(|p| nodes[p].id.clone());
        if hidden(dataset, i) {
            let p = node.parent.unwrap_or(0);
            if !hidden(dataset, p) {
                match under.last_mut().filter(|u| u.parent == nodes[p].id) {
                    Some(u) if u.names.len() < NAMES_KEPT => u.names.push(node.label.clone()),
                    Some(u) => u.more += 1,
                    None => under.push(HiddenUnder {
                        parent: nodes[p].id.clone(),
                        items: below[p],
                        names: vec![node.label.clone()],
                        more: 0,
                    }),
                }
            }
            gone.push(HiddenNode {
                id: node.id.clone(),
                label: node.label.clone(),
                parent: parent_id.unwrap_or_default(),
                depth: node.depth,
                leaf: node.children.is_empty(),
            });
            continue;
        }
        let mut spec = NodeSpec::new(node.id.clone()).label(node.label.clone());
        spec.parent = parent_id;
        spec.weight = node.weight;
        spec.color = node.color;
        spec.features = node.features.clone();
        spec.fields = node.fields.clone();
        spec.relations = node
            .relations
            .iter()
            .filter(|&&r| !hidden(dataset, r))
            .map(|&r| nodes[r].id.clone())
            .collect();
        if node.is_virtual {
            builder.add_virtual(spec);
        } else {
            builder.add(spec);
        }
    }
    // Every spec comes from a valid dataset, minus whole subtrees and the
    // relations into them, so building cannot fail; fall back to the input
    // (drawn with a floor) rather than panic if that reasoning is ever broken.
    match builder.build() {
        Ok(visible) => (visible, gone, under),
        Err(_) => (dataset.clone(), Vec::new(), Vec::new()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(specs: Vec<NodeSpec>) -> Arc<Dataset> {
        let mut b = DatasetBuilder::new();
        for s in specs {
            b.add(s);
        }
        Arc::new(b.build().expect("valid"))
    }

    /// r > {a 3, e 0, pkg > {x 0, y 0}, b 2 > {c 0}} where b has its own weight.
    fn sample() -> Arc<Dataset> {
        tree(vec![
            NodeSpec::new("r"),
            NodeSpec::new("a").parent("r").weight(3.0).relation("e"),
            NodeSpec::new("e").parent("r").weight(0.0).relation("a"),
            NodeSpec::new("pkg").parent("r"),
            NodeSpec::new("x").parent("pkg").weight(0.0),
            NodeSpec::new("y").parent("pkg"),
            NodeSpec::new("b").parent("r").weight(2.0),
            NodeSpec::new("c").parent("b").weight(0.0),
        ])
    }

    #[test]
    fn hide_drops_every_node_of_value_zero_and_says_where() {
        let (visible, record) = apply(&sample(), ZeroWeights::Hide);
        let ids: Vec<&str> = visible.nodes().iter().map(|n| n.id.as_str()).collect();
        assert_eq!(ids, ["r", "a", "b"]);
        // b keeps its own weight and becomes a leaf; a's relation to the
        // hidden e is gone with it.
        assert!(visible.is_leaf(2) && visible.node(2).value == 2.0);
        assert!(visible.node(1).relations.is_empty());
        assert_eq!(record.items, 4, "e, x, y and c");
        let hidden: Vec<(&str, &str, bool)> = record
            .hidden
            .iter()
            .map(|h| (h.id.as_str(), h.parent.as_str(), h.leaf))
            .collect();
        assert_eq!(
            hidden,
            [
                ("e", "r", true),
                ("pkg", "r", false),
                ("x", "pkg", true),
                ("y", "pkg", true),
                ("c", "b", true)
            ]
        );
        let r = record.under("r").expect("r holds hidden items");
        assert_eq!(
            (r.items, r.names.clone(), r.more),
            (3, vec!["e".into(), "pkg".into()], 0)
        );
        assert_eq!(record.under("b").map(|u| u.items), Some(1));
        assert_eq!(record.under("pkg"), None, "pkg is not drawn");
        assert_eq!(
            record.summary().as_deref(),
            Some("4 items of weight 0 not drawn")
        );
    }

    #[test]
    fn floor_and_data_without_zeros_keep_the_dataset_itself() {
        let ds = sample();
        let (same, record) = apply(&ds, ZeroWeights::Floor);
        assert!(Arc::ptr_eq(&same, &ds));
        assert_eq!((record.items, record.hidden.len()), (4, 0));
        assert_eq!(
            record.summary().as_deref(),
            Some("4 items of weight 0 drawn at a minimum size")
        );
        let full = tree(vec![
            NodeSpec::new("r"),
            NodeSpec::new("a").parent("r").weight(1.0),
        ]);
        let (same, record) = apply(&full, ZeroWeights::Hide);
        assert!(Arc::ptr_eq(&same, &full));
        assert_eq!(record.summary(), None);
    }

    #[test]
    fn all_empty_keeps_the_root_alone_and_names_are_bounded() {
        let mut specs = vec![NodeSpec::new("r")];
        specs.extend((0..12).map(|k| NodeSpec::new(format!("f{k}")).parent("r").weight(0.0)));
        let all = tree(specs);
        let (visible, record) = apply(&all, ZeroWeights::Hide);
        assert_eq!(visible.len(), 1);
        assert_eq!(record.items, 12);
        assert_eq!(
            record.summary().as_deref(),
            Some("all 12 items weigh 0: none drawn")
        );
        let (_, floored) = apply(&all, ZeroWeights::Floor);
        assert_eq!(
            floored.summary().as_deref(),
            Some("all 12 items weigh 0: drawn at equal sizes")
        );
        let r = record.under("r").expect("the root holds them");
        assert_eq!(
            (r.items, r.names.len(), r.more),
            (12, NAMES_KEPT, 12 - NAMES_KEPT)
        );
    }

    #[test]
    fn names_round_trip() {
        for z in ZeroWeights::ALL {
            use serde::de::{value::Error, IntoDeserializer};
            let de = IntoDeserializer::<Error>::into_deserializer(z.name());
            assert_eq!(<ZeroWeights as serde::Deserialize>::deserialize(de), Ok(z));
        }
    }
}
