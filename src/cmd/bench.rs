//! `nptreemap bench`: lays one input out several times in one process and prints
//! one JSON line with the median time of the whole layout step (preparation,
//! constraints and layout; parsing excluded) and the layout's quality, for
//! `benches/peers.py`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::LayoutOptions;
use nptreemap::{metrics, workspace};

/// Arguments of `nptreemap bench`.
#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
    /// Hierarchy JSON file.
    input: PathBuf,
    #[command(flatten)]
    options: LayoutOptions,
    /// Layouts to time; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
}

pub(crate) fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let dataset = workspace::read_dataset(&args.input, &args.options.read_options())?;
    let request = args.options.request()?;
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.repeat.max(1) {
        let t = Instant::now();
        let computed = nptreemap::layout::compute(&dataset, &request)?;
        times.push(t.elapsed().as_secs_f64() * 1000.0);
        last = Some(computed);
    }
    let Some(computed) = last else {
        anyhow::bail!("no layout was made");
    };
    let report = &computed.report;
    let q = metrics::quality(&computed.dataset, &computed.layout);
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let line = serde_json::json!({
        "tool": "nptreemap",
        "version": env!("CARGO_PKG_VERSION"),
        "leaves": dataset.leaves().count(),
        "time_ms": sorted[sorted.len() / 2],
        "times_ms": times,
        "area_error_diagram_mean": q.area_error_diagram_mean,
        "area_error_diagram_max": q.area_error_diagram_max,
        "aspect_ratio_mean": q.aspect_ratio_mean,
        "iterations": report.iterations,
        "diagrams": report.diagrams,
        "unconverged": report.unconverged,
        "method": computed.method.name(),
        "constraints": computed.constraints.len(),
        "realized": computed.realized.iter().filter(|r| **r).count(),
    });
    super::say(format_args!("{line}"));
    Ok(())
}
