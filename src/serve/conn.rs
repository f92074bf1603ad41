//! The preview's connections and their bounds. Every connection is a task
//! on the server's one-thread runtime (never a thread of its own), read by
//! hyper's HTTP/1 server with a bounded request head: at most [`HEAD_MAX`]
//! bytes ([`HEAD_BUF`] of buffer), which must arrive within [`HEAD_TIME`]
//! (an idle kept-alive connection is closed then too). At most
//! [`MAX_CONNECTIONS`] are open at once: when a new one finds them all
//! taken, the oldest one that has no response under way is closed to make
//! room (a flood of idle sockets sheds itself, and the page of the person
//! at the keyboard still gets through); when every one has a response under
//! way, the new one is closed at once. A write that makes no progress for
//! [`WRITE_STALL`] ends its connection, so a client that never reads holds
//! only its own connection, and only for that long.

use std::collections::BTreeMap;
use std::convert::Infallible;
use std::future::Future;
use std::io::IoSlice;
use std::pin::{pin, Pin};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll};
use std::time::Duration;

use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::Notify;
use tokio::time::{sleep, Instant, Sleep};

use super::body::Busy;
use super::Shared;

/// Connections open at once (lowered to half the open-file limit when that
/// is lower, so that accepting never runs the daemon out of descriptors).
pub(crate) const MAX_CONNECTIONS: usize = 512;

/// Largest request head (request line and headers); a larger one is
/// answered 431 and the connection closed. Browsers send well under 8 KiB.
const HEAD_MAX: usize = 32 << 10;

/// A connection's read buffer: the most of a head kept in memory.
const HEAD_BUF: usize = 64 << 10;

/// Time for a whole request head to arrive, from the first byte read for it
/// (or from the end of the previous answer, on a kept-alive connection).
const HEAD_TIME: Duration = Duration::from_secs(10);

/// Time a write may make no progress before its connection is dropped.
pub(crate) const WRITE_STALL: Duration = Duration::from_secs(10);

/// Pause after an accept that failed for want of resources (descriptors,
/// memory), so the loop waits for them instead of spinning.
const ACCEPT_PAUSE: Duration = Duration::from_millis(100);

/// Accepts connections on `listener` for as long as the process runs.
pub(crate) async fn accept(listener: std::net::TcpListener, shared: Arc<Shared>) {
    let listener = match TcpListener::from_std(listener) {
        Ok(l) => l,
        Err(e) => {
            tracing::warn!(error = %e, "the preview cannot listen");
            return;
        }
    };
    let slots = Slots::new(connection_cap());
    let mut warned: Option<Instant> = None;
    loop {
        let tcp = match listener.accept().await {
            Ok((tcp, _)) => tcp,
            Err(e) => {
                // A connection reset before it was accepted is its client's
                // business; anything else (EMFILE, ENOMEM) is worth a line,
                // once a minute at most, and a pause.
                if e.kind() != std::io::ErrorKind::ConnectionAborted {
                    if warned.is_none_or(|t| t.elapsed() > Duration::from_secs(60)) {
                        tracing::warn!(error = %e, "the preview cannot accept a connection");
                        warned = Some(Instant::now());
                    }
                    sleep(ACCEPT_PAUSE).await;
                }
                continue;
            }
        };
        // Dropping the socket refuses it: every slot has a response under way.
        let Some(slot) = slots.admit() else { continue };
        tokio::spawn(serve(tcp, slot, shared.clone()));
    }
}

/// [`MAX_CONNECTIONS`], or half the soft open-file limit when lower.
fn connection_cap() -> usize {
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit with a valid resource and a pointer to a local.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut lim) } == 0;
    if !ok || lim.rlim_cur == libc::RLIM_INFINITY {
        return MAX_CONNECTIONS;
    }
    usize::try_from(lim.rlim_cur / 2).map_or(MAX_CONNECTIONS, |half| half.clamp(16, MAX_CONNECTIONS))
}

/// One connection, until it ends, fails, stalls or is shed.
async fn serve(tcp: TcpStream, slot: Slot, shared: Arc<Shared>) {
    let _ = tcp.set_nodelay(true);
    let Ok(local) = tcp.local_addr() else { return };
    let io = TokioIo::new(Stall::new(tcp));
    let busy = slot.state.busy.clone();
    let service = service_fn(move |request| {
        let (shared, mark) = (shared.clone(), Busy::mark(&busy));
        async move {
            let response = super::handle(request, &shared, local).await;
            Ok::<_, Infallible>(response.map(|body| body.with_busy(mark)))
        }
    });
    let mut builder = http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(HEAD_TIME)
        .max_buf_size(HEAD_BUF)
        .max_header_size(HEAD_MAX);
    let connection = pin!(builder.serve_connection(io, service));
    let shed = pin!(slot.state.shed.notified());
    // Whichever comes first: the connection's end or the order to make room.
    let mut both = (connection, shed);
    std::future::poll_fn(|cx| {
        if both.1.as_mut().poll(cx).is_ready() {
            return Poll::Ready(());
        }
        both.0.as_mut().poll(cx).map(|_| ())
    })
    .await;
}

