//! Test fixtures shared by the projection tests: seeded point sets, a rotated
//! embedding in five dimensions, and the checks on distances and variance.
//! Test-only.

use crate::geom::Point;
use crate::rng::Rng;

pub(super) fn random_points(n: usize, seed: u64, sx: f64, sy: f64) -> Vec<Point> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| Point::new(sx * (rng.next_f64() - 0.5), sy * (rng.next_f64() - 0.5)))
        .collect()
}

/// A 5×5 orthogonal matrix (product of Givens rotations), rows as basis vectors.
pub(super) fn rotation5() -> [[f64; 5]; 5] {
    let mut r = [[0.0; 5]; 5];
    for (i, row) in r.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let angles = [
        (0, 1, 0.3),
        (1, 2, 1.1),
        (2, 3, -0.7),
        (3, 4, 2.0),
        (0, 4, 0.5),
        (1, 3, -1.3),
    ];
    for &(a, b, t) in &angles {
        let (s, c) = f64::sin_cos(t);
        for row in r.iter_mut() {
            let (x, y) = (row[a], row[b]);
            row[a] = c * x - s * y;
            row[b] = s * x + c * y;
        }
    }
    r
}

pub(super) fn embed5(points: &[Point], offset: [f64; 5]) -> Vec<Vec<f64>> {
    let r = rotation5();
    points
        .iter()
        .map(|p| {
            (0..5)
                .map(|k| p.x * r[k][0] + p.y * r[k][1] + offset[k])
                .collect()
        })
        .collect()
}

pub(super) fn assert_same_distances(a: &[Point], b: &[Point], tol: f64) {
    assert_eq!(a.len(), b.len());
    for i in 0..a.len() {
        for j in 0..a.len() {
            let (da, db) = (a[i].distance(a[j]), b[i].distance(b[j]));
            assert!((da - db).abs() <= tol, "pair ({i},{j}): {da} vs {db}");
        }
    }
}

pub(super) fn variance(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let n = values.clone().count() as f64;
    let mean = values.clone().sum::<f64>() / n;
    values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / n
}


pub(super) fn euclidean(points: &[Point]) -> impl Fn(usize, usize) -> f64 + '_ {
    move |i, j| points[i].distance(points[j])
}
