//! Test fixture shared by the render tests: one small dataset with its hand-made
//! layout. Test-only; may not be used outside `#[cfg(test)]`.
//!
//! The dataset comes from `nptreemap_formats::DatasetBuilder`; adapt `sample()`
//! here (and only here) if that builder's API differs.

use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec, Rgb};

use crate::layout::{Canvas, Layout, LayoutCell};

/// A 400 × 200 canvas: `A` (left 240 wide, three stacked children, the last only 2
/// units tall) and `B` (right 160 wide, a hostile label and its own colour).
///
/// ```text
/// +--------------+--------+
/// | A1           |        |
/// +--------------+   B    |
/// | A2           |        |
/// +--------------+        |
/// | A3 (2 tall)  |        |
/// +--------------+--------+
/// ```
pub(crate) fn sample() -> (Dataset, Layout) {
    let mut builder = DatasetBuilder::new();
    builder
        .add(NodeSpec::new("root"))
        .add(NodeSpec::new("A").parent("root"))
        .add(
            NodeSpec::new("B")
                .parent("root")
                .weight(32000.0)
                .color(Rgb::new(0xff, 0, 0))
                .label("<script>alert(1)</script> \"q\""),
        )
        .add(NodeSpec::new("A1").parent("A").weight(24000.0))
        .add(NodeSpec::new("A2").parent("A").weight(23520.0))
        .add(NodeSpec::new("A3").parent("A").weight(480.0));
    let dataset = builder.build().expect("sample dataset is valid");
    let rect = |id: &str| match id {
        "root" => (0.0, 0.0, 400.0, 200.0),
        "A" => (0.0, 0.0, 240.0, 200.0),
        "B" => (240.0, 0.0, 160.0, 200.0),
        "A1" => (0.0, 0.0, 240.0, 100.0),
        "A2" => (0.0, 100.0, 240.0, 98.0),
        "A3" => (0.0, 198.0, 240.0, 2.0),
        other => panic!("no rectangle for {other}"),
    };
    let cells = dataset
        .nodes()
        .iter()
        .map(|node| {
            let (x, y, w, h) = rect(&node.id);
            LayoutCell::rectangle(x, y, w, h)
        })
        .collect();
    let layout = Layout {
        canvas: Canvas {
            width: 400.0,
            height: 200.0,
        },
        cells,
    };
    (dataset, layout)
}
