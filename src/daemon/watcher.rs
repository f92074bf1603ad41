//! The file-system side of `watch`: a notify watcher over a set of
//! directories (not files: editors save atomically by writing a temp file and
//! renaming it over the original, which replaces the inode a file watch would
//! follow), and the batching of its events into one rebuild (100 ms of quiet,
//! 500 ms at most, as typst's watcher does, so a burst of saves is one rebuild
//! and a steady stream of them cannot postpone it forever). Owns event
//! filtering and batching, and noticing watched folders that were deleted,
//! replaced or created (inotify drops the watch of a deleted folder, so a
//! folder made again under the same name would go unwatched; missing folders
//! are polled until they exist); may not know about datasets or configs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use notify::event::{EventKind, ModifyKind};
use notify::{RecursiveMode, Watcher as _};

/// What reaches the daemon's loop.
#[derive(Debug)]
pub enum Message {
    /// A file-system event (or a watcher error).
    Fs(notify::Result<notify::Event>),
    /// SIGHUP: read the config (and every input) again.
    Reload,
    /// SIGINT / SIGTERM: finish cleanly.
    Stop,
    /// A dataset's worker finished a task: the loop has an outcome to
    /// report. Ends an idle wait ([`Batch::Idle`]); a batch being collected
    /// goes on (the outcome waits until it closes).
    Wake,
}

/// The result of waiting for the next batch.
#[derive(Debug, PartialEq, Eq)]
pub enum Batch {
    /// Paths touched by relevant events, each once, sorted.
    Paths(BTreeSet<PathBuf>),
    /// A reload was asked for, with the paths of the batch it interrupted.
    Reload(BTreeSet<PathBuf>),
    /// No relevant event came within the idle time asked for.
    Idle,
    /// Stop was asked for (or every sender is gone).
    Stop,
}

/// Batching windows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timing {
    /// A batch closes after this long without a relevant event. Default: 100 ms.
    pub quiet: Duration,
    /// A batch closes at the latest this long after its first event. Default: 500 ms.
    pub cap: Duration,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            quiet: Duration::from_millis(100),
            cap: Duration::from_millis(500),
        }
    }
}

/// A folder's identity (device and inode), to tell a folder made again under
/// the same name from the one that was watched.
type DirId = (u64, u64);

fn dir_id(dir: &Path) -> Option<DirId> {
    crate::workspace::dir_identity(dir)
}

/// A notify watcher over directories, updated by mark-and-sweep; a wanted
/// directory that does not exist is remembered and polled ([`DirWatcher::check`]).
pub struct DirWatcher {
    inner: notify::RecommendedWatcher,
    /// Every wanted directory: its identity when watched, `None` while it is
    /// missing (or cannot be watched).
    dirs: BTreeMap<PathBuf, Option<DirId>>,
}

impl DirWatcher {
    /// A watcher whose events go to `tx`.
    pub fn new(tx: Sender<Message>) -> notify::Result<Self> {
        let inner = notify::recommended_watcher(move |event| {
            // The loop may have ended; a lost event then does not matter.
            let _ = tx.send(Message::Fs(event));
        })?;
        Ok(Self {
            inner,
            dirs: BTreeMap::new(),
        })
    }

    /// Watches exactly `dirs` (non-recursively): new ones are added, ones no
    /// longer wanted removed. A directory that does not exist (yet) cannot be
    /// watched; it is returned with the error so the caller can report it,
    /// and polled by [`DirWatcher::check`] until it exists.
    pub fn sync(&mut self, dirs: &BTreeSet<PathBuf>) -> Vec<(PathBuf, notify::Error)> {
        let stale: Vec<PathBuf> = self
            .dirs
            .keys()
            .filter(|d| !dirs.contains(*d))
            .cloned()
            .collect();
        for dir in stale {
            if let Some(Some(_)) = self.dirs.remove(&dir) {
                let _ = self.inner.unwatch(&dir);
            }
        }
        let mut failed = Vec::new();
        for dir in dirs {
            if self.dirs.contains_key(dir) {
                continue;
            }
            match self.watch(dir) {
                Ok(id) => {
                    self.dirs.insert(dir.clone(), Some(id));
                }
                Err(e) => {
                    self.dirs.insert(dir.clone(), None);
                    failed.push((dir.clone(), e));
                }
            }
        }
        failed
    }

    fn watch(&mut self, dir: &Path) -> notify::Result<DirId> {
        let id = dir_id(dir)
            .ok_or_else(|| notify::Error::path_not_found().add_path(dir.to_path_buf()))?;
        self.inner.watch(dir, RecursiveMode::NonRecursive)?;
        Ok(id)
    }

