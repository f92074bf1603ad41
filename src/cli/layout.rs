//! `nptreemap layout`: one dataset (a hierarchy JSON file, or a dataset of a
//! config) to layout JSON, SVG, PNG and/or HTML files, through the stage
//! graph's stages.

use std::path::PathBuf;

use clap::Args;

use super::progress::LayoutBar;
use super::{LayoutOptions, UsageError};
use crate::config::OutputConfig;
use crate::graph::{DatasetGraph, GraphOptions, StageReport};
use crate::layout::{Method, Start};
use crate::pipeline;
use crate::render::OutputKind;

/// Arguments of `nptreemap layout`.
#[derive(Debug, Args)]
pub(crate) struct LayoutArgs {
    #[command(flatten)]
    options: LayoutOptions,
    /// Layout method (default: neighbor when the data has a similarity, else plain).
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Output file; the extension picks the kind (.json layout, .svg or .png
    /// picture, .html interactive page). Repeatable.
    #[arg(long, required = true, value_name = "FILE")]
    out: Vec<PathBuf>,
    /// Title above the picture (SVG, PNG, HTML).
    #[arg(long)]
    title: Option<String>,
    /// Leave out the legend band under the map.
    #[arg(long)]
    no_legend: bool,
    /// Pixel scale of PNG outputs.
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR")]
    scale: f64,
}

pub(crate) fn run(args: &LayoutArgs) -> anyhow::Result<()> {
    if !(args.scale.is_finite() && args.scale > 0.0) {
        return Err(
            UsageError(format!("--scale {}: must be a positive number", args.scale)).into(),
        );
    }
    // Check every output's kind before doing any work, so a typo costs nothing.
    let outputs = args
        .out
        .iter()
        .map(|path| {
            let kind = OutputKind::of_path(path).ok_or_else(|| {
                UsageError(format!(
                    "{}: unknown output kind (use a .json, .svg, .png or .html extension)",
                    path.display()
                ))
            })?;
            Ok(OutputConfig {
                path: path.clone(),
                kind: Some(kind),
                scale: args.scale,
            })
        })
        .collect::<Result<Vec<_>, UsageError>>()?;
    let mut job = args.options.job(args.method)?;
    job.check_outputs(&args.out)?;
    job.request.previous = args.options.warm_start()?;
    let bar = LayoutBar::attach(&mut job.request, &job.config.name);
    let mut graph = DatasetGraph::new(GraphOptions::from_env());
    let computed = graph.lay_out(
        &job.config,
        &job.dataset,
        &job.request,
        &mut StageReport::default(),
    )?;
    drop(bar);
    if let Start::Refused(why) = &computed.start {
        super::note(format_args!(
            "previous layout not used ({why}); laid out cold"
        ));
    }
    let report = &computed.report;
    if report.unconverged > 0 {
        tracing::warn!(
            unconverged = report.unconverged,
            diagrams = report.diagrams,
            "some diagrams stopped at the iteration cap above the area-error target"
        );
    }
    if args.title.is_some() {
        job.style.title = args.title.clone();
    }
    job.style.legend &= !args.no_legend;
    // Render everything first: a failure leaves every existing output untouched.
    let rendered = pipeline::render_outputs(&computed, &job.style, &outputs)?;
    let written = pipeline::write_outputs(&rendered);
    match written.failed.into_iter().next() {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}
