//! The linear algebra every projection shares: faer's dense self-adjoint
//! EVD (with one Rayleigh–Ritz refinement) and restarted Lanczos partial SVD,
//! both sequential and from fixed start vectors, which eigenpairs count as
//! axes and how an axis is oriented, and the small vector helpers.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
use faer::matrix_free::eigen::{partial_svd, partial_svd_scratch, PartialEigenParams};
use faer::matrix_free::BiLinOp;
use faer::{Col, Mat, MatRef, Par};

use crate::geom::Point;

/// Symmetric matrices up to this order (covariance d×d, Gram n×n, landmark k×k, exact
/// MDS n×n) are decomposed densely (O(m³), about 0.1 s at 512); PCA with both n and d
/// above it goes through the partial SVD of the data, O(n·d) per Lanczos step, and never
/// forms an m×m matrix.
pub(super) const DENSE_MAX: usize = 512;

/// Eigenvalues at most this many ulps of the largest one (times the order) are round-off,
/// not variance: their eigenvectors are arbitrary, so the axis is set to zero instead.
const ZERO_EIG_ULPS: f64 = 16.0;

/// Relative difference below which two loadings count as tied in [`orient`]: far
/// above round-off (1e-16), far below any real difference between loadings.
const TIE_REL: f64 = 1e-9;

/// Partial SVD stops when a Ritz residual is below this fraction of ‖X‖_F: a few hundred
/// ulps, what full reorthogonalisation can reach, so the result matches the dense path.
const PARTIAL_REL_TOL: f64 = 1e-13;

/// Fixed seed for the Lanczos start vector; any constant works, this makes runs
/// repeatable.
const SEED_LANCZOS: u64 = 0x9e37_79b9_7f4a_7c15;

pub(super) fn to_points([xs, ys]: [Vec<f64>; 2]) -> Vec<Point> {
    xs.into_iter()
        .zip(ys)
        .map(|(a, b)| Point::new(a, b))
        .collect()
}

/// The eigenpairs worth keeping as axes: positive, and not round-off relative to the first.
pub(super) fn leading_axes(pairs: Vec<(f64, Vec<f64>)>) -> Vec<(f64, Vec<f64>)> {
    let top = pairs.first().map_or(0.0, |p| p.0);
    let m = pairs.first().map_or(0, |p| p.1.len());
    let floor = top * m as f64 * ZERO_EIG_ULPS * f64::EPSILON;
    pairs
        .into_iter()
        .filter(|(value, v)| *value > 0.0 && *value > floor && v.iter().all(|x| x.is_finite()))
        .collect()
}

/// The two largest eigenpairs (by value, descending; fewer if m < 2) of the symmetric
/// m×m matrix `a` (row-major, both triangles filled), by faer's dense self-adjoint EVD.
/// Vectors have unit length. Empty if faer reports no convergence.
pub(super) fn top2_dense(a: &[f64], m: usize) -> Vec<(f64, Vec<f64>)> {
    if m == 0 {
        return Vec::new();
    }
    let par = Par::Seq;
    let params = Default::default();
    let mut values = Diag::<f64>::zeros(m);
    let mut vectors = Mat::<f64>::zeros(m, m);
    let mut mem = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        m,
        ComputeEigenvectors::Yes,
        par,
        params,
    ));
    let solved = self_adjoint_evd(
        MatRef::from_row_major_slice(a, m, m),
        values.as_mut(),
        Some(vectors.as_mut()),
        par,
        MemStack::new(&mut mem),
        params,
    );
    if solved.is_err() {
        return Vec::new();
    }
    // faer sorts eigenvalues in nondecreasing order.
    let values: Vec<f64> = values.column_vector().iter().copied().collect();
    let top: Vec<(f64, Vec<f64>)> = (0..m.min(2))
        .map(|t| {
            let col = m - 1 - t;
            (values[col], vectors.col_as_slice(col).to_vec())
        })
        .collect();
    if m > 2 {
        refine(a, m, top)
    } else {
        top
    }
}

/// One Rayleigh–Ritz step on span(A·[v₁ v₂]) (one step of subspace iteration): the
/// full EVD's vectors carry round-off from every other eigenvector; one product with
/// A damps that by λ₃/λ₂ and brings the residual to that of the product itself
/// (about the hand-written inverse iteration's, BENCHMARKS.md "Projections").
/// Returns `pairs` unchanged when the step degenerates (rank < 2 of A·V).
fn refine(a: &[f64], m: usize, pairs: Vec<(f64, Vec<f64>)>) -> Vec<(f64, Vec<f64>)> {
    let apply = |v: &[f64]| -> Vec<f64> { a.chunks_exact(m).map(|row| dot(row, v)).collect() };
    let mut w: Vec<Vec<f64>> = pairs.iter().map(|(_, v)| apply(v)).collect();
    for k in 0..w.len() {
        let (done, rest) = w.split_at_mut(k);
        let against: Vec<&[f64]> = done.iter().map(Vec::as_slice).collect();
        orthogonalize(&mut rest[0], &against);
        if !normalize(&mut rest[0]) {
            return pairs;
        }
    }
    let aw: Vec<Vec<f64>> = w.iter().map(|v| apply(v)).collect();
    let r = w.len();
    let mut h = vec![0.0; r * r];
    for i in 0..r {
        for j in 0..r {
            h[i * r + j] = dot(&w[i], &aw[j]);
        }
    }
    // Exactly symmetric for the 2×2 EVD (the two products round differently).
    for i in 0..r {
        for j in i + 1..r {
            let mean = 0.5 * (h[i * r + j] + h[j * r + i]);
            h[i * r + j] = mean;
            h[j * r + i] = mean;
        }
    }
    let small = top2_dense(&h, r);
    if small.len() != r {
        return pairs;
    }
    small
        .into_iter()
        .map(|(value, y)| {
            let mut v = vec![0.0; m];
            for (yi, wi) in y.iter().zip(&w) {
                for (vj, wij) in v.iter_mut().zip(wi) {
                    *vj += yi * wij;
                }
            }
            normalize(&mut v);
            (value, v)
        })
        .collect()
}

