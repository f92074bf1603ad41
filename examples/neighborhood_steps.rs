//! Time and peak memory of the data-side steps of the neighbourhood method (prepare,
//! constraints, projection) on one dataset: a file, or a generated hierarchy. Not a
//! test (no timing in tests). Peak RSS is the process's high-water mark (`VmHWM`)
//! after each step, so run one case per process:
//!
//! ```sh
//! cargo run --release --example neighborhood_steps -- FILE.json
//! cargo run --release --example neighborhood_steps -- CONFIG.yaml DATASET
//! cargo run --release --example neighborhood_steps -- --gen flat 10000
//! ```
//!
//! Generated cases (`--gen KIND N`, seeded): `flat` (N leaves, 64-d random-walk
//! embeddings, cosine), `levels` (N leaves in 3 levels, same), `border` (N rows of a
//! border list without pairs: neighbour lists, no vectors, so MDS), `chain` (a parent
//! chain N deep, neighbour lists) and `caterpillar` (a chain N deep with a leaf on
//! every chain node, vectors, so virtual nodes). Owns only this example.

use std::time::Instant;

use nptreemap::neighborhood::{build_constraints, prepare, projection, similarity, SimilarityKind};
use nptreemap::rng::Rng;
use nptreemap::Dataset;
use nptreemap_formats::{DatasetBuilder, NodeSpec, SimilarityHint};

/// Peak resident set size so far, in MB (Linux `/proc/self/status`).
fn peak_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// A roughly Gaussian deviate (Irwin–Hall of 12 uniforms).
fn gauss(rng: &mut Rng) -> f64 {
    (0..12).map(|_| rng.next_f64()).sum::<f64>() - 6.0
}

/// `n` leaves under `levels` levels of groups (fan-out n^(1/levels)), each vector its
/// parent's plus noise (as `benches/gen_similar.py`).
fn embedded(n: usize, levels: u32, dim: usize) -> Dataset {
    let mut rng = Rng::new(1);
    let fan = (n as f64).powf(1.0 / f64::from(levels)).ceil() as usize;
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("r"));
    b.similarity_hint(SimilarityHint::Cosine);
    // Frontier of (id, vector); the last level holds the leaves.
    let mut frontier = vec![("r".to_string(), vec![0.0; dim])];
    for level in 1..=levels {
        let mut next = Vec::new();
        let want = if level == levels {
            n
        } else {
            fan.pow(level).min(n)
        };
        for k in 0..want {
            let (pid, pv) = &frontier[k * frontier.len() / want];
            let v: Vec<f64> = pv.iter().map(|x| x + gauss(&mut rng)).collect();
            let id = format!("{pid}.{k}");
            let mut spec = NodeSpec::new(id.clone()).parent(pid.clone());
            if level == levels {
                spec = spec.weight(1.0 + 9.0 * rng.next_f64()).features(v.clone());
            }
            b.add(spec);
            next.push((id, v));
        }
        frontier = next;
    }
    b.build().expect("valid")
}

fn generated(kind: &str, n: usize) -> Dataset {
    let mut b = DatasetBuilder::new();
    match kind {
        "flat" => return embedded(n, 1, 64),
        "levels" => return embedded(n, 3, 64),
        "border" => {
            b.add(NodeSpec::new("root"));
            b.similarity_hint(SimilarityHint::NeighborList);
            for i in 0..n {
                b.add(NodeSpec::new(format!("n{i}")).parent("root").weight(1.0));
            }
        }
        "chain" => {
            b.similarity_hint(SimilarityHint::NeighborList);
            b.add(NodeSpec::new("n0").weight(1.0));
            for i in 1..n {
                b.add(
                    NodeSpec::new(format!("n{i}"))
                        .parent(format!("n{}", i - 1))
                        .weight(1.0),
                );
            }
        }
        "caterpillar" => {
            b.similarity_hint(SimilarityHint::Cosine);
            b.add(NodeSpec::new("c0"));
            for i in 1..n {
                b.add(NodeSpec::new(format!("c{i}")).parent(format!("c{}", i - 1)));
                b.add(
                    NodeSpec::new(format!("l{i}"))
                        .parent(format!("c{}", i - 1))
                        .weight(1.0)
                        .features(vec![i as f64, 1.0, (i % 7) as f64]),
                );
            }
        }
        other => panic!("unknown --gen kind {other}"),
    }
    b.build().expect("valid")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let start = Instant::now();
    let dataset = match args.first().map(String::as_str) {
        Some("--gen") => generated(&args[1], args[2].parse()?),
        Some(path) if path.ends_with(".yaml") => {
            let config = nptreemap::config::Config::from_path(path.as_ref())?;
            let d = config
                .datasets
                .iter()
                .find(|d| args.get(1).is_none_or(|name| &d.name == name))
                .ok_or("no such dataset")?;
            nptreemap::pipeline::load(d)?
        }
        Some(path) => nptreemap_formats::parse_hierarchy_json(
            &std::fs::read(path)?,
            &nptreemap_formats::HierarchyJsonOptions::default(),
        )?,
        None => {
            return Err("usage: neighborhood_steps FILE | CONFIG DATASET | --gen KIND N".into())
        }
    };
    println!(
        "input: {} nodes, depth {}, loaded in {:.0} ms, peak {:.0} MB",
        dataset.len(),
        dataset.max_depth(),
        start.elapsed().as_secs_f64() * 1e3,
        peak_mb()
    );
    let kind = SimilarityKind::for_dataset(&dataset);

    let t = Instant::now();
    let prepared = prepare(&dataset);
    println!(
        "prepare:     {:9.1} ms  peak {:6.0} MB  ({} nodes after virtual nodes)",
        t.elapsed().as_secs_f64() * 1e3,
        peak_mb(),
        prepared.len()
    );

    let t = Instant::now();
    let constraints = build_constraints(&prepared, kind);
    println!(
        "constraints: {:9.1} ms  peak {:6.0} MB  ({} pairs, {kind:?})",
        t.elapsed().as_secs_f64() * 1e3,
        peak_mb(),
        constraints.len()
    );

    // The projection the layout takes (`layout::similar::projection_of`): PCA when
    // every node has a vector of one length, else MDS of 1 − similarity.
    let t = Instant::now();
    let nodes = prepared.nodes();
    let features: Vec<_> = nodes.iter().map(|n| n.features.as_ref()).collect();
    let (points, path) = match projection::pca_of_features(&features) {
        Some(points) => (points, "pca"),
        None => {
            let sim = |a, b| 1.0 - similarity::similarity(kind, &prepared, a, b);
            (projection::classical_mds_2d(sim, nodes.len()), "mds")
        }
    };
    println!(
        "projection:  {:9.1} ms  peak {:6.0} MB  ({path}, {} points)",
        t.elapsed().as_secs_f64() * 1e3,
        peak_mb(),
        points.len()
    );
    Ok(())
}
