//! `config/default.yaml` documents the code's defaults: every documented value
//! equals the one in `Params::default()`.

use nptreemap::layout::{Outline, Params};

#[test]
fn default_yaml_matches_params_default() {
    let text = include_str!("../../config/default.yaml");
    let doc: serde_yaml::Value = serde_yaml::from_str(text).expect("default.yaml parses");
    let layout = &doc["layout"];
    let p = Params::default();
    let num = |k: &str| {
        layout[k]
            .as_f64()
            .unwrap_or_else(|| panic!("layout.{k} is a number"))
    };
    assert_eq!(num("width"), p.canvas.width);
    assert_eq!(num("height"), p.canvas.height);
    assert_eq!(num("seed") as u64, p.seed);
    assert_eq!(num("convergence_ratio"), p.convergence_ratio);
    assert_eq!(num("max_iterations") as usize, p.max_iterations);
    assert_eq!(num("min_iterations") as usize, p.min_iterations);
    assert_eq!(num("min_weight_ratio"), p.min_weight_ratio);
    assert_eq!(layout["outline"].as_str(), Some("rect"));
    assert_eq!(p.outline, Outline::Rectangle);
}
