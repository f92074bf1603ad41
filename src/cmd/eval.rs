//! `nptreemap eval`: the paper's Table 2 row for one input and one method (or
//! all of them), and optionally the layout JSON with every constraint's
//! `realized` flag.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::{LayoutOptions, MethodArg, UsageError};
use nptreemap::layout::{compute, Method};
use nptreemap::neighborhood::adjacency::{eval_metrics, EvalMetrics};
use nptreemap::render::layout_json;
use nptreemap::{store, workspace};

/// Arguments of `nptreemap eval`.
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    /// Hierarchy JSON file.
    input: PathBuf,
    #[command(flatten)]
    options: LayoutOptions,
    /// Print JSON lines instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write the layout JSON (with constraints and their `realized` flags).
    #[arg(long, value_name = "FILE.json")]
    out: Option<PathBuf>,
}

pub(crate) fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let all = args.options.method == Some(MethodArg::All);
    if all && args.out.is_some() {
        return Err(UsageError("--out needs one method, not --method all".to_string()).into());
    }
    let dataset = workspace::read_dataset(&args.input, &args.options.read_options())?;
    let methods: Vec<Option<Method>> = if all {
        Method::ALL.into_iter().map(Some).collect()
    } else {
        vec![args.options.method.and_then(MethodArg::method)]
    };
    let mut rows = Vec::new();
    for method in methods {
        let request = args.options.request_with(method);
        let computed = compute(&dataset, &request)?;
        let deepest = computed.dataset.max_depth();
        let leaf_pairs: Vec<(usize, usize)> = computed
            .constraints
            .iter()
            .filter(|c| computed.dataset.node(c.a).depth == deepest)
            .map(|c| (c.a, c.b))
            .collect();
        let m = eval_metrics(&computed.dataset, &computed.layout, &leaf_pairs);
        if let Some(out) = &args.out {
            let json = layout_json(
                &computed.dataset,
                &computed.layout,
                &nptreemap::pipeline::json_extras(&computed),
            );
            store::write_atomic(out, json.as_bytes())
                .with_context(|| format!("{}: cannot write", out.display()))?;
        }
        rows.push((computed.method, m));
    }
    let file = args.input.display().to_string();
    if args.json {
        for (method, m) in &rows {
            super::say(format_args!("{}", row_json(&file, *method, m)));
        }
    } else {
        super::say(format_args!("{}", header()));
        for (method, m) in &rows {
            super::say(format_args!("{}", row_text(*method, m)));
        }
    }
    Ok(())
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
