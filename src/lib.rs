//! nptreemap: neighborhood-preserving Voronoi treemaps.
//!
//! The pipeline, in five steps:
//! 1. **Parse** input bytes into a validated [`Dataset`] (crate `nptreemap-formats`).
//! 2. **Geometry** ([`geom`]): convex polygons, the only shape a cell can have.
//! 3. **Power diagrams** ([`power`]): weighted sites clipped to a convex polygon,
//!    with each cell's neighbours and shared edges.
//! 4. **Layout** ([`layout`]): a one-level optimiser (Lloyd steps plus weight
//!    adaptation towards target areas) run top-down over the hierarchy.
//! 5. **Render** ([`render`]): a finished [`Layout`] becomes layout JSON, SVG,
//!    PNG or an interactive HTML page.
//!
//! Steps 2 to 5 are pure: no files, no clock, no printing, and so are
//! [`neighborhood`] (similarity, constraints, projections, matching),
//! [`measure`] (area error, shape, the paper's Table 2, stability) and
//! [`layout_json`] (the `nptreemap-layout/1` format, written and read back).
//! Around them: [`config`] (the YAML file), [`workspace`] (the one reader of
//! files), [`store`] (the one writer), [`pipeline`] (the stages every command
//! goes through: read → parse → lay out → render → write) and [`daemon`]
//! (`nptreemap watch`: rebuild on change, warm-started).
//!
//! Cargo features: `png` (PNG output through resvg), `watch` ([`daemon`], on
//! notify) and `cli` (the `nptreemap` binary) are on by default; without them
//! (`default-features = false`) the library lays out and renders SVG, layout
//! JSON and HTML, and a PNG output is an error naming the feature.
//!
//! # Quick start
//!
//! Build a [`Dataset`] (here in code; the formats read files), [`compute()`]
//! its layout with the method its data calls for (`neighbor` when it has a
//! similarity, `plain` otherwise), and render the result:
//!
//! ```
//! use nptreemap::{compute, DatasetBuilder, NodeSpec, Request};
//!
//! let mut data = DatasetBuilder::new();
//! data.add(NodeSpec::new("fruit"));
//! for (group, items) in [("citrus", [("orange", 5.0), ("lemon", 2.0)]), ("stone", [("peach", 3.0), ("plum", 1.0)])] {
//!     data.add(NodeSpec::new(group).parent("fruit"));
//!     for (name, weight) in items {
//!         data.add(NodeSpec::new(name).parent(group).weight(weight));
//!     }
//! }
//! let dataset = data.build()?;
//! let computed = compute(&dataset, &Request::default())?;
//!
//! // Every node has a convex cell; the leaves' areas follow their weights.
//! let orange = dataset.find("orange").expect("a node");
//! let canvas = computed.layout.canvas;
//! let share = computed.layout.cells[orange].polygon.area() / (canvas.width * canvas.height);
//! assert!((share - 5.0 / 11.0).abs() < 0.02, "{share}");
//!
//! let svg = nptreemap::render::picture(&computed, &nptreemap::render::Style::default());
//! let json = nptreemap::layout_json::document(&computed);
//! let html = nptreemap::render::html_page(&computed, &nptreemap::render::Style::default());
//! assert!(svg.starts_with("<svg") && json.contains("nptreemap-layout/1") && html.contains("<svg"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A layout can start warm from the previous one ([`layout::Previous`], from a
//! finished computation or read back from layout JSON by [`layout_json::read()`]),
//! so a small change of the data is a small change of the picture;
//! [`measure::stability()`] measures how small.

pub mod config;
#[cfg(feature = "watch")]
pub mod daemon;
pub mod exec;
pub mod geom;
pub mod layout;
pub mod layout_json;
pub mod measure;
pub mod neighborhood;
pub mod pipeline;
pub mod power;
pub mod render;
pub mod rng;
pub mod store;
pub mod workspace;

pub use layout::{
    compute, Canvas, Computed, Layout, LayoutCell, Method, Outline, Params, Report, Request,
};
pub use nptreemap_formats::{Dataset, DatasetBuilder, Node, NodeSpec};
