//! Time and accuracy of the 2-D projections (`pca_2d`, `classical_mds_2d`) on seeded
//! data of 100 to 100,000 points; prints one line per case. Not a test (no timing in
//! tests): run with `cargo run --release --example projection_speed [-- --big]`.
//! Owns only this example; touches no library code.
//!
//! Accuracy is measured from the output alone, so the same example measures any
//! solver behind the same functions. PCA: the coordinates of axis a are `c = X v`
//! with X the centred data, so λ = ‖c‖² and v = Xᵀc / λ; the figure is the relative
//! residual ‖XᵀX v − λ v‖ / λ₁ (0 for an exact eigenpair). MDS: the coordinates are
//! `u √λ`, and the residual is ‖B u − λ u‖ / λ₁ with B = −½ J D² J, formed here
//! densely (so only up to 5,000 points) or, above, against the landmark figure of
//! the distance stress (mean |d̂ − d| / mean d over 20,000 random pairs).

use std::time::Instant;

use nptreemap::geom::Point;
use nptreemap::neighborhood::projection::{classical_mds_2d, pca_2d};
use nptreemap::rng::Rng;

/// `n` points in `d` dimensions, axis k with spread 1/(1+k) (a clear spectrum).
fn data(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            (0..d)
                .map(|k| (rng.next_f64() - 0.5) / (1.0 + k as f64))
                .collect()
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut out = None;
    for _ in 0..reps {
        let start = Instant::now();
        out = Some(f());
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    (median(times), out.expect("reps > 0"))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn pca_residuals(x: &[Vec<f64>], coords: &[Point]) -> [f64; 2] {
    let (n, d) = (x.len(), x[0].len());
    let mut mean = vec![0.0; d];
    for r in x {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v / n as f64;
        }
    }
    let xc: Vec<Vec<f64>> = x
        .iter()
        .map(|r| r.iter().zip(&mean).map(|(v, m)| v - m).collect())
        .collect();
    let xt = |c: &[f64]| {
        let mut out = vec![0.0; d];
        for (ci, r) in c.iter().zip(&xc) {
            for (o, v) in out.iter_mut().zip(r) {
                *o += ci * v;
            }
        }
        out
    };
    let xv = |v: &[f64]| -> Vec<f64> {
        xc.iter()
            .map(|r| r.iter().zip(v).map(|(a, b)| a * b).sum())
            .collect()
    };
    let axes: [Vec<f64>; 2] = [
        coords.iter().map(|p| p.x).collect(),
        coords.iter().map(|p| p.y).collect(),
    ];
    let lambda: Vec<f64> = axes.iter().map(|c| norm(c).powi(2)).collect();
    let mut out = [0.0; 2];
    for a in 0..2 {
        if lambda[a] == 0.0 {
            continue;
        }
        let v: Vec<f64> = xt(&axes[a]).iter().map(|w| w / lambda[a]).collect();
        let cv = xt(&xv(&v));
        let r: Vec<f64> = cv
            .iter()
            .zip(&v)
            .map(|(c, vi)| c - lambda[a] * vi)
            .collect();
        out[a] = norm(&r) / lambda[0];
    }
    out
}

fn mds_residuals(p: &[Vec<f64>], coords: &[Point]) -> [f64; 2] {
    let n = p.len();
    let dist = |i: usize, j: usize| -> f64 {
        p[i].iter()
            .zip(&p[j])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
    };
    let mut b = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            b[i * n + j] = dist(i, j);
        }
    }
    let row: Vec<f64> = b
        .chunks(n)
        .map(|r| r.iter().sum::<f64>() / n as f64)
        .collect();
    let grand = row.iter().sum::<f64>() / n as f64;
    for i in 0..n {
        for j in 0..n {
            b[i * n + j] = -0.5 * (b[i * n + j] - row[i] - row[j] + grand);
        }
    }
    let axes: [Vec<f64>; 2] = [
        coords.iter().map(|q| q.x).collect(),
        coords.iter().map(|q| q.y).collect(),
    ];
    let lambda: Vec<f64> = axes.iter().map(|c| norm(c).powi(2)).collect();
    let mut out = [0.0; 2];
    for a in 0..2 {
        if lambda[a] == 0.0 {
            continue;
        }
        let len = lambda[a].sqrt();
        let u: Vec<f64> = axes[a].iter().map(|c| c / len).collect();
        let r: Vec<f64> = b
            .chunks(n)
            .zip(&u)
            .map(|(row, ui)| row.iter().zip(&u).map(|(x, y)| x * y).sum::<f64>() - lambda[a] * ui)
            .collect();
        out[a] = norm(&r) / lambda[0];
    }
    out
}

/// Mean |‖c_i − c_j‖ − ‖p_i − p_j‖₂ (first two axes)| over random pairs, relative to the
/// mean distance: how well the 2-D layout keeps the distances of the data's top plane.
fn mds_stress(p: &[Vec<f64>], coords: &[Point]) -> f64 {
    let n = p.len();
    let mut rng = Rng::new(77);
    let (mut err, mut tot) = (0.0, 0.0);
    for _ in 0..20_000 {
        let i = (rng.next_f64() * n as f64) as usize;
        let j = (rng.next_f64() * n as f64) as usize;
        let d: f64 = p[i]
            .iter()
            .zip(&p[j])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        err += (coords[i].distance(coords[j]) - d).abs();
        tot += d;
    }
    err / tot
}

fn main() {
    let big = std::env::args().any(|a| a == "--big");
    println!("threads: {}", rayon::current_num_threads());
    let mut pca_cases = vec![
        (100, 64, 20),
        (1_000, 64, 10),
        (5_000, 64, 5),
        (1_000, 600, 3),
    ];
    if big {
        pca_cases.push((100_000, 64, 1));
        pca_cases.push((5_000, 600, 1));
    }
    for (n, d, reps) in pca_cases {
        let x = data(n, d, 0x5eed ^ (n * d) as u64);
        let (ms, coords) = time(reps, || pca_2d(&x));
        let r = pca_residuals(&x, &coords);
        println!(
            "pca  n={n:>6} d={d:>4}: {ms:9.2} ms  residual {:.1e} / {:.1e}",
            r[0], r[1]
        );
    }
    let mut mds_cases = vec![(100, 20), (1_000, 3), (5_000, 1)];
    if big {
        mds_cases.push((20_000, 1));
        mds_cases.push((100_000, 1));
    }
    for (n, reps) in mds_cases {
        let p = data(n, 6, 0xd15 ^ n as u64);
        let dist = |i: usize, j: usize| -> f64 {
            p[i].iter()
                .zip(&p[j])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt()
        };
        let (ms, coords) = time(reps, || classical_mds_2d(dist, n));
        let stress = mds_stress(&p, &coords);
        if n <= 5_000 {
            let r = mds_residuals(&p, &coords);
            println!(
                "mds  n={n:>6}      : {ms:9.2} ms  residual {:.1e} / {:.1e}  stress {stress:.4}",
                r[0], r[1]
            );
        } else {
            println!("mds  n={n:>6}      : {ms:9.2} ms  stress {stress:.4}");
        }
    }
}
