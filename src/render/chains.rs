//! Virtual copies in the picture: the chain of one-child copies that
//! `neighborhood::prepare` hangs under a shallow leaf (§2.2, so that every
//! leaf reaches the deepest level) has the leaf's cell at every level. The
//! picture draws such a chain once, as the leaf of the data, and names,
//! labels and colours it as that leaf; this file says which node is which.

use nptreemap_formats::Dataset;

/// The real node a virtual copy stands for: its nearest real ancestor (a
/// chain of copies hangs under the leaf it continues); `i` itself when it
/// is real.
pub(crate) fn original(dataset: &Dataset, mut i: usize) -> usize {
    // Bounded by the depth: each step goes one level up.
    while dataset.node(i).is_virtual {
        match dataset.node(i).parent {
            Some(p) => i = p,
            None => break,
        }
    }
    i
}

/// The leaf whose fill cell `i` is drawn with: `i` for a leaf, the chain's
/// last copy for a leaf of the data that heads a chain of copies, none for
/// a group.
pub(crate) fn drawn_leaf(dataset: &Dataset, i: usize) -> Option<usize> {
    let mut at = i;
    // A chain is no longer than the tree is deep.
    for _ in 0..=dataset.max_depth() {
        if dataset.is_leaf(at) {
            return Some(at);
        }
        match dataset.node(at).children.as_slice() {
            [only] if dataset.node(*only).is_virtual => at = *only,
            _ => return None,
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighborhood::prepare::prepare;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// A leaf at depth 1 beside a group two levels deep: prepare gives it a
    /// chain of two copies, which stand for it and end in the leaf it is
    /// drawn as; the group's nodes are themselves.
    #[test]
    fn a_chain_stands_for_its_head_and_is_drawn_as_its_last_copy() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        b.add(NodeSpec::new("short").parent("root").weight(2.0));
        b.add(NodeSpec::new("g").parent("root"));
        b.add(NodeSpec::new("h").parent("g"));
        b.add(NodeSpec::new("deep").parent("h").weight(1.0));
        let ds = prepare(&b.build().expect("valid"));
        let at = |id: &str| ds.find(id).expect(id);
        let copies: Vec<usize> = (0..ds.len()).filter(|&i| ds.node(i).is_virtual).collect();
        assert_eq!(copies.len(), 2, "short continues to depth 3");
        let last = *copies
            .iter()
            .find(|&&c| ds.is_leaf(c))
            .expect("the chain ends in a leaf");
        for &c in &copies {
            assert_eq!(original(&ds, c), at("short"));
        }
        assert_eq!(drawn_leaf(&ds, at("short")), Some(last));
        assert_eq!(drawn_leaf(&ds, at("deep")), Some(at("deep")));
        for group in ["g", "h", "root"] {
            assert_eq!(drawn_leaf(&ds, at(group)), None, "{group}");
            assert_eq!(original(&ds, at(group)), at(group));
        }
    }
}
