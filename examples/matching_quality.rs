//! Quality and time of the large-group matching (recursive bisection with exact
//! blocks, `neighborhood::matching`) against exact Kuhn–Munkres: total distance ratio
//! on groups of 200 and 500 for several block sizes, and time up to 100,000 points.
//! Not a test (no timing in tests): `cargo run --release --example matching_quality`.
//! Owns only this example; touches no library code.

use std::time::Instant;

use nptreemap::geom::Point;
use nptreemap::neighborhood::matching::{bisection_match, match_points, min_cost_assignment};
use nptreemap::rng::Rng;

/// CVT-like sites: a jittered grid over the unit square (what 0.8-Lloyd CVT sites look
/// like), `n` of them.
fn sites(n: usize, rng: &mut Rng) -> Vec<Point> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (gx, gy) = ((i % side) as f64, (i / side) as f64);
        out.push(Point::new(
            (gx + 0.3 + 0.4 * rng.next_f64()) / side as f64,
            (gy + 0.3 + 0.4 * rng.next_f64()) / side as f64,
        ));
    }
    out
}

/// Projection-like points: eight Gaussian-ish clusters in a box twice the sites' size
/// (the projections of a level fill the root box, the sites one parent cell).
fn points(n: usize, rng: &mut Rng) -> Vec<Point> {
    let centres: Vec<Point> = (0..8)
        .map(|_| Point::new(2.0 * rng.next_f64(), 2.0 * rng.next_f64()))
        .collect();
    (0..n)
        .map(|i| {
            let c = centres[i % 8];
            let g = |r: &mut Rng| (0..4).map(|_| r.next_f64() - 0.5).sum::<f64>() * 0.3;
            c + Point::new(g(rng), g(rng))
        })
        .collect()
}

fn total(sites: &[Point], points: &[Point], a: &[usize]) -> f64 {
    a.iter()
        .zip(points)
        .map(|(&s, p)| p.distance(sites[s]))
        .sum()
}

fn exact(s: &[Point], p: &[Point]) -> Vec<usize> {
    let cost: Vec<f64> = p
        .iter()
        .flat_map(|q| s.iter().map(move |t| q.distance(*t)))
        .collect();
    min_cost_assignment(&cost, p.len(), s.len())
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    for k in [200usize, 500] {
        for block in [32usize, 64, 128, 250] {
            let mut ratios = Vec::new();
            let (mut t_exact, mut t_bis) = (0.0, 0.0);
            for seed in 1..=5u64 {
                let mut rng = Rng::new(seed * 7919 + k as u64);
                let s = sites(k, &mut rng);
                let p = points(k, &mut rng);
                let t = Instant::now();
                let e = exact(&s, &p);
                t_exact += t.elapsed().as_secs_f64() * 1e3;
                let t = Instant::now();
                let b = bisection_match(&s, &p, block);
                t_bis += t.elapsed().as_secs_f64() * 1e3;
                ratios.push(total(&s, &p, &b) / total(&s, &p, &e));
            }
            let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
            let max = ratios.iter().copied().fold(0.0, f64::max);
            println!(
                "k={k:>4} block={block:>3}: total / exact mean {mean:.4} max {max:.4}; time exact {:.1} ms, bisection {:.2} ms (mean of 5)",
                t_exact / 5.0,
                t_bis / 5.0
            );
        }
    }
    for k in [501usize, 3_000, 10_000, 100_000] {
        let mut rng = Rng::new(k as u64);
        let s = sites(k, &mut rng);
        let p = points(k, &mut rng);
        let t = Instant::now();
        let a = match_points(&s, &p);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        println!(
            "k={k:>6}: match_points {ms:9.1} ms, mean distance {:.4}",
            total(&s, &p, &a) / k as f64
        );
    }
}
