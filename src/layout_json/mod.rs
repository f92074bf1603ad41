//! Layout JSON, format `nptreemap-layout/1` (the layout-JSON contract): the
//! one home of that format. [`write`](mod@write) turns a finished layout into the
//! document, [`read()`] turns a document back into the [`Previous`] layout a warm
//! start begins from, and [`extras`] chooses what beyond the geometry goes in.
//! Pure: text in, text out; the caller reads and writes the files.

/// The precision choice's checks, kept from one document to the next.
mod checks;
/// What a document carries beyond the geometry: constraints and metrics.
pub mod extras;
/// How precisely each cell is spelled: a grid from the canvas, refined where
/// the checker's rules need it.
mod precision;
/// The reader: a document back into a previous layout, naming the bad field.
pub mod read;
/// One cell as the writer spells it.
mod spelled;
/// The writer: a finished layout into a document, deterministic bytes.
pub mod write;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::layout::{Computed, Previous};
use crate::line_memo::LineMemo;

pub use checks::{CheckCounts, Checks};
pub use extras::{ConstraintOut, JsonExtras};
pub use read::ReadError;
pub use write::{layout_json, layout_json_with};

/// The value of the `format` field.
pub const FORMAT: &str = "nptreemap-layout/1";

/// What the documents of one process keep for the next (issue 32, item 2):
/// the node lines ([`LineMemo`]), the precision choice's checks
/// ([`Checks`]), and the extras of the computation being rendered, which
/// its stored layout and its `.json` output share. Held by the render's
/// parts; the bytes are those written without it.
#[derive(Debug, Default)]
pub struct DocumentMemo {
    /// Node lines of this build and the last, once [`DocumentMemo::keep_lines`]
    /// turned them on.
    pub lines: LineMemo,
    lines_on: AtomicBool,
    /// The last precision choice's checks.
    pub checks: Checks,
    /// The extras of the computation held: the address is compared only
    /// while the memo holds the computation, so it cannot have been reused.
    extras: Mutex<Option<(Arc<Computed>, Arc<JsonExtras>)>>,
}

impl DocumentMemo {
    /// A memo that keeps node lines from its first document on.
    pub fn with_lines() -> DocumentMemo {
        let memo = DocumentMemo::default();
        memo.keep_lines();
        memo
    }

    /// Keeps node lines from now on. A process's first render (every
    /// one-shot build) has none to find, and keeping its lines would cost
    /// it a third of the documents' time for nothing; the render's parts
    /// turn them on from the second.
    pub fn keep_lines(&self) {
        self.lines_on.store(true, Ordering::Relaxed);
    }

    /// The node lines, when they are kept.
    pub fn lines(&self) -> Option<&LineMemo> {
        self.lines_on.load(Ordering::Relaxed).then_some(&self.lines)
    }

    /// The extras of `computed`: the ones kept when `computed` is the
    /// computation they were kept for, else computed.
    fn extras(&self, computed: &Computed) -> Arc<JsonExtras> {
        let kept = match &*self.lock_extras() {
            Some((c, extras)) if std::ptr::eq(Arc::as_ptr(c), computed) => Some(Arc::clone(extras)),
            _ => None,
        };
        // Computed with the lock released: the figures run on the rayon
        // pool, whose thread, waiting on them, may take up another document
        // of this memo and ask for the lock itself.
        kept.unwrap_or_else(|| Arc::new(JsonExtras::of(computed)))
    }

    /// Computes and keeps the extras of `computed`, for the documents of
    /// this render that follow.
    pub fn keep_extras(&self, computed: &Arc<Computed>) -> Arc<JsonExtras> {
        let extras = self.extras(computed);
        *self.lock_extras() = Some((Arc::clone(computed), Arc::clone(&extras)));
        extras
    }

    /// Starts a new build: drops the older node lines and the extras (the
    /// computation they belong to is no longer held for them).
    pub fn next_build(&self) -> crate::line_memo::LineCounts {
        *self.lock_extras() = None;
        self.lines.next_build()
    }

    fn lock_extras(&self) -> std::sync::MutexGuard<'_, Option<(Arc<Computed>, Arc<JsonExtras>)>> {
        // A panic while the lock was held leaves a whole entry or none.
        self.extras.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The document of a finished computation, as the `.json` output: its
/// constraints and quality figures, coordinates rounded to a grid chosen from
/// the canvas (four places on 1000 × 1000) and finer where a cell needs it.
pub fn document(computed: &Computed) -> String {
    document_with(computed, None)
}

/// [`document`] with the memo of the documents written before.
pub fn document_with(computed: &Computed, memo: Option<&DocumentMemo>) -> String {
    let extras = match memo {
        Some(m) => m.extras(computed),
        None => Arc::new(JsonExtras::of(computed)),
    };
    write::write_document(&computed.dataset, &computed.layout, &extras, false, memo)
}

/// The document kept beside the outputs for the next warm start: the same as
/// [`document`] but in full precision, so the cells come back bit for bit
/// (a rebuild that reuses every diagram then writes the same bytes).
pub fn state(computed: &Computed) -> String {
    write::write_document(
        &computed.dataset,
        &computed.layout,
        &JsonExtras::of(computed),
        true,
        None,
    )
}

/// [`state`] with the memo of the documents written before; its extras are
/// kept there for the `.json` output of the same computation.
pub fn state_with(computed: &Arc<Computed>, memo: Option<&DocumentMemo>) -> String {
    let extras = match memo {
        Some(m) => m.keep_extras(computed),
        None => Arc::new(JsonExtras::of(computed)),
    };
    write::write_document(&computed.dataset, &computed.layout, &extras, true, memo)
}

/// Reads a document (as written by [`document`] or [`state`], or by another
/// producer of the format) into the previous layout a warm start begins from.
pub fn read(text: &str) -> Result<Previous, ReadError> {
    read::previous(text)
}
