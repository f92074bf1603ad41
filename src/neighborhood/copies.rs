//! The bins of the virtual copies (paper §4, method-reference §2.2) derived
//! from their leaves' similarities instead of recomputed at every level
//! (issue 23 item 2).
//!
//! Level k holds its real nodes R_k and one copy of every leaf shallower than
//! k (C_k); C_{k+1} is C_k plus a copy of each leaf of R_k that heads a chain
//! (the heads H_k). A copy shares its leaf's features, so its row at level k is
//! the leaf's similarities to the other leaves of C_k, the same values at
//! every level, and its similarities to R_k. Each chain's leaf keeps a
//! [`ScoreTops`] of the first part (counts per score, each score's first
//! entries), started when the leaf is a head (its similarities to C_k and to
//! the other heads) and grown by the heads of every level below; the copy's
//! row is that summary merged with its fresh similarities to R_k, binned.
//! Real nodes' rows are computed as before, over the whole level. So the
//! copies' block C_k × C_k is never recomputed: per level the work is
//! R_k × level + C_k × R_k + H_k × (C_k + H_k) instead of level², and the
//! bins are bit for bit those of the full rows (tests below and in
//! `constraints.rs`).
//!
//! Orders: a copy sits at level k+1 where its parent sat at level k
//! (breadth-first order), so the leaves' copies keep one relative order on
//! every level, the order of the deepest level; summaries name leaves by
//! their position there (their rank) and are renamed to a level's positions
//! when merged, which keeps every tie where the full row puts it.
//!
//! Where it is used: Jaccard and binary similarity (rows from an index of the
//! columns, like `sparse_rows`). Not for neighbour lists (a copy lists no
//! relation: its row is empty and costs nothing already), nor for datasets
//! without copies or where an estimate of the pairs visited says it does not
//! pay. Not for cosine and Pearson either, though it derives their bins
//! exactly too (tested): its pairs are exact f64 one at a time, and the full
//! rows' f32-filtered scan and nearest-neighbour search were faster than the
//! work it saves (BENCHMARKS.md, "Copies' constraints derived from the
//! leaves").
//! Real rows of a level with copies are scanned, never searched through the
//! nearest-neighbour index of `knn_rows` (which indexes a level for all of
//! its rows); both give the same lists.

use rayon::prelude::*;
use std::collections::HashMap;

use nptreemap_formats::Dataset;

use super::bins::{Bins, BIN_HEAD};
use super::rows::{level_bins, level_rows_bins};
use super::score_tops::{ScoreTops, TopsBuilder};
use super::similarity::{pair_similarity, NodeFeatures, SimilarityKind};

/// Every node's bins (indexed like `prepared`) with the copies' rows derived
/// from their leaves', or `None` where derivation is not used (module docs);
/// `levels` are the nodes of each depth in breadth-first order, `sparse` as
/// for [`level_bins`].
pub(super) fn derived_bins(
    prepared: &Dataset,
    kind: SimilarityKind,
    levels: &[Vec<usize>],
    sparse: bool,
) -> Option<Vec<Bins>> {
    if !matches!(kind, SimilarityKind::Jaccard | SimilarityKind::Binary) {
        return None;
    }
    derive(prepared, kind, levels, sparse, true)
}

/// [`derived_bins`] for any measure but neighbour lists, whether it pays
/// (`check_cost`) or not.
fn derive(
    prepared: &Dataset,
    kind: SimilarityKind,
    levels: &[Vec<usize>],
    sparse: bool,
    check_cost: bool,
) -> Option<Vec<Bins>> {
    if kind == SimilarityKind::NeighborList {
        return None;
    }
    let nodes = prepared.nodes();
    let deepest = levels.last()?;
    // The original leaf of every copy (a copy's parent is its leaf or a copy).
    let mut leaf_of: Vec<usize> = (0..nodes.len()).collect();
    for (index, node) in nodes.iter().enumerate() {
        if node.is_virtual {
            leaf_of[index] = leaf_of[node.parent?];
        }
    }
    let mut rank = vec![u32::MAX; nodes.len()];
    for (position, &node) in deepest.iter().enumerate() {
        rank[leaf_of[node]] = u32::try_from(position).ok()?;
    }
    let roles: Vec<Vec<Role>> = levels
        .iter()
        .map(|level| level.iter().map(|&n| role(prepared, n)).collect())
        .collect();
    if !has_copies(&roles) || (check_cost && !pays(&roles)) {
        return None;
    }

    let mut chains = Chains {
        prepared,
        kind,
        sparse,
        rank,
        leaf_of,
        bins: vec![Bins::default(); nodes.len()],
        summaries: vec![None; deepest.len()],
        position_of_rank: vec![u32::MAX; deepest.len()],
    };
    for (level, roles) in levels.iter().zip(&roles).skip(1) {
        chains.level(level, roles);
    }
    Some(chains.bins)
}

