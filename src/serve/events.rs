//! The push channel of the live preview: the daemon's rebuild reports become
//! small JSON events, sent to every open page as server-sent events
//! (`text/event-stream`). Owns the event's shape, the set of open streams
//! (capped) and the problems that still stand (a page opened during a bad
//! edit sees it at once). Publishing never blocks the daemon: each stream has
//! a small bounded queue, and a stream too slow to empty it is dropped (the
//! browser reconnects by itself and is sent what stands).

use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use serde::Serialize;

use crate::daemon::status::Status;

/// Most event streams open at once; more are answered 503.
pub(crate) const MAX_STREAMS: usize = 32;

/// Events queued for one stream before it counts as stuck and is dropped.
const QUEUE: usize = 16;

/// How often an idle stream sends a comment, which also finds closed
/// connections (the write fails).
const KEEPALIVE: Duration = Duration::from_secs(10);

/// One push to the pages.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub(crate) enum Event {
    /// A dataset was rebuilt: its outputs are current (pages fetch theirs
    /// again when `changed`).
    Built {
        /// The dataset.
        dataset: String,
        /// Whether any output's bytes changed.
        changed: bool,
        /// Counts the rebuilds, so a page can tell a new one from a resend.
        seq: u64,
    },
    /// A rebuild failed; the last good outputs stay. `dataset` is `config`
    /// for a bad config, which concerns every page.
    Problem {
        /// The dataset, or `config`.
        dataset: String,
        /// The file at fault, when the error names one.
        #[serde(skip_serializing_if = "Option::is_none")]
        file: Option<String>,
        /// Its line, when the error names one.
        #[serde(skip_serializing_if = "Option::is_none")]
        line: Option<u64>,
        /// The whole error, naming the file and line where the reader knows them.
        message: String,
        /// What the daemon does about it.
        consequence: String,
    },
}

impl Event {
    /// The event of a daemon report, if it is one pages care about.
    // glue: issue 25. The daemon's typed rebuild event (issue 22's stage
    // graph) replaces `Status` here: built (outputs written/unchanged) or
    // failed (file, line, message).
    fn of(status: &Status, seq: u64) -> Option<Event> {
        match status {
            Status::Built {
                dataset, written, ..
            } => Some(Event::Built {
                dataset: dataset.clone(),
                changed: !written.is_empty(),
                seq,
            }),
            Status::Problem {
                subject,
                message,
                consequence,
            } => Some(Event::Problem {
                dataset: subject.clone(),
                file: where_(message).map(|w| w.0),
                line: where_(message).and_then(|w| w.1),
                message: message.clone(),
                consequence: consequence.clone(),
            }),
            _ => None,
        }
    }
}

/// The file and line an error message starts with (`<file>: line 7, column
/// 3: …`, as the readers write them), if it does.
fn where_(message: &str) -> Option<(String, Option<u64>)> {
    let (file, rest) = message.split_once(": ")?;
    let line = rest
        .strip_prefix("line ")
        .map(|r| r.chars().take_while(char::is_ascii_digit).collect::<String>())
        .and_then(|d| d.parse().ok());
    // A file names a path, not a word of the message.
    let path = file.contains(['/', '\\']) || (file.contains('.') && !file.contains(' '));
    path.then(|| (file.to_string(), line))
}

#[derive(Default)]
struct State {
    streams: Vec<SyncSender<Arc<str>>>,
    /// The standing problem of each subject, as sent.
    standing: BTreeMap<String, Arc<str>>,
    seq: u64,
}

/// The open streams and what stands; cheap to clone (shared).
#[derive(Clone, Default)]
pub(crate) struct Hub {
    state: Arc<Mutex<State>>,
    open: Arc<AtomicUsize>,
}

impl Hub {
    /// Sends the event of `status` (if any) to every stream, without
    /// waiting for any of them.
    pub(crate) fn publish(&self, status: &Status) {
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        state.seq += 1;
        let Some(event) = Event::of(status, state.seq) else {
            return;
        };
        let text: Arc<str> = match serde_json::to_string(&event) {
            Ok(t) => t.into(),
            Err(_) => return,
        };
        match &event {
            Event::Built { dataset, .. } => {
                state.standing.remove(dataset);
                // A good build after a bad config means the config is good.
                state.standing.remove("config");
            }
            Event::Problem { dataset, .. } => {
                state.standing.insert(dataset.clone(), text.clone());
            }
        }
        // A full queue is a stuck reader, a closed one a gone reader: both
        // are dropped here, never waited for.
        state.streams.retain(|tx| match tx.try_send(text.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => false,
        });
    }

