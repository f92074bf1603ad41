//! What each dataset rebuilds next (issue 21 item 3): work that arrives
//! while a dataset's rebuild runs waits here, coalesced into one rebuild
//! per dataset (three edits during a slow adapter are one rebuild after it,
//! reading the last of them), and outputs that could not be written are
//! written again with a bounded backoff until they are (issue 21 item 9).
//! PURE: names, reasons and instants in, the next task out; no threads, no
//! clock of its own (the caller passes `now`).

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use super::change::Reason;

/// What a dataset's worker does next.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Next {
    /// Read, parse, lay out, render and write.
    Build(Reason),
    /// Render the last good layout again (a render-only config change).
    Render,
    /// Write again the outputs the last rebuild could not write.
    Retry,
}

/// The first wait before writing failed outputs again; each failed retry
/// doubles it, up to [`RETRY_MAX`].
pub const RETRY_FIRST: Duration = Duration::from_secs(1);

/// The longest wait between two retries: a disk that has room again is
/// written to within this.
pub const RETRY_MAX: Duration = Duration::from_secs(60);

/// The wait before retry number `attempt` (0 for the first).
pub fn backoff(attempt: u32) -> Duration {
    RETRY_FIRST
        .checked_mul(1u32.checked_shl(attempt).unwrap_or(u32::MAX))
        .map_or(RETRY_MAX, |d| d.min(RETRY_MAX))
}

/// One reason for two rebuilds coalesced into one. A rebuild that must run
/// whatever the inputs (start, a new dataset, a layout setting) wins over
/// one that runs only if the inputs' bytes changed (an edit, a reload); two
/// edits name the files of both.
pub fn merge(first: Reason, then: Reason) -> Reason {
    match (first, then) {
        (Reason::Data(mut a), Reason::Data(b)) => {
            for f in b {
                if !a.contains(&f) {
                    a.push(f);
                }
            }
            Reason::Data(a)
        }
        (a, b) if data_only(&a) && !data_only(&b) => b,
        (a, _) => a,
    }
}

/// Whether a rebuild for `reason` runs only if the inputs' bytes changed (an
/// edit, a reload); every other reason makes it run whatever they are.
pub fn data_only(reason: &Reason) -> bool {
    matches!(reason, Reason::Data(_) | Reason::Reload)
}

/// Work waiting per dataset, and the retries of failed writes.
#[derive(Debug, Default)]
pub struct Queue {
    /// The next rebuild of each dataset that has one waiting.
    waiting: BTreeMap<String, Next>,
    /// When each dataset with unwritten outputs writes them again.
    due: BTreeMap<String, Instant>,
    /// Failed retries so far per dataset, for the backoff; forgotten once
    /// everything is written.
    attempts: BTreeMap<String, u32>,
}

impl Queue {
    /// Adds a full rebuild of `name`, coalesced with what already waits. A
    /// waiting render is never dropped (issue 30 item 6): the rebuild renders
    /// too, but it must then run even if the inputs turn out unchanged, so it
    /// takes the render's reason unless its own already makes it run.
    pub fn build(&mut self, name: &str, reason: Reason) {
        let next = match self.waiting.remove(name) {
            Some(Next::Build(before)) => Next::Build(merge(before, reason)),
            Some(Next::Render) if data_only(&reason) => Next::Build(Reason::Render),
            // A full rebuild writes every output, so it serves as the retry.
            Some(Next::Render | Next::Retry) | None => Next::Build(reason),
        };
        self.waiting.insert(name.to_string(), next);
    }

    /// Adds a render-only rebuild of `name`. A full rebuild waiting renders
    /// too, but it must then run even if its inputs turn out unchanged: its
    /// reason becomes the render change's.
    pub fn render(&mut self, name: &str) {
        let next = match self.waiting.remove(name) {
            Some(Next::Build(before)) => Next::Build(merge(before, Reason::Render)),
            Some(Next::Render | Next::Retry) | None => Next::Render,
        };
        self.waiting.insert(name.to_string(), next);
    }

