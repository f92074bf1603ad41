//! `nptreemap eval`: the paper's Table 2 row for one dataset (a hierarchy JSON
//! file, or a dataset of a config) and one method (or all of them), and
//! optionally the layout JSON with every constraint's `realized` flag. With
//! `--previous`, also issue 6's stability figures of a warm and of a cold
//! layout against that previous layout, with their times.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::Args;

use super::progress::LayoutBar;
use super::{LayoutOptions, UsageError};
use crate::config::DatasetConfig;
use crate::graph::{DatasetGraph, GraphOptions, StageReport};
use crate::layout::{Computed, Method, Previous, Request, Start};
use crate::measure::{stability, table2, EvalMetrics, Stability};
use crate::pipeline::{self, Rendered};
use crate::{layout_json, Dataset};

/// Arguments of `nptreemap eval`.
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    #[command(flatten)]
    options: LayoutOptions,
    /// Layout method, or `all` for one row per method (default: neighbor when
    /// the data has a similarity, else plain).
    #[arg(long, value_parser = methods_parser(), value_name = "METHOD|all")]
    method: Option<Methods>,
    /// Print JSON lines instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write the layout JSON (with constraints and their `realized` flags).
    #[arg(long, value_name = "FILE.json")]
    out: Option<PathBuf>,
}

/// What `--method` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Methods {
    /// One method.
    One(Method),
    /// Every method, one row each.
    All,
}

/// `--method`'s parser: every method's name and `all` as possible values,
/// so that completions offer them.
fn methods_parser() -> impl clap::builder::TypedValueParser<Value = Methods> {
    use clap::builder::TypedValueParser as _;
    let names = Method::ALL.map(Method::name).into_iter().chain(["all"]);
    clap::builder::PossibleValuesParser::new(names).try_map(|name: String| parse_methods(&name))
}

fn parse_methods(name: &str) -> Result<Methods, String> {
    if name == "all" {
        return Ok(Methods::All);
    }
    Method::parse(name)
        .map(Methods::One)
        .ok_or_else(|| format!("expected all or one of {}", Method::names()))
}

/// One start's figures against the previous layout.
struct StabilityRow {
    start: &'static str,
    used_previous: bool,
    time_ms: f64,
    iterations: usize,
    figures: Stability,
}

pub(crate) fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let all = args.method == Some(Methods::All);
    if all && args.out.is_some() {
        return Err(UsageError("--out needs one method, not --method all".to_string()).into());
    }
    if all && args.options.previous.is_some() {
        return Err(UsageError("--previous needs one method, not --method all".to_string()).into());
    }
    let one = match args.method {
        Some(Methods::One(m)) => Some(m),
        _ => None,
    };
    let mut job = args.options.job(one)?;
    // The Table 2 row counts what every method realises, `plain` included.
    job.request.realized = true;
    job.check_outputs(args.out.as_slice())?;
    // Read even with --cold: the figures compare both starts with it.
    let previous = args.options.previous_layout()?;
    let methods: Vec<Option<Method>> = if all {
        Method::ALL.into_iter().map(Some).collect()
    } else {
        vec![job.request.method]
    };
    // One graph for every row: preparation and constraints are computed
    // once, before any layout is timed, so every time is the layout's alone.
    let mut graph = DatasetGraph::new(GraphOptions::from_env());
    graph.prepare_for(&job.config, &job.dataset, &job.request)?;
    let mut rows = Vec::new();
    let mut stability_rows = Vec::new();
    for method in methods {
        let mut request = job.request.clone();
        request.method = method;
        request.previous =
            crate::graph::start::given(args.options.cold, || previous.clone()).flatten();
        let (computed, time_ms) = timed(&mut graph, &job.config, &job.dataset, &request)?;
        let m = table2(&computed);
        if let Some(out) = &args.out {
            let rendered = [Rendered {
                path: out.clone(),
                bytes: layout_json::document(&computed).into_bytes(),
            }];
            if let Some(e) = pipeline::write_outputs(&rendered).failed.into_iter().next() {
                return Err(e.into());
            }
        }
        if let Some(previous) = &previous {
            stability_rows =
                stability_against(&mut graph, previous, &job, request, (&computed, time_ms))?;
            if let Start::Refused(why) = &computed.start {
                super::note(format_args!(
                    "previous layout not used ({why}); laid out cold"
                ));
            }
        }
        rows.push((computed.method, m));
    }
    let file = job.config.name.clone();
    let previous_file = args
        .options
        .previous
        .as_ref()
        .map(|p| p.display().to_string());
    if args.json {
        for (method, m) in &rows {
            super::say(format_args!("{}", row_json(&file, *method, m)));
        }
        for s in &stability_rows {
            let line = stability_json(&file, previous_file.as_deref().unwrap_or(""), s);
            super::say(format_args!("{line}"));
        }
    } else {
        super::say(format_args!("{}", header()));
        for (method, m) in &rows {
            super::say(format_args!("{}", row_text(*method, m)));
        }
        if let Some(previous_file) = &previous_file {
            super::say(format_args!("\nagainst {previous_file}:"));
            super::say(format_args!("{}", stability_header()));
            for s in &stability_rows {
                super::say(format_args!("{}", stability_text(s)));
            }
        }
    }
    Ok(())
}

