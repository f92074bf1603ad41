//! Same input and seed give byte-identical JSON and SVG; another seed gives
//! another layout.

use crate::support;

#[test]
fn same_seed_same_bytes() {
    let dir = support::temp_dir("determinism");
    let input = support::generate(&dir, 300, 2, 5);
    let run = |tag: &str, seed: &str| {
        let json = dir.join(format!("{tag}.json"));
        let svg = dir.join(format!("{tag}.svg"));
        support::layout(&input, &[&json, &svg], &["--seed", seed]);
        (
            std::fs::read(json).expect("json"),
            std::fs::read(svg).expect("svg"),
        )
    };
    let a = run("a", "7");
    let b = run("b", "7");
    let c = run("c", "8");
    assert!(a.0 == b.0, "layout JSON differs between identical runs");
    assert!(a.1 == b.1, "SVG differs between identical runs");
    assert!(
        a.0 != c.0,
        "a different seed should give a different layout"
    );
}