    /// Whether no rebuild waits (retries not due yet aside).
    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }

    /// Drops everything of `name` (it left the config).
    pub fn forget(&mut self, name: &str) {
        self.waiting.remove(name);
        self.due.remove(name);
        self.attempts.remove(name);
    }

    /// Some outputs of `name` could not be written (at `now`): they are
    /// tried again after the next wait of the backoff, which is returned.
    pub fn failed(&mut self, name: &str, now: Instant) -> Duration {
        let attempt = self.attempts.entry(name.to_string()).or_insert(0);
        let wait = backoff(*attempt);
        *attempt = attempt.saturating_add(1);
        self.due.insert(name.to_string(), now + wait);
        wait
    }

    /// Every output of `name` is written: no retry, and the backoff starts
    /// over at the next failure.
    pub fn written(&mut self, name: &str) {
        self.due.remove(name);
        self.attempts.remove(name);
    }

    /// When the next retry is due, if one is scheduled.
    pub fn next_due(&self) -> Option<Instant> {
        self.due.values().min().copied()
    }

    /// Datasets with a rebuild waiting or a retry due at `now`, by name.
    pub fn ready(&self, now: Instant) -> Vec<String> {
        let mut names: Vec<String> = self.waiting.keys().cloned().collect();
        for (name, at) in &self.due {
            if *at <= now && !self.waiting.contains_key(name) {
                names.push(name.clone());
            }
        }
        names.sort();
        names
    }

    /// The task for `name`'s idle worker at `now`: the waiting rebuild
    /// (which writes every output anew, so it serves as the retry too; a
    /// retry stays scheduled until a rebuild says everything is written),
    /// else a retry that is due.
    pub fn take(&mut self, name: &str, now: Instant) -> Option<Next> {
        if let Some(next) = self.waiting.remove(name) {
            return Some(next);
        }
        match self.due.get(name) {
            Some(at) if *at <= now => {
                self.due.remove(name);
                Some(Next::Retry)
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(files: &[&str]) -> Reason {
        Reason::Data(files.iter().map(|f| f.to_string()).collect())
    }

    /// Three edits while a rebuild runs are one rebuild after it, naming
    /// each changed file once; a rebuild that must run wins over edits.
    #[test]
    fn work_that_waits_is_coalesced() {
        let now = Instant::now();
        let mut q = Queue::default();
        q.build("a", data(&["nodes.csv"]));
        q.build("a", data(&["pairs.csv"]));
        q.build("a", data(&["nodes.csv"]));
        q.build("b", Reason::Start);
        q.build("b", data(&["x.csv"]));
        q.render("c");
        assert_eq!(q.ready(now), ["a", "b", "c"]);
        assert_eq!(q.take("a", now), Some(Next::Build(data(&["nodes.csv", "pairs.csv"]))));
        assert_eq!(q.take("a", now), None);
        assert_eq!(q.take("b", now), Some(Next::Build(Reason::Start)));
        assert_eq!(q.take("c", now), Some(Next::Render));
        q.render("c");
        q.build("c", Reason::Start);
        assert_eq!(q.take("c", now), Some(Next::Build(Reason::Start)));
        // A render change after an edit: the rebuild runs even if the edit
        // changed no byte.
        q.build("c", data(&["x.csv"]));
        q.render("c");
        assert_eq!(q.take("c", now), Some(Next::Build(Reason::Render)));
        q.build("c", Reason::Start);
        q.render("c");
        assert_eq!(q.take("c", now), Some(Next::Build(Reason::Start)));
        assert_eq!(merge(Reason::Reload, Reason::Layout), Reason::Layout);
        assert_eq!(merge(Reason::Added, data(&["x"])), Reason::Added);
        q.build("d", Reason::Layout);
        q.forget("d");
        assert!(q.ready(now).is_empty());
    }

    /// Issue 30 item 6: a render change waiting when an edit arrives (a
    /// `render:` edit during a rebuild, then an input saved with the same
    /// bytes) is not replaced by a rebuild that runs only if the bytes
    /// changed: the coalesced rebuild must run, under the render's reason.
    #[test]
    fn a_waiting_render_survives_an_edit() {
        let now = Instant::now();
        let mut q = Queue::default();
        q.render("a");
        q.build("a", data(&["nodes.csv"]));
        assert_eq!(q.take("a", now), Some(Next::Build(Reason::Render)));
        q.render("a");
        q.build("a", Reason::Reload);
        assert_eq!(q.take("a", now), Some(Next::Build(Reason::Render)));
        // A rebuild that must run anyway keeps its own reason.
        q.render("a");
        q.build("a", Reason::Layout);
        assert_eq!(q.take("a", now), Some(Next::Build(Reason::Layout)));
        // A retry due is served by any rebuild (it writes every output).
        q.failed("a", now);
        q.build("a", data(&["nodes.csv"]));
        assert_eq!(q.take("a", now), Some(Next::Build(data(&["nodes.csv"]))));
    }

    /// Issue 21 item 9: failed writes are retried after 1, 2, 4, ... s, never
    /// more than a minute apart, until everything is written; a waiting
    /// rebuild goes first.
    #[test]
    fn failed_writes_are_retried_with_a_bounded_backoff() {
        let t0 = Instant::now();
        let mut q = Queue::default();
        let waits: Vec<u64> = (0..10).map(|_| q.failed("a", t0).as_secs()).collect();
        assert_eq!(waits, [1, 2, 4, 8, 16, 32, 60, 60, 60, 60]);
        assert_eq!(backoff(u32::MAX), RETRY_MAX);
        q.written("a");
        assert_eq!(q.failed("a", t0), RETRY_FIRST);
        assert_eq!(q.next_due(), Some(t0 + RETRY_FIRST));
        assert!(q.ready(t0).is_empty());
        assert_eq!(q.take("a", t0), None, "not due yet");
        let later = t0 + RETRY_FIRST;
        assert_eq!(q.ready(later), ["a"]);
        q.build("a", data(&["n.csv"]));
        assert_eq!(q.take("a", later), Some(Next::Build(data(&["n.csv"]))));
        assert_eq!(q.take("a", later), Some(Next::Retry));
        assert_eq!(q.next_due(), None);
        // A failed retry waits longer.
        assert_eq!(q.failed("a", later), Duration::from_secs(2));
    }
}
