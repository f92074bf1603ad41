//! The constraint pipeline of the prototype (method-reference §3.1–3.6): per-node
//! similarity lists over a whole level, min–max binning, the capped top bin
//! (Stage A), propagation to parents (Stage B), one extra link per following bin
//! (Stage C) and symmetrisation (Stage D), ending in the unordered pairs with
//! score > 1 that the paper counts. Stage E (the optimiser's per-round reordering)
//! is left to the optimiser; it can be derived from `ConstraintLists`. This file
//! holds the results and runs the parts in order: a level's bins (`rows`,
//! `bins`), then the stages (`stages`).

use std::collections::BTreeMap;

use nptreemap_formats::Dataset;

use super::bins::Bins;
use super::copies::derived_bins;
use super::rows::level_bins;
use super::similarity::{clamp_unit, pair_similarity, NodeFeatures, SimilarityKind};
use super::stages;
pub use super::stages::ListEntry;

/// A pair is a constraint when its score exceeds this (§3.6: `s > 1`).
const MIN_PAIR_SCORE: u8 = 1;

/// One undirected constraint between two nodes at the same depth of a prepared
/// dataset (one with virtual nodes for a uniform leaf depth).
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Index of the first node in the prepared dataset; `a < b`.
    pub a: usize,
    /// Index of the second node, at the same depth as `a`.
    pub b: usize,
    /// The pipeline's integer score in 2..=100: the larger of the scores the two
    /// directed lists hold for the pair (a propagated link carries its child
    /// link's score, §3.4).
    pub score: u8,
    /// The raw similarity of the two nodes in [0, 1], recomputed from the measure
    /// (for the directed neighbour flag, the larger of both directions).
    pub similarity: f64,
    /// 1..=3 for the layout JSON: 3 when the link came from a node's top bin or
    /// has score 100, 2 when it came from the second bin, 1 for later bins and
    /// for weaker links propagated from children; the larger of both directions.
    pub strength: u8,
}

/// Per-node ordered constraint lists, indexed like the prepared dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintLists {
    /// After Stage C: what each node asked for itself (top bin, propagation,
    /// one per following bin), in the order added.
    pub directed: Vec<Vec<ListEntry>>,
    /// After Stage D: `directed` plus the reverse of every link the node lacked,
    /// appended in level order. Undirected from here on; may exceed the caps.
    pub symmetric: Vec<Vec<ListEntry>>,
}

/// Runs Stages A to D (method-reference §3.1–3.6) on a prepared dataset (uniform
/// leaf depth, vectors aggregated: [`super::prepare::prepare`]) and returns every
/// node's list after Stage C and after Stage D.
///
/// Similarities are computed level by level, rows in parallel (results independent
/// of the thread count): neighbour lists, binary and Jaccard from sparse rows
/// (`SparseLevel`: the relations, groups of equal vectors, an inverted index of
/// supports; O(n + pairs that share a coordinate) per level), cosine and Pearson over
/// all pairs (`O(n²·d)` per level), through the f32 filter of `filtered_rows` where
/// the level allows it (same bins, bit for bit).
pub fn constraint_lists(prepared: &Dataset, kind: SimilarityKind) -> ConstraintLists {
    constraint_lists_with(prepared, kind, true, true)
}

/// [`constraint_lists`] with every row of every level computed, the virtual
/// copies' too: the reference the derived rows of `copies` are tested
/// against (issue 23 item 2). Not for production use.
#[doc(hidden)]
#[cfg(any(test, feature = "internals"))]
pub fn constraint_lists_recomputed(prepared: &Dataset, kind: SimilarityKind) -> ConstraintLists {
    constraint_lists_with(prepared, kind, true, false)
}