    /// Looks at every wanted directory (a few `stat`s; the daemon calls it
    /// between batches) and returns those whose content may have changed
    /// unseen: one that appeared (it is watched from now on), one replaced by
    /// another of the same name (watched anew), one that disappeared (its
    /// files are gone; polled until it is back).
    pub fn check(&mut self) -> Vec<PathBuf> {
        let mut changed = Vec::new();
        let dirs: Vec<(PathBuf, Option<DirId>)> =
            self.dirs.iter().map(|(d, id)| (d.clone(), *id)).collect();
        for (dir, known) in dirs {
            let now = dir_id(&dir);
            if now == known {
                continue;
            }
            if known.is_some() {
                // Deleted or replaced: the old watch is dead either way.
                let _ = self.inner.unwatch(&dir);
            }
            let watched = match now {
                Some(_) => self.watch(&dir).ok(),
                None => None,
            };
            tracing::debug!(?dir, ?known, ?watched, "watched folder changed");
            self.dirs.insert(dir.clone(), watched);
            // A folder that exists but cannot be watched yet is retried at
            // the next check; it counts as changed once it is watched.
            if watched.is_some() || known.is_some() {
                changed.push(dir);
            }
        }
        changed
    }

    /// The directories currently watched.
    pub fn watched(&self) -> BTreeSet<PathBuf> {
        self.dirs
            .iter()
            .filter(|(_, id)| id.is_some())
            .map(|(d, _)| d.clone())
            .collect()
    }
}

/// Whether an event kind can mean new content: creations, writes, renames and
/// removals. Access events (reads, opens, closes without writing) and metadata
/// changes (touch, chmod) cannot.
fn changes_content(kind: &EventKind) -> bool {
    match kind {
        EventKind::Create(_) | EventKind::Remove(_) => true,
        EventKind::Modify(ModifyKind::Metadata(_)) => false,
        EventKind::Modify(_) => true,
        EventKind::Access(_) => false,
        // Some back ends report a close-after-write only as "other"/"any";
        // the content hash decides later whether anything changed.
        EventKind::Any | EventKind::Other => true,
    }
}

