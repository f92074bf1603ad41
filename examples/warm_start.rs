//! Warm start (issue 6) in a few lines: lay a dataset out, change one weight,
//! lay it out again from the previous layout, and print how far the other
//! cells moved and how many realised neighbourhoods stayed, next to what a
//! cold layout of the same data does. No files.
//!
//! Run with `cargo run --release --example warm_start`.

use std::sync::Arc;

use nptreemap::layout::{compute, Request};
use nptreemap::measure::stability;
use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec, SimilarityHint};

/// 8 groups of 12 leaves with varied weights and feature vectors (so the
/// default method is the neighbourhood-preserving one); leaf `l5` weighs `l5`.
fn dataset(l5: f64) -> Result<Dataset, Box<dyn std::error::Error>> {
    let mut builder = DatasetBuilder::new();
    builder.similarity_hint(SimilarityHint::Cosine);
    builder.add(NodeSpec::new("root"));
    for g in 0..8 {
        builder.add(NodeSpec::new(format!("g{g}")).parent("root"));
        for k in 0..12 {
            let id = g * 12 + k;
            let weight = if id == 5 {
                l5
            } else {
                1.0 + (id * 7 % 10) as f64
            };
            // Leaves of a group on an arc of their own, so neighbours in
            // feature space are mostly siblings.
            let angle = 0.7 * g as f64 + 0.05 * k as f64;
            builder.add(
                NodeSpec::new(format!("l{id}"))
                    .parent(format!("g{g}"))
                    .weight(weight)
                    .features(vec![angle.cos(), angle.sin(), (k % 3) as f64]),
            );
        }
    }
    Ok(builder.build()?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let before = compute(&dataset(6.0)?, &Request::default())?;
    // The previous layout is an explicit argument, never hidden state.
    let previous = Arc::new(before.previous());

    let edited = dataset(6.6)?; // l5 grows by 10%
    let warm = compute(&edited, &{
        let mut warm = Request::default();
        warm.previous = Some(Arc::clone(&previous));
        warm
    })?;
    let cold = compute(&edited, &Request::default())?;

    for (name, run) in [("warm", &warm), ("cold", &cold)] {
        let s = stability(&previous, run);
        println!(
            "{name}: {:>5} ticks; unchanged leaves moved {:.4}% of the diagonal on average; \
             {} of {} realised constraints kept",
            run.report.iterations,
            100.0 * s.displacement_unchanged_mean,
            s.kept,
            s.realized_before
        );
    }
    Ok(())
}
