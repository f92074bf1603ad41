//! Euclidean PCA of dense feature vectors to 2-D (method-reference §4.1): the
//! covariance or the Gram matrix decomposed densely, or the centred data by
//! a partial SVD when both of its sides are large.

use faer::MatRef;

use crate::geom::Point;
use crate::neighborhood::pow2::pow2_floor;

use super::linalg::{
    dot, finite_or_clamped, leading_axes, mirror_upper, normalize, orient, to_points, top2_dense,
    top2_singular_of, DENSE_MAX,
};

/// Projects feature vectors to 2-D by plain Euclidean PCA (method-reference §4.1: one PCA
/// over all nodes of the tree).
///
/// Point `i` is the centred vector `i` projected onto the two leading principal axes,
/// first axis (x) the one with the larger variance. Each axis is oriented so that its
/// largest-magnitude loading (ties: lowest feature index) is positive, which makes the
/// output deterministic.
///
/// Rows are expected to have equal length; callers should resolve ragged or missing rows.
/// If lengths differ anyway, the dimension is the longest row and missing entries count
/// as 0. NaN and infinite entries also count as 0. Fewer than two rows, zero variance, or
/// variance in only one direction give zeros on the affected axes; the output is always
/// finite and has one point per row.
///
/// Cost: one dense n×d copy. With m = min(n, d) ≤ 512, O(n·d·m) to form the smaller of
/// the covariance (d×d) and Gram (n×n) matrices and O(m³) for faer's dense EVD; above,
/// faer's partial SVD of the centred data, O(n·d) per step and O((n + d)·64) extra memory.
pub fn pca_2d(vectors: &[Vec<f64>]) -> Vec<Point> {
    let n = vectors.len();
    let d = vectors.iter().map(Vec::len).max().unwrap_or(0);
    if n < 2 || d == 0 {
        return vec![Point::ZERO; n];
    }

    // Dense copy with non-finite and missing entries as 0.
    let mut x = vec![0.0; n * d];
    let mut amax = 0.0_f64;
    for (row, v) in x.chunks_exact_mut(d).zip(vectors) {
        for (dst, &src) in row.iter_mut().zip(v) {
            if src.is_finite() {
                *dst = src;
                amax = amax.max(src.abs());
            }
        }
    }
    if amax == 0.0 {
        return vec![Point::ZERO; n];
    }
    // Scaling by a power of two is exact and keeps the covariance far from overflow
    // (entries ≤ 16·n) for any finite input.
    let scale = pow2_floor(amax);
    let mut mean = vec![0.0; d];
    for row in x.chunks_exact_mut(d) {
        for (v, m) in row.iter_mut().zip(mean.iter_mut()) {
            *v /= scale;
            *m += *v;
        }
    }
    for m in &mut mean {
        *m /= n as f64;
    }
    for row in x.chunks_exact_mut(d) {
        for (v, m) in row.iter_mut().zip(&mean) {
            *v -= m;
        }
    }

    let axes = loadings(&x, n, d);
    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, mut v) in axes.into_iter().enumerate() {
        orient(&mut v);
        for (c, r) in coords[axis].iter_mut().zip(x.chunks_exact(d)) {
            *c = finite_or_clamped(dot(r, &v) * scale);
        }
    }
    to_points(coords)
}

/// The loadings (unit vectors in feature space) of the two leading axes of the
/// centred n×d data `x` (row-major): from the partial SVD of the data when both
/// sides are above [`DENSE_MAX`], else from the dense EVD of the smaller of the
/// covariance and the Gram matrix.
fn loadings(x: &[f64], n: usize, d: usize) -> Vec<Vec<f64>> {
    if n.min(d) > DENSE_MAX {
        leading_axes(top2_singular(x, n, d))
            .into_iter()
            .map(|(_, v)| v)
            .collect()
    } else if d <= n {
        let mut cov = vec![0.0; d * d];
        // Upper triangle as a sum of rank-1 updates: contiguous rows, vectorisable.
        for r in x.chunks_exact(d) {
            for (i, &ri) in r.iter().enumerate() {
                if ri == 0.0 {
                    continue;
                }
                for (c, &rj) in cov[i * d + i..(i + 1) * d].iter_mut().zip(&r[i..]) {
                    *c += ri * rj;
                }
            }
        }
        mirror_upper(&mut cov, d);
        leading_axes(top2_dense(&cov, d))
            .into_iter()
            .map(|(_, v)| v)
            .collect()
    } else {
        // Fewer points than features: the Gram matrix X·Xᵀ has the same non-zero
        // spectrum, and Xᵀu is the loading that goes with its eigenvector u.
        let mut gram = vec![0.0; n * n];
        for i in 0..n {
            let ri = &x[i * d..(i + 1) * d];
            for j in i..n {
                gram[i * n + j] = dot(ri, &x[j * d..(j + 1) * d]);
            }
        }
        mirror_upper(&mut gram, n);
        leading_axes(top2_dense(&gram, n))
            .into_iter()
            .map(|(_, u)| {
                let mut v = vec![0.0; d];
                for (ui, r) in u.iter().zip(x.chunks_exact(d)) {
                    for (vj, &rj) in v.iter_mut().zip(r) {
                        *vj += ui * rj;
                    }
                }
                normalize(&mut v);
                v
            })
            .collect()
    }
}

