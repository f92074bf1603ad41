//! Similarity-driven layouts on data the paper's files do not cover: relations
//! without feature vectors (projection by classical MDS), and every method on
//! one dataset, each ending with `sanity_check`.

use nptreemap::layout::{compute, Method, Request};
use nptreemap::measure;
use nptreemap::neighborhood::SimilarityKind;
use nptreemap_formats::{DatasetBuilder, NodeSpec};

/// Two groups of six; the leaves form a ring of "borders" that crosses groups.
fn ring() -> nptreemap_formats::Dataset {
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("root"));
    for g in ["west", "east"] {
        b.add(NodeSpec::new(g).parent("root"));
    }
    for i in 0..12 {
        let group = if i < 6 { "west" } else { "east" };
        b.add(
            NodeSpec::new(format!("n{i}"))
                .parent(group)
                .weight(1.0 + (i % 3) as f64)
                .relation(format!("n{}", (i + 1) % 12)),
        );
    }
    b.build().expect("valid dataset")
}

#[test]
fn relations_without_vectors_use_mds_and_realize_constraints() {
    let ds = ring();
    let mut request = Request::default();
    request.similarity = Some(SimilarityKind::NeighborList);
    let c = compute(&ds, &request).expect("layout");
    assert_eq!(c.method, Method::Neighbor);
    c.layout.sanity_check(&c.dataset).expect("sane");
    assert!(measure::quality(&c.dataset, &c.layout).area_error_diagram_mean <= 0.01);
    let leaf_depth = c.dataset.max_depth();
    let leaf: Vec<bool> = c
        .constraints
        .iter()
        .zip(&c.realized)
        .filter(|(k, _)| c.dataset.node(k.a).depth == leaf_depth)
        .map(|(_, r)| *r)
        .collect();
    // A ring of 12 borders: the constraint pipeline keeps each of them.
    assert_eq!(leaf.len(), 12);
    let realized = leaf.iter().filter(|r| **r).count();
    assert!(realized >= 9, "only {realized} of 12 ring borders realised");
}

#[test]
fn every_method_gives_a_sound_layout() {
    let ds = ring();
    for method in Method::ALL {
        let mut request = Request::default();
        request.method = Some(method);
        request.similarity = Some(SimilarityKind::NeighborList);
        let c = compute(&ds, &request).expect("layout");
        assert_eq!(c.method, method);
        c.layout.sanity_check(&c.dataset).expect("sane");
        let q = measure::quality(&c.dataset, &c.layout);
        assert!(
            q.area_error_diagram_mean <= 0.01,
            "{}: {q:?}",
            method.name()
        );
        assert_eq!(c.realized.len(), c.constraints.len());
    }
}