    /// A new stream's queue and the events it starts with, or `None` when
    /// [`MAX_STREAMS`] are open.
    fn subscribe(&self) -> Option<Subscription> {
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        if self.open.load(Ordering::SeqCst) >= MAX_STREAMS {
            return None;
        }
        self.open.fetch_add(1, Ordering::SeqCst);
        let guard = StreamGuard(self.open.clone());
        let (tx, rx) = sync_channel(QUEUE);
        state.streams.push(tx);
        let standing = state.standing.values().cloned().collect();
        Some(Subscription(rx, standing, guard))
    }

    /// Answers an event-stream request on a thread of its own (or with 503
    /// when too many are open). The thread ends when the page goes away, the
    /// stream is dropped as stuck, or the process ends.
    pub(crate) fn serve(&self, request: tiny_http::Request, headers: &str) {
        let Some(Subscription(rx, standing, guard)) = self.subscribe() else {
            let _ = request.respond(super::plain(503, "too many open pages"));
            return;
        };
        let head = format!(
            "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n{headers}\r\n"
        );
        let spawned = std::thread::Builder::new()
            .name("np-serve-events".to_string())
            .spawn(move || {
                let _guard = guard;
                let mut out = request.into_writer();
                let _ = stream(&mut out, &head, &standing, &rx);
            });
        if let Err(e) = spawned {
            tracing::warn!(error = %e, "cannot start an event stream");
        }
    }
}

/// A new stream: its queue, the events it starts with, its place in the count.
struct Subscription(Receiver<Arc<str>>, Vec<Arc<str>>, StreamGuard);

/// Counts an open stream until dropped.
struct StreamGuard(Arc<AtomicUsize>);

impl Drop for StreamGuard {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Writes the stream until a write fails or the queue is gone.
fn stream(
    out: &mut dyn Write,
    head: &str,
    standing: &[Arc<str>],
    rx: &Receiver<Arc<str>>,
) -> std::io::Result<()> {
    out.write_all(head.as_bytes())?;
    // Reconnect soon after the daemon restarts.
    out.write_all(b"retry: 1000\n\n")?;
    for event in standing {
        write!(out, "data: {event}\n\n")?;
    }
    out.flush()?;
    loop {
        match rx.recv_timeout(KEEPALIVE) {
            Ok(event) => write!(out, "data: {event}\n\n")?,
            Err(RecvTimeoutError::Timeout) => out.write_all(b": keepalive\n\n")?,
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        }
        out.flush()?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::change::Reason;
    use crate::daemon::status::LayoutKind;

    fn built(dataset: &str) -> Status {
        Status::Built {
            dataset: dataset.to_string(),
            reason: Reason::Start,
            layout: LayoutKind::Warm,
            ms: 1.0,
            written: vec!["out/a.html".into()],
            unchanged: 0,
            failed: 0,
            recovered: false,
        }
    }

    fn problem(subject: &str) -> Status {
        Status::Problem {
            subject: subject.to_string(),
            message: "a.csv: line 3: weight: not a number".to_string(),
            consequence: "last good outputs kept".to_string(),
        }
    }

    #[test]
    fn a_problem_stands_until_its_dataset_builds() {
        let hub = Hub::default();
        hub.publish(&problem("a"));
        let Subscription(_, standing, _g) = hub.subscribe().expect("room");
        assert_eq!(standing.len(), 1);
        assert!(standing[0].contains("\"problem\""));
        assert!(standing[0].contains("\"file\":\"a.csv\",\"line\":3"), "{}", standing[0]);
        hub.publish(&built("a"));
        let Subscription(_, standing, _g2) = hub.subscribe().expect("room");
        assert!(standing.is_empty());
    }

    #[test]
    fn a_stuck_stream_is_dropped_and_publishing_never_waits() {
        let hub = Hub::default();
        let Subscription(rx, _, _g) = hub.subscribe().expect("room");
        // Nobody reads `rx`: far more events than its queue holds.
        for _ in 0..QUEUE * 4 {
            hub.publish(&built("a"));
        }
        assert_eq!(rx.try_iter().count(), QUEUE);
        assert!(hub.state.lock().expect("lock").streams.is_empty());
    }

    #[test]
    fn streams_are_capped_and_freed() {
        let hub = Hub::default();
        let held: Vec<_> = (0..MAX_STREAMS)
            .map(|_| hub.subscribe().expect("room"))
            .collect();
        assert!(hub.subscribe().is_none());
        drop(held);
        assert!(hub.subscribe().is_some());
    }
}