/// Subtracts the projections onto `against` (unit vectors), twice for stability.
fn orthogonalize(x: &mut [f64], against: &[&[f64]]) {
    for _ in 0..2 {
        for a in against {
            let f = dot(x, a);
            for (xi, ai) in x.iter_mut().zip(a.iter()) {
                *xi -= f * ai;
            }
        }
    }
}

/// [`top2_singular`] of any operator (`frob`: its Frobenius norm, for the
/// stopping tolerance): the dense data or the implicitly centred sparse rows.
pub(super) fn top2_singular_of(op: &dyn BiLinOp<f64>, frob: f64) -> Vec<(f64, Vec<f64>)> {
    let (n, d) = (op.nrows(), op.ncols());
    let par = Par::Seq;
    let params = PartialEigenParams::default();
    let want = 2.min(n.min(d));
    let mut left = Mat::<f64>::zeros(n, want);
    let mut right = Mat::<f64>::zeros(d, want);
    let mut sigma = vec![0.0; want];
    let start = Col::<f64>::from_fn(d, {
        let v = start_vector(d, SEED_LANCZOS);
        move |i| v[i]
    });
    let mut mem = MemBuffer::new(partial_svd_scratch::<f64>(op, want, par, params));
    let info = partial_svd(
        left.as_mut(),
        right.as_mut(),
        &mut sigma,
        op,
        start.as_ref(),
        PARTIAL_REL_TOL * frob,
        par,
        MemStack::new(&mut mem),
        params,
    );
    (0..info.n_converged_eigen.min(want))
        .map(|t| {
            let mut v = right.col_as_slice(t).to_vec();
            normalize(&mut v);
            (sigma[t] * sigma[t], v)
        })
        .collect()
}

/// Scales `x` to unit length; false (and `x` untouched) if its length is 0 or not finite.
pub(super) fn normalize(x: &mut [f64]) -> bool {
    let len = dot(x, x).sqrt();
    if len.is_finite() && len > 0.0 {
        for v in x.iter_mut() {
            *v /= len;
        }
        true
    } else {
        false
    }
}

/// Flips `v` so that its largest-magnitude entry (ties: lowest index) is positive.
/// Magnitudes within [`TIE_REL`] of each other count as tied, so that round-off
/// (a different solver, a different summation order) cannot flip an axis whose two
/// largest loadings are equal in exact arithmetic (the synthetic paper datasets).
pub(super) fn orient(v: &mut [f64]) {
    let mut best = 0;
    for (i, x) in v.iter().enumerate() {
        if x.abs() > v[best].abs() * (1.0 + TIE_REL) {
            best = i;
        }
    }
    if v.get(best).is_some_and(|&x| x < 0.0) {
        for x in v.iter_mut() {
            *x = -*x;
        }
    }
}

/// A fixed pseudo-random vector in [−1, 1)^m (SplitMix64): generic enough to have a
/// component along any eigenvector, and the same on every run and platform.
fn start_vector(m: usize, seed: u64) -> Vec<f64> {
    let mut rng = crate::rng::Rng::new(seed);
    (0..m).map(|_| 2.0 * rng.next_f64() - 1.0).collect()
}

/// Copies the upper triangle of the n×n row-major matrix into the lower one.
pub(super) fn mirror_upper(a: &mut [f64], n: usize) {
    for i in 0..n {
        for j in i + 1..n {
            a[j * n + i] = a[i * n + j];
        }
    }
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Overflow in the final unscaling (inputs near f64::MAX) saturates instead of going
/// infinite.
pub(super) fn finite_or_clamped(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(f64::MIN, f64::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rng::Rng;

    #[test]
    fn dense_eigenpairs_have_small_residuals() {
        let m = 80;
        let mut rng = Rng::new(4);
        let mut a = vec![0.0; m * m];
        for i in 0..m {
            for j in i..m {
                a[i * m + j] = rng.next_f64() - 0.5;
            }
        }
        mirror_upper(&mut a, m);
        for (value, v) in top2_dense(&a, m) {
            let r: f64 = a
                .chunks_exact(m)
                .zip(&v)
                .map(|(row, vi)| (dot(row, &v) - value * vi).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(r < 1e-12, "residual {r}");
        }
    }
}
