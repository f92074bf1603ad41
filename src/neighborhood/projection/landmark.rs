//! Landmark MDS to 2-D (de Silva & Tenenbaum 2004): MaxMin landmarks from a
//! fixed seed, classical MDS of the landmarks, and every point placed by
//! distance-based triangulation from its distances to them; O(n·k) memory
//! and dissimilarity calls.

use crate::geom::Point;
use crate::neighborhood::pow2::pow2_floor;

use super::linalg::{finite_or_clamped, leading_axes, orient, to_points, top2_dense};
use super::mds::double_center;

/// Fixed seed for the first landmark; any constant works, this makes runs
/// repeatable.
const SEED_LANDMARK: u64 = 0x6e70_7472_6565_6d61;

/// Landmark MDS of `n` points with up to `k` landmarks (see [`classical_mds_2d`]).
///
/// Landmarks: the first from a fixed seed, then MaxMin (each next one the point farthest
/// from all chosen so far; ties: lowest index; non-finite counts as farthest), which
/// spreads them over the data and needs the k·n distances the triangulation reads anyway.
/// Stops early when every remaining point duplicates a landmark.
pub(super) fn landmark_mds_2d(dissimilarity: &impl Fn(usize, usize) -> f64, n: usize, k: usize) -> Vec<Point> {
    let k = k.min(n);
    let pair = |i: usize, j: usize| -> f64 {
        let v = match i.cmp(&j) {
            std::cmp::Ordering::Equal => return 0.0,
            std::cmp::Ordering::Less => dissimilarity(i, j),
            std::cmp::Ordering::Greater => dissimilarity(j, i),
        };
        if v.is_finite() {
            v.abs()
        } else {
            f64::NAN
        }
    };
    let mut rng = crate::rng::Rng::new(SEED_LANDMARK);
    let mut landmarks = vec![(rng.next_u64() % n as u64) as usize];
    // rows[a][j]: |dissimilarity| between landmark a and point j, NaN when unknown.
    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(k);
    let mut nearest = vec![f64::INFINITY; n];
    // One landmark row per round, `k` rounds at most.
    for _ in 0..k {
        let l = landmarks[rows.len()];
        let row: Vec<f64> = (0..n).map(|j| pair(l, j)).collect();
        for (m, &v) in nearest.iter_mut().zip(&row) {
            let v = if v.is_nan() { f64::INFINITY } else { v };
            *m = m.min(v);
        }
        rows.push(row);
        if rows.len() == k {
            break;
        }
        for &l in &landmarks {
            nearest[l] = f64::NEG_INFINITY;
        }
        let mut best = 0;
        for (j, &m) in nearest.iter().enumerate() {
            if m > nearest[best] {
                best = j;
            }
        }
        if nearest[best] <= 0.0 {
            break;
        }
        landmarks.push(best);
    }
    let k = rows.len();

    let dmax = rows
        .iter()
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, &v| m.max(v));
    if dmax == 0.0 {
        return vec![Point::ZERO; n];
    }
    // As in the exact path: power-of-two scale, unknown = largest, then squares.
    let scale = pow2_floor(dmax);
    let fill = dmax / scale;
    for v in rows.iter_mut().flatten() {
        let s = if v.is_nan() { fill } else { *v / scale };
        *v = s * s;
    }
    let mut b: Vec<f64> = (0..k)
        .flat_map(|a| landmarks.iter().map(|&l| rows[a][l]).collect::<Vec<_>>())
        .collect();
    // Mean squared distance of each landmark to the landmarks (δ_μ of the paper).
    let mean_row: Vec<f64> = b
        .chunks_exact(k)
        .map(|r| r.iter().sum::<f64>() / k as f64)
        .collect();
    double_center(&mut b, k);

    // x_j = −½ L# (δ_j − δ_μ), with L# the rows v_a / √λ_a: exact for the landmarks
    // themselves, and for every point when the input is Euclidean of rank ≤ 2.
    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, (value, v)) in leading_axes(top2_dense(&b, k)).into_iter().enumerate() {
        let f = -0.5 / value.sqrt();
        let c = &mut coords[axis];
        for (a, row) in rows.iter().enumerate() {
            let w = f * v[a];
            for (cj, &dj) in c.iter_mut().zip(row) {
                *cj += w * (dj - mean_row[a]);
            }
        }
        orient(c);
        for cj in c.iter_mut() {
            *cj = finite_or_clamped(*cj * scale);
        }
    }
    to_points(coords)
}