/// What the derivation carries down the levels: every node's bins so far,
/// and per leaf rank its row over the copies of the current level other than
/// its own (leaves with a chain only, from the level of their head on).
struct Chains<'a> {
    prepared: &'a Dataset,
    kind: SimilarityKind,
    sparse: bool,
    /// Position of every original leaf in the deepest level.
    rank: Vec<u32>,
    /// The original leaf of every node (itself unless a copy).
    leaf_of: Vec<usize>,
    bins: Vec<Bins>,
    summaries: Vec<Option<ScoreTops>>,
    /// The current level's position of each leaf rank's copy.
    position_of_rank: Vec<u32>,
}

impl Chains<'_> {
    /// The bins of one level's nodes: real rows scanned, copies' rows derived.
    fn level(&mut self, level: &[usize], roles: &[Role]) {
        let (prepared, kind, sparse) = (self.prepared, self.kind, self.sparse);
        let of = |r: Role| -> Vec<usize> { (0..level.len()).filter(|&p| roles[p] == r).collect() };
        let (copies, heads) = (of(Role::Copy), of(Role::Head));
        if copies.is_empty() && heads.is_empty() {
            for (&node, node_bins) in level.iter().zip(level_bins(prepared, kind, level, sparse)) {
                self.bins[node] = node_bins;
            }
            return;
        }
        let reals: Vec<usize> = (0..level.len()).filter(|&p| roles[p] != Role::Copy).collect();
        let real_bins = if copies.is_empty() {
            level_bins(prepared, kind, level, sparse)
        } else {
            level_rows_bins(prepared, kind, level, Some(&reals), sparse)
        };
        for (&p, node_bins) in reals.iter().zip(real_bins) {
            self.bins[level[p]] = node_bins;
        }
        let others = of(Role::Other);
        self.chain_rows(level, copies, heads, others);
    }

    /// The rows of a level's copies (their leaf's summary renamed to the
    /// level, merged with fresh columns of the real nodes) and the heads'
    /// summaries for the levels below.
    fn chain_rows(
        &mut self,
        level: &[usize],
        copies: Vec<usize>,
        heads: Vec<usize>,
        others: Vec<usize>,
    ) {
        let (prepared, kind) = (self.prepared, self.kind);
        let features: Vec<NodeFeatures<'_>> = level
            .iter()
            .map(|&n| NodeFeatures::new(kind, prepared, n))
            .collect();
        let (rank, leaf_of) = (&self.rank, &self.leaf_of);
        let to_rank = |p: u32| rank[leaf_of[level[p as usize]]];
        for &p in &copies {
            self.position_of_rank[to_rank(p as u32) as usize] = p as u32;
        }
        let copy_columns = Columns::new(kind, &features, copies.clone());
        let head_columns = Columns::new(kind, &features, heads.clone());
        let other_columns = Columns::new(kind, &features, others);
        let row_of = |tops: &mut TopsBuilder, p: usize, columns: &Columns| {
            columns.row(kind, &features, level, p, tops)
        };
        let (summaries, position_of_rank) = (&self.summaries, &self.position_of_rank);
        // Copies: the leaf's summary, renamed to this level, and the fresh
        // columns of the real nodes.
        let derived: Vec<(Bins, Option<ScoreTops>)> = copies
            .par_iter()
            .map_init(TopsBuilder::default, |tops, &p| {
                let leaf = to_rank(p as u32) as usize;
                let summary = summaries[leaf]
                    .as_ref()
                    .expect("invariant: a copy's leaf was summarised at its head");
                let to_heads = row_of(tops, p, &head_columns);
                let mut row = summary.clone().renamed(|r| position_of_rank[r as usize]);
                row.merge(&row_of(tops, p, &other_columns));
                row.merge(&to_heads);
                let grown = (!heads.is_empty()).then(|| {
                    let mut grown = summary.clone();
                    grown.merge(&to_heads.renamed(to_rank));
                    grown
                });
                (row.bins(level.len(), level), grown)
            })
            .collect();
        for (&p, (node_bins, grown)) in copies.iter().zip(derived) {
            self.bins[level[p]] = node_bins;
            if let Some(grown) = grown {
                self.summaries[to_rank(p as u32) as usize] = Some(grown);
            }
        }
        // Heads: their leaf's row over the copies and the other heads, which
        // are the copies of the level below.
        let started: Vec<ScoreTops> = heads
            .par_iter()
            .map_init(TopsBuilder::default, |tops, &p| {
                let mut summary = row_of(tops, p, &copy_columns);
                summary.merge(&row_of(tops, p, &head_columns));
                summary.renamed(to_rank)
            })
            .collect();
        for (&p, summary) in heads.iter().zip(started) {
            self.summaries[to_rank(p as u32) as usize] = Some(summary);
        }
    }
}

