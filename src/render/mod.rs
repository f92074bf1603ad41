//! Rendering: a finished layout ([`Computed`](crate::layout::Computed)) and a
//! style become pictures (SVG text, PNG, an interactive HTML page) and, through
//! [`json`], the layout JSON of [`crate::layout_json`]. PURE: may not run or alter a layout, read
//! or write files; every renderer is a function of finished data and gives
//! identical bytes for identical input. Only PNG can fail, and then on a bug
//! (its input is our own SVG) or an absurd pixel size.

/// Virtual copies in the picture: a chain drawn once, as its leaf.
pub(crate) mod chains;
/// Colour by a numeric field: the scales and the values.
pub mod color_by;
/// CIELAB and the CIEDE2000 colour difference.
pub mod color_difference;
/// The picture as data beside its SVG text: the cells as shapes.
pub mod display;
/// The Tableau palette past twenty groups: colours picked farthest apart.
pub mod distinct;
/// Interactive HTML page: the SVG with inline hover script, style and node data.
pub mod html;
/// Which text a node's label shows (`render.labels.text`).
pub mod label_text;
/// Leaf labels fitted into their cells and group names across their groups.
pub mod labels;
/// The legend band: top-level groups and the overlay's glyphs.
pub mod legend;
/// The kinds of output and their renderers.
pub mod output;
/// Interlocking tabs and unrealised-link markers drawn over the treemap.
pub mod overlay;
/// One element as the PNG paints it: path, fill, stroke, rows, digest.
#[cfg(feature = "png")]
mod paint;
/// Colours: hex parsing, the Tableau palettes, lightness variations for children.
pub mod palette;
/// What one render keeps for the next: each leaf's label by its drawn cell.
pub mod parts;
/// The framed picture: map, overlay, title, legend, border; its [`Style`].
pub mod picture;
/// PNG from the SVG text, painted with tiny-skia and a built-in font.
#[cfg(feature = "png")]
pub mod png;
/// The PNG's pixels in bands, and the repaint of the bands an edit touched.
#[cfg(feature = "png")]
mod png_bands;
/// The SVG writer's text read back into what the PNG paints.
#[cfg(feature = "png")]
mod png_plan;
/// The SVG picture: filled cells, level-weighted outlines, fitted labels.
pub mod svg;
/// The built-in font: metrics, shaping and glyph outlines, cached.
pub(crate) mod text;

#[cfg(test)]
pub(crate) mod test_support;

/// The built-in font's metrics, for the repository's own tests: the page's
/// label fitter (`page/fit.js`) is held to the picture's with them.
#[cfg(feature = "internals")]
#[doc(hidden)]
pub mod metrics {
    pub use super::labels::line_step_em;
    pub use super::text::{ascent_em, width_em};
}

pub use color_by::{ColorBy, ColorScale};
pub use display::Picture;
pub use html::{
    html, html_page, html_page_with_history, html_page_with_parts, page_patch, HtmlData, HtmlEmpty,
    HtmlFrame, HtmlLayout, HtmlNode,
};
pub use label_text::{DisplayNames, LabelText};
pub use labels::LabelStyle;
pub use output::{OutputError, OutputKind};
pub use palette::{PaletteKind, Rgb};
pub use parts::{LabelCounts, Parts};
pub use picture::{
    fit_labels, group_colors, picture, picture_with, Border, LegendOrder, PageFields, Style,
};
#[cfg(feature = "png")]
pub use png::{png, PngError};
pub use svg::{svg, Kept, SvgStyle};

/// The layout JSON (`nptreemap-layout/1`) of a finished computation, beside the
/// pictures: [`crate::layout_json::document`], which also reads it back.
pub fn json(computed: &crate::layout::Computed) -> String {
    crate::layout_json::document(computed)
}
