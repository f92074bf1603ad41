//! Preparation of a hierarchy for the constraint pipeline (paper §4,
//! method-reference §2.2–2.4): virtual nodes that give every leaf the same depth,
//! and feature vectors aggregated bottom-up for nodes that have none.

use std::collections::HashSet;

use nptreemap_formats::{Dataset, DatasetBuilder, Features, Node, NodeSpec, SparseVector};

/// Virtual nodes of a chain that get the prototype's compound id (§2.2); later ones
/// are named after the leaf, so ids stay short on deep chains.
const COMPOUND_IDS: usize = 4;

/// Returns `dataset` with uniform leaf depth and aggregated feature vectors.
///
/// - **Virtual nodes** (§2.2): every leaf shallower than the maximum depth `D`
///   becomes the head of a chain of single-child virtual nodes reaching depth `D`.
///   A virtual node's id is `<parent id>depth<parent depth>` (so a chain below
///   `X` at depth 1 is `Xdepth1`, `Xdepth1depth2`, ...); if that id is taken, `~2`,
///   `~3`, ... is appended, the first free one in that order. From the fifth virtual
///   node of a chain on, the id is `<leaf id>depth<parent depth>` instead (`X` at
///   depth 1: ..., `Xdepth1depth2depth3depth4`, then `Xdepth5`, `Xdepth6`): the
///   prototype's ids grow by a segment per level, so a leaf at depth 1 under a
///   5,000-deep chain would spell ids of 40 kB, O(D³) bytes over a caterpillar tree
///   (issue 11 item 5). No paper dataset has a chain that long. Label, colour and
///   feature vector are copied from the node it hangs under; it has no relations
///   and [`nptreemap_formats::Node::is_virtual`] is set. Features are shared
///   ([`Features`] holds them behind an `Arc`): a chain of copies costs a
///   pointer per node, not a row.
/// - **Weights** (§2.3): the *last* virtual node of a chain carries the original
///   leaf's own weight and the original leaf's own weight becomes `None`. The
///   prototype keeps the weight on the leaf and gives virtual nodes weight 0; both
///   give the original nodes exactly the same values (here `0 + w`, bit for bit),
///   and here every virtual node's value is the leaf's weight too, which is the
///   area its cell must get (the prototype reaches the same through its "value 0
///   counts as 1" rule in the optimiser, which only matters for one-child diagrams).
/// - **Vectors** (§2.4): in post-order, a node without a vector gets the
///   element-wise mean of its children's vectors (sum left to right, divided by
///   the count, as mathjs's `mean`); nodes with their own (CIFAR's internal nodes)
///   keep it. Only children with a vector count; if those vectors differ in
///   length, the mean is undefined and the node stays without a vector (its
///   similarities are then 0, method-reference §10 #3). Sparse vectors (sets)
///   are averaged sparsely: the sum of each member's values in child order,
///   divided by the count, zeros dropped; that is the dense mean bit for bit
///   (the dense sum only adds exact zeros for the absent members), so the
///   support of a mean of sets is the union of the sets (what Jaccard reads),
///   and cosine and binary see the dense means. Dense and sparse children
///   together have no mean.
///
/// Original nodes keep their ids, relations and colours; the result is built
/// through [`DatasetBuilder`], so it is in breadth-first order, the tie-break order
/// of §2.1 step 4. A dataset that already has uniform depth comes back with only
/// its vectors aggregated.
pub fn prepare(dataset: &Dataset) -> Dataset {
    let features = aggregate_features(dataset);
    let max_depth = dataset.max_depth();
    let nodes = dataset.nodes();

    let mut taken: HashSet<String> = nodes.iter().map(|n| n.id.clone()).collect();
    let mut builder = DatasetBuilder::new();
    if let Some(hint) = dataset.similarity_hint() {
        builder.similarity_hint(hint);
    }
    // Chains to add after the originals: (leaf index, chain length).
    let mut chains: Vec<(usize, usize)> = Vec::new();
    for (index, node) in nodes.iter().enumerate() {
        let is_short_leaf = node.children.is_empty() && node.depth < max_depth;
        let mut spec = NodeSpec::new(node.id.clone()).label(node.label.clone());
        spec.parent = node.parent.map(|p| nodes[p].id.clone());
        spec.weight = if is_short_leaf { None } else { node.weight };
        spec.color = node.color;
        spec.features = features[index].clone();
        spec.fields = node.fields.clone();
        spec.relations = node
            .relations
            .iter()
            .map(|&r| nodes[r].id.clone())
            .collect();
        builder.add(spec);
        if is_short_leaf {
            chains.push((index, max_depth - node.depth));
        }
    }
    for (leaf, length) in chains {
        let node = &nodes[leaf];
        let mut parent_id = node.id.clone();
        for (step, parent_depth) in (node.depth..node.depth + length).enumerate() {
            let stem = if step < COMPOUND_IDS {
                &parent_id
            } else {
                &node.id
            };
            let id = unique_id(format!("{stem}depth{parent_depth}"), &mut taken);
            let mut spec = NodeSpec::new(id.clone())
                .label(node.label.clone())
                .parent(parent_id);
            spec.color = node.color;
            spec.features = features[leaf].clone();
            if step + 1 == length {
                spec.weight = node.weight;
            }
            builder.add_virtual(spec);
            parent_id = id;
        }
    }
    // Every spec comes from a valid dataset (ids unique by `unique_id`, parents
    // added, values already checked), so building cannot fail; fall back to the
    // input rather than panic if that reasoning is ever broken.
    builder.build().unwrap_or_else(|_| dataset.clone())
}

