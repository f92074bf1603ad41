//! The shape trade-off of the `neighbor` method (issue 12, item 2): for a few
//! settings of [`NeighborParams::shape_weight`] and
//! [`NeighborParams::centroid_pull`], the leaf constraints realised and the leaf
//! aspect ratio (as a ratio to `plain`'s on the same data and seed), medians over
//! seeds, on the paper's Table 2 datasets and any files or configs given. Not a
//! test (it takes minutes); its table goes in BENCHMARKS.md.
//!
//! ```sh
//! cargo run --release --example pareto                       # Table 2 files, seeds 1-5
//! cargo run --release --example pareto -- --seeds 3 tests/data/real/debian-packages/nptreemap.yaml
//! ```
//!
//! Files are hierarchy JSON; a `.yaml` argument is a config whose every dataset
//! is added. Owns only this example.

use std::path::{Path, PathBuf};

use nptreemap::config::{Config, DatasetConfig};
use nptreemap::layout::{compute, Method, Request};
use nptreemap::measure::table2;
use nptreemap::{pipeline, Dataset};

/// The settings compared: off, each term alone, and the two together at
/// growing strength (the default, 0.25 / 0.1, among them).
const SETTINGS: [(f64, f64); 7] = [
    (0.0, 0.0),
    (0.25, 0.0),
    (0.0, 0.1),
    (0.1, 0.05),
    (0.25, 0.1),
    (0.5, 0.15),
    (1.0, 0.2),
];

/// The Table 2 files (MANIFEST.md), in its order.
const TABLE2: [&str; 6] = [
    "country_pop_50M_AUS.json",
    "cifar10.json",
    "flare.json",
    "imdb_100_genre_sim_2child.json",
    "syntheticPoints_10nodes_2components.json",
    "2_level_4_cousin_constraints.json",
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Every dataset named on the command line (or the Table 2 files), with the
/// request its config gives.
fn datasets(args: &[String]) -> Vec<(String, Dataset, Request)> {
    let mut out = Vec::new();
    let mut add = |d: DatasetConfig, request: Request| {
        let dataset = pipeline::load(&d).unwrap_or_else(|e| panic!("{}: {e}", d.name));
        out.push((d.name.clone(), dataset, request));
    };
    let paths: Vec<PathBuf> = if args.is_empty() {
        let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/paper");
        TABLE2.iter().map(|f| paper.join(f)).collect()
    } else {
        args.iter().map(PathBuf::from).collect()
    };
    for path in paths {
        if path.extension().is_some_and(|e| e == "yaml" || e == "yml") {
            let config = Config::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
            for d in &config.datasets {
                add(d.clone(), config.request(d));
            }
        } else {
            add(
                DatasetConfig::hierarchy_file(&path, None),
                Request::default(),
            );
        }
    }
    out
}

fn main() {
    let mut seeds = 5u64;
    let mut files = Vec::new();
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        if a == "--seeds" {
            seeds = it.next().and_then(|v| v.parse().ok()).unwrap_or(seeds);
        } else {
            files.push(a);
        }
    }
    let data = datasets(&files);
    // Plain's aspect per dataset and seed: the reference of every ratio.
    let plain: Vec<Vec<f64>> = data
        .iter()
        .map(|(_, dataset, request)| {
            (1..=seeds)
                .map(|seed| {
                    let mut r = request.clone();
                    r.method = Some(Method::Plain);
                    r.params.seed = seed;
                    table2(&compute(dataset, &r).expect("plain lays out")).aspect_ratio
                })
                .collect()
        })
        .collect();
    print!("| shape_weight / centroid_pull |");
    for (name, ..) in &data {
        print!(" {name} |");
    }
    println!();
    println!("|---|{}", "---|".repeat(data.len()));
    for (shape_weight, centroid_pull) in SETTINGS {
        print!("| {shape_weight} / {centroid_pull} |");
        for ((_, dataset, request), plain) in data.iter().zip(&plain) {
            let (mut realized, mut ratio, mut wh) = (Vec::new(), Vec::new(), Vec::new());
            for seed in 1..=seeds {
                let mut r = request.clone();
                r.method = Some(Method::Neighbor);
                r.params.seed = seed;
                r.neighbor.shape_weight = shape_weight;
                r.neighbor.centroid_pull = centroid_pull;
                let m = table2(&compute(dataset, &r).expect("neighbor lays out"));
                realized.push(m.realized as f64);
                ratio.push(m.aspect_ratio / plain[seed as usize - 1]);
                wh.push(m.aspect_ratio_proto);
            }
            print!(
                " {:.0} · {:.2}× · w/h {:.2} |",
                median(realized),
                median(ratio),
                median(wh)
            );
        }
        println!();
    }
}
