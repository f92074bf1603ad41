//! Progress bars for layouts (issue 12 item 4): an indicatif bar on stderr fed
//! by the layout core's progress callback, shown only when stderr is a
//! terminal and only once a layout has run for about a second; nothing
//! otherwise, so logs, pipes and CI stay clean.

use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nptreemap::layout::{ProgressSink, Request};

/// Steps of the bar: the layout's [`fraction`](nptreemap::layout::Progress::fraction)
/// in thousandths.
const STEPS: u64 = 1000;

/// A layout shorter than this shows no bar at all.
const QUIET_FOR: Duration = Duration::from_secs(1);

/// A bar attached to one layout request; cleared when dropped.
pub(crate) struct LayoutBar {
    bar: ProgressBar,
}

impl LayoutBar {
    /// Attaches a bar labelled `what` to `request` when stderr is a terminal;
    /// `None` (and `request` untouched) otherwise. The bar only ever
    /// continues: it never stops a layout.
    pub(crate) fn attach(request: &mut Request, what: &str) -> Option<Self> {
        if !std::io::stderr().is_terminal() || super::quiet() {
            return None;
        }
        let bar = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::hidden());
        if let Ok(style) =
            ProgressStyle::with_template("{prefix} [{bar:30}] {percent:>3}% {msg} {elapsed}")
        {
            bar.set_style(style.progress_chars("#>-"));
        }
        bar.set_prefix(what.to_string());
        let shown = bar.clone();
        let started = Instant::now();
        request.progress = Some(ProgressSink::new(move |p| {
            if shown.is_hidden() && started.elapsed() >= QUIET_FOR {
                shown.set_draw_target(ProgressDrawTarget::stderr());
            }
            shown.set_message(format!("level {}/{}", p.level, p.levels));
            shown.set_position((p.fraction() * STEPS as f64) as u64);
            ControlFlow::Continue(())
        }));
        Some(Self { bar })
    }
}

impl Drop for LayoutBar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
