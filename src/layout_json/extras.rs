//! What a layout-JSON document carries beyond the dataset and the geometry:
//! the constraints with their `realized` flags and the producer's own quality
//! figures, taken from a finished computation. Owns that selection; the writer
//! (`super::write`) owns how it is spelled.
//!
//! A constraint is listed once even where the paper's uniform depth repeats
//! it: an only child takes its parent's cell unchanged, so two nodes with one
//! child each whose children carry the same constraint (same similarity,
//! strength and flag) are that constraint again, one level up. Down a chain
//! of virtual copies (paper §4) the leaf constraints came back at every level
//! (on a 6,000-leaf C-headers tree, 86,000 of 113,000 entries). Only the
//! lowest of such a run is written, with `also_above: k` (a field the
//! contract allows) saying that the k levels above it hold it too, between
//! the two nodes' ancestors; the reader gives the pairs back.

use std::sync::{Arc, OnceLock};

use nptreemap_formats::Dataset;
use serde::Serialize;

use crate::layout::{Computed, ZeroItems};
use crate::measure;

/// One neighbourhood constraint as written to the `constraints` array.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConstraintOut {
    /// Id of one node (same depth as `b`); the pair is undirected and listed once.
    pub a: String,
    /// Id of the other node.
    pub b: String,
    /// Value of the similarity function, in `[0, 1]`.
    pub similarity: f64,
    /// 1 (weak) to 3 (strong): the bin the constraint came from.
    pub strength: u8,
    /// True when the two cells share an edge in this layout.
    pub realized: bool,
    /// How many levels above this one hold the same constraint between the
    /// ancestors of `a` and `b` (each an only child up to there); see the
    /// module doc. Written only when above 0.
    pub also_above: usize,
}

/// What the layout JSON carries beyond the dataset and the geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JsonExtras {
    /// The `constraints` array, written in this order. Default: empty.
    pub constraints: Arc<ConstraintList>,
    /// The producer's own figures, written as the `metrics` object in this order
    /// (keys should be unique); the field is left out when empty. Default: empty.
    pub metrics: Vec<(String, f64)>,
    /// Write coordinates in full precision instead of rounding them to six
    /// places: for the layout kept for warm starts (issue 6), which must
    /// reproduce the cells bit for bit so that a rebuild of unchanged data
    /// gives unchanged bytes. Default: false.
    pub exact: bool,
    /// What became of the items of weight 0 (issue 34): written, when there
    /// were any, as `zero_weights` (the setting and the count) and `hidden`
    /// (the nodes left out, without cells). Default: none.
    pub zero: Arc<ZeroItems>,
    /// Per node, the weight it is drawn at when that is not its value
    /// (`zero_weights: floor`, [`Computed::drawn_weights`]): written as the
    /// node's `drawn_weight`, the weight its metrics are measured against.
    /// Default: `None`.
    pub drawn_weights: Option<Vec<f64>>,
}

impl JsonExtras {
    /// The constraints and quality figures of a finished computation, with
    /// coordinates rounded (`exact: false`).
    pub fn of(computed: &Computed) -> JsonExtras {
        JsonExtras::with_list(computed, Arc::new(ConstraintList::of(computed)))
    }

    /// [`JsonExtras::of`] with its constraints given: `list` must be
    /// [`ConstraintList::of`] the same computation (or of one with the same
    /// [`ConstraintList::key`]).
    pub(super) fn with_list(computed: &Computed, list: Arc<ConstraintList>) -> JsonExtras {
        let q = measure::drawn_quality(computed);
        JsonExtras {
            constraints: list,
            metrics: vec![
                (
                    "area_error_diagram_mean".to_string(),
                    q.area_error_diagram_mean,
                ),
                (
                    "area_error_diagram_max".to_string(),
                    q.area_error_diagram_max,
                ),
                ("aspect_ratio_mean".to_string(), q.aspect_ratio_mean),
            ],
            exact: false,
            zero: Arc::clone(&computed.zero),
            drawn_weights: computed.drawn_weights(),
        }
    }
}