/// The open connections, oldest first.
struct Slots {
    open: Arc<Mutex<Open>>,
    cap: usize,
}

#[derive(Default)]
struct Open {
    next: u64,
    by_age: BTreeMap<u64, Arc<SlotState>>,
}

#[derive(Default)]
struct SlotState {
    /// A response is under way (set while a request's answer lasts).
    busy: Arc<AtomicBool>,
    /// Told to close, to make room.
    shed: Notify,
}

/// A connection's place among the open ones, given back when dropped.
struct Slot {
    id: u64,
    state: Arc<SlotState>,
    open: Arc<Mutex<Open>>,
}

impl Drop for Slot {
    fn drop(&mut self) {
        let mut open = self.open.lock().unwrap_or_else(PoisonError::into_inner);
        open.by_age.remove(&self.id);
    }
}

impl Slots {
    fn new(cap: usize) -> Slots {
        Slots {
            open: Arc::default(),
            cap,
        }
    }

    /// A place for a new connection: a free one, or the place of the oldest
    /// connection without a response under way, which is told to close.
    /// `None` when every connection has a response under way.
    fn admit(&self) -> Option<Slot> {
        let mut open = self.open.lock().unwrap_or_else(PoisonError::into_inner);
        if open.by_age.len() >= self.cap {
            let idle = open
                .by_age
                .iter()
                .find(|(_, s)| !s.busy.load(Ordering::SeqCst))
                .map(|(id, _)| *id)?;
            if let Some(state) = open.by_age.remove(&idle) {
                state.shed.notify_one();
            }
        }
        let id = open.next;
        open.next += 1;
        let state = Arc::new(SlotState::default());
        open.by_age.insert(id, state.clone());
        Some(Slot {
            id,
            state,
            open: self.open.clone(),
        })
    }
}

/// A socket whose writes fail once they have made no progress for
/// [`WRITE_STALL`]: hyper then ends the connection.
struct Stall {
    io: TcpStream,
    since: Option<Pin<Box<Sleep>>>,
}

impl Stall {
    fn new(io: TcpStream) -> Stall {
        Stall { io, since: None }
    }

    /// `poll`'s result, or a timeout error when it has been pending too long.
    fn watch<T>(
        &mut self,
        cx: &mut Context<'_>,
        poll: Poll<std::io::Result<T>>,
    ) -> Poll<std::io::Result<T>> {
        if poll.is_ready() {
            self.since = None;
            return poll;
        }
        let timer = self
            .since
            .get_or_insert_with(|| Box::pin(sleep(WRITE_STALL)));
        match timer.as_mut().poll(cx) {
            Poll::Ready(()) => Poll::Ready(Err(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                "the client stopped reading",
            ))),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl AsyncRead for Stall {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.get_mut().io).poll_read(cx, buf)
    }
}

impl AsyncWrite for Stall {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<std::io::Result<usize>> {
        let me = self.get_mut();
        let poll = Pin::new(&mut me.io).poll_write(cx, buf);
        me.watch(cx, poll)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[IoSlice<'_>],
    ) -> Poll<std::io::Result<usize>> {
        let me = self.get_mut();
        let poll = Pin::new(&mut me.io).poll_write_vectored(cx, bufs);
        me.watch(cx, poll)
    }

    fn is_write_vectored(&self) -> bool {
        self.io.is_write_vectored()
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        let me = self.get_mut();
        let poll = Pin::new(&mut me.io).poll_flush(cx);
        me.watch(cx, poll)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        let me = self.get_mut();
        let poll = Pin::new(&mut me.io).poll_shutdown(cx);
        me.watch(cx, poll)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_house_sheds_its_oldest_idle_connection() {
        let slots = Slots::new(3);
        let a = slots.admit().expect("room");
        let b = slots.admit().expect("room");
        let c = slots.admit().expect("room");
        a.state.busy.store(true, Ordering::SeqCst);
        // Full: b is the oldest without a response under way.
        let d = slots.admit().expect("b's place");
        let open: Vec<u64> = slots
            .open
            .lock()
            .expect("lock")
            .by_age
            .keys()
            .copied()
            .collect();
        assert_eq!(open, vec![a.id, c.id, d.id]);
        // b was told to close.
        let told = pin!(b.state.shed.notified());
        let waker = std::task::Waker::noop();
        assert!(told.poll(&mut Context::from_waker(waker)).is_ready());
        // Every one busy: the next is refused.
        for s in [&c, &d] {
            s.state.busy.store(true, Ordering::SeqCst);
        }
        assert!(slots.admit().is_none());
        drop(c);
        assert!(slots.admit().is_some(), "a closed connection frees its place");
    }

    #[test]
    fn the_cap_follows_the_open_file_limit() {
        let cap = connection_cap();
        assert!((16..=MAX_CONNECTIONS).contains(&cap), "{cap}");
    }
}