/// [`prepare`] of `after` from `prepared` = `prepare(before)`, when `after`
/// differs from `before` in its weights only (the same nodes, labels,
/// colours, vectors, fields and relations): the prepared tree with its
/// weights set as `prepare` sets them (a short leaf's weight on the last
/// copy of its chain) and its values summed again. The same dataset as
/// `prepare(after)`, bit for bit (tested), for a fraction of its cost (a
/// weight edit of 6,000 C headers: the tree of 38,629 nodes is not built
/// again). `None` when anything but weights differs.
// Only the build's stage graph reweighs; the library alone has none.
#[cfg_attr(
    not(any(feature = "cli", feature = "watch", feature = "internals")),
    allow(dead_code)
)]
pub fn reweigh(prepared: &Dataset, before: &Dataset, after: &Dataset) -> Option<Dataset> {
    let same_but_weights = before.len() == after.len()
        && before.similarity_hint() == after.similarity_hint()
        && before.nodes().iter().zip(after.nodes()).all(|(b, a)| {
            b.id == a.id
                && b.label == a.label
                && b.parent == a.parent
                && b.children == a.children
                && b.color == a.color
                && b.features == a.features
                && b.relations == a.relations
                && b.is_virtual == a.is_virtual
                && b.fields == a.fields
        });
    if !same_but_weights {
        return None;
    }
    let max_depth = after.max_depth();
    let short_leaf = |n: &Node| n.children.is_empty() && n.depth < max_depth;
    let weights: Vec<Option<f64>> = prepared
        .nodes()
        .iter()
        .map(|node| {
            if !node.is_virtual {
                let source = after.node(after.find(&node.id)?);
                return if short_leaf(source) { None } else { source.weight };
            }
            if !node.children.is_empty() {
                return None;
            }
            // The last copy of a chain carries its leaf's weight.
            let mut up = node.parent?;
            while prepared.node(up).is_virtual {
                up = prepared.node(up).parent?;
            }
            after.node(after.find(&prepared.node(up).id)?).weight
        })
        .collect();
    // `prepare` falls back to its input if building fails: then no copies.
    let copies = after
        .nodes()
        .iter()
        .filter(|n| short_leaf(n))
        .map(|n| max_depth - n.depth)
        .sum::<usize>();
    (prepared.len() == after.len() + copies)
        .then(|| prepared.with_weights(&weights).ok())
        .flatten()
}

/// `candidate` if free, else `candidate~2`, `candidate~3`, ...: the first free one.
/// Records the result as taken.
fn unique_id(candidate: String, taken: &mut HashSet<String>) -> String {
    let id = if taken.contains(&candidate) {
        // Among `taken.len() + 1` suffixes one is free (pigeonhole), so the
        // search ends there at the latest.
        (2..taken.len() + 3)
            .map(|k| format!("{candidate}~{k}"))
            .find(|attempt| !taken.contains(attempt))
            .unwrap_or_else(|| format!("{candidate}~{}", taken.len() + 3))
    } else {
        candidate
    };
    taken.insert(id.clone());
    id
}

