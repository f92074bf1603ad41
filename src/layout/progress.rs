//! Progress of a layout run, and the way to stop one: the pure core reports
//! where it is through a caller's callback (`Request::progress`)
//! and never prints or reads a clock itself. Owns [`Progress`], the callback
//! type and the run's `Monitor`; may not change a layout: the callback's
//! answer can only stop a run (`LayoutError::Cancelled`),
//! never alter what it computes, so a layout with a callback is byte for byte
//! the layout without one.

use std::fmt;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Where a layout run is. Levels are laid out one after another from the
/// root down; within a level, the similarity methods optimise every diagram
/// together tick by tick, the plain method finishes diagrams one by one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Depth of the level being laid out (1 = the root's children).
    pub level: usize,
    /// Depth of the deepest level.
    pub levels: usize,
    /// Diagrams of the level finished so far (the plain method and warm
    /// starts); the similarity methods report 0 until the level ends.
    pub diagram: usize,
    /// Diagrams of the level (parents with two or more children).
    pub diagrams: usize,
    /// Ticks of the level's joint optimisation made so far (0 for the plain
    /// method).
    pub tick: usize,
    /// The most ticks that optimisation may take; it usually stops earlier,
    /// when its score has plateaued.
    pub ticks: usize,
}

impl Progress {
    /// A rough share of the run done, in `[0, 1]`, for a progress bar: levels
    /// count equally, a level's share goes by ticks or by diagrams.
    pub fn fraction(&self) -> f64 {
        let levels = self.levels.max(1) as f64;
        let within = if self.ticks > 0 {
            self.tick as f64 / self.ticks as f64
        } else if self.diagrams > 0 {
            self.diagram as f64 / self.diagrams as f64
        } else {
            0.0
        };
        ((self.level.saturating_sub(1) as f64 + within.clamp(0.0, 1.0)) / levels).clamp(0.0, 1.0)
    }
}

/// The callback type: called with every [`Progress`] report, possibly from
/// several threads at once (the plain method finishes diagrams in parallel);
/// returning `ControlFlow::Break(())` stops the run.
pub type ProgressFn = dyn Fn(Progress) -> ControlFlow<()> + Send + Sync;

/// A shared progress callback, as [`Request::progress`](super::Request::progress) holds it.
#[derive(Clone)]
pub struct ProgressSink(pub Arc<ProgressFn>);

impl ProgressSink {
    /// Wraps a closure.
    pub fn new(f: impl Fn(Progress) -> ControlFlow<()> + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ProgressSink(..)")
    }
}

/// One run's view of the callback: forwards reports and remembers a stop, so
/// that every thread of the run sees it at its next check.
pub(crate) struct Monitor<'a> {
    sink: Option<&'a ProgressFn>,
    stopped: AtomicBool,
}

impl<'a> Monitor<'a> {
    /// A monitor forwarding to `sink`, if any.
    pub(crate) fn new(sink: Option<&'a ProgressSink>) -> Self {
        Self {
            sink: sink.map(|s| &*s.0),
            stopped: AtomicBool::new(false),
        }
    }

    /// A monitor that reports nowhere and never stops.
    pub(crate) fn silent() -> Self {
        Self::new(None)
    }

    /// Reports `progress`; false once the callback has asked to stop (now or
    /// earlier).
    pub(crate) fn report(&self, progress: Progress) -> bool {
        if let Some(sink) = self.sink {
            if sink(progress).is_break() {
                self.stopped.store(true, Ordering::Relaxed);
            }
        }
        !self.stopped()
    }

    /// Whether the callback has asked to stop.
    pub(crate) fn stopped(&self) -> bool {
        self.stopped.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    fn at(level: usize, tick: usize) -> Progress {
        Progress {
            level,
            levels: 2,
            diagram: 0,
            diagrams: 4,
            tick,
            ticks: 100,
        }
    }

    #[test]
    fn fraction_counts_levels_and_ticks() {
        assert_eq!(at(1, 0).fraction(), 0.0);
        assert!((at(1, 50).fraction() - 0.25).abs() < 1e-12);
        assert!((at(2, 100).fraction() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_break_stops_the_monitor_for_good() {
        let calls = Arc::new(AtomicUsize::new(0));
        let seen = calls.clone();
        let sink = ProgressSink::new(move |p| {
            seen.fetch_add(1, Ordering::Relaxed);
            if p.tick >= 3 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        let monitor = Monitor::new(Some(&sink));
        assert!(monitor.report(at(1, 1)));
        assert!(!monitor.stopped());
        assert!(!monitor.report(at(1, 3)));
        assert!(!monitor.report(at(1, 1)), "a stop is not taken back");
        assert!(monitor.stopped());
        assert_eq!(calls.load(Ordering::Relaxed), 3);
        assert!(Monitor::silent().report(at(1, 1)));
    }
}
