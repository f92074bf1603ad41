//! nptreemap: neighborhood-preserving Voronoi treemaps.
//!
//! The public API is a small facade:
//! - [`Dataset`] (built with [`DatasetBuilder`], or read by the formats crate
//!   `nptreemap-formats`): a validated tree whose leaves carry weights and,
//!   optionally, a similarity ([`SimilarityKind`]) between nodes;
//! - [`Request`] (with its [`Params`]) and [`compute()`], which runs the method
//!   the data calls for: the neighbourhood-preserving method of the paper when
//!   the data has a similarity, the plain Voronoi treemap otherwise;
//! - [`Computed`] with its [`Layout`] (one convex cell per node, [`geom`]'s
//!   polygons), its [`Constraint`]s and a [`Report`];
//! - [`render`] (SVG, PNG, the interactive HTML page) and [`layout_json`] (the
//!   `nptreemap-layout/1` format, written and read back for warm starts);
//! - [`measure`]: area error, shape, the paper's Table 2, stability.
//!
//! All of it is pure: no files, no clock, no printing. The configuration file,
//! the file system, the build pipeline and `nptreemap watch` are the binary's
//! and stay private to the crate.
//!
//! Cargo features: `png` (PNG output through resvg), `watch` (`nptreemap watch`,
//! on notify) and `cli` (the `nptreemap` binary) are on by default; without them
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

// Items of the internal modules are `pub` for the `internals` build; without
// it they are crate-private through their module, which is the point.
#![cfg_attr(not(feature = "internals"), allow(unreachable_pub))]

// Declares the internal modules: `pub(crate)`, except with the `internals`
// feature, which the repository's own tests, examples and benchmarks turn on
// (through their dev-dependency on this crate) to reach the pieces they
// measure. There they are public but hidden from the docs and outside any
// compatibility promise.
macro_rules! internal {
    ($($(#[$attr:meta])* mod $name:ident;)*) => {$(
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        $(#[$attr])*
        pub mod $name;
        #[cfg(not(feature = "internals"))]
        $(#[$attr])*
        pub(crate) mod $name;
    )*};
}

// The edge of the tool (config, files, the build pipeline) serves the binary
// and the daemon; the library alone is the pure core and its renderers.
internal! {
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod config;
    #[cfg(feature = "watch")]
    mod daemon;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod exec;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod fingerprint;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod graph;
    mod neighborhood;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod pipeline;
    mod power;
    mod rng;
    #[cfg(feature = "serve")]
    mod serve;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod state;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod store;
    #[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
    mod workspace;
}

/// The `nptreemap` binary's command line (not part of the API).
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod cli;
pub mod geom;
pub mod layout;
pub mod layout_json;
pub mod line_memo;
pub mod measure;
pub mod render;

/// Lays out `dataset` with the method its data calls for (the paper's
/// neighbourhood-preserving method when it has a similarity, the plain Voronoi
/// treemap otherwise, unless `request` names one): the library's entry point,
/// the same as [`compute()`]. `layout::layout` is the plain treemap alone.
///
/// ```
/// use nptreemap::{DatasetBuilder, NodeSpec, Request};
///
/// let mut data = DatasetBuilder::new();
/// data.add(NodeSpec::new("root"));
/// for (name, weight) in [("a", 3.0), ("b", 1.0)] {
///     data.add(NodeSpec::new(name).parent("root").weight(weight));
/// }
/// let computed = nptreemap::layout(&data.build()?, &Request::default())?;
/// let json = nptreemap::render::json(&computed);
/// assert!(json.contains("nptreemap-layout/1"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn layout(dataset: &Dataset, request: &Request) -> Result<Computed, layout::LayoutError> {
    compute(dataset, request)
}

pub use layout::{
    compute, Canvas, Computed, Layout, LayoutCell, Method, Outline, Params, Report, Request,
};
pub use neighborhood::{Constraint, SimilarityKind};
pub use nptreemap_formats::{Dataset, DatasetBuilder, Node, NodeSpec};
