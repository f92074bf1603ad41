//! The smallest complete use of the library: a dataset built in code, laid out,
//! and printed as SVG on stdout. No files are read or written.
//!
//! Run with `cargo run --example minimal > minimal.svg`.

use nptreemap::render::{picture, Style};
use nptreemap::{DatasetBuilder, NodeSpec, Request};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut builder = DatasetBuilder::new();
    builder.add(NodeSpec::new("fruit"));
    for (group, items) in [
        (
            "citrus",
            &[("orange", 5.0), ("lemon", 2.0), ("lime", 1.0)][..],
        ),
        ("berries", &[("strawberry", 4.0), ("blueberry", 3.0)][..]),
        (
            "stone",
            &[("peach", 2.5), ("cherry", 1.5), ("plum", 1.0)][..],
        ),
    ] {
        builder.add(NodeSpec::new(group).parent("fruit"));
        for (name, weight) in items {
            builder.add(NodeSpec::new(*name).parent(group).weight(*weight));
        }
    }
    let dataset = builder.build()?;
    let computed = nptreemap::layout(&dataset, &Request::default())?;
    eprintln!(
        "{} diagrams, mean area error {:.4}",
        computed.report.diagrams, computed.report.area_error_mean
    );
    println!("{}", picture(&computed, &Style::default()));
    Ok(())
}