/// What a node is on its level, for the derivation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// A virtual copy of a shallower leaf.
    Copy,
    /// A leaf that heads a chain of copies (its only child is a copy).
    Head,
    /// Any other real node.
    Other,
}

fn role(prepared: &Dataset, index: usize) -> Role {
    let node = prepared.node(index);
    if node.is_virtual {
        Role::Copy
    } else if node.children.len() == 1 && prepared.node(node.children[0]).is_virtual {
        Role::Head
    } else {
        Role::Other
    }
}

/// True when some level holds a copy.
fn has_copies(roles: &[Vec<Role>]) -> bool {
    roles.iter().flatten().any(|&r| r == Role::Copy)
}

/// True when the pairs the derivation visits are fewer than the full rows'
/// on the levels it touches (a proxy: the sparse rows visit only pairs that
/// share a member, in the same proportion on both sides).
fn pays(roles: &[Vec<Role>]) -> bool {
    let (mut full, mut derived) = (0u64, 0u64);
    for level in roles {
        let count = |r: Role| level.iter().filter(|&&x| x == r).count() as u64;
        let (copies, heads, all) = (count(Role::Copy), count(Role::Head), level.len() as u64);
        if copies + heads == 0 {
            continue;
        }
        let reals = all - copies;
        full += all * all;
        derived += reals * all + copies * reals + heads * (copies + heads);
    }
    derived < full
}

/// A set of a level's positions (ascending) indexed for one measure, for rows
/// over those columns alone.
struct Columns {
    positions: Vec<usize>,
    index: Index,
}

enum Index {
    /// Every column is visited (cosine, Pearson).
    All,
    /// Jaccard: per support coordinate, the columns holding it.
    Supports(HashMap<u32, Vec<u32>>),
    /// Binary: the columns of each vector.
    Equal(HashMap<Vec<u64>, Vec<u32>>),
}