/// The `constraints` array of a document and what its writers share: the
/// nodes of each entry (so the precision choice need not look its ids up)
/// and, once written, the array's text, which the stored layout and the
/// `.json` output spell alike. One computation's documents share it, and so
/// does the next computation's when its constraints, their flags and its
/// nodes are the same (a weight edit; issue 32): at 6,000 C headers its
/// 27,000 entries took a fifth of the stored layout's time, each build.
#[derive(Clone, Debug, Default)]
pub struct ConstraintList {
    /// The entries, in the order written.
    entries: Vec<ConstraintOut>,
    /// Per entry, its two nodes' indices in the dataset it was taken from;
    /// empty for a list made from entries alone (the writer then looks the
    /// ids up).
    nodes: Vec<(usize, usize)>,
    /// The array's text, once written.
    text: OnceLock<String>,
}

impl PartialEq for ConstraintList {
    fn eq(&self, other: &ConstraintList) -> bool {
        self.entries == other.entries
    }
}

impl From<Vec<ConstraintOut>> for ConstraintList {
    fn from(entries: Vec<ConstraintOut>) -> ConstraintList {
        ConstraintList {
            entries,
            ..ConstraintList::default()
        }
    }
}

impl ConstraintList {
    /// The constraints of a finished computation, as written: a run of
    /// copies' constraints folded into its lowest (module doc).
    pub fn of(computed: &Computed) -> ConstraintList {
        let ds = &computed.dataset;
        let links: Vec<Link> = computed
            .constraints
            .iter()
            .map(|c| (c.a, c.b, c.similarity, c.strength))
            .collect();
        let above = repeats_above(ds, &links, &computed.realized);
        let (entries, nodes) = computed
            .constraints
            .iter()
            .zip(&computed.realized)
            .zip(above)
            .filter_map(|((c, r), above)| {
                let entry = ConstraintOut {
                    a: ds.node(c.a).id.clone(),
                    b: ds.node(c.b).id.clone(),
                    similarity: c.similarity,
                    strength: c.strength,
                    realized: *r,
                    also_above: above?,
                };
                Some((entry, (c.a, c.b)))
            })
            .unzip();
        ConstraintList {
            entries,
            nodes,
            text: OnceLock::new(),
        }
    }

    /// What [`ConstraintList::of`] reads of a computation: its constraints
    /// with their flags, and its nodes' ids and tree (what decides the
    /// folding and the indices), as a 128-bit digest. Equal keys give equal
    /// lists.
    pub fn key(computed: &Computed) -> u128 {
        // One buffer hashed at once: a hasher call per field of 113,000
        // constraints cost more than the bytes.
        let ds = &computed.dataset;
        let mut bytes = Vec::with_capacity(32 * computed.constraints.len() + 24 * ds.len());
        let put = |bytes: &mut Vec<u8>, v: u64| bytes.extend_from_slice(&v.to_le_bytes());
        put(&mut bytes, computed.constraints.len() as u64);
        put(&mut bytes, computed.realized.len() as u64);
        for (c, r) in computed.constraints.iter().zip(&computed.realized) {
            put(&mut bytes, c.a as u64);
            put(&mut bytes, c.b as u64);
            put(&mut bytes, c.similarity.to_bits());
            put(&mut bytes, u64::from(c.strength) << 1 | u64::from(*r));
        }
        put(&mut bytes, ds.len() as u64);
        for node in ds.nodes() {
            put(&mut bytes, node.parent.map_or(u64::MAX, |p| p as u64));
            put(&mut bytes, node.children.len() as u64);
            put(&mut bytes, node.id.len() as u64);
            bytes.extend_from_slice(node.id.as_bytes());
        }
        xxhash_rust::xxh3::xxh3_128(&bytes)
    }

    /// The entries, in the order written.
    pub fn entries(&self) -> &[ConstraintOut] {
        &self.entries
    }

    /// How many entries the array has.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the array is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Per entry, its two nodes in the dataset the list was taken from,
    /// when the list knows them.
    pub(super) fn nodes(&self) -> Option<&[(usize, usize)]> {
        (self.nodes.len() == self.entries.len()).then_some(&self.nodes)
    }

    /// The array's text: `write`'s the first time, kept for the next.
    pub(super) fn text(&self, write: impl FnOnce() -> String) -> &str {
        self.text.get_or_init(write)
    }
}

/// A constraint as the fold compares it: nodes `a` and `b`, similarity and
/// strength (a tuple, so this format does not depend on the constraint
/// pipeline's types).
type Link = (usize, usize, f64, u8);

