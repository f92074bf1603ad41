//! `nptreemap layout`: one input file to layout JSON, SVG, PNG and/or HTML files.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::{LayoutOptions, UsageError};
use nptreemap::config::{kind_of, OutputConfig};
use nptreemap::layout::Start;
use nptreemap::render::Style;
use nptreemap::{pipeline, store, workspace};

/// Arguments of `nptreemap layout`.
#[derive(Debug, Args)]
pub(crate) struct LayoutArgs {
    /// Hierarchy JSON file (the paper's format or d3-hierarchy style).
    input: PathBuf,
    #[command(flatten)]
    options: LayoutOptions,
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
    let kinds = args
        .out
        .iter()
        .map(|p| {
            kind_of(p).ok_or_else(|| {
                UsageError(format!(
                    "{}: unknown output kind (use a .json, .svg, .png or .html extension)",
                    p.display()
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let dataset = workspace::read_dataset(&args.input, &args.options.read_options())?;
    let mut request = args.options.request()?;
    request.previous = args.options.warm_start()?;
    let computed = nptreemap::layout::compute(&dataset, &request)?;
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
    let style = Style {
        title: args.title.clone(),
        legend: !args.no_legend,
        ..Style::default()
    };
    let outputs: Vec<OutputConfig> = args
        .out
        .iter()
        .zip(&kinds)
        .map(|(path, kind)| OutputConfig {
            path: path.clone(),
            kind: Some(*kind),
            scale: args.scale,
        })
        .collect();
    // Render everything first: a failure leaves every existing output untouched.
    let rendered = pipeline::render_outputs(&computed, &style, &outputs)?;
    for (path, bytes) in &rendered {
        store::write_atomic(path, bytes)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}
