//! Layout JSON, format `nptreemap-layout/1` (the layout-JSON contract): the
//! one home of that format. [`write`](mod@write) turns a finished layout into the
//! document, [`read()`] turns a document back into the [`Previous`] layout a warm
//! start begins from, and [`extras`] chooses what beyond the geometry goes in.
//! Pure: text in, text out; the caller reads and writes the files.

/// What a document carries beyond the geometry: constraints and metrics.
pub mod extras;
/// How precisely each cell is spelled: a grid from the canvas, refined where
/// the checker's rules need it.
mod precision;
/// The reader: a document back into a previous layout, naming the bad field.
pub mod read;
/// The writer: a finished layout into a document, deterministic bytes.
pub mod write;

use crate::layout::{Computed, Previous};
use crate::line_memo::LineMemo;

pub use extras::{ConstraintOut, JsonExtras};
pub use read::ReadError;
pub use write::{layout_json, layout_json_with};

/// The value of the `format` field.
pub const FORMAT: &str = "nptreemap-layout/1";

/// The document of a finished computation, as the `.json` output: its
/// constraints and quality figures, coordinates rounded to a grid chosen from
/// the canvas (four places on 1000 × 1000) and finer where a cell needs it.
pub fn document(computed: &Computed) -> String {
    document_with(computed, None)
}

/// [`document`] with the node lines of the documents written before.
pub fn document_with(computed: &Computed, lines: Option<&LineMemo>) -> String {
    layout_json_with(
        &computed.dataset,
        &computed.layout,
        &JsonExtras::of(computed),
        lines,
    )
}

/// The document kept beside the outputs for the next warm start: the same as
/// [`document`] but in full precision, so the cells come back bit for bit
/// (a rebuild that reuses every diagram then writes the same bytes).
pub fn state(computed: &Computed) -> String {
    state_with(computed, None)
}

/// [`state`] with the node lines of the documents written before.
pub fn state_with(computed: &Computed, lines: Option<&LineMemo>) -> String {
    let mut extras = JsonExtras::of(computed);
    extras.exact = true;
    layout_json_with(&computed.dataset, &computed.layout, &extras, lines)
}

/// Reads a document (as written by [`document`] or [`state`], or by another
/// producer of the format) into the previous layout a warm start begins from.
pub fn read(text: &str) -> Result<Previous, ReadError> {
    read::previous(text)
}
