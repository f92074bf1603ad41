//! Progress for long builds: a single updating line on stderr when stderr is a
//! terminal, nothing otherwise (logs and CI stay clean).

use std::io::{IsTerminal, Write};

/// A progress line over `total` steps.
pub(crate) struct Progress {
    total: usize,
    enabled: bool,
}

impl Progress {
    pub(crate) fn new(total: usize) -> Self {
        Self {
            total,
            enabled: std::io::stderr().is_terminal() && total > 0 && !super::quiet(),
        }
    }

    /// Shows step `done` of the total, working on `what`.
    pub(crate) fn step(&self, done: usize, what: &str) {
        if !self.enabled {
            return;
        }
        let width = 24;
        let filled = width * done / self.total;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r\x1b[2K[{}{}] {done}/{} {what}",
            "#".repeat(filled),
            "-".repeat(width - filled),
            self.total
        );
        let _ = err.flush();
    }

    /// Clears the line.
    pub(crate) fn finish(&self) {
        if self.enabled {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r\x1b[2K");
            let _ = err.flush();
        }
    }
}