/// Feature vectors after the bottom-up mean (§2.4), indexed like `dataset`.
fn aggregate_features(dataset: &Dataset) -> Vec<Option<Features>> {
    let nodes = dataset.nodes();
    let mut features: Vec<Option<Features>> = nodes.iter().map(|n| n.features.clone()).collect();
    // Children have larger indices than their parent (breadth-first order), so a
    // reverse sweep is a valid post-order for this purpose.
    for index in (0..nodes.len()).rev() {
        if features[index].is_some() {
            continue;
        }
        let children: Vec<&Features> = nodes[index]
            .children
            .iter()
            .filter_map(|&c| features[c].as_ref())
            .collect();
        features[index] = mean_of(&children);
    }
    features
}

/// Element-wise mean of the vectors; `None` for no vectors, differing lengths,
/// or dense and sparse vectors together.
fn mean_of(vectors: &[&Features]) -> Option<Features> {
    let first = vectors.first()?;
    if vectors.iter().any(|v| v.len() != first.len()) {
        return None;
    }
    match first {
        Features::Dense(_) => {
            let dense: Option<Vec<&[f64]>> = vectors.iter().map(|v| v.as_dense()).collect();
            dense_mean(&dense?).map(Features::from)
        }
        Features::Sparse(_) => {
            let sparse: Option<Vec<&SparseVector>> =
                vectors.iter().map(|v| v.as_sparse()).collect();
            sparse_mean(&sparse?).map(Features::from)
        }
    }
}

/// Element-wise mean of dense vectors of one length (sum left to right, then
/// divided by the count, as mathjs's `mean`).
fn dense_mean(vectors: &[&[f64]]) -> Option<Vec<f64>> {
    let (first, rest) = vectors.split_first()?;
    let mut sum = first.to_vec();
    for v in rest {
        for (acc, x) in sum.iter_mut().zip(v.iter()) {
            *acc += x;
        }
    }
    let n = vectors.len() as f64;
    for value in &mut sum {
        *value /= n;
    }
    Some(sum)
}

/// [`dense_mean`] of sparse vectors of one length, without densifying: each
/// member's values summed in child order (a stable sort by member keeps it).
fn sparse_mean(vectors: &[&SparseVector]) -> Option<SparseVector> {
    let len = u32::try_from(vectors.first()?.len()).ok()?;
    let mut entries: Vec<(u32, f64)> = vectors.iter().flat_map(|v| v.entries()).collect();
    entries.sort_by_key(|&(index, _)| index);
    let n = vectors.len() as f64;
    let mut summed: Vec<(u32, f64)> = Vec::with_capacity(entries.len());
    for (index, value) in entries {
        match summed.last_mut() {
            Some((last, sum)) if *last == index => *sum += value,
            _ => summed.push((index, value)),
        }
    }
    SparseVector::from_entries(len, summed.into_iter().map(|(k, sum)| (k, sum / n)))
}

/// The paper's datasets for tests, embedded at compile time so that the tests of
/// these pure modules do no file I/O.
#[cfg(test)]
pub(crate) mod test_data {
    use nptreemap_formats::{parse_hierarchy_json, Dataset, HierarchyJsonOptions};

    macro_rules! paper_file {
        ($name:literal) => {
            include_bytes!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/tests/data/paper/",
                $name
            ))
            .as_slice()
        };
    }

    /// The bytes of a file in `tests/data/paper`.
    pub(crate) fn bytes(name: &str) -> &'static [u8] {
        match name {
            "country_pop_50M_AUS.json" => paper_file!("country_pop_50M_AUS.json"),
            "cifar10.json" => paper_file!("cifar10.json"),
            "flare.json" => paper_file!("flare.json"),
            "imdb_100_genre_sim_2child.json" => paper_file!("imdb_100_genre_sim_2child.json"),
            "syntheticPoints_10nodes_2components.json" => {
                paper_file!("syntheticPoints_10nodes_2components.json")
            }
            "2_level_4_cousin_constraints.json" => {
                paper_file!("2_level_4_cousin_constraints.json")
            }
            other => panic!("no embedded paper file {other}"),
        }
    }

    /// A paper dataset read by the real reader with its own flags.
    pub(crate) fn dataset(name: &str) -> Dataset {
        parse_hierarchy_json(bytes(name), &HierarchyJsonOptions::default()).expect("parses")
    }
}

#[cfg(test)]
mod tests {
    use super::test_data::dataset as paper;
    use super::*;

    fn build(specs: Vec<NodeSpec>) -> Dataset {
        let mut builder = DatasetBuilder::new();
        for spec in specs {
            builder.add(spec);
        }
        builder.build().expect("valid")
    }

