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

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::layout::{Computed, Previous};
use crate::line_memo::LineMemo;

pub use checks::{CheckCounts, Checks};
pub use extras::{ConstraintList, ConstraintOut, JsonExtras};
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
    /// The last constraint list by its key, kept across builds: a weight
    /// edit's computation has the same.
    list: Mutex<Option<(u128, Arc<ConstraintList>)>>,
    /// How many constraint lists this memo made (the rest it kept).
    lists_made: AtomicUsize,
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
        kept.unwrap_or_else(|| Arc::new(JsonExtras::with_list(computed, self.list(computed))))
    }

    /// The constraint list of `computed`: the last one when its key is the
    /// same, else made (and kept).
    fn list(&self, computed: &Computed) -> Arc<ConstraintList> {
        let key = ConstraintList::key(computed);
        let last = lock(&self.list)
            .as_ref()
            .filter(|(k, _)| *k == key)
            .map(|(_, list)| Arc::clone(list));
        last.unwrap_or_else(|| {
            self.lists_made.fetch_add(1, Ordering::Relaxed);
            let list = Arc::new(ConstraintList::of(computed));
            *lock(&self.list) = Some((key, Arc::clone(&list)));
            list
        })
    }

    /// Computes and keeps the extras of `computed`, for the documents of
    /// this render that follow.
    pub fn keep_extras(&self, computed: &Arc<Computed>) -> Arc<JsonExtras> {
        let extras = self.extras(computed);
        *self.lock_extras() = Some((Arc::clone(computed), Arc::clone(&extras)));
        extras
    }

    /// How many constraint lists the documents written with this memo
    /// made; the others found the last one.
    pub fn lists_made(&self) -> usize {
        self.lists_made.load(Ordering::Relaxed)
    }

    /// Starts a new build: drops the older node lines and the extras (the
    /// computation they belong to is no longer held for them).
    pub fn next_build(&self) -> crate::line_memo::LineCounts {
        *self.lock_extras() = None;
        self.lines.next_build()
    }

    fn lock_extras(&self) -> std::sync::MutexGuard<'_, Option<(Arc<Computed>, Arc<JsonExtras>)>> {
        lock(&self.extras)
    }
}

/// `mutex`'s guard. A panic while the lock was held leaves a whole entry or
/// none.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{compute, Method, Request};
    use crate::neighborhood::SimilarityKind;
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

    /// Three groups of 12 leaves with 3-d vectors; leaf `edited` weighs
    /// `factor` times its base weight.
    fn tree(edited: usize, factor: f64) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for g in 0..3 {
            b.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for k in 0..12 {
                let leaf = g * 12 + k;
                let x = ((leaf * 7919) % 101) as f64 / 101.0;
                let weight =
                    (1.0 + ((leaf * 31) % 17) as f64) * if leaf == edited { factor } else { 1.0 };
                b.add(
                    NodeSpec::new(format!("g{g}l{k}"))
                        .parent(format!("g{g}"))
                        .weight(weight)
                        .features(vec![x, 1.0 - x, g as f64 / 3.0]),
                );
            }
        }
        b.build().expect("valid")
    }

    /// Issue 32: the documents of a weight edit keep the last build's
    /// constraint list (its constraints, flags and nodes are the same) and
    /// write the bytes written without the memo; a changed flag makes a new
    /// list, and its documents are again those written from scratch.
    #[test]
    fn a_weight_edit_keeps_the_constraint_list_and_writes_the_same_bytes() {
        let mut request = Request {
            similarity: Some(SimilarityKind::Cosine),
            method: Some(Method::Neighbor),
            ..Request::default()
        };
        let memo = DocumentMemo::with_lines();
        let both = |c: &Arc<Computed>| {
            memo.next_build();
            (state_with(c, Some(&memo)), document_with(c, Some(&memo)))
        };
        let first = Arc::new(compute(&tree(usize::MAX, 1.0), &request).expect("cold"));
        assert!(
            first.constraints.len() > 10,
            "{} constraints",
            first.constraints.len()
        );
        assert_eq!(both(&first), (state(&first), document(&first)));
        assert_eq!(
            memo.lists_made(),
            1,
            "the state and the .json share one list"
        );

        request.previous = Some(first.previous());
        let edited = Arc::new(compute(&tree(5, 1.1), &request).expect("warm"));
        assert_eq!(edited.constraints, first.constraints);
        assert_eq!(edited.realized, first.realized, "the edit is small");
        assert_ne!(document(&edited), document(&first), "the edit shows");
        assert_eq!(both(&edited), (state(&edited), document(&edited)));
        assert_eq!(memo.lists_made(), 1, "the weight edit kept the list");

        let mut flipped = (*edited).clone();
        flipped.realized[0] = !flipped.realized[0];
        let flipped = Arc::new(flipped);
        let (kept_state, kept_doc) = both(&flipped);
        assert_eq!(memo.lists_made(), 2, "a changed flag makes a new list");
        assert_eq!(
            (kept_state, kept_doc),
            (state(&flipped), document(&flipped))
        );
        assert_ne!(document(&flipped), document(&edited));
    }
}
