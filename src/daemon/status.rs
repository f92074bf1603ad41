//! The daemon's status lines: one per rebuild (dataset, what changed, how it
//! was laid out, milliseconds, outputs written) and one per problem, with the
//! whole error chain on one line, each after its time of day ([`Line`]).
//! Owns their wording, and that a line is one line: control characters in
//! names, paths and quoted messages are printed escaped ([`escape`]), so a
//! file named with a newline cannot forge a line (log injection) nor an
//! escape sequence colour the terminal. May not print (the caller decides
//! where lines go).

use std::borrow::Cow;
use std::fmt;
use std::path::PathBuf;
use std::time::SystemTime;

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
    /// Nothing had changed since the outputs were made (by the state
    /// folder's manifest): nothing was laid out or drawn.
    UpToDate,
    /// Nothing was laid out or drawn: outputs that could not be written
    /// before were written again.
    Kept,
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
        /// The layout stage's own time, ms, when it ran.
        layout_ms: Option<f64>,
        /// Why it was laid out cold, when it was.
        why: Option<String>,
        /// The constraints realised and in all, when there are any.
        realized: Option<(usize, usize)>,
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
        Status::Problem {
            subject: subject.into(),
            message: chain(error),
            consequence: consequence.into(),
        }
    }
}

/// An error's message with its whole `source()` chain, each part once.
pub fn chain(error: &(dyn std::error::Error + 'static)) -> String {
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
    message
}

fn file_name(p: &std::path::Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

impl fmt::Display for Status {
    /// The line, its control characters escaped.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&escape(&self.raw()))
    }
}

/// `text` with every control character (C0, DEL, C1, the Unicode line and
/// paragraph separators, and the bidirectional overrides that reorder what
/// a terminal shows) written as Rust writes it in a string literal (`\n`,
/// `\t`, `\u{1b}`), so that it stays one line and cannot drive a terminal.
/// Everything else, backslashes included, is left as it is, so ordinary
/// paths read as before.
pub fn escape(text: &str) -> Cow<'_, str> {
    let special = |c: char| {
        c.is_control()
            || matches!(c, '\u{2028}' | '\u{2029}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if !text.contains(special) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if special(c) {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// A status line as printed: the time of day it was made, in UTC
/// (`HH:MM:SS`, as journald and most log collectors keep the date and the
/// zone themselves), then the [`Status`].
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// When it was made.
    pub at: SystemTime,
    /// What it says.
    pub status: Status,
}

impl Line {
    /// `status`, made now.
    pub fn now(status: Status) -> Self {
        Line {
            at: SystemTime::now(),
            status,
        }
    }
}

/// The UTC time of day of `at`, `HH:MM:SS` (a clock before 1970 shows
/// 00:00:00).
pub fn time_of_day(at: SystemTime) -> String {
    let secs = at
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let day = secs % 86_400;
    format!("{:02}:{:02}:{:02}", day / 3600, day % 3600 / 60, day % 60)
}

impl fmt::Display for Line {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", time_of_day(self.at), self.status)
    }
}

impl Status {
    /// The line before escaping.
    fn raw(&self) -> String {
        let mut f = String::new();
        // Writing to a String cannot fail.
        let _ = self.write_raw(&mut f);
        f
    }

    fn write_raw(&self, f: &mut String) -> fmt::Result {
        use fmt::Write as _;
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
                layout_ms,
                why,
                realized,
                ms,
                written,
                unchanged,
                failed,
                recovered,
            } => {
                let how = match layout {
                    LayoutKind::Cold => "laid out cold",
                    LayoutKind::Warm => "laid out warm",
                    LayoutKind::Reused => "re-rendered",
                    LayoutKind::UpToDate => "found up to date",
                    LayoutKind::Kept => "written again",
                };
                let again = if *recovered { "ok again, " } else { "" };
                // Like `build`'s line: how the layout was got (and why
                // cold), its own time, then the whole rebuild's, then the
                // constraints realised.
                write!(f, "{dataset}: {again}{reason}; {how} in ")?;
                match (layout, layout_ms) {
                    (LayoutKind::Cold | LayoutKind::Warm, Some(l)) => write!(f, "{l:.0} ms")?,
                    _ => write!(f, "{ms:.0} ms")?,
                }
                if let Some(why) = why {
                    write!(f, " ({why})")?;
                }
                if let (LayoutKind::Cold | LayoutKind::Warm, Some(_)) = (layout, layout_ms) {
                    write!(f, ", on disk in {ms:.0} ms")?;
                }
                if let Some((done, all)) = realized {
                    let share = 100.0 * *done as f64 / (*all).max(1) as f64;
                    write!(f, "; {done} of {all} constraints realized ({share:.1}%)")?;
                }
                f.write_str("; ")?;
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
        let line = |layout, layout_ms| {
            Status::Built {
                dataset: "countries".to_string(),
                reason: Reason::Data(vec!["borders.csv".to_string()]),
                layout,
                layout_ms,
                why: None,
                realized: Some((74, 88)),
                ms: 41.6,
                written: vec![PathBuf::from("out/c.svg"), PathBuf::from("out/c.png")],
                unchanged: 1,
                failed: 0,
                recovered: false,
            }
            .to_string()
        };
        // The layout's time and the whole rebuild's, each named.
        assert_eq!(
            line(LayoutKind::Warm, Some(8.2)),
            "countries: data: borders.csv; laid out warm in 8 ms, on disk in 42 ms; \
             74 of 88 constraints realized (84.1%); wrote c.svg, c.png (1 unchanged)"
        );
        // A rebuild that only drew again has one time.
        assert!(line(LayoutKind::Reused, None).contains("; re-rendered in 42 ms; 74 of 88 constraints"));
    }

    #[test]
    fn failed_writes_and_recoveries_are_said() {
        let built = |written: Vec<PathBuf>, failed, recovered| {
            Status::Built {
                dataset: "c".to_string(),
                reason: Reason::Start,
                layout: LayoutKind::Cold,
                layout_ms: None,
                why: Some("no stored layout".to_string()),
                realized: None,
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
            "c: start; laid out cold in 5 ms (no stored layout); 3 output(s) not written"
        );
        assert_eq!(
            built(vec![PathBuf::from("o/a.svg")], 1, true),
            "c: ok again, start; laid out cold in 5 ms (no stored layout); wrote a.svg (1 not written)"
        );
    }

    /// Issue 21 item 9: a name with a newline, a carriage return or an
    /// escape sequence stays on its line and prints no control character.
    #[test]
    fn control_characters_are_escaped_in_every_line() {
        let evil = "a\nfake: line\r\u{1b}[31mred\u{2028}\u{202e}x";
        let lines = [
            Status::Built {
                dataset: evil.to_string(),
                reason: Reason::Data(vec![evil.to_string()]),
                layout: LayoutKind::Cold,
                layout_ms: None,
                why: None,
                realized: None,
                ms: 1.0,
                written: vec![PathBuf::from(format!("out/{evil}.svg"))],
                unchanged: 0,
                failed: 0,
                recovered: false,
            },
            Status::Problem {
                subject: evil.to_string(),
                message: evil.to_string(),
                consequence: evil.to_string(),
            },
            Status::Warning {
                subject: evil.to_string(),
                message: evil.to_string(),
            },
            Status::Note {
                subject: evil.to_string(),
                message: evil.to_string(),
            },
            Status::Watching {
                config: PathBuf::from(evil),
                datasets: 1,
                dirs: 1,
            },
        ];
        for status in lines {
            let line = status.to_string();
            assert!(
                !line.chars().any(|c| c.is_control()
                    || matches!(c, '\u{2028}' | '\u{202e}')),
                "{line:?}"
            );
            assert!(
                line.contains("a\\nfake: line\\r\\u{1b}[31mred\\u{2028}\\u{202e}x"),
                "{line:?}"
            );
        }
        // Ordinary text, backslashes and non-ASCII letters included, is as it was.
        assert_eq!(escape("C:\\data\\日本.csv"), "C:\\data\\日本.csv");
    }

    /// Issue 22 item 4: each line starts with its time of day, in UTC.
    #[test]
    fn lines_start_with_the_time_of_day() {
        let at = SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(19_999 * 86_400 + 3_723);
        let line = Line {
            at,
            status: Status::Stopped,
        };
        assert_eq!(line.to_string(), "01:02:03 stopped");
        assert_eq!(
            time_of_day(SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(86_399)),
            "23:59:59"
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
