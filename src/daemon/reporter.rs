//! The watch daemon's status reporter: every line and event goes out
//! through it, and it owns what keeps them worth reading: a problem is
//! reported once until it is fixed ("ok again"), an input warning once until
//! it was gone, a parse failure only when its inputs stayed quiet for
//! [`SETTLE`] (a file caught mid-write), and at most [`MAX_WARNINGS`]
//! warnings per rebuild.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::event::{self, Report};
use super::queue::Queue;
use super::status::{Line, Status};
use super::worker::{self, Done, Outcome};
use super::{Reason, POLL};
use crate::config::DatasetConfig;
use crate::pipeline::Fault;
use crate::graph::Stage;

/// How long the inputs must stay unchanged after a parse failure before it
/// is reported (see [`Reporter::pending`]): long enough for a writer
/// descheduled mid-write on a busy machine, short for a person fixing a typo.
const SETTLE: Duration = Duration::from_millis(1000);

/// The most input warnings printed for one rebuild; more are summed up in
/// one line (a million repeated pairs must not flood the journal).
const MAX_WARNINGS: usize = 50;

/// What the queue should do after an outcome was reported.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum Follow {
    /// Nothing.
    Nothing,
    /// Some output or the state could not be written: try again later.
    Retry,
    /// Everything was written.
    Written,
}

/// The reporter: where lines go, and what was said.
pub(super) struct Reporter<'a> {
    report: &'a mut dyn FnMut(Report),
    /// Parse failures not reported yet, by dataset, with when they happened:
    /// a file read while a writer is still at it (editors and scripts writing
    /// in place truncate first) fails to parse, and the write's own events
    /// bring a rebuild that succeeds. A failure is reported only when the
    /// inputs then stay quiet for [`SETTLE`]; a good rebuild forgets it.
    pending: BTreeMap<String, (Status, Instant)>,
    /// When the last relevant event arrived (for [`SETTLE`]).
    last_event: Instant,
    /// The problems last reported per subject (a dataset or `config`), until
    /// they are fixed: the same problems are not reported twice in a row,
    /// and the fix is announced ("ok again").
    troubled: BTreeMap<String, BTreeSet<String>>,
    /// The input warnings last reported per dataset: a warning is printed
    /// again only when it was gone in between (issue 21 item 4).
    warned: BTreeMap<String, BTreeSet<String>>,
}

impl<'a> Reporter<'a> {
    /// A reporter sending to `report`.
    pub(super) fn new(report: &'a mut dyn FnMut(Report)) -> Self {
        Reporter {
            report,
            pending: BTreeMap::new(),
            last_event: Instant::now(),
            troubled: BTreeMap::new(),
            warned: BTreeMap::new(),
        }
    }

    /// Notes that relevant events arrived (a pending problem waits again).
    pub(super) fn events(&mut self, at: Instant) {
        self.last_event = at;
    }

    /// Whether a problem of `subject` is open (its next rebuild should run
    /// even if nothing changed, to find out whether it is gone).
    pub(super) fn troubled(&self, subject: &str) -> bool {
        self.troubled.contains_key(subject)
    }

    /// Forgets a dataset that left the config.
    pub(super) fn forget(&mut self, name: &str) {
        self.pending.remove(name);
        self.troubled.remove(name);
        self.warned.remove(name);
    }

    /// Reports one line, with its time of day.
    pub(super) fn say(&mut self, status: Status) {
        (self.report)(Report::Line(Line::now(status)));
    }


    /// How long the loop may wait for events: until the next pending problem
    /// or retry is due, and at most [`POLL`].
    pub(super) fn wait(&self, queue: &Queue) -> Duration {
        let now = Instant::now();
        self.pending
            .values()
            .map(|(_, at)| (*at).max(self.last_event) + SETTLE)
            .chain(queue.next_due())
            .map(|due| due.saturating_duration_since(now))
            .fold(POLL, Duration::min)
    }


    /// Reports the pending problems whose inputs stayed quiet for [`SETTLE`].
    pub(super) fn settle(&mut self) {
        let now = Instant::now();
        let due: Vec<String> = self
            .pending
            .iter()
            .filter(|(_, (_, at))| now >= (*at).max(self.last_event) + SETTLE)
            .map(|(name, _)| name.clone())
            .collect();
        for name in due {
            if let Some((problem, _)) = self.pending.remove(&name) {
                self.problems(&name, vec![problem]);
            }
        }
    }


    /// Reports the problems of one outcome about `subject`, except those
    /// reported for it last time (a retry failing as before says nothing
    /// new; a problem gone and back is reported again).
    pub(super) fn problems(&mut self, subject: &str, problems: Vec<Status>) {
        let key = |p: &Status| match p {
            // The error, not the consequence: the same failure is the same
            // problem whatever became of the other outputs meanwhile.
            Status::Problem { message, .. } => message.clone(),
            other => other.to_string(),
        };
        let before = self.troubled.remove(subject).unwrap_or_default();
        let now: BTreeSet<String> = problems.iter().map(key).collect();
        for problem in problems {
            if !before.contains(&key(&problem)) {
                self.say(problem);
            }
        }
        self.troubled.insert(subject.to_string(), now);
    }


