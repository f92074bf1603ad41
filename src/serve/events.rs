//! The push channel of the live preview: the daemon's rebuild reports become
//! small JSON events, sent to every open page as server-sent events
//! (`text/event-stream`). Owns the event's shape, the set of open streams
//! (capped), the problems that still stand (a page opened during a bad edit
//! sees it at once; a problem goes when its subject builds again or, for the
//! config, when the config reloads) and the build keys. Publishing never
//! blocks the daemon: each stream has a small bounded queue, and a stream
//! too slow to empty it is dropped (the browser reconnects by itself).
//!
//! A build key names the build a dataset's outputs come from: this
//! server's instance (random, fresh at every start) and the number of the
//! last event that changed them. A served page carries the key of its
//! dataset taken before its file is read, so a page's key is never newer
//! than its content (at worst a page fetches again what it has). Every
//! stream starts with the current keys: a page that reconnects after
//! missing rebuilds, or after the daemon restarted, sees a key not its own
//! and fetches the current page. Why not a hash of the page on disk: it
//! would read and hash every dataset's page at every connection; the key
//! costs nothing, and a restart costs each open page one fetch.

use std::collections::BTreeMap;
use std::pin::Pin;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::Bytes;
use serde::Serialize;
use tokio::sync::mpsc::{channel, error::TrySendError, Receiver, Sender};
use tokio::time::{Instant, Interval};

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
    /// again when `key` is not theirs).
    Built {
        /// The dataset.
        dataset: String,
        /// Whether any output's bytes changed.
        changed: bool,
        /// Counts the events, so a page can tell a new one from a resend.
        seq: u64,
        /// The build key of the dataset's outputs now.
        key: String,
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
    /// A subject's problem no longer stands without a rebuild: the config
    /// reloaded, or a dataset left it.
    Cleared {
        /// The dataset, or `config`.
        dataset: String,
    },
    /// The first event of every stream: the build keys as they are now.
    Current {
        /// This server's instance, the first part of every key.
        instance: String,
        /// The key of every dataset built since the server started; a
        /// dataset not named has the key `<instance>.0`.
        keys: BTreeMap<String, String>,
    },
}

