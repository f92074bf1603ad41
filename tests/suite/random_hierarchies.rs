//! Random hierarchies of 100, 1,000 and 10,000 leaves (the peers' generator)
//! pass the checker at d3's area-error target, in both outlines.

use crate::support;

fn run(leaves: usize, depth: usize, outline: &str) {
    let dir = support::temp_dir(&format!("random_{leaves}_{depth}_{outline}"));
    let input = support::generate(&dir, leaves, depth, 1);
    let json = dir.join("layout.json");
    support::layout(&input, &[&json], &["--outline", outline]);
    let report = support::check_layout(&json);
    assert_eq!(report["leaves"].as_u64(), Some(leaves as u64));
    support::assert_area_error(&report, 0.01);
}

#[test]
fn hundred_leaves_depth_3() {
    run(100, 3, "rect");
}

#[test]
fn hundred_leaves_in_a_circle() {
    run(100, 2, "circle");
}

#[test]
fn thousand_leaves_depth_3() {
    run(1000, 3, "rect");
}

#[test]
fn ten_thousand_leaves_depth_3() {
    run(10_000, 3, "rect");
}

#[test]
fn two_thousand_siblings_flat() {
    run(2000, 1, "rect");
}
