//! The picture as data beside its SVG text (issue 32, item 1: "one
//! picture, two painters"): the picture writer (`picture`, `svg`) writes the
//! SVG text and, as it writes them, keeps the cells (nine tenths and more of
//! a map's text: 9.4 of 9.8 MB at 6,000 C headers) as shapes with the
//! numbers the text spells. The PNG paints those shapes as they are and
//! reads back only the rest of the text (title, tabs, labels, legend:
//! some 60 KB there), instead of parsing the whole document to find the
//! cells again. Renderer-neutral (colours as [`Rgb`], coordinates as
//! `f64`): the painter turns a shape into its own path.

use std::ops::Range;

use super::palette::Rgb;

/// A finished picture: its SVG text and its cells as shapes.
#[derive(Clone, Debug)]
pub struct Picture {
    /// The SVG document, byte for byte what the SVG output writes.
    pub text: String,
    /// The cells' group: its bytes in [`Picture::text`] and its shapes in
    /// paint order. `None` when the writer kept no shapes (a number it could
    /// not spell as the text does, or a build without PNG output): the
    /// painter then reads the whole text.
    #[cfg_attr(not(feature = "png"), allow(dead_code))]
    pub(crate) cells: Option<Cells>,
}

/// The cells' group of a picture (see [`Picture::cells`]).
#[derive(Clone, Debug)]
#[cfg_attr(not(feature = "png"), allow(dead_code))]
pub(crate) struct Cells {
    /// The group element's bytes in the picture's text.
    pub range: Range<usize>,
    /// Every cell's shape, in the order the text draws them.
    pub shapes: Vec<Shape>,
}

/// A closed polygon filled and outlined with round joins, the way the SVG
/// writer draws a cell: every number is the one its text spells.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Shape {
    /// The corners, as read back from the text's two decimals.
    pub points: Vec<[f64; 2]>,
    /// The fill; `None` for `fill="none"` (a group's cell).
    pub fill: Option<Rgb>,
    /// The outline's colour.
    pub stroke: Rgb,
    /// The outline's width, as spelled.
    pub width: f64,
}

impl Picture {
    /// A picture known only by its text (the painter reads all of it).
    pub fn from_text(text: String) -> Picture {
        Picture { text, cells: None }
    }
}