/// The two leading right singular vectors of the centred n×d data `x` (row-major) as
/// (σ², v) pairs, descending: the covariance's top eigenpairs without forming it, by
/// faer's restarted Lanczos bidiagonalisation from a fixed start vector.
fn top2_singular(x: &[f64], n: usize, d: usize) -> Vec<(f64, Vec<f64>)> {
    top2_singular_of(&MatRef::from_row_major_slice(x, n, d), dot(x, x).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::neighborhood::projection::test_support::{
        assert_same_distances, embed5, random_points, variance,
    };
    use crate::rng::Rng;

    #[test]
    fn pca_recovers_a_rotated_planar_embedding() {
        let pts = random_points(40, 7, 10.0, 3.0);
        let vectors = embed5(&pts, [1.0, -2.0, 3.0, 0.5, 100.0]);
        let proj = pca_2d(&vectors);
        assert_same_distances(&pts, &proj, 1e-9);
    }

    #[test]
    fn pca_gram_path_matches_covariance_path() {
        // d > n takes the Gram route; zero-padding the covariance case to many more
        // features must give the same projection.
        let pts = random_points(12, 3, 5.0, 2.0);
        let narrow = embed5(&pts, [0.0; 5]);
        let wide: Vec<Vec<f64>> = narrow
            .iter()
            .map(|v| {
                let mut w = v.clone();
                w.resize(40, 0.0);
                w
            })
            .collect();
        let a = pca_2d(&narrow);
        let b = pca_2d(&wide);
        for (p, q) in a.iter().zip(&b) {
            assert!(p.distance(*q) < 1e-9, "{p} vs {q}");
        }
        assert_same_distances(&pts, &b, 1e-9);
    }

    #[test]
    fn pca_first_axis_has_the_larger_variance() {
        // Wide in y, narrow in x: the projection must swap them.
        let pts = random_points(200, 11, 1.0, 8.0);
        let vectors: Vec<Vec<f64>> = pts.iter().map(|p| vec![p.x, p.y, 0.0]).collect();
        let proj = pca_2d(&vectors);
        let vx = variance(proj.iter().map(|p| p.x));
        let vy = variance(proj.iter().map(|p| p.y));
        assert!(vx > 10.0 * vy, "{vx} vs {vy}");
        assert_same_distances(&pts, &proj, 1e-9);
    }

    #[test]
    fn pca_is_deterministic_and_sign_normalized() {
        let mut rng = Rng::new(99);
        let vectors: Vec<Vec<f64>> = (0..300)
            .map(|_| (0..20).map(|_| rng.next_f64()).collect())
            .collect();
        let a = pca_2d(&vectors);
        let b = pca_2d(&vectors);
        assert_eq!(a, b);
        // Flipping every feature flips the data, not the normalised output.
        let neg: Vec<Vec<f64>> = vectors
            .iter()
            .map(|v| v.iter().map(|x| -x).collect())
            .collect();
        let c = pca_2d(&neg);
        // Negated data with positive-oriented loadings: the projection flips sign.
        for (p, q) in a.iter().zip(&c) {
            assert!((*p + *q).length() < 1e-9);
        }
    }

    #[test]
    fn pca_degenerate_inputs_are_finite() {
        let finite = |p: &[Point]| p.iter().all(|q| q.is_finite());
        assert!(pca_2d(&[]).is_empty());
        assert_eq!(pca_2d(&[vec![1.0, 2.0]]), vec![Point::ZERO]);
        assert_eq!(pca_2d(&[vec![], vec![]]), vec![Point::ZERO; 2]);
        assert_eq!(pca_2d(&vec![vec![3.0; 4]; 5]), vec![Point::ZERO; 5]);
        // Collinear: second axis zero.
        let line: Vec<Vec<f64>> = (0..10)
            .map(|i| vec![i as f64, 2.0 * i as f64, 1.0])
            .collect();
        let p = pca_2d(&line);
        assert!(finite(&p) && p.iter().all(|q| q.y == 0.0));
        assert!((p[9].x - p[0].x).abs() > 1.0);
        // One feature: second axis zero.
        let p = pca_2d(&[vec![1.0], vec![2.0], vec![4.0]]);
        assert!(finite(&p) && p.iter().all(|q| q.y == 0.0));
        // NaN, inf, ragged, huge and tiny values.
        let nasty = vec![
            vec![f64::NAN, 1.0, 2.0],
            vec![f64::INFINITY, -1.0],
            vec![1e308, -1e308, 5.0],
            vec![-1e308, 1e-320, f64::NEG_INFINITY],
            vec![],
        ];
        let p = pca_2d(&nasty);
        assert_eq!(p.len(), 5);
        assert!(finite(&p));
        let tiny: Vec<Vec<f64>> = (0..6).map(|i| vec![1e-320 * i as f64, 5e-324]).collect();
        assert!(finite(&pca_2d(&tiny)));
        // Two distinct points: a line.
        let p = pca_2d(&[vec![0.0, 0.0], vec![3.0, 4.0]]);
        assert!((p[0].distance(p[1]) - 5.0).abs() < 1e-12 && p[0].y == 0.0);
    }

    #[test]
    fn pca_repeated_top_eigenvalue_gives_two_axes() {
        // A square: equal variance in both directions, any orthonormal pair is right.
        let sq = [
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
        ];
        let vectors: Vec<Vec<f64>> = sq.iter().map(|v| v.to_vec()).collect();
        let pts: Vec<Point> = sq.iter().map(|v| Point::new(v[0], v[1])).collect();
        assert_same_distances(&pts, &pca_2d(&vectors), 1e-12);
        // The same through a non-trivial Householder reduction: a regular 12-gon, rotated.
        let ring: Vec<Point> = (0..12)
            .map(|i| Point::from_angle(i as f64 * std::f64::consts::TAU / 12.0) * 2.0)
            .collect();
        assert_same_distances(&ring, &pca_2d(&embed5(&ring, [1.0; 5])), 1e-12);
    }

    #[test]
    fn pca_partial_svd_path_matches_the_dense_path() {
        // n and d above DENSE_MAX: faer's partial SVD of the data. A rotated planar
        // embedding must come back exactly, and full-rank data must match the dense
        // decomposition of its covariance.
        let n = DENSE_MAX + 40;
        let d = DENSE_MAX + 8;
        let pts = random_points(n, 13, 10.0, 3.0);
        let planar: Vec<Vec<f64>> = embed5(&pts, [1.0, -2.0, 3.0, 0.5, 7.0])
            .into_iter()
            .map(|mut v| {
                v.resize(d, 0.25);
                v
            })
            .collect();
        assert_same_distances(&pts, &pca_2d(&planar), 1e-9);
        let mut rng = Rng::new(17);
        let full: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                (0..d)
                    .map(|k| (rng.next_f64() - 0.5) / (1.0 + 0.1 * k as f64))
                    .collect()
            })
            .collect();
        let proj = pca_2d(&full);
        // Dense reference: covariance of the centred data, faer's full EVD.
        let mean: Vec<f64> = (0..d)
            .map(|k| full.iter().map(|v| v[k]).sum::<f64>() / n as f64)
            .collect();
        let centred: Vec<Vec<f64>> = full
            .iter()
            .map(|v| v.iter().zip(&mean).map(|(x, m)| x - m).collect())
            .collect();
        let mut cov = vec![0.0; d * d];
        for v in &centred {
            for i in 0..d {
                for j in 0..d {
                    cov[i * d + j] += v[i] * v[j];
                }
            }
        }
        for (axis, (value, mut u)) in top2_dense(&cov, d).into_iter().enumerate() {
            orient(&mut u);
            let ours: Vec<f64> = proj
                .iter()
                .map(|p| if axis == 0 { p.x } else { p.y })
                .collect();
            let var: f64 = ours.iter().map(|c| c * c).sum();
            assert!((var - value).abs() < 1e-9 * value, "{var} vs {value}");
            for (a, v) in ours.iter().zip(&centred) {
                assert!((a - dot(v, &u)).abs() < 1e-7, "axis {axis}");
            }
        }
    }
}
