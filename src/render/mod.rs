//! Rendering: a finished [`Layout`](crate::layout::Layout) and a style become
//! bytes (layout JSON or SVG text). PURE: may not run or alter a layout, read or
//! write files, or fail; every renderer is a total function of finished data and
//! gives identical bytes for identical input.

/// Layout JSON in the `nptreemap-layout/1` format of `shared/spec/layout-json.md`.
pub mod json;
/// Colours: hex parsing, the Tableau palettes, lightness variations for children.
pub mod palette;
/// The SVG picture: filled cells, level-weighted outlines, fitted labels.
pub mod svg;

#[cfg(test)]
mod test_support;

pub use json::{layout_json, ConstraintOut, JsonExtras};
pub use palette::Rgb;
pub use svg::{svg, SvgStyle};
