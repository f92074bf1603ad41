//! The typed event of a rebuild attempt (issue 22 item 2, for issue 25's
//! `watch --serve`): after each attempt to rebuild a dataset the daemon
//! hands one [`Rebuilt`] to whoever runs it, through the same callback that
//! receives the status lines ([`Report`]), right after the outputs are on
//! disk. A live preview subscribes to this event, not to the files or to
//! the wording of the lines: the outputs it names are the files as written.
//! Owns the event's shape and the mapping of a build error to a file, a
//! line and a message; may not print.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::SystemTime;

use super::change::Reason;
use super::status::{chain, LayoutKind, Line};
use super::worker::Outcome;
use crate::graph::StageReport;
use crate::measure::Stability;
use crate::pipeline::BuildError;
use crate::workspace::FileError;

/// What the daemon reports to its runner: the status lines, and the event
/// of each rebuild attempt.
#[derive(Clone, Debug)]
pub enum Report {
    /// A status line (printed by `nptreemap watch`).
    Line(Line),
    /// A dataset's rebuild attempt ended.
    Rebuilt(Arc<Rebuilt>),
}

/// One dataset's rebuild attempt.
#[derive(Clone, Debug)]
pub struct Rebuilt {
    /// The dataset's name.
    pub dataset: String,
    /// When the attempt ended.
    pub at: SystemTime,
    /// Why it ran.
    pub reason: Reason,
    /// What it wrote, or why it could not build.
    pub result: Result<Outputs, Failure>,
}

/// A rebuild that got as far as writing.
#[derive(Clone, Debug)]
pub struct Outputs {
    /// How the layout came about.
    pub layout: LayoutKind,
    /// From the end of the batch of events that caused it to the outputs on
    /// disk, ms (from the start of the task for a start build or a retry).
    pub ms: f64,
    /// Outputs whose bytes changed, written, in config order.
    pub written: Vec<PathBuf>,
    /// Outputs whose file already held their bytes.
    pub unchanged: Vec<PathBuf>,
    /// Outputs that could not be written (retried by the daemon).
    pub failed: Vec<Failure>,
    /// How far the cells moved against the previous picture of this
    /// session, when the dataset was laid out and there was one.
    pub stability: Option<Stability>,
    /// What each stage of the graph did, with its time.
    pub stages: StageReport,
}

/// Why a rebuild failed (or one output could not be written).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Failure {
    /// The file at fault (an input, an output), when one is.
    pub file: Option<PathBuf>,
    /// Its 1-based line, when the error knows it.
    pub line: Option<usize>,
    /// The whole message, as the status line has it.
    pub message: String,
}

impl Failure {
    /// The failure of `error`, its message with the whole chain.
    pub fn of(error: &BuildError) -> Self {
        let (file, line) = location(error);
        Failure {
            file,
            line,
            message: chain(error),
        }
    }
}

/// The event of a task's outcome, if the task attempted a rebuild (one whose
/// inputs had not changed, or that a stop abandoned, did not).
pub fn of(dataset: &str, reason: &Reason, outcome: &Outcome) -> Option<Rebuilt> {
    let result = match outcome {
        Outcome::Unchanged | Outcome::Abandoned | Outcome::Unsaved(_) => return None,
        Outcome::Unreadable(e, _) | Outcome::Failed(e, _) => Err(Failure::of(e)),
        Outcome::Panicked(message) => Err(Failure {
            file: None,
            line: None,
            message: panicked(message),
        }),
        Outcome::Built(built) => Ok(Outputs {
            layout: built.layout,
            ms: built.ms,
            written: built.written.written.clone(),
            unchanged: built.written.unchanged.clone(),
            failed: built.written.failed.iter().map(Failure::of).collect(),
            stability: built.stability,
            stages: built.stages.clone(),
        }),
    };
    Some(Rebuilt {
        dataset: dataset.to_string(),
        at: SystemTime::now(),
        reason: reason.clone(),
        result,
    })
}

/// What a panic in a rebuild says (a bug, to be reported).
pub fn panicked(message: &str) -> String {
    format!("internal error (a bug; please report it with this line): {message}")
}

/// The file and line a build error is about, when it names them.
fn location(error: &BuildError) -> (Option<PathBuf>, Option<usize>) {
    match error {
        BuildError::File(file) => match file {
            FileError::Parse { path, source } => (Some(path.clone()), source.line()),
            FileError::Read { path, .. }
            | FileError::NotRegular { path, .. }
            | FileError::TooLarge { path, .. }
            | FileError::Text { path, .. } => (Some(path.clone()), None),
        },
        BuildError::Previous { path, .. }
        | BuildError::Unsupported { path, .. }
        | BuildError::Write { path, .. }
        | BuildError::OutputClash { path, .. }
        | BuildError::OutputSpecial { path, .. } => (Some(path.clone()), None),
        #[cfg(feature = "png")]
        BuildError::Png { path, .. } => (Some(path.clone()), None),
        _ => (None, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A parse error names its file and line; a write error its output.
    #[test]
    fn failures_name_the_file_and_line() {
        let path = PathBuf::from("data/t.json");
        let parse = nptreemap_formats::FormatError::Syntax {
            line: 7,
            column: 3,
            message: "expected a value".to_string(),
        };
        let e = BuildError::File(FileError::Parse {
            path: path.clone(),
            source: Box::new(parse),
        });
        let failure = Failure::of(&e);
        assert_eq!(failure.file.as_deref(), Some(path.as_path()));
        assert_eq!(failure.line, Some(7));
        assert!(failure.message.contains("data/t.json"), "{}", failure.message);
        let e = BuildError::Write {
            path: PathBuf::from("out/a.svg"),
            source: std::io::Error::other("disk full"),
        };
        let failure = Failure::of(&e);
        assert_eq!(failure.file, Some(PathBuf::from("out/a.svg")));
        assert_eq!(failure.line, None);
    }
}