/// Lays out and measures the wall time of the layout stage (preparation and
/// constraints are the graph's already).
fn timed(
    graph: &mut DatasetGraph,
    d: &DatasetConfig,
    dataset: &Dataset,
    request: &Request,
) -> anyhow::Result<(Computed, f64)> {
    let mut request = request.clone();
    let bar = LayoutBar::attach(&mut request, &d.name);
    let t = Instant::now();
    let computed = graph.lay_out(d, dataset, &request, &mut StageReport::default())?;
    let time_ms = t.elapsed().as_secs_f64() * 1000.0;
    drop(bar);
    Ok((computed, time_ms))
}

/// The warm and the cold row against `previous`; `done` is the layout of
/// `request` already made (warm unless --cold), so only the other start runs.
fn stability_against(
    graph: &mut DatasetGraph,
    previous: &Arc<Previous>,
    job: &super::Resolved,
    mut request: Request,
    done: (&Computed, f64),
) -> anyhow::Result<Vec<StabilityRow>> {
    let made_warm = request.previous.is_some();
    request.previous = if made_warm {
        None
    } else {
        Some(Arc::clone(previous))
    };
    let (other, other_ms) = timed(graph, &job.config, &job.dataset, &request)?;
    let row = |start, computed: &Computed, time_ms| StabilityRow {
        start,
        used_previous: matches!(computed.start, Start::Warm { .. }),
        time_ms,
        iterations: computed.report.iterations,
        figures: stability(previous, computed),
    };
    let (warm, cold) = if made_warm {
        (row("warm", done.0, done.1), row("cold", &other, other_ms))
    } else {
        (row("warm", &other, other_ms), row("cold", done.0, done.1))
    };
    Ok(vec![warm, cold])
}

fn header() -> String {
    format!(
        "{:<11} {:>6} {:>6} {:>6} {:>11} {:>9} {:>7} {:>9} {:>8} {:>8} {:>7} {:>7}",
        "method",
        "levels",
        "nodes",
        "leaves",
        "constraints",
        "realized",
        "%",
        "area_err",
        "dist_med",
        "dist_max",
        "aspect",
        "w/h"
    )
}

fn row_text(method: Method, m: &EvalMetrics) -> String {
    let med = m
        .graph_distance_median
        .map_or("-".to_string(), |d| format!("{d}"));
    let max = m
        .graph_distance_max
        .map_or("-".to_string(), |d| d.to_string());
    format!(
        "{:<11} {:>6} {:>6} {:>6} {:>11} {:>9} {:>7.2} {:>9.4} {:>8} {:>8} {:>7.3} {:>7.3}",
        method.name(),
        m.levels,
        m.nodes,
        m.leaves,
        m.leaf_constraints,
        m.realized,
        m.realized_pct,
        m.area_error,
        med,
        max,
        m.aspect_ratio,
        m.aspect_ratio_proto
    )
}

fn row_json(file: &str, method: Method, m: &EvalMetrics) -> serde_json::Value {
    serde_json::json!({
        "file": file,
        "method": method.name(),
        "levels": m.levels,
        "nodes": m.nodes,
        "leaves": m.leaves,
        "leaf_constraints": m.leaf_constraints,
        "realized": m.realized,
        "realized_pct": m.realized_pct,
        "area_error": m.area_error,
        "graph_distance_median": m.graph_distance_median,
        "graph_distance_max": m.graph_distance_max,
        "aspect_ratio": m.aspect_ratio,
        "aspect_ratio_proto": m.aspect_ratio_proto,
    })
}

fn stability_header() -> String {
    format!(
        "{:<6} {:>9} {:>10} {:>6} {:>9} {:>11} {:>9} {:>7} {:>7} {:>7}",
        "start",
        "time_ms",
        "iterations",
        "leaves",
        "moved_%",
        "unchanged_%",
        "max_%",
        "kept",
        "of",
        "kept_%"
    )
}

/// Displacements in per cent of the canvas diagonal.
fn stability_text(s: &StabilityRow) -> String {
    let f = &s.figures;
    let start = if s.start == "warm" && !s.used_previous {
        "warm*"
    } else {
        s.start
    };
    let kept = f
        .kept_share()
        .map_or("-".to_string(), |k| format!("{:.2}", 100.0 * k));
    format!(
        "{:<6} {:>9.1} {:>10} {:>6} {:>9.4} {:>11.4} {:>9.4} {:>7} {:>7} {:>7}",
        start,
        s.time_ms,
        s.iterations,
        f.leaves,
        100.0 * f.displacement_mean,
        100.0 * f.displacement_unchanged_mean,
        100.0 * f.displacement_max,
        f.kept,
        f.realized_before,
        kept
    )
}

fn stability_json(file: &str, previous: &str, s: &StabilityRow) -> serde_json::Value {
    let f = &s.figures;
    serde_json::json!({
        "file": file,
        "previous": previous,
        "start": s.start,
        "used_previous": s.used_previous,
        "time_ms": s.time_ms,
        "iterations": s.iterations,
        "leaves": f.leaves,
        "unchanged": f.unchanged,
        "displacement_mean": f.displacement_mean,
        "displacement_unchanged_mean": f.displacement_unchanged_mean,
        "displacement_max": f.displacement_max,
        "realized_before": f.realized_before,
        "kept": f.kept,
        "kept_share": f.kept_share(),
    })
}
