//! The constraints of one level in level-local indices ([`LevelLinks`]), and
//! what a level's arrangement scores: its own constraints realised plus the
//! deeper ones whose ancestors touch (method-reference §5.3), less what long
//! cells cost ([`Score`]).

use crate::geom::LevelAdjacency;
use crate::neighborhood::Constraint;
use nptreemap_formats::Dataset;

/// Weight of a lifted deeper constraint in a level's score, against 1 for the
/// level's own: the leaf level is what Table 2 counts.
pub(super) const LIFTED_WEIGHT: usize = 2;

/// The constraints of one level, in level-local indices.
pub(super) struct LevelLinks {
    /// Level-local index of every node, `usize::MAX` off the level.
    pub(super) local: Vec<usize>,
    /// Node index of every level-local index.
    pub(super) nodes: Vec<usize>,
    /// Partners and scores per level-local index, Stage E order (§3.7): all
    /// score-100 links first, then by score descending; ties by index.
    pub(super) links: Vec<Vec<(usize, u8)>>,
    /// Constraints of deeper levels lifted to this level: per level-local index,
    /// the partners whose subtrees hold constrained pairs with its subtree, and
    /// how many. A deeper pair can only become neighbours across parents whose
    /// cells touch, so these count towards a level's score.
    pub(super) lifted: Vec<Vec<(usize, usize)>>,
}

impl LevelLinks {
    pub(super) fn new(
        dataset: &Dataset,
        level: &[usize],
        constraints: &[Constraint],
        depth: usize,
    ) -> Self {
        let mut local = vec![usize::MAX; dataset.len()];
        for (k, &i) in level.iter().enumerate() {
            local[i] = k;
        }
        let mut links = vec![Vec::new(); level.len()];
        for c in constraints {
            if dataset.node(c.a).depth != depth || c.score <= 1 {
                continue;
            }
            let (a, b) = (local[c.a], local[c.b]);
            if a == usize::MAX || b == usize::MAX {
                continue;
            }
            links[a].push((b, c.score));
            links[b].push((a, c.score));
        }
        for l in &mut links {
            l.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
        }
        let ancestor = |mut i: usize| {
            while dataset.node(i).depth > depth {
                match dataset.node(i).parent {
                    Some(p) => i = p,
                    None => break,
                }
            }
            local[i]
        };
        let mut counts = std::collections::BTreeMap::new();
        for c in constraints {
            if dataset.node(c.a).depth <= depth {
                continue;
            }
            let (a, b) = (ancestor(c.a), ancestor(c.b));
            if a != b && a != usize::MAX && b != usize::MAX {
                *counts.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
            }
        }
        let mut lifted = vec![Vec::new(); level.len()];
        for ((a, b), n) in counts {
            lifted[a].push((b, n));
            lifted[b].push((a, n));
        }
        Self {
            local,
            nodes: level.to_vec(),
            links,
            lifted,
        }
    }

    /// True when the level has nothing to preserve: no constraint of its own
    /// and none below it between different parents' subtrees.
    pub(super) fn is_empty(&self) -> bool {
        self.links.iter().all(Vec::is_empty) && self.lifted.iter().all(Vec::is_empty)
    }

    /// What the realised pairs of `a` (level-local) with partners `b` for which
    /// `count(b)` holds are worth: 1 per own constraint, [`LIFTED_WEIGHT`]
    /// per lifted one.
    pub(super) fn worth(&self, a: usize, count: impl Fn(usize) -> bool) -> usize {
        let own = self.links[a].iter().filter(|(b, _)| count(*b)).count();
        let deep: usize = self.lifted[a]
            .iter()
            .filter(|(b, _)| count(*b))
            .map(|(_, n)| n)
            .sum();
        own + LIFTED_WEIGHT * deep
    }

    /// The level's realised constraints for an adjacency: its own plus lifted
    /// deeper constraints across touching cells (weighted).
    pub(super) fn realized(&self, adjacency: &LevelAdjacency) -> usize {
        (0..self.nodes.len())
            .map(|a| self.worth(a, |b| b > a && adjacency.are_adjacent(a, b)))
            .sum()
    }

    /// The score of the link between `a` and `b`, if there is one.
    pub(super) fn score(&self, a: usize, b: usize) -> Option<u8> {
        self.links[a].iter().find(|(t, _)| *t == b).map(|(_, s)| *s)
    }
}

/// What a level's arrangement is worth: realised constraints (own plus
/// weighted lifted ones) against the shape of its cells.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Score {
    /// [`LevelLinks::realized`].
    pub(super) realized: usize,
    /// Σ over the level's cells of (bounding-box aspect − 1).
    pub(super) elongation: f64,
    /// [`NeighborParams::shape_weight`](super::NeighborParams::shape_weight).
    pub(super) shape_weight: f64,
}

impl Score {
    /// The one number states are compared by.
    pub(super) fn value(&self) -> f64 {
        self.realized as f64 - self.shape_weight * self.elongation
    }
}