/// Waits for the next batch of events whose paths `relevant` accepts. Blocks
/// until the first such event (or Stop; or [`Batch::Idle`] once `idle` has
/// passed without one, when given, or a [`Message::Wake`] came), then
/// collects until `timing.quiet` passes without another one or `timing.cap`
/// after the first.
pub fn next_batch(
    rx: &Receiver<Message>,
    timing: Timing,
    relevant: &dyn Fn(&Path) -> bool,
    idle: Option<Duration>,
) -> Batch {
    let mut paths = BTreeSet::new();
    let mut first: Option<Instant> = None;
    let mut last = Instant::now();
    let idle_at = idle.map(|d| last + d);
    loop {
        let message = match (first, idle_at) {
            (None, None) => match rx.recv() {
                Ok(m) => m,
                Err(_) => return Batch::Stop,
            },
            (None, Some(at)) => {
                let now = Instant::now();
                if now >= at {
                    return Batch::Idle;
                }
                match rx.recv_timeout(at - now) {
                    Ok(m) => m,
                    Err(RecvTimeoutError::Timeout) => return Batch::Idle,
                    Err(RecvTimeoutError::Disconnected) => return Batch::Stop,
                }
            }
            (Some(start), _) => {
                let now = Instant::now();
                let deadline = (last + timing.quiet).min(start + timing.cap);
                if now >= deadline {
                    return Batch::Paths(paths);
                }
                match rx.recv_timeout(deadline - now) {
                    Ok(m) => m,
                    Err(RecvTimeoutError::Timeout) => return Batch::Paths(paths),
                    Err(RecvTimeoutError::Disconnected) => return Batch::Stop,
                }
            }
        };
        match message {
            Message::Stop => return Batch::Stop,
            Message::Reload => return Batch::Reload(paths),
            Message::Wake if first.is_none() => return Batch::Idle,
            Message::Wake => {}
            Message::Fs(Err(e)) => {
                // Debug-quoted: the message may name a path, which may hold a
                // newline (a log line must stay one line).
                tracing::warn!(error = ?e.to_string(), "file watcher error");
            }
            Message::Fs(Ok(event)) => {
                if !changes_content(&event.kind) {
                    continue;
                }
                let mut hit = false;
                for p in event.paths.iter().filter(|p| relevant(p)) {
                    paths.insert(p.clone());
                    hit = true;
                }
                tracing::trace!(kind = ?event.kind, paths = ?event.paths, relevant = hit, "event");
                if hit {
                    last = Instant::now();
                    first.get_or_insert(last);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::{AccessKind, CreateKind, DataChange, MetadataKind};
    use std::sync::mpsc::channel;

    fn event(kind: EventKind, path: &str) -> Message {
        Message::Fs(Ok(notify::Event::new(kind).add_path(PathBuf::from(path))))
    }

    fn short() -> Timing {
        Timing {
            quiet: Duration::from_millis(30),
            cap: Duration::from_millis(200),
        }
    }

    #[test]
    fn irrelevant_paths_and_access_events_do_not_open_a_batch() {
        let (tx, rx) = channel();
        tx.send(event(EventKind::Access(AccessKind::Any), "/d/a.csv"))
            .expect("send");
        tx.send(event(
            EventKind::Modify(ModifyKind::Metadata(MetadataKind::Any)),
            "/d/a.csv",
        ))
        .expect("send");
        tx.send(event(EventKind::Create(CreateKind::File), "/d/.a.csv.swp"))
            .expect("send");
        tx.send(event(
            EventKind::Modify(ModifyKind::Data(DataChange::Any)),
            "/d/a.csv",
        ))
        .expect("send");
        let relevant = |p: &Path| p == Path::new("/d/a.csv");
        // Closed by the quiet window: exactly the one relevant content change.
        assert_eq!(
            next_batch(&rx, short(), &relevant, None),
            Batch::Paths([PathBuf::from("/d/a.csv")].into_iter().collect())
        );
        tx.send(Message::Stop).expect("send");
        assert_eq!(next_batch(&rx, short(), &relevant, None), Batch::Stop);
    }

    /// A stream of events that never pauses for the quiet window still
    /// closes a batch (at the cap) while it goes on. The stream lasts until
    /// the batch is closed (at most a minute), so what shows the cap worked
    /// is that the stream had not ended, whatever the machine's load; no
    /// duration is asserted.
    #[test]
    fn a_steady_stream_is_cut_at_the_cap() {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::sync::Arc;
        let (tx, rx) = channel();
        let (closed, ended) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
        let feeder = {
            let (closed, ended) = (closed.clone(), ended.clone());
            std::thread::spawn(move || {
                // An event every 10 ms: never quiet for 30 ms.
                let until = Instant::now() + Duration::from_secs(60);
                while !closed.load(Ordering::SeqCst) && Instant::now() < until {
                    let modify = EventKind::Modify(ModifyKind::Data(DataChange::Any));
                    if tx.send(event(modify, "/d/a.csv")).is_err() {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                ended.store(true, Ordering::SeqCst);
            })
        };
        let batch = next_batch(&rx, short(), &|_| true, None);
        let cut = !ended.load(Ordering::SeqCst);
        closed.store(true, Ordering::SeqCst);
        assert!(matches!(batch, Batch::Paths(ref p) if p.len() == 1));
        assert!(cut, "the batch closed only when the stream ended");
        drop(rx);
        feeder.join().expect("feeder");
    }

    /// A worker's outcome ends an idle wait at once, but not a batch being
    /// collected (its events stay together).
    #[test]
    fn a_wake_ends_an_idle_wait_only() {
        let (tx, rx) = channel();
        tx.send(Message::Wake).expect("send");
        let idle = Some(Duration::from_secs(600));
        assert_eq!(next_batch(&rx, short(), &|_| true, idle), Batch::Idle);
        tx.send(event(EventKind::Create(CreateKind::File), "/d/a.csv"))
            .expect("send");
        tx.send(Message::Wake).expect("send");
        tx.send(event(EventKind::Create(CreateKind::File), "/d/b.csv"))
            .expect("send");
        let both: BTreeSet<PathBuf> = ["/d/a.csv", "/d/b.csv"].iter().map(PathBuf::from).collect();
        assert_eq!(next_batch(&rx, short(), &|_| true, idle), Batch::Paths(both));
    }

    #[test]
    fn idle_when_nothing_relevant_comes() {
        let (tx, rx) = channel();
        tx.send(event(EventKind::Access(AccessKind::Any), "/d/a.csv"))
            .expect("send");
        let idle = Some(Duration::from_millis(50));
        assert_eq!(next_batch(&rx, short(), &|_| true, idle), Batch::Idle);
        drop(tx);
    }

    #[test]
    fn stop_wins_while_waiting() {
        let (tx, rx) = channel();
        tx.send(Message::Stop).expect("send");
        assert_eq!(
            next_batch(&rx, Timing::default(), &|_| true, None),
            Batch::Stop
        );
        drop(tx);
    }
}
