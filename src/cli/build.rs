//! `nptreemap build [CONFIG]` and `nptreemap check [CONFIG]`: every output of a
//! config, or only the validation of config and data. All datasets are built in
//! memory before anything is written, so a bad input leaves every output as it was.
//! `build --check` compares instead of writing, as `cargo fmt --check` does.

use std::path::PathBuf;

use clap::Args;

use super::config_file::ConfigArg;
use super::progress::LayoutBar;
use crate::config::Config;
use crate::graph::{DatasetBuild, DatasetGraph, GraphOptions, Job, LayoutStep};
use crate::layout::zero;
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
    // Every dataset is built in memory before anything is written.
    let options = GraphOptions::from_env();
    let mut built = Vec::new();
    let total = config.datasets.len();
    for (i, d) in config.datasets.iter().enumerate() {
        let mut job = Job {
            dataset: d,
            request: config.request(d),
            style: config.style(d),
            cold: args.cold,
        };
        let label = format!("{} ({}/{total})", d.name, i + 1);
        let bar = LayoutBar::attach(&mut job.request, &label);
        let mut graph = DatasetGraph::new(options);
        let result = graph.build(&job);
        drop(bar);
        job.request.progress = None;
        built.push((graph, job, result?));
    }
    if args.check {
        for (_, _, b) in &built {
            say_layout(b);
        }
        return compare_outputs(built.iter().map(|(_, _, b)| b));
    }
    for (graph, job, b) in &mut built {
        for line in &b.warnings {
            super::warn(line);
        }
        for line in &b.notes {
            super::note(line);
        }
        say_layout(b);
        let written = graph.commit(job, b);
        if let Some(e) = written.failed.into_iter().next() {
            return Err(e.into());
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
                out.len,
                b.name
            ));
        }
    }
    // The process exits next and its memory goes back with it: freeing the
    // graphs piece by piece took 40 ms at 6,000 C headers.
    std::mem::forget(built);
    Ok(())
}

/// The dataset's status line: how its layout was got, in how long, and the
/// constraints it realises.
fn say_layout(b: &DatasetBuild) {
    let how = match &b.layout {
        LayoutStep::UpToDate => {
            "up to date (inputs, layout settings and outputs as recorded)".to_string()
        }
        LayoutStep::Reused => "layout reused (every diagram as it was)".to_string(),
        LayoutStep::Warm => format!("laid out warm in {:.0} ms", b.layout_ms),
        LayoutStep::Cold(why) => format!("laid out cold in {:.0} ms ({why})", b.layout_ms),
    };
    let realized = if b.constraints == 0 {
        "no constraints".to_string()
    } else {
        format!(
            "{} of {} constraints realized ({:.1}%)",
            b.realized,
            b.constraints,
            100.0 * b.realized as f64 / b.constraints as f64
        )
    };
    // Items of weight 0, hidden or floored (issue 34), when there are any.
    let zero = b
        .computed
        .as_ref()
        .and_then(|c| c.zero.summary())
        .map_or_else(String::new, |s| format!("; {s}"));
    super::status(format_args!("{}: {how}; {realized}{zero}", b.name));
    if let Some(report) = b.computed.as_ref().map(|c| &c.report) {
        if report.unconverged > 0 {
            tracing::warn!(
                dataset = %b.name,
                unconverged = report.unconverged,
                diagrams = report.diagrams,
                "some diagrams stopped at the iteration cap above the area-error target"
            );
        }
    }
}

/// Names each output whose file would change (or is missing); writes nothing.
fn compare_outputs<'a>(built: impl Iterator<Item = &'a DatasetBuild>) -> anyhow::Result<()> {
    let mut stale = Vec::new();
    let mut fresh = 0;
    for b in built {
        // A file that cannot be read is as stale as a missing one.
        for out in b.stale() {
            super::status(format_args!("stale {}", out.path.display()));
            stale.push(out.path.clone());
        }
        fresh += b.outputs.len() - b.stale().count();
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
    let mode = config.params().zero_weights;
    for d in &config.datasets {
        let files = pipeline::read_inputs(d)?;
        let dataset = pipeline::parse_inputs(d, &files)?;
        for line in pipeline::warnings(&files, &dataset) {
            super::warn(line);
        }
        if let Some(line) = crate::state::layout::read(d).warning {
            super::warn(line);
        }
        let zero = zero::counted(&dataset, mode)
            .summary()
            .map_or_else(String::new, |s| {
                format!("; {s} (layout.zero_weights: {})", mode.name())
            });
        super::status(format_args!(
            "ok {}: {} nodes, {} leaves, {} outputs{zero}",
            d.name,
            dataset.len(),
            dataset.leaves().count(),
            d.outputs.len()
        ));
    }
    Ok(())
}
