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

pub use layout::{Canvas, Layout, LayoutCell, Outline, Params, Report};
pub use nptreemap_formats::{Dataset, Node};
