//! The `nptreemap` command line: parses arguments, runs one subcommand, and maps
//! errors to exit codes (2 for bad input or usage, 1 for anything else).

mod cmd;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Neighborhood-preserving Voronoi treemaps.
#[derive(Debug, Parser)]
#[command(name = "nptreemap", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Build every output of a YAML config (default: ./nptreemap.yaml).
    Build(cmd::build::BuildArgs),
    /// Keep a config's outputs current: rebuild what changes, warm-started,
    /// until SIGINT or SIGTERM.
    #[cfg(feature = "watch")]
    Watch(cmd::watch::WatchArgs),
    /// Validate a YAML config and its data without writing anything.
    Check(cmd::build::BuildArgs),
    /// Lay out one hierarchy file and write JSON, SVG, PNG and/or HTML.
    Layout(cmd::layout::LayoutArgs),
    /// Print the paper's Table 2 row (constraints realised, area error, graph
    /// distance, aspect ratio) for one file and one method or all of them.
    Eval(cmd::eval::EvalArgs),
    /// Time the layout of one file (parsing excluded) and print one JSON line.
    Bench(cmd::bench::BenchArgs),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Build(args) => cmd::build::build(&args),
        Command::Check(args) => cmd::build::check(&args),
        #[cfg(feature = "watch")]
        Command::Watch(args) => cmd::watch::run(&args),
        Command::Layout(args) => cmd::layout::run(&args),
        Command::Eval(args) => cmd::eval::run(&args),
        Command::Bench(args) => cmd::bench::run(&args),
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
            ExitCode::from(cmd::exit_code(&err))
        }
    }
}
