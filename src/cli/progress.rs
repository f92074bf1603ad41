//! Progress bars for layouts: an indicatif bar on stderr fed by the layout
//! core's progress callback (`layout`, `eval`, `build` and `watch`'s first
//! build), shown only when stderr is a
//! terminal and only once a layout has run for about a second; nothing
//! otherwise, so logs, pipes and CI stay clean.

use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use crate::layout::{ProgressSink, Request};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};

/// Steps of the bar: the layout's [`fraction`](crate::layout::Progress::fraction)
/// in thousandths.
const STEPS: u64 = 1000;

/// A layout shorter than this shows no bar at all.
const QUIET_FOR: Duration = Duration::from_secs(1);

/// `NPTREEMAP_PROGRESS_AFTER_MS` overrides [`QUIET_FOR`] (0: a bar from the
/// start), so that tests of the bar do not depend on how fast the machine is.
fn quiet_for() -> Duration {
    std::env::var("NPTREEMAP_PROGRESS_AFTER_MS")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .map_or(QUIET_FOR, Duration::from_millis)
}

/// A bar attached to one layout request; cleared when dropped.
pub(crate) struct LayoutBar {
    bar: ProgressBar,
}

impl LayoutBar {
    /// Attaches a bar labelled `what` to `request` when stderr is a terminal;
    /// `None` (and `request` untouched) otherwise. The bar only ever
    /// continues: it never stops a layout.
    pub(crate) fn attach(request: &mut Request, what: &str) -> Option<Self> {
        let (bar, sink) = bar_and_sink(what)?;
        request.progress = Some(sink);
        Some(Self { bar })
    }
}

/// A reporter for one layout labelled `what` that draws a terminal bar, or
/// `None` when stderr is not a terminal (or `-q`): the bar clears itself
/// when the last holder of the sink lets go of it (the daemon, once its
/// layout is done).
pub(crate) fn sink(what: &str) -> Option<ProgressSink> {
    bar_and_sink(what).map(|(_, sink)| sink)
}

fn bar_and_sink(what: &str) -> Option<(ProgressBar, ProgressSink)> {
    if !std::io::stderr().is_terminal() || super::quiet() {
        return None;
    }
    let bar = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::hidden())
        .with_finish(ProgressFinish::AndClear);
    if let Ok(style) =
        ProgressStyle::with_template("{prefix} [{bar:30}] {percent:>3}% {msg} {elapsed}")
    {
        bar.set_style(style.progress_chars("#>-"));
    }
    bar.set_prefix(what.to_string());
    let shown = bar.clone();
    let started = Instant::now();
    let quiet_for = quiet_for();
    let sink = ProgressSink::new(move |p| {
        if shown.is_hidden() && started.elapsed() >= quiet_for {
            shown.set_draw_target(ProgressDrawTarget::stderr());
        }
        shown.set_message(format!("level {}/{}", p.level, p.levels));
        shown.set_position((p.fraction() * STEPS as f64) as u64);
        ControlFlow::Continue(())
    });
    Some((bar, sink))
}

impl Drop for LayoutBar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
