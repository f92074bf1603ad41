//! The daemon's status lines: one per rebuild (dataset, what changed, how it
//! was laid out, milliseconds, outputs written) and one per problem, with the
//! whole error chain on one line. Owns their wording; may not print (the
//! caller decides where lines go).

use std::fmt;
use std::path::PathBuf;

use super::change::Reason;

/// How a dataset's layout was obtained in a rebuild.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutKind {
    /// From scratch.
    Cold,
    /// Warm-started from the previous layout.
    Warm,
    /// The stored layout was reused (render-only change).
    Reused,
}

/// One line of daemon output.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// The daemon is watching.
    Watching {
        /// The config file.
        config: PathBuf,
        /// Datasets in it.
        datasets: usize,
        /// Directories watched.
        dirs: usize,
    },
    /// A dataset was rebuilt (or found unchanged).
    Built {
        /// Its name.
        dataset: String,
        /// What changed.
        reason: Reason,
        /// How the layout came about.
        layout: LayoutKind,
        /// Wall time of read + parse + layout + render + write, ms.
        ms: f64,
        /// Outputs whose bytes changed and were written.
        written: Vec<PathBuf>,
        /// Outputs left alone because their bytes would not change.
        unchanged: usize,
        /// Outputs that could not be written (each reported as a problem).
        failed: usize,
        /// Whether the dataset had a problem reported since its last good
        /// build: the line then says it is ok again.
        recovered: bool,
    },
    /// Something went wrong; the last good outputs stay.
    Problem {
        /// What it concerns: a dataset name, or `config`.
        subject: String,
        /// The error chain, outermost first.
        message: String,
        /// What the daemon does about it.
        consequence: String,
    },
    /// Something in an input that was read but probably not meant.
    Warning {
        /// The dataset.
        subject: String,
        /// The warning, naming the file and line.
        message: String,
    },
    /// A note that is not an error (a dataset left the config, ...).
    Note {
        /// What it concerns.
        subject: String,
        /// The note.
        message: String,
    },
    /// The daemon is stopping.
    Stopped,
}

impl Status {
    /// A problem from an error, with its whole `source()` chain.
    pub fn problem(
        subject: impl Into<String>,
        error: &(dyn std::error::Error + 'static),
        consequence: impl Into<String>,
    ) -> Self {
        let mut message = error.to_string();
        let mut source = error.source();
        while let Some(e) = source {
            let text = e.to_string();
            // thiserror's transparent and "{source}" variants repeat the inner
            // message; print each part once.
            if !message.contains(&text) {
                message.push_str(": ");
                message.push_str(&text);
            }
            source = e.source();
        }
        Status::Problem {
            subject: subject.into(),
            message,
            consequence: consequence.into(),
        }
    }
}

fn file_name(p: &std::path::Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Status::Watching {
                config,
                datasets,
                dirs,
            } => write!(
                f,
                "watching {} ({datasets} dataset(s), {dirs} folder(s)); Ctrl-C stops",
                config.display()
            ),
            Status::Built {
                dataset,
                reason,
                layout,
                ms,
                written,
                unchanged,
                failed,
                recovered,
            } => {
                let how = match layout {
                    LayoutKind::Cold => "laid out",
                    LayoutKind::Warm => "laid out warm",
                    LayoutKind::Reused => "re-rendered",
                };
                let again = if *recovered { "ok again, " } else { "" };
                write!(f, "{dataset}: {again}{reason}; {how} in {ms:.0} ms; ")?;
                if written.is_empty() && *failed == 0 {
                    f.write_str("no output changed")?;
                } else if written.is_empty() {
                    write!(f, "{failed} output(s) not written")?;
                    if *unchanged > 0 {
                        write!(f, ", {unchanged} unchanged")?;
                    }
                } else {
                    let names: Vec<String> = written.iter().map(|p| file_name(p)).collect();
                    write!(f, "wrote {}", names.join(", "))?;
                    let mut rest = Vec::new();
                    if *unchanged > 0 {
                        rest.push(format!("{unchanged} unchanged"));
                    }
                    if *failed > 0 {
                        rest.push(format!("{failed} not written"));
                    }
                    if !rest.is_empty() {
                        write!(f, " ({})", rest.join(", "))?;
                    }
                }
                Ok(())
            }
            Status::Problem {
                subject,
                message,
                consequence,
            } => write!(f, "{subject}: error: {message} ({consequence})"),
            Status::Warning { subject, message } => write!(f, "{subject}: warning: {message}"),
            Status::Note { subject, message } => write!(f, "{subject}: {message}"),
            Status::Stopped => f.write_str("stopped"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rebuild_line_names_dataset_change_time_and_outputs() {
        let line = Status::Built {
            dataset: "countries".to_string(),
            reason: Reason::Data(vec!["borders.csv".to_string()]),
            layout: LayoutKind::Warm,
            ms: 41.6,
            written: vec![PathBuf::from("out/c.svg"), PathBuf::from("out/c.png")],
            unchanged: 1,
            failed: 0,
            recovered: false,
        }
        .to_string();
        assert_eq!(
            line,
            "countries: data: borders.csv; laid out warm in 42 ms; wrote c.svg, c.png (1 unchanged)"
        );
    }

    #[test]
    fn failed_writes_and_recoveries_are_said() {
        let built = |written: Vec<PathBuf>, failed, recovered| {
            Status::Built {
                dataset: "c".to_string(),
                reason: Reason::Start,
                layout: LayoutKind::Cold,
                ms: 5.0,
                written,
                unchanged: 0,
                failed,
                recovered,
            }
            .to_string()
        };
        assert_eq!(
            built(Vec::new(), 3, false),
            "c: start; laid out in 5 ms; 3 output(s) not written"
        );
        assert_eq!(
            built(vec![PathBuf::from("o/a.svg")], 1, true),
            "c: ok again, start; laid out in 5 ms; wrote a.svg (1 not written)"
        );
    }

    #[test]
    fn problems_carry_the_error_chain_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("outer")]
        struct Outer(#[source] std::io::Error);
        let e = Outer(std::io::Error::other("inner"));
        let line = Status::problem("config", &e, "previous config kept").to_string();
        assert_eq!(line, "config: error: outer: inner (previous config kept)");
    }
}
