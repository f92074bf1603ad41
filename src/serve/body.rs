//! The preview's response bodies and what they hold while they are being
//! sent: a body in memory (a file, a page, a short text) handed to the
//! connection in slices, or an event stream that lasts as long as the page.
//! Owns the memory budget of bodies: a file's bytes count against
//! [`BUDGET_KIB`] from before they are read until the last slice has been
//! handed over, so that clients that never read cannot pile up copies of
//! large outputs (a stuck connection is dropped by its write timeout,
//! `conn.rs`, which frees its share).

use std::convert::Infallible;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll};

use bytes::Bytes;
use http_body::{Frame, SizeHint};
use tokio::sync::OwnedSemaphorePermit;

use super::events::EventStream;

/// Bodies read into memory at once, in KiB: 256 MiB, sixteen of the largest
/// pages we expect (a 20,000-leaf page is about 16 MB).
pub(crate) const BUDGET_KIB: u32 = 256 << 10;

/// A body is handed to the connection this many bytes at a time, so that the
/// connection's own buffer never holds more than a slice ahead of the socket.
const SLICE: usize = 64 << 10;

/// What a response holds until it has been sent (or its connection dropped).
#[derive(Default)]
pub(crate) struct Hold {
    /// Its share of the body budget.
    pub(crate) budget: Option<OwnedSemaphorePermit>,
    /// Marks its connection busy (not to be shed) while it lasts.
    pub(crate) busy: Option<Busy>,
}

/// A connection's "a response is under way" mark, cleared when dropped.
pub(crate) struct Busy(Arc<AtomicBool>);

impl Busy {
    /// Marks `flag` busy until the returned value is dropped.
    pub(crate) fn mark(flag: &Arc<AtomicBool>) -> Busy {
        flag.store(true, Ordering::SeqCst);
        Busy(flag.clone())
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        self.0.store(false, Ordering::SeqCst);
    }
}

/// A response body.
pub(crate) enum Body {
    /// Bytes in memory, sent in slices.
    Bytes {
        /// What is left to send.
        rest: Bytes,
        /// Held until the last slice is handed over.
        hold: Hold,
    },
    /// A page's event stream.
    Events(Box<EventStream>, Hold),
}

impl Body {
    /// A body of `bytes`, holding nothing.
    pub(crate) fn bytes(bytes: impl Into<Bytes>) -> Body {
        Body::Bytes {
            rest: bytes.into(),
            hold: Hold::default(),
        }
    }

    /// Attaches `busy` to the body, so its connection counts as busy until
    /// the body has been sent.
    pub(crate) fn with_busy(mut self, busy: Busy) -> Body {
        match &mut self {
            Body::Bytes { hold, .. } | Body::Events(_, hold) => hold.busy = Some(busy),
        }
        self
    }
}

impl http_body::Body for Body {
    type Data = Bytes;
    type Error = Infallible;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, Infallible>>> {
        match self.get_mut() {
            Body::Bytes { rest, hold } => {
                if rest.is_empty() {
                    // Sent: give back the share now, not when hyper drops us.
                    *hold = Hold::default();
                    return Poll::Ready(None);
                }
                let slice = rest.split_to(rest.len().min(SLICE));
                if rest.is_empty() {
                    hold.budget = None;
                }
                Poll::Ready(Some(Ok(Frame::data(slice))))
            }
            Body::Events(stream, _) => stream.poll_next(cx).map(|e| e.map(|b| Ok(Frame::data(b)))),
        }
    }

    fn is_end_stream(&self) -> bool {
        match self {
            Body::Bytes { rest, .. } => rest.is_empty(),
            Body::Events(..) => false,
        }
    }

    fn size_hint(&self) -> SizeHint {
        match self {
            Body::Bytes { rest, .. } => SizeHint::with_exact(rest.len() as u64),
            Body::Events(..) => SizeHint::default(),
        }
    }
}

/// The share of [`BUDGET_KIB`] a body of `len` bytes takes: its size in
/// KiB and a little more for the page's rewriting, at most the whole budget
/// (a file larger than the budget is still served, alone).
pub(crate) fn share(len: u64) -> u32 {
    let kib = len.div_ceil(1024).saturating_add(64);
    u32::try_from(kib).unwrap_or(u32::MAX).min(BUDGET_KIB)
}

#[cfg(test)]
mod tests {
    use super::*;
    use http_body::Body as _;

    fn drain(mut body: Body) -> Vec<usize> {
        let waker = std::task::Waker::noop();
        let mut cx = Context::from_waker(waker);
        let mut sizes = Vec::new();
        while let Poll::Ready(Some(Ok(frame))) = Pin::new(&mut body).poll_frame(&mut cx) {
            sizes.push(frame.into_data().map_or(0, |d| d.len()));
        }
        sizes
    }

    #[test]
    fn a_body_goes_in_slices_and_says_its_length() {
        let body = Body::bytes(vec![7u8; 3 * SLICE + 5]);
        assert_eq!(body.size_hint().exact(), Some(3 * SLICE as u64 + 5));
        assert_eq!(drain(body), vec![SLICE, SLICE, SLICE, 5]);
        assert!(drain(Body::bytes(Vec::new())).is_empty());
    }

    #[test]
    fn the_budget_share_is_given_back_with_the_last_slice() {
        let budget = Arc::new(tokio::sync::Semaphore::new(BUDGET_KIB as usize));
        let permit = budget
            .clone()
            .try_acquire_many_owned(share(2 * SLICE as u64))
            .expect("room");
        let mut body = Body::Bytes {
            rest: Bytes::from(vec![1u8; 2 * SLICE]),
            hold: Hold {
                budget: Some(permit),
                busy: None,
            },
        };
        let waker = std::task::Waker::noop();
        let mut cx = Context::from_waker(waker);
        let _ = Pin::new(&mut body).poll_frame(&mut cx);
        assert!(budget.available_permits() < BUDGET_KIB as usize);
        let _ = Pin::new(&mut body).poll_frame(&mut cx);
        assert_eq!(budget.available_permits(), BUDGET_KIB as usize);
    }

    #[test]
    fn shares_are_capped_by_the_budget() {
        assert_eq!(share(0), 64);
        assert_eq!(share(1024 * 1024), 1024 + 64);
        assert_eq!(share(u64::MAX), BUDGET_KIB);
    }

    #[test]
    fn busy_is_cleared_when_the_body_goes() {
        let flag = Arc::new(AtomicBool::new(false));
        let body = Body::bytes("x").with_busy(Busy::mark(&flag));
        assert!(flag.load(Ordering::SeqCst));
        drop(body);
        assert!(!flag.load(Ordering::SeqCst));
    }
}