/// [`constraint_lists`], with the sparse rows allowed or not (the all-pairs scan is
/// the reference the sparse rows are tested against), and the copies' rows
/// derived from their leaves' (`copies`) or recomputed per level.
fn constraint_lists_with(
    prepared: &Dataset,
    kind: SimilarityKind,
    sparse: bool,
    derive: bool,
) -> ConstraintLists {
    let nodes = prepared.nodes();

    // Levels in breadth-first order: the tie-break order of §2.1.
    let mut levels: Vec<Vec<usize>> = vec![Vec::new(); prepared.max_depth() + 1];
    for (index, node) in nodes.iter().enumerate() {
        levels[node.depth].push(index);
    }

    let bins = level_by_level_bins(prepared, kind, &levels, sparse, derive);

    let mut lists = stages::top_bin(&bins);
    stages::propagate(nodes, &mut lists);
    stages::following_bins(&bins, &mut lists);
    let directed = lists.clone();
    stages::symmetrise(&mut lists);
    ConstraintLists {
        directed,
        symmetric: lists,
    }
}

/// §3.1–3.2: bins per non-root node, level by level, rows in parallel; the
/// virtual copies' derived from their leaves' where `derive` and it pays.
fn level_by_level_bins(
    prepared: &Dataset,
    kind: SimilarityKind,
    levels: &[Vec<usize>],
    sparse: bool,
    derive: bool,
) -> Vec<Bins> {
    if let Some(bins) = derive
        .then(|| derived_bins(prepared, kind, levels, sparse))
        .flatten()
    {
        return bins;
    }
    let mut bins: Vec<Bins> = vec![Bins::default(); prepared.len()];
    for level in levels.iter().skip(1) {
        for (&node, node_bins) in level.iter().zip(level_bins(prepared, kind, level, sparse)) {
            bins[node] = node_bins;
        }
    }
    bins
}

/// The unordered pairs with score > 1 (§3.6) of every level of a prepared dataset,
/// sorted by (depth, a, b). See [`Constraint`] for score, similarity and strength.
pub fn build_constraints(prepared: &Dataset, kind: SimilarityKind) -> Vec<Constraint> {
    pairs(prepared, kind, &constraint_lists(prepared, kind))
}