    /// Forgets `subject`'s problems; true when there were some (it is ok again).
    pub(super) fn fixed(&mut self, subject: &str) -> bool {
        self.troubled.remove(subject).is_some()
    }


    /// Reports one outcome: its event, then its lines.
    pub(super) fn outcome(&mut self, d: &DatasetConfig, Done { name, reason, outcome }: Done) -> Follow {
        if let Some(event) = event::of(&name, &reason, &outcome) {
            (self.report)(Report::Rebuilt(Arc::new(event)));
        }
        match outcome {
            Outcome::Unchanged => {}
            Outcome::Abandoned => tracing::debug!(dataset = name, "stopping; rebuild abandoned"),
            Outcome::Unreadable(e, consequence) => {
                self.problems(&name, vec![Status::problem(&name, &e, consequence)]);
            }
            Outcome::Failed(e, consequence) if e.fault() == Fault::Input => {
                tracing::debug!(dataset = name, error = ?e.to_string(), "input refused; reported unless the input changes again");
                let problem = Status::problem(&name, &e, consequence);
                self.pending.insert(name, (problem, Instant::now()));
            }
            Outcome::Failed(e, consequence) => {
                self.problems(&name, vec![Status::problem(&name, &e, consequence)]);
            }
            Outcome::Panicked(message) => {
                let problem = Status::Problem {
                    subject: name.clone(),
                    message: event::panicked(&message),
                    consequence: worker::kept(d, false).to_string(),
                };
                self.problems(&name, vec![problem]);
            }
            Outcome::Built(built) => return self.built(&name, built),
            Outcome::Unsaved(e) => {
                tracing::warn!(dataset = name, error = ?e.to_string(), "cannot store the layout for warm starts; retried");
                return Follow::Retry;
            }
        }
        Follow::Nothing
    }

    /// Reports a rebuild that wrote its outputs (or tried): its new warnings,
    /// each output that failed, then its line; schedules a retry of what was
    /// not written.
    fn built(&mut self, name: &str, built: worker::Built) -> Follow {
        let worker::Built {
            reason,
            layout,
            why,
            realized,
            ms,
            written,
            warnings,
            unsaved,
            stages,
            ..
        } = built;
        // The layout's own time, beside the whole rebuild's: a warm layout
        // of 81 ms in a rebuild of 1.5 s is not "laid out warm in 1540 ms".
        let layout_ms = stages
            .runs
            .iter()
            .find(|r| r.stage == Stage::Layout && r.ran)
            .map(|r| r.ms);
        self.pending.remove(name);
        let retry = reason == Reason::Retry;
        if !retry {
            self.warn(name, warnings);
        }
        // With -v: the figure benches/incremental.py reads.
        tracing::info!("{name}: outputs on disk {ms:.1} ms after the batch ({reason})");
        let failed = written.failed.len();
        let others = match (written.written.len(), written.unchanged.len()) {
            (0, 0) => "no output written".to_string(),
            (0, _) => "the other outputs unchanged".to_string(),
            (w, 0) => format!("{w} other output(s) written"),
            (w, u) => format!("{w} other output(s) written, {u} unchanged"),
        };
        if let Some(e) = &unsaved {
            tracing::warn!(dataset = name, error = ?e.to_string(), "cannot store the layout for warm starts; retried");
        }
        let recovered = if failed == 0 {
            self.fixed(name)
        } else {
            let consequence = format!("{others}; written again as soon as it can be");
            let problems = written
                .failed
                .iter()
                .map(|e| Status::problem(name, e, consequence.clone()))
                .collect();
            self.problems(name, problems);
            false
        };
        let follow = if failed > 0 || unsaved.is_some() {
            Follow::Retry
        } else {
            Follow::Written
        };
        // A retry says something only when it made a difference: the
        // outputs are all written now after a reported failure.
        if retry && !recovered {
            return follow;
        }
        self.say(Status::Built {
            dataset: name.to_string(),
            reason,
            layout,
            layout_ms,
            why,
            realized,
            ms,
            written: written.written,
            unchanged: written.unchanged.len(),
            failed,
            recovered,
        });
        follow
    }

    /// Reports the warnings of a rebuild that were not reported for the
    /// dataset's last one, at most [`MAX_WARNINGS`] of them.
    fn warn(&mut self, name: &str, warnings: Vec<String>) {
        let before = self.warned.remove(name).unwrap_or_default();
        let fresh: Vec<&String> = warnings.iter().filter(|w| !before.contains(*w)).collect();
        for message in fresh.iter().take(MAX_WARNINGS) {
            self.say(Status::Warning {
                subject: name.to_string(),
                message: (*message).clone(),
            });
        }
        if fresh.len() > MAX_WARNINGS {
            self.say(Status::Warning {
                subject: name.to_string(),
                message: format!(
                    "and {} more warning(s) (`nptreemap check` lists them all)",
                    fresh.len() - MAX_WARNINGS
                ),
            });
        }
        self.warned
            .insert(name.to_string(), warnings.into_iter().collect());
    }
}