impl Event {
    /// The event of a daemon report, if it is one pages care about.
    // glue: issue 25. The daemon's typed rebuild event (issue 22's stage
    // graph) replaces `Status` here: built (outputs written/unchanged) or
    // failed (file, line, message).
    fn of(status: &Status, seq: u64, key: impl FnOnce(&str, bool) -> String) -> Option<Event> {
        match status {
            Status::Built {
                dataset, written, ..
            } => Some(Event::Built {
                dataset: dataset.clone(),
                changed: !written.is_empty(),
                seq,
                key: key(dataset, !written.is_empty()),
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
            // The daemon notes a subject only when its problem is over: the
            // config reloaded ("ok again", "reloaded on SIGHUP"), or a
            // dataset left the config.
            Status::Note { subject, .. } => Some(Event::Cleared {
                dataset: subject.clone(),
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
    streams: Vec<Sender<Arc<str>>>,
    /// The standing problem of each subject, as sent.
    standing: BTreeMap<String, Arc<str>>,
    /// The event number of each dataset's last changing build.
    built: BTreeMap<String, u64>,
    seq: u64,
}

/// The open streams, what stands and the build keys; cheap to clone (shared).
#[derive(Clone)]
pub(crate) struct Hub {
    state: Arc<Mutex<State>>,
    open: Arc<AtomicUsize>,
    instance: Arc<str>,
}

impl Hub {
    /// A hub for a server whose instance is `instance`.
    pub(crate) fn new(instance: &str) -> Hub {
        Hub {
            state: Arc::default(),
            open: Arc::default(),
            instance: instance.into(),
        }
    }

    /// The build key of `dataset`'s outputs as of now.
    pub(crate) fn key(&self, dataset: &str) -> String {
        let state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        self.key_in(&state, dataset)
    }

    fn key_in(&self, state: &State, dataset: &str) -> String {
        format!(
            "{}.{}",
            self.instance,
            state.built.get(dataset).copied().unwrap_or(0)
        )
    }

    /// Sends the event of `status` (if any) to every stream, without
    /// waiting for any of them.
    pub(crate) fn publish(&self, status: &Status) {
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        state.seq += 1;
        let seq = state.seq;
        let key = |dataset: &str, changed: bool| {
            if changed {
                state.built.insert(dataset.to_string(), seq);
            }
            self.key_in(&state, dataset)
        };
        let Some(event) = Event::of(status, seq, key) else {
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
            Event::Cleared { dataset } => {
                state.standing.remove(dataset);
            }
            Event::Problem { dataset, .. } => {
                state.standing.insert(dataset.clone(), text.clone());
            }
            Event::Current { .. } => {}
        }
        // A full queue is a stuck reader, a closed one a gone reader: both
        // are dropped here, never waited for.
        state.streams.retain(|tx| match tx.try_send(text.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Closed(_)) => false,
        });
    }

    /// A new stream (its queue, and first the current keys and what
    /// stands), or `None` when [`MAX_STREAMS`] are open.
    pub(crate) fn subscribe(&self) -> Option<EventStream> {
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        if self.open.load(Ordering::SeqCst) >= MAX_STREAMS {
            return None;
        }
        self.open.fetch_add(1, Ordering::SeqCst);
        let guard = StreamGuard(self.open.clone());
        let (tx, rx) = channel(QUEUE);
        state.streams.push(tx);
        let current = Event::Current {
            instance: self.instance.to_string(),
            keys: state
                .built
                .keys()
                .map(|d| (d.clone(), self.key_in(&state, d)))
                .collect(),
        };
        // Reconnect soon after the daemon restarts.
        let mut first = String::from("retry: 1000\n\n");
        if let Ok(text) = serde_json::to_string(&current) {
            first.push_str(&format!("data: {text}\n\n"));
        }
        for event in state.standing.values() {
            first.push_str(&format!("data: {event}\n\n"));
        }
        Some(EventStream {
            first: Some(Bytes::from(first)),
            rx,
            keepalive: None,
            _guard: guard,
        })
    }
}

/// One page's stream: what it starts with, then its queue's events, and a
/// comment after every quiet [`KEEPALIVE`].
pub(crate) struct EventStream {
    first: Option<Bytes>,
    rx: Receiver<Arc<str>>,
    keepalive: Option<Pin<Box<Interval>>>,
    _guard: StreamGuard,
}

impl EventStream {
    /// The next piece of the stream; `None` once the hub has dropped it.
    pub(crate) fn poll_next(&mut self, cx: &mut Context<'_>) -> Poll<Option<Bytes>> {
        if let Some(first) = self.first.take() {
            return Poll::Ready(Some(first));
        }
        match self.rx.poll_recv(cx) {
            Poll::Ready(Some(event)) => {
                if let Some(k) = &mut self.keepalive {
                    k.reset();
                }
                return Poll::Ready(Some(Bytes::from(format!("data: {event}\n\n"))));
            }
            Poll::Ready(None) => return Poll::Ready(None),
            Poll::Pending => {}
        }
        let keepalive = self.keepalive.get_or_insert_with(|| {
            Box::pin(tokio::time::interval_at(Instant::now() + KEEPALIVE, KEEPALIVE))
        });
        match keepalive.as_mut().poll_tick(cx) {
            Poll::Ready(_) => Poll::Ready(Some(Bytes::from_static(b": keepalive\n\n"))),
            Poll::Pending => Poll::Pending,
        }
    }
}

/// Counts an open stream until dropped.
struct StreamGuard(Arc<AtomicUsize>);

impl Drop for StreamGuard {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::change::Reason;
    use crate::daemon::status::LayoutKind;

    fn built(dataset: &str, changed: bool) -> Status {
        Status::Built {
            dataset: dataset.to_string(),
            reason: Reason::Start,
            layout: LayoutKind::Warm,
            layout_ms: None,
            why: None,
            realized: None,
            ms: 1.0,
            written: if changed { vec!["out/a.html".into()] } else { Vec::new() },
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

    /// The events a new stream starts with (after `retry:`).
    fn first_events(stream: &mut EventStream) -> Vec<String> {
        let first = stream.first.take().expect("a start");
        String::from_utf8_lossy(&first)
            .split("\n\n")
            .filter_map(|e| e.strip_prefix("data: ").map(str::to_string))
            .collect()
    }

    fn queued(stream: &mut EventStream) -> Vec<String> {
        let mut out = Vec::new();
        while let Ok(e) = stream.rx.try_recv() {
            out.push(e.to_string());
        }
        out
    }

    #[test]
    fn a_problem_stands_until_its_dataset_builds() {
        let hub = Hub::new("i");
        hub.publish(&problem("a"));
        let mut s = hub.subscribe().expect("room");
        let events = first_events(&mut s);
        assert_eq!(events.len(), 2, "{events:?}");
        assert!(events[0].contains("\"current\""));
        assert!(events[1].contains("\"problem\""));
        assert!(events[1].contains("\"file\":\"a.csv\",\"line\":3"), "{}", events[1]);
        hub.publish(&built("a", true));
        let mut s2 = hub.subscribe().expect("room");
        assert_eq!(first_events(&mut s2).len(), 1, "only the keys");
    }

    #[test]
    fn a_config_problem_goes_when_the_config_reloads() {
        let hub = Hub::new("i");
        let mut open = hub.subscribe().expect("room");
        hub.publish(&problem("config"));
        hub.publish(&Status::Note {
            subject: "config".to_string(),
            message: "ok again".to_string(),
        });
        let mut late = hub.subscribe().expect("room");
        let events = first_events(&mut late);
        assert!(
            events.iter().all(|e| !e.contains("\"problem\"")),
            "{events:?}"
        );
        // The open page hears it too.
        let told = queued(&mut open);
        assert_eq!(told.len(), 2, "{told:?}");
        assert_eq!(told[1], "{\"kind\":\"cleared\",\"dataset\":\"config\"}");
    }

    #[test]
    fn keys_change_with_the_outputs_and_the_instance() {
        let hub = Hub::new("one");
        assert_eq!(hub.key("a"), "one.0");
        hub.publish(&built("a", true));
        let changed = hub.key("a");
        assert_ne!(changed, "one.0");
        hub.publish(&built("a", false));
        assert_eq!(hub.key("a"), changed, "an unchanged build keeps the key");
        assert_eq!(hub.key("b"), "one.0");
        let mut s = hub.subscribe().expect("room");
        let current = &first_events(&mut s)[0];
        assert!(current.contains(&format!("\"a\":\"{changed}\"")), "{current}");
        assert_ne!(Hub::new("two").key("a"), hub.key("a"), "a restart changes every key");
    }

    #[test]
    fn a_stuck_stream_is_dropped_and_publishing_never_waits() {
        let hub = Hub::new("i");
        let mut s = hub.subscribe().expect("room");
        // Nobody reads the stream: far more events than its queue holds.
        for _ in 0..QUEUE * 4 {
            hub.publish(&built("a", true));
        }
        assert_eq!(queued(&mut s).len(), QUEUE);
        assert!(hub.state.lock().expect("lock").streams.is_empty());
    }

    #[test]
    fn streams_are_capped_and_freed() {
        let hub = Hub::new("i");
        let held: Vec<_> = (0..MAX_STREAMS)
            .map(|_| hub.subscribe().expect("room"))
            .collect();
        assert!(hub.subscribe().is_none());
        drop(held);
        assert!(hub.subscribe().is_some());
    }
}