impl Columns {
    fn new(kind: SimilarityKind, features: &[NodeFeatures<'_>], positions: Vec<usize>) -> Self {
        let index = match kind {
            SimilarityKind::Jaccard => {
                let mut postings: HashMap<u32, Vec<u32>> = HashMap::new();
                for &p in &positions {
                    if features[p].len().is_some() {
                        for &k in features[p].support() {
                            postings.entry(k).or_default().push(p as u32);
                        }
                    }
                }
                Index::Supports(postings)
            }
            SimilarityKind::Binary => {
                let mut groups: HashMap<Vec<u64>, Vec<u32>> = HashMap::new();
                for &p in &positions {
                    if let Some(key) = features[p].binary_key() {
                        groups.entry(key).or_default().push(p as u32);
                    }
                }
                Index::Equal(groups)
            }
            _ => Index::All,
        };
        Columns { positions, index }
    }

    /// The summary of position `row`'s similarities to these columns (itself
    /// left out), ids the columns' positions.
    fn row(
        &self,
        kind: SimilarityKind,
        features: &[NodeFeatures<'_>],
        level: &[usize],
        row: usize,
        tops: &mut TopsBuilder,
    ) -> ScoreTops {
        tops.reset();
        let a = &features[row];
        // Columns of non-zero similarity, ascending (sparse measures).
        let mut shown: Vec<usize> = Vec::new();
        match &self.index {
            Index::All => {
                for &j in self.positions.iter().filter(|&&j| j != row) {
                    tops.take(pair_similarity(kind, a, &features[j], level[j]), j as u32);
                }
                return tops.finish();
            }
            Index::Supports(postings) => {
                if let Some(len) = a.len() {
                    let mut touched: Vec<u32> = a
                        .support()
                        .iter()
                        .filter_map(|k| postings.get(k))
                        .flatten()
                        .copied()
                        .collect();
                    touched.sort_unstable();
                    touched.dedup();
                    for j in touched.into_iter().map(|j| j as usize) {
                        let b = &features[j];
                        if j != row && b.len() == Some(len) {
                            let s = pair_similarity(SimilarityKind::Jaccard, a, b, level[j]);
                            if s != 0.0 {
                                tops.take(s, j as u32);
                                shown.push(j);
                            }
                        }
                    }
                }
            }
            Index::Equal(groups) => {
                let members = a.binary_key().and_then(|key| groups.get(&key));
                for &j in members.into_iter().flatten() {
                    if j as usize != row {
                        tops.take(1.0, j);
                        shown.push(j as usize);
                    }
                }
            }
        }
        // The rest are exact zeros: counted, and the first of them offered.
        let with_row = usize::from(self.positions.binary_search(&row).is_ok());
        tops.count_zeros(self.positions.len() - with_row - shown.len());
        let mut next = shown.iter().peekable();
        let mut offered = 0;
        for &j in self.positions.iter().filter(|&&j| j != row) {
            if offered == BIN_HEAD {
                break;
            }
            while next.next_if(|&&s| s < j).is_some() {}
            if next.peek() != Some(&&j) {
                tops.keep_zero(j as u32);
                offered += 1;
            }
        }
        tops.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::super::bins::stage_view;
    use super::super::constraints::{constraint_lists, constraint_lists_recomputed};
    use super::super::prepare::prepare;
    use super::*;
    use crate::rng::Rng;
    use nptreemap_formats::{DatasetBuilder, NodeSpec, SparseVector};

    /// A bin as (count, head as (similarity bits, node, score)).
    type BinBits = (usize, Vec<(u64, usize, u8)>);

    /// The old path: every row of every level computed.
    fn recomputed(p: &Dataset, kind: SimilarityKind, sparse: bool) -> Vec<Bins> {
        let mut levels: Vec<Vec<usize>> = vec![Vec::new(); p.max_depth() + 1];
        for (index, node) in p.nodes().iter().enumerate() {
            levels[node.depth].push(index);
        }
        let mut bins = vec![Bins::default(); p.len()];
        for level in levels.iter().skip(1) {
            for (&node, b) in level.iter().zip(level_bins(p, kind, level, sparse)) {
                bins[node] = b;
            }
        }
        bins
    }

    /// Derived and recomputed bins and lists of a prepared dataset, compared
    /// bit for bit (similarities by their bits); true when the derivation ran.
    fn same_as_recomputed(p: &Dataset, kind: SimilarityKind, what: &str) -> bool {
        let mut levels: Vec<Vec<usize>> = vec![Vec::new(); p.max_depth() + 1];
        for (index, node) in p.nodes().iter().enumerate() {
            levels[node.depth].push(index);
        }
        let bits = |bins: &[Bins]| -> Vec<Vec<BinBits>> {
            bins.iter()
                .map(|b| {
                    stage_view(b)
                        .bins
                        .iter()
                        .map(|bin| {
                            let head = bin
                                .head
                                .iter()
                                .map(|c| (c.similarity.to_bits(), c.node, c.score))
                                .collect();
                            (bin.len, head)
                        })
                        .collect()
                })
                .collect()
        };
        let mut derived_any = false;
        for sparse in [true, false] {
            let old = recomputed(p, kind, sparse);
            if let Some(new) = derive(p, kind, &levels, sparse, false) {
                derived_any = true;
                assert_eq!(bits(&new), bits(&old), "{what}, {kind:?}, sparse {sparse}");
                // The sparse measures' rows are full bins (the dense ones'
                // are stage views, `row_best`).
                if !matches!(kind, SimilarityKind::Cosine | SimilarityKind::Pearson) {
                    assert_eq!(new, old, "{what}, {kind:?}, sparse {sparse}: full bins");
                }
            }
        }
        assert_eq!(
            constraint_lists(p, kind),
            constraint_lists_recomputed(p, kind),
            "{what}, {kind:?}"
        );
        derived_any
    }

    /// A tree of leaves at every depth from 1 to `depth` (so chains of copies
    /// of every length), internal nodes of 1 to 5 children, leaf features from
    /// `leaf`.
    fn uneven_tree(
        seed: u64,
        leaves: usize,
        depth: usize,
        mut leaf: impl FnMut(&mut Rng, usize) -> NodeSpec,
    ) -> Dataset {
        let mut rng = Rng::new(seed);
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        // Open internal nodes with their depth; a leaf hangs under a random one.
        let mut open: Vec<(String, usize)> = vec![("r".into(), 0)];
        let mut made = 0;
        let mut groups = 0;
        while made < leaves {
            let (parent, d) = open[(rng.next_u64() % open.len() as u64) as usize].clone();
            if d + 1 < depth && rng.next_u64() % 3 == 0 {
                let id = format!("g{groups}");
                groups += 1;
                builder.add(NodeSpec::new(id.clone()).parent(parent));
                open.push((id, d + 1));
                continue;
            }
            builder.add(leaf(&mut rng, made).parent(parent));
            made += 1;
        }
        // Internal nodes without a leaf get one, so every group is a subtree.
        let ids: Vec<(String, usize)> = open.into_iter().skip(1).collect();
        for (id, _) in ids {
            builder.add(NodeSpec::new(format!("{id}-leaf")).parent(id).weight(1.0));
        }
        builder.build().expect("valid")
    }

    /// Sets over 60 members drawn with a skewed (about Zipf) distribution, a
    /// fifth of them repeated exactly, some empty and some missing.
    fn set_leaf(rng: &mut Rng, i: usize, seen: &mut Vec<Vec<u32>>) -> NodeSpec {
        let spec = NodeSpec::new(format!("n{i}")).weight(1.0 + (i % 3) as f64);
        match rng.next_u64() % 10 {
            0 => spec,
            1 if !seen.is_empty() => {
                let again = seen[(rng.next_u64() % seen.len() as u64) as usize].clone();
                spec.features(SparseVector::set(60, again).expect("set"))
            }
            _ => {
                let size = rng.next_u64() % 6;
                let members: Vec<u32> = (0..size)
                    .map(|_| {
                        let u = (rng.next_u64() % 1000) as f64 / 1000.0;
                        (60.0 * u * u * u) as u32
                    })
                    .collect();
                let mut sorted = members.clone();
                sorted.sort_unstable();
                sorted.dedup();
                seen.push(sorted.clone());
                spec.features(SparseVector::set(60, sorted).expect("set"))
            }
        }
    }

    #[test]
    fn skewed_sets_derive_the_recomputed_bins() {
        let mut derived = 0;
        for seed in 0..24 {
            let leaves = [5, 12, 40, 150][seed as usize % 4];
            let depth = 2 + seed as usize % 5;
            let mut seen = Vec::new();
            let d = uneven_tree(seed, leaves, depth, |rng, i| set_leaf(rng, i, &mut seen));
            let p = prepare(&d);
            for kind in [
                SimilarityKind::Jaccard,
                SimilarityKind::Binary,
                SimilarityKind::Cosine,
            ] {
                derived += usize::from(same_as_recomputed(&p, kind, &format!("seed {seed}")));
            }
        }
        assert!(derived > 30, "the derivation ran on {derived} cases only");
    }

    #[test]
    fn uneven_dense_trees_with_duplicates_derive_the_recomputed_bins() {
        let mut derived = 0;
        for seed in 0..16 {
            let leaves = [6, 30, 120, 260][seed as usize % 4];
            let depth = 2 + seed as usize % 4;
            let mut earlier: Vec<Vec<f64>> = Vec::new();
            let d = uneven_tree(100 + seed, leaves, depth, |rng, i| {
                let spec = NodeSpec::new(format!("n{i}")).weight(1.0);
                let v: Vec<f64> = match rng.next_u64() % 8 {
                    // Exact duplicates (ties broken by level order) and a
                    // scaled copy (equal cosine, other bits on the way).
                    0 | 1 if !earlier.is_empty() => {
                        earlier[(rng.next_u64() % earlier.len() as u64) as usize].clone()
                    }
                    2 if !earlier.is_empty() => earlier[0].iter().map(|x| 4.0 * x).collect(),
                    3 => vec![0.0; 5],
                    // Few distinct values: many similarities on one score.
                    _ => (0..5).map(|_| (rng.next_u64() % 3) as f64 - 1.0).collect(),
                };
                earlier.push(v.clone());
                spec.features(v)
            });
            let p = prepare(&d);
            for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson, SimilarityKind::Binary] {
                derived += usize::from(same_as_recomputed(&p, kind, &format!("seed {seed}")));
            }
        }
        assert!(derived > 20, "the derivation ran on {derived} cases only");
    }

    #[test]
    fn paper_datasets_derive_the_recomputed_lists() {
        for name in [
            "flare.json",
            "cifar10.json",
            "imdb_100_genre_sim_2child.json",
            "country_pop_50M_AUS.json",
            "2_level_4_cousin_constraints.json",
            "syntheticPoints_10nodes_2components.json",
        ] {
            let p = prepare(&super::super::prepare::test_data::dataset(name));
            let kind = SimilarityKind::for_dataset(&p);
            same_as_recomputed(&p, kind, name);
        }
    }
}
