//! Exact similarity rows without all-pairs work, for the measures whose similarity is
//! 0 for most pairs (issue 12 item 3): neighbour lists (a node is similar only to the
//! nodes it lists), binary equality (only to nodes with an identical vector) and
//! Jaccard (only to nodes whose support shares a coordinate, found through an
//! inverted index). A row holds what the binning of method-reference §3.2 reads from a
//! node's similarities to the rest of its level: every non-zero similarity that can
//! reach a bin's head, counts of the others, and the first zeros in breadth-first
//! order. The bins built from it are bit for bit those of the all-pairs scan
//! (tested against it in `constraints.rs`). Cosine and Pearson have no such
//! structure (every pair is non-zero) and keep the all-pairs scan.

use std::collections::HashMap;

use super::similarity::{pair_similarity, NodeFeatures, SimilarityKind};

/// What the binning of one node needs from its row.
#[derive(Clone, Debug, Default)]
pub(crate) struct SparseRow {
    /// Other nodes of the level (positions, ascending) with a non-zero similarity
    /// that may enter a bin's head, with that similarity.
    pub(crate) shown: Vec<(usize, f64)>,
    /// Further nodes with the similarity of `hidden.0`, `hidden.1` of them, all after
    /// at least [`HEAD`] shown nodes of the same similarity in level order, so they
    /// can only count.
    pub(crate) hidden: Option<(f64, usize)>,
    /// How many other nodes of the level have similarity exactly 0.
    pub(crate) zeros: usize,
    /// The first (up to [`HEAD`]) of those, positions ascending.
    pub(crate) zero_head: Vec<usize>,
}

/// Entries of a bin's head that the binning keeps (`constraints::BIN_HEAD`).
pub(crate) const HEAD: usize = 8;

/// A level indexed for one sparse measure; `None` from [`SparseLevel::new`] for the
/// dense ones (cosine, Pearson).
pub(crate) enum SparseLevel {
    /// Neighbour lists: rows come from each node's relations.
    Relations,
    /// Binary: nodes grouped by identical vector.
    Equal {
        /// Group of each position.
        group: Vec<usize>,
        /// Members of each group, positions ascending: only the first `HEAD + 1`.
        first_members: Vec<Vec<usize>>,
        /// Size of each group.
        sizes: Vec<usize>,
        /// First `HEAD` positions outside each group, ascending.
        first_outside: Vec<Vec<usize>>,
    },
    /// Jaccard: positions holding each support coordinate, ascending.
    Supports { postings: Vec<Vec<u32>> },
}