    /// A weight edit of a prepared tree gives `prepare` of the edited
    /// dataset bit for bit, on the paper's deep and uneven trees (virtual
    /// chains, shared vectors) and with weights going to and from zero; any
    /// other edit is refused.
    #[test]
    fn reweighing_a_prepared_tree_is_preparing_the_edited_one() {
        for name in ["flare.json", "cifar10.json", "country_pop_50M_AUS.json"] {
            let before = paper(name);
            let prepared = prepare(&before);
            for (k, factor) in [(0usize, 1.1), (3, 0.0), (7, 40.0)] {
                let leaves: Vec<usize> = before.leaves().collect();
                let leaf = leaves[k % leaves.len()];
                let mut builder = DatasetBuilder::new();
                for (i, n) in before.nodes().iter().enumerate() {
                    let mut spec = NodeSpec::new(n.id.clone()).label(n.label.clone());
                    spec.parent = n.parent.map(|p| before.node(p).id.clone());
                    spec.weight = if i == leaf {
                        Some(n.weight.unwrap_or(1.0) * factor + 0.5)
                    } else {
                        n.weight
                    };
                    spec.color = n.color;
                    spec.features = n.features.clone();
                    spec.fields = n.fields.clone();
                    spec.relations = n.relations.iter().map(|&r| before.node(r).id.clone()).collect();
                    builder.add(spec);
                }
                if let Some(hint) = before.similarity_hint() {
                    builder.similarity_hint(hint);
                }
                let after = builder.build().expect("valid");
                assert_eq!(after.len(), before.len(), "{name}: same order");
                let fast = reweigh(&prepared, &before, &after).expect("weights only");
                assert_eq!(fast, prepare(&after), "{name}: leaf {leaf} ×{factor}");
            }
        }
        let u = uneven();
        let relabelled = {
            let mut b = DatasetBuilder::new();
            for n in u.nodes() {
                let mut spec = NodeSpec::new(n.id.clone()).label(format!("{}!", n.label));
                spec.parent = n.parent.map(|p| u.node(p).id.clone());
                spec.weight = n.weight;
                spec.features = n.features.clone();
                b.add(spec);
            }
            b.build().expect("valid")
        };
        assert!(reweigh(&prepare(&u), &u, &relabelled).is_none(), "a label edit is refused");
    }

