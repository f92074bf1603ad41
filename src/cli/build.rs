//! `nptreemap build [CONFIG]` and `nptreemap check [CONFIG]`: every output of a
//! config, or only the validation of config and data. All datasets are built in
//! memory before anything is written, so a bad input leaves every output as it was.
//! `build --check` compares instead of writing, as `cargo fmt --check` does.

use std::path::PathBuf;

use clap::Args;

use super::config_file::ConfigArg;
use super::progress::LayoutBar;
use crate::config::Config;
use crate::pipeline::{self, BuildError};

/// Arguments of `nptreemap build`.
#[derive(Debug, Args)]
pub(crate) struct BuildArgs {
    #[command(flatten)]
    config: ConfigArg,
    /// Lay out from scratch instead of warm from the layout stored beside
    /// the outputs by the last build or watch.
    #[arg(long)]
    cold: bool,
    /// Write nothing; exit 1 naming every output a build would change (for
    /// CI: are the committed pictures up to date?).
    #[arg(long)]
    check: bool,
}

/// Arguments of `nptreemap check`.
#[derive(Debug, Args)]
pub(crate) struct CheckArgs {
    #[command(flatten)]
    config: ConfigArg,
}

/// `build --check` found outputs a build would change: exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{} output(s) out of date (`nptreemap build` would rewrite them): {}", .0.len(), list(.0))]
pub(crate) struct Stale(Vec<PathBuf>);

fn list(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

pub(crate) fn build(args: &BuildArgs) -> anyhow::Result<()> {
    let path = args.config.path()?;
    let config = Config::from_path(&path).map_err(BuildError::from)?;
    // Before anything is read or written: no output may land on an input,
    // the config, another output or a special file.
    let (reads, writes) = pipeline::files_of(&path, &config.datasets);
    pipeline::check_outputs(&reads, &writes)?;
    if !args.check {
        pipeline::remove_stale_temps(&writes);
    }
    let mut built = Vec::new();
    let total = config.datasets.len();
    for (i, d) in config.datasets.iter().enumerate() {
        let mut request = config.request(d);
        let label = format!("{} ({}/{total})", d.name, i + 1);
        let bar = LayoutBar::attach(&mut request, &label);
        let result = pipeline::build(d, &request, &config.style(d), args.cold);
        drop(bar);
        built.push((d, result?));
    }
    if args.check {
        return compare_outputs(built.iter().map(|(_, b)| b));
    }
    for (d, b) in &built {
        for line in &b.warnings {
            super::warn(line);
        }
        let written = pipeline::write_outputs(&b.outputs);
        if let Some(e) = written.failed.into_iter().next() {
            return Err(e.into());
        }
        // Losing the stored layout only costs the next build its warm start.
        if let Err(e) = pipeline::store_layout(d, &b.computed) {
            tracing::warn!(dataset = %b.name, error = %e, "cannot store the layout for warm starts");
        }
        for out in &b.outputs {
            let state = if written.written.contains(&out.path) {
                "wrote"
            } else {
                "unchanged"
            };
            super::status(format_args!(
                "{state} {} ({} bytes, dataset {})",
                out.path.display(),
                out.bytes.len(),
                b.name
            ));
        }
    }
    Ok(())
}

/// Names each output whose file would change (or is missing); writes nothing.
fn compare_outputs<'a>(built: impl Iterator<Item = &'a pipeline::Built>) -> anyhow::Result<()> {
    let mut stale = Vec::new();
    let mut fresh = 0;
    for out in built.flat_map(|b| &b.outputs) {
        // A file that cannot be read is as stale as a missing one.
        if crate::workspace::read_bytes(&out.path).is_ok_and(|bytes| bytes == out.bytes) {
            fresh += 1;
        } else {
            super::status(format_args!("stale {}", out.path.display()));
            stale.push(out.path.clone());
        }
    }
    if stale.is_empty() {
        super::status(format_args!("{fresh} outputs up to date"));
        Ok(())
    } else {
        Err(Stale(stale).into())
    }
}

pub(crate) fn check(args: &CheckArgs) -> anyhow::Result<()> {
    let path = args.config.path()?;
    let config = Config::from_path(&path).map_err(BuildError::from)?;
    let (reads, writes) = pipeline::files_of(&path, &config.datasets);
    pipeline::check_outputs(&reads, &writes)?;
    for d in &config.datasets {
        let files = pipeline::read_inputs(d)?;
        let dataset = pipeline::parse_inputs(d, &files)?;
        for line in pipeline::warnings(&files, &dataset) {
            super::warn(line);
        }
        if let Some(line) = pipeline::stored_layout(d).warning {
            super::warn(line);
        }
        super::status(format_args!(
            "ok {}: {} nodes, {} leaves, {} outputs",
            d.name,
            dataset.len(),
            dataset.leaves().count(),
            d.outputs.len()
        ));
    }
    Ok(())
}
