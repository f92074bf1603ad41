//! PCA of sparse features (sets among them) to 2-D without a dense copy:
//! faer's partial SVD of the implicitly centred sparse matrix
//! (`CentredSparse`), O(non-zeros + n + d) per Lanczos step (issue 23).

use faer::dyn_stack::{MemStack, StackReq};
use faer::matrix_free::{BiLinOp, LinOp};
use faer::reborrow::ReborrowMut;
use faer::{MatMut, MatRef, Par};
use nptreemap_formats::SparseVector;

use crate::geom::Point;
use crate::neighborhood::pow2::pow2_floor;

use super::linalg::{dot, finite_or_clamped, leading_axes, orient, to_points, top2_singular_of};

/// [`pca_2d`] of sparse vectors of dimension `d` without a dense copy: the two
/// leading right singular vectors of the centred data by faer's partial SVD of
/// [`CentredSparse`], O(non-zeros + n + d) per Lanczos step and O((n + d)·64)
/// extra memory. Same scaling, start vector, tolerance and orientation as the
/// dense partial-SVD path, so the axes agree with it up to round-off.
pub(super) fn sparse_pca_2d(vectors: &[&SparseVector], d: usize) -> Vec<Point> {
    let n = vectors.len();
    if n < 2 || d == 0 {
        return vec![Point::ZERO; n];
    }
    let amax = vectors
        .iter()
        .flat_map(|v| v.entries())
        .fold(0.0_f64, |m, (_, x)| if x.is_finite() { m.max(x.abs()) } else { m });
    if amax == 0.0 {
        return vec![Point::ZERO; n];
    }
    let scale = pow2_floor(amax);
    let op = CentredSparse::new(vectors, d, scale);
    let pairs = top2_singular_of(&op, op.frobenius());
    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, (_, mut v)) in leading_axes(pairs).into_iter().enumerate() {
        orient(&mut v);
        let shift = dot(&op.mean, &v);
        for (c, row) in coords[axis].iter_mut().zip(vectors) {
            let mut sum = 0.0;
            for (k, x) in row.entries() {
                sum += op.value(x) * v[k as usize];
            }
            *c = finite_or_clamped((sum - shift) * scale);
        }
    }
    to_points(coords)
}

/// The n×d matrix of sparse rows divided by `scale`, minus its column means,
/// applied without forming it: `A·v = X·v − 1·(μ·v)` and `Aᵀ·u = Xᵀ·u − μ·(1·u)`.
#[derive(Debug)]
struct CentredSparse<'a> {
    rows: &'a [&'a SparseVector],
    d: usize,
    scale: f64,
    mean: Vec<f64>,
}

impl<'a> CentredSparse<'a> {
    fn new(rows: &'a [&'a SparseVector], d: usize, scale: f64) -> Self {
        let mut mean = vec![0.0; d];
        for row in rows {
            for (k, x) in row.entries() {
                mean[k as usize] += if x.is_finite() { x / scale } else { 0.0 };
            }
        }
        for m in &mut mean {
            *m /= rows.len() as f64;
        }
        CentredSparse {
            rows,
            d,
            scale,
            mean,
        }
    }

    /// A stored value as the matrix holds it (scaled; non-finite as 0).
    fn value(&self, x: f64) -> f64 {
        if x.is_finite() {
            x / self.scale
        } else {
            0.0
        }
    }

    /// ‖A‖_F, from the non-zeros and the means: Σ(x − μ)² over every entry.
    fn frobenius(&self) -> f64 {
        let mut squares = 0.0;
        let mut count = vec![0usize; self.d];
        for row in self.rows {
            for (k, x) in row.entries() {
                let c = self.value(x) - self.mean[k as usize];
                squares += c * c;
                count[k as usize] += 1;
            }
        }
        let n = self.rows.len();
        for (m, c) in self.mean.iter().zip(count) {
            squares += (n - c) as f64 * m * m;
        }
        squares.sqrt()
    }

    /// `out = A·rhs` (`transpose` false) or `out = Aᵀ·rhs`, column by column.
    fn product(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, transpose: bool) {
        for c in 0..rhs.ncols() {
            if transpose {
                let mut total = 0.0;
                for k in 0..self.d {
                    *out.rb_mut().get_mut(k, c) = 0.0;
                }
                for (i, row) in self.rows.iter().enumerate() {
                    let u = *rhs.get(i, c);
                    total += u;
                    for (k, x) in row.entries() {
                        *out.rb_mut().get_mut(k as usize, c) += self.value(x) * u;
                    }
                }
                for (k, m) in self.mean.iter().enumerate() {
                    *out.rb_mut().get_mut(k, c) -= m * total;
                }
            } else {
                let mut shift = 0.0;
                for (k, m) in self.mean.iter().enumerate() {
                    shift += m * rhs.get(k, c);
                }
                for (i, row) in self.rows.iter().enumerate() {
                    let mut sum = 0.0;
                    for (k, x) in row.entries() {
                        sum += self.value(x) * rhs.get(k as usize, c);
                    }
                    *out.rb_mut().get_mut(i, c) = sum - shift;
                }
            }
        }
    }
}

impl LinOp<f64> for CentredSparse<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.rows.len()
    }

    fn ncols(&self) -> usize {
        self.d
    }

    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        self.product(out, rhs, false);
    }

    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        _par: Par,
        _stack: &mut MemStack,
    ) {
        self.product(out, rhs, false);
    }
}

impl BiLinOp<f64> for CentredSparse<'_> {
    fn transpose_apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn transpose_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        _par: Par,
        _stack: &mut MemStack,
    ) {
        self.product(out, rhs, true);
    }

    fn adjoint_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        _par: Par,
        _stack: &mut MemStack,
    ) {
        self.product(out, rhs, true);
    }
}