    /// r ─ a (leaf, w 2, [1,0]) ; r ─ b ─ c ─ d (w 3, [0,1]) ; b ─ e (leaf, w 1, [1,1])
    fn uneven() -> Dataset {
        build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("a")
                .parent("r")
                .weight(2.0)
                .features(vec![1.0, 0.0])
                .color(nptreemap_formats::Rgb::new(0xff, 0, 0)),
            NodeSpec::new("b").parent("r"),
            NodeSpec::new("c").parent("b"),
            NodeSpec::new("e")
                .parent("b")
                .weight(1.0)
                .features(vec![1.0, 1.0]),
            NodeSpec::new("d")
                .parent("c")
                .weight(3.0)
                .features(vec![0.0, 1.0]),
        ])
    }

    fn ids(d: &Dataset) -> Vec<&str> {
        d.nodes().iter().map(|n| n.id.as_str()).collect()
    }

    #[test]
    fn virtual_chains_reach_the_maximum_depth() {
        let p = prepare(&uneven());
        assert_eq!(
            ids(&p),
            [
                "r",
                "a",
                "b",
                "adepth1",
                "c",
                "e",
                "adepth1depth2",
                "d",
                "edepth2"
            ]
        );
        let max = p.max_depth();
        assert_eq!(max, 3);
        for leaf in p.leaves() {
            assert_eq!(p.node(leaf).depth, max, "{}", p.node(leaf).id);
        }
        let virtuals: Vec<&str> = p
            .nodes()
            .iter()
            .filter(|n| n.is_virtual)
            .map(|n| n.id.as_str())
            .collect();
        assert_eq!(virtuals, ["adepth1", "adepth1depth2", "edepth2"]);
        let v = p.node(p.find("adepth1depth2").expect("exists"));
        assert_eq!(v.label, "a");
        assert_eq!(v.color, Some(nptreemap_formats::Rgb::new(0xff, 0, 0)));
        assert_eq!(v.features.as_ref().map(Features::to_dense), Some(vec![1.0, 0.0]));
        assert!(v.relations.is_empty());
    }

    #[test]
    fn values_are_unchanged_at_every_original_node() {
        let d = uneven();
        let p = prepare(&d);
        for node in d.nodes() {
            let q = p.node(p.find(&node.id).expect("kept"));
            assert_eq!(q.value.to_bits(), node.value.to_bits(), "{}", node.id);
        }
        // Weight moved to the end of the chain.
        assert_eq!(p.node(p.find("a").expect("a")).weight, None);
        assert_eq!(p.node(p.find("adepth1").expect("v")).weight, None);
        assert_eq!(
            p.node(p.find("adepth1depth2").expect("v")).weight,
            Some(2.0)
        );
        assert_eq!(p.node(p.find("adepth1depth2").expect("v")).value, 2.0);
        // Per level, values sum to the root's.
        for depth in 0..=p.max_depth() {
            let total: f64 = p
                .nodes()
                .iter()
                .filter(|n| n.depth == depth)
                .map(|n| n.value)
                .sum();
            assert_eq!(total, 6.0, "depth {depth}");
        }
    }

    #[test]
    fn vectors_are_mean_aggregated() {
        let p = prepare(&uneven());
        let f = |id: &str| {
            p.node(p.find(id).expect("exists"))
                .features
                .as_ref()
                .map(Features::to_dense)
        };
        assert_eq!(f("c"), Some(vec![0.0, 1.0]));
        assert_eq!(f("b"), Some(vec![0.5, 1.0]));
        assert_eq!(f("r"), Some(vec![0.75, 0.5]));
        assert_eq!(f("a"), Some(vec![1.0, 0.0]));
    }

    #[test]
    fn own_vectors_are_kept_and_mismatched_lengths_give_none() {
        let d = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("x").parent("r").features(vec![9.0]),
            NodeSpec::new("x1")
                .parent("x")
                .weight(1.0)
                .features(vec![1.0]),
            NodeSpec::new("y").parent("r"),
            NodeSpec::new("y1")
                .parent("y")
                .weight(1.0)
                .features(vec![1.0]),
            NodeSpec::new("y2")
                .parent("y")
                .weight(1.0)
                .features(vec![1.0, 2.0]),
            NodeSpec::new("z").parent("r"),
            NodeSpec::new("z1").parent("z").weight(1.0),
            NodeSpec::new("z2")
                .parent("z")
                .weight(1.0)
                .features(vec![4.0]),
        ]);
        let p = prepare(&d);
        let f = |id: &str| {
            p.node(p.find(id).expect("exists"))
                .features
                .as_ref()
                .map(Features::to_dense)
        };
        assert_eq!(f("x"), Some(vec![9.0]));
        assert_eq!(f("y"), None);
        // Only children with a vector count.
        assert_eq!(f("z"), Some(vec![4.0]));
        assert_eq!(f("r"), Some(vec![6.5]));
    }

    #[test]
    fn long_chains_get_short_ids() {
        // A leaf at depth 1 beside a chain 12 deep: 11 virtual nodes below it.
        let mut specs = vec![
            NodeSpec::new("r"),
            NodeSpec::new("x").parent("r").weight(1.0),
        ];
        let mut parent = "r".to_string();
        for i in 0..12 {
            let id = format!("c{i}");
            specs.push(NodeSpec::new(id.clone()).parent(parent).weight(1.0));
            parent = id;
        }
        let p = prepare(&build(specs));
        let chain: Vec<&str> = p
            .nodes()
            .iter()
            .filter(|n| n.is_virtual)
            .map(|n| n.id.as_str())
            .collect();
        assert_eq!(chain.len(), 11);
        assert_eq!(
            chain[..6],
            [
                "xdepth1",
                "xdepth1depth2",
                "xdepth1depth2depth3",
                "xdepth1depth2depth3depth4",
                "xdepth5",
                "xdepth6"
            ]
        );
        assert_eq!(chain[10], "xdepth11");
        for leaf in p.leaves() {
            assert_eq!(p.node(leaf).depth, 12);
        }
    }

    #[test]
    fn colliding_virtual_ids_get_a_suffix() {
        let d = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("adepth1").parent("r"),
            NodeSpec::new("q").parent("adepth1").weight(1.0),
            NodeSpec::new("a").parent("r").weight(1.0),
        ]);
        let p = prepare(&d);
        assert_eq!(ids(&p), ["r", "adepth1", "a", "q", "adepth1~2"]);
        assert!(p.node(4).is_virtual);
        assert!(!p.node(1).is_virtual);
    }

    #[test]
    fn relations_and_hint_are_kept() {
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add(NodeSpec::new("a").parent("r").relation("b").weight(1.0))
            .add(NodeSpec::new("b").parent("r").weight(1.0))
            .similarity_hint(nptreemap_formats::SimilarityHint::NeighborList);
        let p = prepare(&builder.build().expect("valid"));
        assert_eq!(p.node(1).relations, vec![2]);
        assert_eq!(
            p.similarity_hint(),
            Some(nptreemap_formats::SimilarityHint::NeighborList)
        );
    }

    #[test]
    fn manifest_node_counts_include_virtual_nodes() {
        for (file, nodes, levels) in [
            ("country_pop_50M_AUS.json", 36, 3),
            ("cifar10.json", 20, 4),
            ("flare.json", 524, 5),
            ("imdb_100_genre_sim_2child.json", 80, 3),
            ("syntheticPoints_10nodes_2components.json", 11, 2),
            ("2_level_4_cousin_constraints.json", 23, 3),
        ] {
            let original = paper(file);
            let p = prepare(&original);
            assert_eq!(p.len(), nodes, "{file}");
            assert_eq!(p.max_depth() + 1, levels, "{file}");
            for leaf in p.leaves() {
                assert_eq!(p.node(leaf).depth, p.max_depth(), "{file}");
            }
            assert_eq!(p.node(0).value.to_bits(), original.node(0).value.to_bits());
            assert!(p.nodes().iter().all(|n| n.features.is_some()), "{file}");
        }
    }

    #[test]
    fn cifar_keeps_its_own_internal_vectors() {
        let original = paper("cifar10.json");
        let p = prepare(&original);
        let mut internal_with_own = 0;
        for node in original.nodes() {
            if !node.children.is_empty() {
                if let Some(own) = &node.features {
                    internal_with_own += 1;
                    let q = p.node(p.find(&node.id).expect("kept"));
                    assert_eq!(q.features.as_ref(), Some(own), "{}", node.id);
                }
            }
        }
        assert!(internal_with_own > 0);
    }

    /// Issue 23 item 2: a virtual copy shares its original's features (the
    /// same allocation, not a cloned row), and the mean of sets is the dense
    /// mean bit for bit, its support the union of the sets.
    #[test]
    fn copies_share_their_features_and_sets_average_as_vectors() {
        let set = |members: &[u32]| {
            nptreemap_formats::SparseVector::set(4, members.iter().copied()).expect("set")
        };
        let d = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("a").parent("r").weight(1.0).features(set(&[0, 3])),
            NodeSpec::new("b").parent("r"),
            NodeSpec::new("c").parent("b"),
            NodeSpec::new("c1").parent("c").weight(1.0).features(set(&[1])),
            NodeSpec::new("c2").parent("c").weight(1.0).features(set(&[1, 2])),
            NodeSpec::new("c3").parent("c").weight(1.0).features(set(&[2, 3])),
        ]);
        let p = prepare(&d);
        let node = |id: &str| p.node(p.find(id).expect(id));
        let Some(Features::Sparse(original)) = &node("a").features else {
            panic!("a keeps its set");
        };
        for copy in ["adepth1", "adepth1depth2"] {
            let Some(Features::Sparse(shared)) = &node(copy).features else {
                panic!("{copy} has the set");
            };
            assert!(
                std::ptr::eq(shared.indices().as_ptr(), original.indices().as_ptr()),
                "{copy} shares a's members"
            );
        }
        let mean = node("c").features.clone().expect("a mean");
        let third = 1.0 / 3.0;
        assert_eq!(mean.to_dense(), [0.0, 2.0 * third, 2.0 / 3.0, third]);
        assert_eq!(
            mean.as_sparse().map(|s| s.indices().to_vec()),
            Some(vec![1, 2, 3])
        );
        // The dense path on the same data gives the same bits.
        let dense = build(vec![
            NodeSpec::new("r"),
            NodeSpec::new("c").parent("r"),
            NodeSpec::new("c1").parent("c").weight(1.0).features(vec![0.0, 1.0, 0.0, 0.0]),
            NodeSpec::new("c2").parent("c").weight(1.0).features(vec![0.0, 1.0, 1.0, 0.0]),
            NodeSpec::new("c3").parent("c").weight(1.0).features(vec![0.0, 0.0, 1.0, 1.0]),
        ]);
        let dense = prepare(&dense);
        let want = dense.node(dense.find("c").expect("c")).features.clone().expect("mean");
        let bits = |v: Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(mean.to_dense()), bits(want.to_dense()));
    }
}
