//! `nptreemap watch [CONFIG]`: runs the daemon ([`crate::daemon`]) until
//! SIGINT or SIGTERM, printing one status line per rebuild on stdout. Owns
//! the signals: SIGHUP reloads the config (as daemons do; the systemd unit's
//! `ExecReload` sends it); SIGINT and SIGTERM stop the daemon with exit code
//! 0, between the stages of a rebuild, or, when a layout runs on, after a
//! grace period by exiting outright.
//!
//! Why exiting outright is safe: every output is written to a temp file and
//! renamed into place ([`crate::store`]), so a process that ends at any
//! instant leaves each output either old or new, never torn; the exit waits
//! for the write lock, so it never falls between two outputs of one dataset;
//! the temp file of an interrupted write is removed by the next start. What
//! is lost is only the rebuild under way, which the next start redoes (warm,
//! from the stored layout).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::Args;
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

use super::config_file::ConfigArg;

use crate::daemon::{self, watcher::Message, FirstBuildProgress, Options};

/// Arguments of `nptreemap watch`.
#[derive(Debug, Args)]
pub(crate) struct WatchArgs {
    #[command(flatten)]
    config: ConfigArg,
    /// Lay every dataset out from scratch at start instead of warm from the
    /// layout stored beside its outputs.
    #[arg(long)]
    cold: bool,
    /// Also serve a live preview over HTTP at ADDR (HOST, PORT or HOST:PORT;
    /// default 127.0.0.1:7878, or the next free port): an index of the
    /// datasets and each dataset's page, which follows every rebuild.
    #[cfg(feature = "serve")]
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "")]
    serve: Option<String>,
    /// With --serve: open the default browser on the first page (a line,
    /// not a failure, where the system has no browser to open).
    #[cfg(feature = "serve")]
    #[arg(long, requires = "serve")]
    open: bool,
}

/// How long a stop signal waits for the daemon to stop by itself (it checks
/// between the stages of a rebuild) before the process exits: short enough
/// that SIGTERM ends the process within a second (issue 11), long enough for
/// a write under way to finish.
const GRACE: Duration = Duration::from_millis(600);

pub(crate) fn run(args: &WatchArgs) -> anyhow::Result<()> {
    // The preview's URL is the first line, before the daemon's.
    #[cfg(feature = "serve")]
    let preview = match &args.serve {
        Some(addr) => {
            let config = std::path::absolute(args.config.path()?)?;
            let preview = crate::serve::start(addr, &config).map_err(|e| {
                // A malformed or refused address is the arguments' fault
                // (exit code 2).
                if e.is_usage() {
                    anyhow::Error::new(super::UsageError(e.to_string()))
                } else {
                    anyhow::Error::new(e)
                }
            })?;
            super::say(preview.first_line());
            if args.open {
                super::browser::open(&preview.first_page());
            }
            Some(preview)
        }
        None => None,
    };
    let (tx, rx) = daemon::channel();
    let stop = Arc::new(AtomicBool::new(false));
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    {
        let (tx, stop) = (tx.clone(), stop.clone());
        std::thread::spawn(move || {
            for signal in signals.forever() {
                if signal == SIGHUP {
                    let _ = tx.send(Message::Reload);
                    continue;
                }
                let again = stop.swap(true, Ordering::SeqCst);
                // Adapters run in process groups of their own: stop them too.
                crate::exec::shut_down();
                let _ = tx.send(Message::Stop);
                if again {
                    // A second stop signal: no more waiting.
                    exit_now();
                }
                std::thread::spawn(|| {
                    std::thread::sleep(GRACE);
                    exit_now();
                });
            }
        });
    }
    let options = Options {
        cold: args.cold,
        stop: Some(stop),
        // The first build may be a long cold layout: show a bar on a terminal.
        first_build_progress: Some(FirstBuildProgress(Arc::new(super::progress::sink))),
        ..Options::default()
    };
    // The status lines are printed (and pushed to the preview's pages); the
    // rebuild events are logged with `-vv`.
    daemon::run(
        &args.config.path()?,
        options,
        tx,
        &rx,
        &mut |report| match report {
            daemon::event::Report::Line(line) => {
                // glue: issue 25. The preview is told of every rebuild by
                // the same line that reports it (after the outputs are
                // written).
                #[cfg(feature = "serve")]
                if let Some(preview) = &preview {
                    preview.publish(&line.status);
                }
                super::say(line)
            }
            daemon::event::Report::Rebuilt(event) => log_event(&event),
        },
    )?;
    Ok(())
}

/// Logs a rebuild event at debug level (`-vv`), every field of it.
fn log_event(event: &daemon::event::Rebuilt) {
    let at = daemon::status::time_of_day(event.at);
    let (dataset, reason) = (&event.dataset, &event.reason);
    match &event.result {
        Ok(o) => tracing::debug!(
            %dataset, %at, %reason, layout = ?o.layout, ms = o.ms,
            written = o.written.len(), unchanged = o.unchanged.len(), failed = o.failed.len(),
            stages = o.stages.runs.len(),
            moved_mean = ?o.stability.map(|s| s.displacement_mean),
            "rebuild event"
        ),
        Err(f) => tracing::debug!(
            %dataset, %at, %reason, file = ?f.file, line = ?f.line, message = %f.message,
            "rebuild event: failed"
        ),
    }
}

/// Ends the process with exit code 0 once no set of outputs is being written
/// (see the module docs for why this is safe, and [`daemon::shutdown`]).
fn exit_now() -> ! {
    daemon::shutdown();
    super::say(daemon::status::Line::now(daemon::status::Status::Note {
        subject: "stopped".to_string(),
        message: "a rebuild under way was abandoned; it is redone at the next start".to_string(),
    }));
    std::process::exit(0);
}
