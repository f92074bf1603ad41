//! `nptreemap bench`: lays one input out several times in one process and prints
//! one JSON line with the median time of the whole layout step (preparation,
//! constraints and layout; parsing excluded) and the layout's quality, for
//! `benches/peers.py`; with `--render`, also the SVG and PNG rendering times.
//! With `--previous` the layouts start warm (unless `--cold`), and the line
//! adds the stability figures against that layout (`benches/stability.py`).

use std::time::Instant;

use clap::Args;

use super::LayoutOptions;
use crate::layout::{Method, Start};
use crate::render::picture;
use crate::{measure, pipeline};

/// Arguments of `nptreemap bench`.
#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
    #[command(flatten)]
    options: LayoutOptions,
    /// Layout method (default: neighbor when the data has a similarity, else plain).
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Layouts to time; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Also time rendering the last layout to SVG text and to PNG pixels
    /// (median of `--repeat` runs each; the PNG time includes parsing the SVG).
    #[arg(long)]
    render: bool,
    /// Compute the constraints and count the realised ones even for `--method
    /// plain`, which otherwise computes none.
    #[arg(long)]
    realized: bool,
}

pub(crate) fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let job = args.options.job(args.method)?;
    let (dataset, mut request) = (&job.dataset, job.request.clone());
    request.realized = args.realized;
    // Read even with --cold, for the stability figures.
    let previous = args.options.previous_layout()?;
    request.previous = crate::graph::start::given(args.options.cold, || previous.clone()).flatten();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.repeat.max(1) {
        let t = Instant::now();
        let computed = pipeline::lay_out(&job.config, dataset, &request)?;
        times.push(t.elapsed().as_secs_f64() * 1000.0);
        last = Some(computed);
    }
    let Some(computed) = last else {
        anyhow::bail!("no layout was made");
    };
    let report = &computed.report;
    let q = measure::drawn_quality(&computed);
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let mut line = serde_json::json!({
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
        "zero_weights": computed.zero.mode.name(),
        "zero_items": computed.zero.items,
        "method": computed.method.name(),
        "constraints": computed.constraints.len(),
        "realized": computed.realized.iter().filter(|r| **r).count(),
        "start": match &computed.start {
            Start::Cold => "cold",
            Start::Refused(_) => "refused",
            Start::Warm { .. } => "warm",
        },
    });
    if let (Some(previous), Some(fields)) = (&previous, line.as_object_mut()) {
        let s = measure::stability(previous, &computed);
        for (key, value) in [
            ("stable_leaves", serde_json::json!(s.leaves)),
            ("unchanged_leaves", serde_json::json!(s.unchanged)),
            ("displacement_mean", serde_json::json!(s.displacement_mean)),
            (
                "displacement_unchanged_mean",
                serde_json::json!(s.displacement_unchanged_mean),
            ),
            ("displacement_max", serde_json::json!(s.displacement_max)),
            ("realized_before", serde_json::json!(s.realized_before)),
            ("kept", serde_json::json!(s.kept)),
            ("kept_share", serde_json::json!(s.kept_share())),
        ] {
            fields.insert(key.to_string(), value);
        }
    }
    if args.render {
        let style = &job.style;
        let mut svg_ms = Vec::new();
        #[cfg_attr(not(feature = "png"), allow(unused_mut))]
        let mut png_ms: Vec<f64> = Vec::new();
        let mut sizes = (0, 0);
        for _ in 0..args.repeat.max(1) {
            let t = Instant::now();
            let svg = picture(&computed, style);
            svg_ms.push(t.elapsed().as_secs_f64() * 1000.0);
            sizes.0 = svg.len();
            #[cfg(feature = "png")]
            {
                let t = Instant::now();
                let png = crate::render::png(&svg, 1.0)?;
                png_ms.push(t.elapsed().as_secs_f64() * 1000.0);
                sizes.1 = png.len();
            }
        }
        line["render_svg_ms"] = median(&svg_ms).into();
        line["svg_bytes"] = sizes.0.into();
        // Without the `png` feature there is no PNG to time.
        if !png_ms.is_empty() {
            line["render_png_ms"] = median(&png_ms).into();
            line["png_bytes"] = sizes.1.into();
        }
    }
    super::say(format_args!("{line}"));
    Ok(())
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