/// Per constraint: `None` when it repeats the one between the only children
/// of its two nodes (it is then left out), else how many levels above it
/// repeat it. Walks each run once, upward from its lowest constraint.
fn repeats_above(ds: &Dataset, constraints: &[Link], realized: &[bool]) -> Vec<Option<usize>> {
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    // Only a constraint between two nodes of one child each can be another's
    // one level up: the index holds those alone (at 6,000 C headers, a
    // fraction of the 113,000 constraints; the whole set took 28 ms a call).
    let single = |n: usize| ds.node(n).children.len() == 1;
    let index = PairIndex::new(
        ds.len(),
        constraints
            .iter()
            .enumerate()
            .filter(|(_, c)| single(c.0) && single(c.1))
            .map(|(i, c)| (key(c.0, c.1), i)),
    );
    let same = |i: usize, j: usize| {
        let (x, y) = (&constraints[i], &constraints[j]);
        x.2.to_bits() == y.2.to_bits() && x.3 == y.3 && realized.get(i) == realized.get(j)
    };
    // The constraint between the parents of `i`'s nodes when each is their
    // parent's only child and it carries the same values: `i` one level up.
    let only_child_of = |n: usize| {
        let p = ds.node(n).parent?;
        single(p).then_some(p)
    };
    let ups: Vec<Option<usize>> = constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let j = index.get(key(only_child_of(c.0)?, only_child_of(c.1)?))?;
            same(i, j).then_some(j)
        })
        .collect();
    let up = |i: usize| ups[i];
    let mut out = vec![Some(0); constraints.len()];
    let mut repeated = vec![false; constraints.len()];
    for i in 0..constraints.len() {
        // Each step climbs a level, so a run is at most the depth long.
        let mut j = i;
        while let Some(k) = up(j).filter(|&k| !repeated[k]) {
            repeated[k] = true;
            j = k;
        }
    }
    for i in 0..constraints.len() {
        if repeated[i] {
            out[i] = None;
            continue;
        }
        let mut count = 0;
        let mut j = i;
        while let Some(k) = up(j) {
            count += 1;
            j = k;
        }
        out[i] = Some(count);
    }
    out
}

/// Constraints by their pair of nodes `(lo, hi)`: each node's pairs where
/// it is `lo`, in one array (counted, then filled). A node's pairs are few,
/// so a lookup scans them; no hashing (a `HashMap` of the 86,000 pairs of
/// 6,000 C headers took most of this fold's 20 ms).
struct PairIndex {
    /// Where node `lo`'s pairs start in `pairs`; one more entry than nodes.
    start: Vec<usize>,
    /// `(hi, constraint)` per pair, grouped by `lo`.
    pairs: Vec<(usize, usize)>,
}

impl PairIndex {
    fn new(nodes: usize, entries: impl Iterator<Item = ((usize, usize), usize)> + Clone) -> Self {
        let mut start = vec![0usize; nodes + 2];
        for ((lo, _), _) in entries.clone() {
            start[lo + 2] += 1;
        }
        for k in 2..start.len() {
            start[k] += start[k - 1];
        }
        let mut pairs = vec![(0, 0); start[nodes + 1]];
        for ((lo, hi), i) in entries {
            pairs[start[lo + 1]] = (hi, i);
            start[lo + 1] += 1;
        }
        start.pop();
        PairIndex { start, pairs }
    }

    /// The last constraint listed for pair `(lo, hi)` (a pair is listed
    /// once; were it not, the last wins, as in a map filled in order).
    fn get(&self, (lo, hi): (usize, usize)) -> Option<usize> {
        let range = *self.start.get(lo)?..*self.start.get(lo + 1)?;
        self.pairs[range]
            .iter()
            .rev()
            .find(|p| p.0 == hi)
            .map(|p| p.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_index_finds_each_pair_and_the_last_of_a_repeat() {
        let entries = [
            ((0, 3), 0),
            ((2, 5), 1),
            ((0, 4), 2),
            ((2, 5), 3),
            ((6, 7), 4),
        ];
        let index = PairIndex::new(8, entries.iter().copied());
        assert_eq!(index.get((0, 3)), Some(0));
        assert_eq!(index.get((0, 4)), Some(2));
        assert_eq!(index.get((2, 5)), Some(3), "the last listed wins");
        assert_eq!(index.get((6, 7)), Some(4));
        assert_eq!(index.get((0, 5)), None);
        assert_eq!(index.get((7, 8)), None, "a node without pairs");
        assert_eq!(index.get((9, 10)), None, "past the nodes");
    }
}
