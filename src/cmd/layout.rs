//! `nptreemap layout`: one input file to layout JSON and/or SVG files.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::{LayoutOptions, UsageError};
use nptreemap::render::{layout_json, svg, SvgStyle};
use nptreemap::{store, workspace};

/// Arguments of `nptreemap layout`.
#[derive(Debug, Args)]
pub(crate) struct LayoutArgs {
    /// Hierarchy JSON file (the paper's format or d3-hierarchy style).
    input: PathBuf,
    #[command(flatten)]
    options: LayoutOptions,
    /// Output file; the extension picks the kind (.json layout, .svg picture). Repeatable.
    #[arg(long, required = true, value_name = "FILE")]
    out: Vec<PathBuf>,
}

enum Kind {
    Json,
    Svg,
}

pub(crate) fn run(args: &LayoutArgs) -> anyhow::Result<()> {
    // Check every output's kind before doing any work, so a typo costs nothing.
    let kinds = args
        .out
        .iter()
        .map(|p| match p.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("json") => Ok(Kind::Json),
            Some(e) if e.eq_ignore_ascii_case("svg") => Ok(Kind::Svg),
            _ => Err(UsageError(format!(
                "{}: unknown output kind (use a .json or .svg extension)",
                p.display()
            ))),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let dataset = workspace::read_dataset(&args.input, &args.options.read_options())?;
    let computed = nptreemap::layout::compute(&dataset, &args.options.request()?)?;
    let report = &computed.report;
    if report.unconverged > 0 {
        tracing::warn!(
            unconverged = report.unconverged,
            diagrams = report.diagrams,
            "some diagrams stopped at the iteration cap above the area-error target"
        );
    }
    let extras = nptreemap::pipeline::json_extras(&computed);
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    // Render everything first: a failure leaves every existing output untouched.
    let rendered: Vec<(PathBuf, Vec<u8>)> = args
        .out
        .iter()
        .zip(&kinds)
        .map(|(path, kind)| {
            let bytes = match kind {
                Kind::Json => layout_json(dataset, layout, &extras).into_bytes(),
                Kind::Svg => svg(dataset, layout, &SvgStyle::default()).into_bytes(),
            };
            (path.clone(), bytes)
        })
        .collect();
    for (path, bytes) in &rendered {
        store::write_atomic(path, bytes)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}