/// The pairs of [`build_constraints`] from lists already computed with
/// [`constraint_lists`] for the same dataset and measure.
pub fn pairs(prepared: &Dataset, kind: SimilarityKind, lists: &ConstraintLists) -> Vec<Constraint> {
    // A BTreeMap keyed by (a, b) gives the (depth, a, b) order directly: indices
    // are breadth-first, so a deeper node always has a larger index.
    let mut best: BTreeMap<(usize, usize), (u8, u8)> = BTreeMap::new();
    for (c, list) in lists.symmetric.iter().enumerate() {
        for link in list {
            let key = (c.min(link.target), c.max(link.target));
            let entry = best.entry(key).or_insert((0, 0));
            entry.0 = entry.0.max(link.score);
            entry.1 = entry.1.max(link.strength);
        }
    }
    best.into_iter()
        .filter(|&(_, (score, _))| score > MIN_PAIR_SCORE)
        .map(|((a, b), (score, strength))| {
            let fa = NodeFeatures::new(kind, prepared, a);
            let fb = NodeFeatures::new(kind, prepared, b);
            let s = pair_similarity(kind, &fa, &fb, b).max(pair_similarity(kind, &fb, &fa, a));
            Constraint {
                a,
                b,
                score,
                similarity: clamp_unit(s),
                strength: if score == 100 { 3 } else { strength },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::prepare::prepare;
    use super::*;

    fn paper(name: &str) -> (Dataset, SimilarityKind) {
        let dataset = super::super::prepare::test_data::dataset(name);
        let prepared = prepare(&dataset);
        let kind = SimilarityKind::for_dataset(&prepared);
        (prepared, kind)
    }

    /// Pair counts per depth 1..=D.
    fn counts_per_level(name: &str) -> Vec<usize> {
        let (p, kind) = paper(name);
        let pairs = build_constraints(&p, kind);
        (1..=p.max_depth())
            .map(|depth| pairs.iter().filter(|c| p.node(c.a).depth == depth).count())
            .collect()
    }

    #[test]
    fn golden_counts_per_level() {
        // Method-reference §3.9; leaf-level values are Table 2's.
        assert_eq!(counts_per_level("country_pop_50M_AUS.json"), [1, 18]);
        assert_eq!(counts_per_level("imdb_100_genre_sim_2child.json"), [25, 42]);
        assert_eq!(
            counts_per_level("syntheticPoints_10nodes_2components.json"),
            [11]
        );
        assert_eq!(
            counts_per_level("2_level_4_cousin_constraints.json"),
            [4, 24]
        );
        assert_eq!(counts_per_level("cifar10.json"), [1, 12, 19]);
        assert_eq!(counts_per_level("flare.json"), [14, 209, 488, 547]);
    }

    fn id_pair(p: &Dataset, c: &Constraint) -> String {
        let (a, b) = (&p.node(c.a).id, &p.node(c.b).id);
        if a < b {
            format!("{a}-{b}")
        } else {
            format!("{b}-{a}")
        }
    }

    #[test]
    fn golden_country_pairs() {
        let (p, kind) = paper("country_pop_50M_AUS.json");
        assert_eq!(kind, SimilarityKind::NeighborList);
        let pairs = build_constraints(&p, kind);
        let mut leaf: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 2)
            .map(|c| id_pair(&p, c))
            .collect();
        leaf.sort();
        let expected = [
            "BD-IN", "BD-MM", "CD-TZ", "CN-IN", "CN-MM", "CN-PK", "CN-RU", "CN-VN", "DE-FR",
            "ET-KE", "FR-IT", "IN-MM", "IN-PK", "IR-PK", "IR-TR", "KE-TZ", "MM-TH", "MX-US",
        ];
        assert_eq!(leaf, expected);
        for c in &pairs {
            assert_eq!(c.score, 100);
            assert_eq!(c.strength, 3);
            // Leaves share a border; the continents' link is propagated (§3.4) and
            // continents list no neighbours, so their own similarity is 0.
            let expected = if p.node(c.a).depth == 2 { 1.0 } else { 0.0 };
            assert_eq!(c.similarity, expected, "{}", id_pair(&p, c));
        }
        let level1: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 1)
            .map(|c| id_pair(&p, c))
            .collect();
        assert_eq!(level1, ["Cont_AS-Cont_EU"]);
    }

    #[test]
    fn synthetic_two_level_lists() {
        let (p, kind) = paper("2_level_4_cousin_constraints.json");
        let lists = constraint_lists(&p, kind);
        let ids = |node: &str| -> Vec<String> {
            let index = p.find(node).expect("exists");
            let mut v: Vec<String> = lists.directed[index]
                .iter()
                .map(|e| p.node(e.target).id.clone())
                .collect();
            v.sort();
            v
        };
        assert_eq!(ids("P13"), ["P1", "P14", "P15", "P16", "P17"]);
        assert_eq!(ids("P2"), ["P3"]);
        // Level 1: P21 linked to P22..P25 (through Stage B), nothing else.
        let pairs = build_constraints(&p, kind);
        let level1: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 1)
            .map(|c| id_pair(&p, c))
            .collect();
        assert_eq!(level1, ["P21-P25", "P21-P24", "P21-P23", "P21-P22"]);
    }

    #[test]
    fn pairs_are_sorted_symmetric_and_never_weak() {
        for name in [
            "flare.json",
            "cifar10.json",
            "imdb_100_genre_sim_2child.json",
            "country_pop_50M_AUS.json",
        ] {
            let (p, kind) = paper(name);
            let lists = constraint_lists(&p, kind);
            let pairs = pairs(&p, kind, &lists);
            for w in pairs.windows(2) {
                let key = |c: &Constraint| (p.node(c.a).depth, c.a, c.b);
                assert!(key(&w[0]) < key(&w[1]), "{name}");
            }
            for c in &pairs {
                assert!(c.a < c.b);
                assert_eq!(p.node(c.a).depth, p.node(c.b).depth);
                assert!(p.node(c.a).depth >= 1);
                assert!(c.score > 1 && c.score <= 100);
                assert!((1..=3).contains(&c.strength));
                assert!((0.0..=1.0).contains(&c.similarity));
            }
            for (n, list) in lists.symmetric.iter().enumerate() {
                for e in list {
                    assert!(e.score > 0, "{name}: score-0 link");
                    assert!(lists.symmetric[e.target].iter().any(|r| r.target == n));
                }
            }
            // Deterministic.
            assert_eq!(pairs, build_constraints(&p, kind), "{name}");
        }
    }

    #[test]
    fn all_zero_similarities_give_no_links() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for i in 0..4 {
            builder.add(NodeSpec::new(format!("n{i}")).parent("r").weight(1.0));
        }
        let p = prepare(&builder.build().expect("valid"));
        let lists = constraint_lists(&p, SimilarityKind::Cosine);
        assert!(lists.symmetric.iter().all(Vec::is_empty));
        assert!(build_constraints(&p, SimilarityKind::Cosine).is_empty());
        // A single node: nothing to compare with.
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add(NodeSpec::new("x").parent("r").features(vec![1.0]));
        let p = prepare(&builder.build().expect("valid"));
        assert!(build_constraints(&p, SimilarityKind::Cosine).is_empty());
    }

    /// Random two- and three-level datasets for the sparse measures: short 0/1-ish
    /// vectors (many equal, many disjoint), some missing, some of another length, some
    /// with −0, and relations to any node (own level or not, itself, repeated).
    fn sparse_case(seed: u64, leaves: usize) -> Dataset {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut rng = crate::rng::Rng::new(seed);
        let mut below = |n: u64| (rng.next_u64() % n) as usize;
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        let groups = 1 + below(5);
        for g in 0..groups {
            builder.add(NodeSpec::new(format!("g{g}")).parent("r"));
        }
        let total = groups + leaves + 1;
        for i in 0..leaves {
            let parent = format!("g{}", below(groups as u64));
            let mut spec = NodeSpec::new(format!("n{i}")).parent(parent).weight(1.0);
            match below(12) {
                0 => {}
                1 => spec = spec.features(vec![1.0; 3]),
                2 => spec = spec.features(vec![0.0, 1.0]),
                3 => spec = spec.features(vec![-0.0, 1.0, 0.0, 0.0]),
                _ => {
                    let v: Vec<f64> = (0..4).map(|_| (below(3) == 0) as u8 as f64).collect();
                    spec = spec.features(v);
                }
            }
            for _ in 0..below(4) {
                let t = below(total as u64);
                let id = match t {
                    0 => "r".to_string(),
                    t if t <= groups => format!("g{}", t - 1),
                    t => format!("n{}", (t - groups - 1).min(leaves - 1)),
                };
                spec = spec.relation(id);
            }
            builder.add(spec);
        }
        builder.build().expect("valid")
    }

    #[test]
    fn sparse_rows_match_the_all_pairs_scan() {
        for seed in 0..60 {
            let leaves = [2, 3, 9, 17, 40, 120][seed as usize % 6];
            let d = sparse_case(seed, leaves);
            let p = prepare(&d);
            for kind in [
                SimilarityKind::NeighborList,
                SimilarityKind::Binary,
                SimilarityKind::Jaccard,
            ] {
                let sparse = constraint_lists_with(&p, kind, true, true);
                let dense = constraint_lists_with(&p, kind, false, true);
                assert_eq!(sparse, dense, "seed {seed}, {kind:?}");
            }
        }
        // Paper data through both paths (Flare is Jaccard, Country neighbour lists).
        for name in [
            "flare.json",
            "country_pop_50M_AUS.json",
            "imdb_100_genre_sim_2child.json",
        ] {
            let (p, kind) = paper(name);
            assert_eq!(
                constraint_lists_with(&p, kind, true, true),
                constraint_lists_with(&p, kind, false, true),
                "{name}"
            );
        }
    }
}
