//! Classical (Torgerson) MDS to 2-D, exact: the n×n matrix of squared
//! dissimilarities double-centred and decomposed densely.

use crate::geom::Point;
use crate::neighborhood::pow2::pow2_floor;

use super::linalg::{finite_or_clamped, leading_axes, mirror_upper, orient, to_points, top2_dense};

/// Exact classical MDS of `n` points (see [`super::classical_mds_2d`]): n(n−1)/2
/// calls of `dissimilarity`, O(n²) memory, faer's dense EVD (O(n³)).
pub(super) fn exact_mds_2d(dissimilarity: impl Fn(usize, usize) -> f64, n: usize) -> Vec<Point> {
    let mut b = vec![0.0; n * n];
    let mut dmax = 0.0_f64;
    for i in 0..n {
        for j in i + 1..n {
            let v = dissimilarity(i, j);
            if v.is_finite() {
                dmax = dmax.max(v.abs());
                b[i * n + j] = v.abs();
            } else {
                // Marked for now; replaced by the largest finite value once it is known.
                b[i * n + j] = f64::NAN;
            }
        }
    }
    if dmax == 0.0 {
        return vec![Point::ZERO; n];
    }
    // Power-of-two scale: exact, and squares stay ≤ 4.
    let scale = pow2_floor(dmax);
    let fill = dmax / scale;
    for i in 0..n {
        for j in i + 1..n {
            let v = &mut b[i * n + j];
            let s = if v.is_nan() { fill } else { *v / scale };
            *v = s * s;
        }
    }
    mirror_upper(&mut b, n);
    double_center(&mut b, n);

    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, (value, mut u)) in leading_axes(top2_dense(&b, n)).into_iter().enumerate() {
        orient(&mut u);
        let s = value.max(0.0).sqrt() * scale;
        for (c, ui) in coords[axis].iter_mut().zip(&u) {
            *c = finite_or_clamped(ui * s);
        }
    }
    to_points(coords)
}

/// B = −½ J D² J in place (`b` holds the symmetric squared dissimilarities), via row
/// means (= column means) and the grand mean, then forced exactly symmetric: row i and
/// column i come from the same formula with operands in a different order.
pub(super) fn double_center(b: &mut [f64], n: usize) {
    let row_mean: Vec<f64> = b
        .chunks_exact(n)
        .map(|r| r.iter().sum::<f64>() / n as f64)
        .collect();
    let grand = row_mean.iter().sum::<f64>() / n as f64;
    for (i, r) in b.chunks_exact_mut(n).enumerate() {
        for (j, v) in r.iter_mut().enumerate() {
            *v = -0.5 * (*v - row_mean[i] - row_mean[j] + grand);
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            b[j * n + i] = b[i * n + j];
        }
    }
}