impl SparseLevel {
    /// The index of a level (`features[j]` is the node at position `j`), or `None`
    /// when `kind` is dense.
    pub(crate) fn new(kind: SimilarityKind, features: &[NodeFeatures<'_>]) -> Option<Self> {
        match kind {
            SimilarityKind::Cosine | SimilarityKind::Pearson => None,
            SimilarityKind::NeighborList => Some(SparseLevel::Relations),
            SimilarityKind::Binary => Some(equal_groups(features)),
            SimilarityKind::Jaccard => {
                let width = features
                    .iter()
                    .filter_map(|f| f.support().last())
                    .max()
                    .map_or(0, |&m| m as usize + 1);
                let mut postings: Vec<Vec<u32>> = vec![Vec::new(); width];
                for (j, f) in features.iter().enumerate() {
                    if f.len().is_some() {
                        for &k in f.support() {
                            postings[k as usize].push(j as u32);
                        }
                    }
                }
                Some(SparseLevel::Supports { postings })
            }
        }
    }

    /// The row of position `i`. `level[j]` is the dataset index at position `j`;
    /// `counts` is scratch space (reused between calls, grown as needed).
    pub(crate) fn row(
        &self,
        features: &[NodeFeatures<'_>],
        level: &[usize],
        i: usize,
        counts: &mut Vec<u32>,
    ) -> SparseRow {
        let others = level.len() - 1;
        let mut row = SparseRow::default();
        match self {
            SparseLevel::Relations => {
                // Directed: the nodes `i` lists, on this level (levels are ascending
                // dataset indices), itself excluded, each once.
                for &target in features[i].relations() {
                    if let Ok(j) = level.binary_search(&target) {
                        if j != i && row.shown.last().is_none_or(|&(last, _)| last != j) {
                            row.shown.push((j, 1.0));
                        }
                    }
                }
                row.zeros = others - row.shown.len();
                // The neighbour-list binning ignores zeros (one bin, §3.2 variant).
            }
            SparseLevel::Equal {
                group,
                first_members,
                sizes,
                first_outside,
            } => {
                let g = group[i];
                row.shown = first_members[g]
                    .iter()
                    .filter(|&&j| j != i)
                    .take(HEAD)
                    .map(|&j| (j, 1.0))
                    .collect();
                let equal = sizes[g] - 1;
                if equal > row.shown.len() {
                    row.hidden = Some((1.0, equal - row.shown.len()));
                }
                row.zeros = others - equal;
                row.zero_head = first_outside[g].clone();
            }
            SparseLevel::Supports { postings } => {
                let a = &features[i];
                let Some(len) = a.len() else {
                    row.zeros = others;
                    row.zero_head = (0..level.len()).filter(|&j| j != i).take(HEAD).collect();
                    return row;
                };
                counts.clear();
                counts.resize(level.len(), 0);
                let mut touched: Vec<usize> = Vec::new();
                for &k in a.support() {
                    for &j in &postings[k as usize] {
                        let j = j as usize;
                        if counts[j] == 0 {
                            touched.push(j);
                        }
                        counts[j] += 1;
                    }
                }
                touched.sort_unstable();
                for &j in &touched {
                    let b = &features[j];
                    // Different lengths have no similarity (as `vector_similarity`).
                    if j != i && b.len() == Some(len) {
                        // The measure itself: a dense and a sparse vector of one
                        // length are still unrelated.
                        let s = pair_similarity(SimilarityKind::Jaccard, a, b, level[j]);
                        if s != 0.0 {
                            row.shown.push((j, s));
                        }
                    }
                }
                for &j in &touched {
                    counts[j] = 0;
                }
                row.zeros = others - row.shown.len();
                // First zeros: positions not shown and not `i`, walking both in order.
                let mut next = row.shown.iter().map(|&(j, _)| j).peekable();
                for j in (0..level.len()).filter(|&j| j != i) {
                    if row.zero_head.len() == HEAD {
                        break;
                    }
                    while next.peek().is_some_and(|&s| s < j) {
                        next.next();
                    }
                    if next.peek() != Some(&j) {
                        row.zero_head.push(j);
                    }
                }
            }
        }
        row
    }
}

/// Groups of identical vectors (`==` per element, so −0 equals 0 and NaN equals
/// nothing; lengths must match; a missing vector equals nothing; sets by their
/// members), as `vector_similarity` decides binary similarity.
fn equal_groups(features: &[NodeFeatures<'_>]) -> SparseLevel {
    let mut ids: HashMap<Vec<u64>, usize> = HashMap::new();
    let mut group = Vec::with_capacity(features.len());
    let mut sizes: Vec<usize> = Vec::new();
    let mut first_members: Vec<Vec<usize>> = Vec::new();
    for (j, f) in features.iter().enumerate() {
        let g = match f.binary_key() {
            Some(key) => *ids.entry(key).or_insert(sizes.len()),
            None => sizes.len(),
        };
        if g == sizes.len() {
            sizes.push(0);
            first_members.push(Vec::new());
        }
        sizes[g] += 1;
        if first_members[g].len() <= HEAD {
            first_members[g].push(j);
        }
        group.push(g);
    }
    // First positions outside each group: each walk passes at most `HEAD` outsiders
    // and its own members, so all walks together cost O(n + groups · HEAD).
    let first_outside = (0..sizes.len())
        .map(|g| {
            group
                .iter()
                .enumerate()
                .filter(|&(_, &h)| h != g)
                .map(|(j, _)| j)
                .take(HEAD)
                .collect()
        })
        .collect();
    SparseLevel::Equal {
        group,
        first_members,
        sizes,
        first_outside,
    }
}
