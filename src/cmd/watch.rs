//! `nptreemap watch [CONFIG]`: runs the daemon ([`nptreemap::daemon`]) until
//! SIGINT or SIGTERM, printing one status line per rebuild on stdout. A stop
//! signal ends it cleanly with exit code 0.

use clap::Args;

use super::config_file::ConfigArg;

use nptreemap::daemon::{self, watcher::Message, Options};

/// Arguments of `nptreemap watch`.
#[derive(Debug, Args)]
pub(crate) struct WatchArgs {
    #[command(flatten)]
    config: ConfigArg,
    /// Lay every dataset out from scratch at start instead of warm from the
    /// layout stored beside its outputs.
    #[arg(long)]
    cold: bool,
}

pub(crate) fn run(args: &WatchArgs) -> anyhow::Result<()> {
    let (tx, rx) = daemon::channel();
    let stop = tx.clone();
    // ctrlc's `termination` feature also routes SIGTERM (systemd's stop) here.
    ctrlc::set_handler(move || {
        let _ = stop.send(Message::Stop);
    })?;
    let options = Options {
        cold: args.cold,
        ..Options::default()
    };
    daemon::run(&args.config.path()?, options, tx, &rx, &mut |status| {
        super::say(status);
    })?;
    Ok(())
}
