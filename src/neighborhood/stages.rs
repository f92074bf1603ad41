//! Stages A to D of the constraint pipeline (method-reference §3.3–3.6): from
//! every node's bins to its directed list (the capped top bin, propagation to
//! parents, one link per following bin) and the symmetric lists. Each stage is
//! its own function, in the order [`super::constraints::constraint_lists`]
//! runs them.

use super::bins::{strength_for, Bins};
use nptreemap_formats::Node;

/// One entry of a node's constraint list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListEntry {
    /// Index of the linked node (same depth) in the prepared dataset.
    pub target: usize,
    /// Integer score 1..=100 (never 0: such links are not created, §3.5).
    pub score: u8,
    /// Strength 1..=3, as for [`super::constraints::Constraint::strength`].
    pub strength: u8,
}

/// Stage A keeps at most this many links from the top bin (`slice(0, 6)`, §3.3).
const TOP_BIN_CAP: usize = 6;
/// Stage C stops once a node holds more than this many links (§3.5).
const STAGE_C_STOP_ABOVE: usize = 3;

/// True when `list` already links to `target`.
fn has(list: &[ListEntry], target: usize) -> bool {
    list.iter().any(|e| e.target == target)
}

/// Stage A (§3.3): each node's top bin, capped; nothing when its best score
/// is 0.
pub(super) fn top_bin(bins: &[Bins]) -> Vec<Vec<ListEntry>> {
    bins.iter()
        .map(|node_bins| {
            let Some(top) = node_bins.bins.first() else {
                return Vec::new();
            };
            if top.head.first().is_none_or(|c| c.score == 0) {
                return Vec::new();
            }
            top.head
                .iter()
                .take(TOP_BIN_CAP)
                .map(|c| ListEntry {
                    target: c.node,
                    score: c.score,
                    strength: strength_for(0, c.score),
                })
                .collect()
        })
        .collect()
}

/// Stage B (§3.4): children's links become links between their parents.
/// Children come after their parent in breadth-first order, so the reverse
/// sweep sees every child's list complete, as the prototype's post-order walk
/// does.
pub(super) fn propagate(nodes: &[Node], lists: &mut [Vec<ListEntry>]) {
    for d in (0..nodes.len()).rev() {
        for &p in &nodes[d].children {
            for k in 0..lists[p].len() {
                let link = lists[p][k];
                let parent = nodes[link.target].parent.unwrap_or(0);
                if parent == d || has(&lists[d], parent) {
                    continue;
                }
                // A perfect child link always propagates; a weaker one only gives
                // the parent its first link.
                if link.score == 100 || lists[d].is_empty() {
                    lists[d].push(ListEntry {
                        target: parent,
                        score: link.score,
                        strength: strength_for(usize::MAX, link.score),
                    });
                }
            }
        }
    }
}

/// Stage C (§3.5): one more link from each following non-empty bin while the
/// node holds at most 3, stopping at the first empty bin. Skipped when the top
/// bin is empty; score-0 links are never created (§3.5, §10 #2).
pub(super) fn following_bins(bins: &[Bins], lists: &mut [Vec<ListEntry>]) {
    for (node, node_bins) in bins.iter().enumerate() {
        if node_bins.bins.first().is_none_or(|top| top.len == 0) {
            continue;
        }
        for (b, bin) in node_bins.bins.iter().enumerate() {
            if lists[node].len() > STAGE_C_STOP_ABOVE || bin.len == 0 {
                break;
            }
            if let Some(c) = bin.head.iter().find(|c| !has(&lists[node], c.node)) {
                if c.score > 0 {
                    lists[node].push(ListEntry {
                        target: c.node,
                        score: c.score,
                        strength: strength_for(b, c.score),
                    });
                }
            }
        }
    }
}

/// Stage D (§3.6): every link's reverse where the target lacks it. Per level,
/// parents in order and their children in order, i.e. breadth-first order;
/// links only join nodes of one level, so one sweep over all nodes is the
/// same as one sweep per level.
pub(super) fn symmetrise(lists: &mut [Vec<ListEntry>]) {
    for c in 0..lists.len() {
        for k in 0..lists[c].len() {
            let link = lists[c][k];
            if !has(&lists[link.target], c) {
                lists[link.target].push(ListEntry {
                    target: c,
                    score: link.score,
                    strength: link.strength,
                });
            }
        }
    }
}
