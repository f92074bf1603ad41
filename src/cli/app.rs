//! The `nptreemap` command line: parses arguments, runs one subcommand, and maps
//! errors to exit codes (2 for bad input or usage, 1 for anything else).

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Neighborhood-preserving Voronoi treemaps.
#[derive(Debug, Parser)]
#[command(name = "nptreemap", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print errors only: no status lines of build and check, no notes, no
    /// progress (watch's status lines and eval's and bench's results stay).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Log more on stderr: -v what each stage does, -vv details (RUST_LOG, when
    /// set, decides instead).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    /// Threads to use at most (default: NPTREEMAP_THREADS, else every core).
    /// The outputs are the same bytes whatever the number.
    #[arg(short = 'j', long = "jobs", global = true, value_name = "N",
          value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Build every output of a YAML config (default: the nearest
    /// nptreemap.yaml from the working directory upward).
    Build(super::build::BuildArgs),
    /// Keep a config's outputs current: rebuild what changes, warm-started,
    /// until SIGINT or SIGTERM.
    #[cfg(feature = "watch")]
    Watch(super::watch::WatchArgs),
    /// Write a commented nptreemap.yaml for your tables (CSV or TSV): the node
    /// table and a pairs, vectors or series table, or a genres column.
    Init(super::init::InitArgs),
    /// Validate a YAML config and its data without writing anything.
    ///
    /// Reading the data runs the `command:` of every `format: exec` dataset,
    /// as `build` does: check only configs you trust (without CONFIG, the
    /// nearest nptreemap.yaml from the working directory upward is used).
    Check(super::build::CheckArgs),
    /// Lay out one hierarchy file and write JSON, SVG, PNG and/or HTML.
    Layout(super::layout::LayoutArgs),
    /// Print the paper's Table 2 row (constraints realised, area error, graph
    /// distance, aspect ratio) for one file and one method or all of them.
    Eval(super::eval::EvalArgs),
    /// Time the layout of one file (parsing excluded) and print one JSON line.
    Bench(super::bench::BenchArgs),
    /// Print the documented defaults of every config key (`--defaults`).
    Config(super::defaults::ConfigArgs),
    /// Print a shell completion script.
    Completions(super::shell::CompletionsArgs),
    /// Print the man page (roff), or a subcommand's (`nptreemap man build`).
    Man(super::man::ManArgs),
}

/// Whether log lines may carry colour codes: only on a terminal, and not when
/// `NO_COLOR` is set to anything but the empty string (no-color.org). A log
/// read from a file, a pipe or the journal gets plain text.
fn colour() -> bool {
    use std::io::IsTerminal;
    let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
    !no_color && std::io::stderr().is_terminal()
}

/// SIGINT and SIGTERM still end the process as they would, but first kill
/// the exec adapters it runs: each runs in a process group of its own, which
/// neither a signal to nptreemap nor the terminal's Ctrl-C reaches. (`watch`
/// stops its daemon, and its adapters, itself.)
fn stop_adapters_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        tracing::warn!(
            "cannot handle SIGINT and SIGTERM: a stop signal may leave an adapter running"
        );
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            crate::exec::shut_down();
            let _ = signal_hook::low_level::emulate_default_handler(signal);
            std::process::exit(128 + signal);
        }
    });
}

/// The command line's definition, with what derive cannot say: `man`'s
/// SUBCOMMAND takes the names of the other subcommands (so completion
/// scripts offer them).
fn command() -> clap::Command {
    let cli = Cli::command();
    let pages: Vec<String> = cli
        .get_subcommands()
        .map(|s| s.get_name().to_owned())
        .collect();
    cli.mut_subcommand("man", |man| {
        man.mut_arg(super::man::SUBCOMMAND_ARG, |arg| {
            arg.value_parser(clap::builder::PossibleValuesParser::new(pages))
        })
    })
}

/// Bounds the threads of every parallel loop (rayon's global pool) by `-j N`,
/// else by `NPTREEMAP_THREADS` (for a background service), else leaves one
/// per core. Every parallel loop collects in index order, so the number
/// changes the time only, never the bytes (tests/suite/threads.rs).
fn set_threads(jobs: Option<u16>) -> Result<(), String> {
    let threads = match jobs {
        Some(n) => usize::from(n),
        None => match std::env::var("NPTREEMAP_THREADS") {
            Ok(v) if !v.trim().is_empty() => match v.trim().parse::<usize>() {
                Ok(n) if (1..=u16::MAX as usize).contains(&n) => n,
                _ => {
                    return Err(format!(
                        "NPTREEMAP_THREADS={v:?}: expected a whole number from 1 to {}",
                        u16::MAX
                    ))
                }
            },
            _ => return Ok(()),
        },
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))
}

/// Runs the command line on the process's arguments.
pub fn main() -> ExitCode {
    let cli = Cli::from_arg_matches(&command().get_matches()).unwrap_or_else(|e| e.exit());
    super::set_quiet(cli.quiet);
    let level = match (cli.quiet, cli.verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        (false, _) => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    // Lines that read like cargo's: the level and the message (which names
    // the dataset, the stage and the output), no module path; the status
    // lines carry their own time.
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_target(false)
        .without_time()
        .with_writer(std::io::stderr)
        .with_ansi(colour())
        .init();
    if let Err(message) = set_threads(cli.jobs) {
        eprintln!("error: {message}");
        return ExitCode::from(2);
    }
    #[cfg(feature = "watch")]
    let stops_itself = matches!(cli.command, Command::Watch(_));
    #[cfg(not(feature = "watch"))]
    let stops_itself = false;
    if !stops_itself {
        stop_adapters_on_signals();
    }
    let result = match cli.command {
        Command::Build(args) => super::build::build(&args),
        Command::Check(args) => super::build::check(&args),
        Command::Init(args) => super::init::run(&args),
        #[cfg(feature = "watch")]
        Command::Watch(args) => super::watch::run(&args),
        Command::Layout(args) => super::layout::run(&args),
        Command::Eval(args) => super::eval::run(&args),
        Command::Bench(args) => super::bench::run(&args),
        Command::Config(args) => super::defaults::run(&args),
        Command::Completions(args) => super::shell::completions(&args, command()),
        Command::Man(args) => super::man::man(&args, command()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // Our error types already quote their causes; add only what a
            // context message (e.g. "cannot write") leaves out.
            let mut message = err.to_string();
            for cause in err.chain().skip(1) {
                let text = cause.to_string();
                if !message.contains(&text) {
                    message = format!("{message}: {text}");
                }
            }
            eprintln!("error: {message}");
            ExitCode::from(super::exit_code(&err))
        }
    }
}
