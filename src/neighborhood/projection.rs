//! 2-D projections for the geometric initialisation (method-reference §4.1): Euclidean
//! PCA of feature vectors, classical (Torgerson) MDS of a dissimilarity (landmark MDS
//! above `MDS_EXACT_MAX` nodes), and the per-axis min–max rescale into a box. Pure and
//! deterministic: start vectors and landmarks come from fixed seeds, faer runs
//! sequentially (`Par::Seq`, so the thread count cannot change a bit), no I/O.
//!
//! The eigen-decompositions are faer's (issue 12 item 5): its dense self-adjoint
//! EVD for matrices up to `DENSE_MAX`, and its restarted Lanczos partial SVD of the
//! centred data for PCA above. Measured against the hand-written solver this replaced
//! (Householder, Sturm bisection, inverse iteration, Lanczos) in BENCHMARKS.md
//! ("Projections"): as accurate or better everywhere, and faster on every size.
//!
//! Sets and other sparse features ([`SparseVector`]) are projected by the same PCA:
//! densified when small (at most [`DENSIFY_MAX`] values, so small data gives the
//! dense path's projection bit for bit), else by faer's partial SVD of the implicitly
//! centred sparse matrix ([`CentredSparse`]), never a dense n×d copy (issue 23).

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
use faer::matrix_free::eigen::{partial_svd, partial_svd_scratch, PartialEigenParams};
use faer::dyn_stack::StackReq;
use faer::matrix_free::{BiLinOp, LinOp};
use faer::reborrow::ReborrowMut;
use faer::{Col, Mat, MatMut, MatRef, Par};
use nptreemap_formats::{Features, SparseVector};

use crate::geom::Point;

/// Symmetric matrices up to this order (covariance d×d, Gram n×n, landmark k×k, exact
/// MDS n×n) are decomposed densely (O(m³), about 0.1 s at 512); PCA with both n and d
/// above it goes through the partial SVD of the data, O(n·d) per Lanczos step, and never
/// forms an m×m matrix.
const DENSE_MAX: usize = 512;

/// Classical MDS is exact (an n×n matrix, dense EVD) up to this many points; above it,
/// landmark MDS (de Silva & Tenenbaum 2004) with [`LANDMARKS`] MaxMin landmarks keeps
/// memory and dissimilarity calls at O(n·k). 512 keeps the exact matrix at 2 MB and its
/// EVD near 0.1 s; the paper's datasets all have vectors (PCA), so none takes this path.
const MDS_EXACT_MAX: usize = DENSE_MAX;

/// Landmarks of landmark MDS. The projection only seeds the matching (method-reference
/// §4.3), and two axes are stable with far fewer landmarks; 128 keeps the n·k distance
/// table at 100 MB for 100,000 nodes (see BENCHMARKS.md for the stress against exact MDS).
const LANDMARKS: usize = 128;

/// Eigenvalues at most this many ulps of the largest one (times the order) are round-off,
/// not variance: their eigenvectors are arbitrary, so the axis is set to zero instead.
const ZERO_EIG_ULPS: f64 = 16.0;

/// Relative difference below which two loadings count as tied in [`orient`]: far
/// above round-off (1e-16), far below any real difference between loadings.
const TIE_REL: f64 = 1e-9;

/// Partial SVD stops when a Ritz residual is below this fraction of ‖X‖_F: a few hundred
/// ulps, what full reorthogonalisation can reach, so the result matches the dense path.
const PARTIAL_REL_TOL: f64 = 1e-13;

/// Fixed seeds for the Lanczos start vector and the first landmark; any constant works,
/// these make runs repeatable.
const SEED_LANCZOS: u64 = 0x9e37_79b9_7f4a_7c15;
const SEED_LANDMARK: u64 = 0x6e70_7472_6565_6d61;

/// Sparse features of at most this many coordinates in all (nodes × dimension) are
/// densified for [`pca_2d`]: 32 MB, far below the dense copy that used to take
/// gigabytes, and large enough for every paper and real dataset in `tests/data`.
pub const DENSIFY_MAX: usize = 1 << 22;

/// PCA to 2-D of every node's features (method-reference §4.1) when all of them
/// have features of one length and one kind (all dense or all sparse) and that
/// length is not 0; `None` otherwise (the caller then uses MDS of a similarity).
/// Dense vectors go to [`pca_2d`]; sparse ones too when small ([`DENSIFY_MAX`]),
/// else to the sparse PCA (same axes up to round-off, no dense copy).
pub fn pca_of_features(features: &[Option<&Features>]) -> Option<Vec<Point>> {
    let first = (*features.first()?)?;
    let d = first.len();
    let uniform = d > 0
        && features.iter().all(|f| {
            f.is_some_and(|f| f.len() == d && f.as_dense().is_some() == first.as_dense().is_some())
        });
    if !uniform {
        return None;
    }
    let all = features.iter().flatten();
    if first.as_dense().is_some() || features.len().saturating_mul(d) <= DENSIFY_MAX {
        let vectors: Vec<Vec<f64>> = all.map(|f| f.to_dense()).collect();
        return Some(pca_2d(&vectors));
    }
    let sparse: Vec<&SparseVector> = all.filter_map(|f| f.as_sparse()).collect();
    Some(sparse_pca_2d(&sparse, d))
}

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

    // Loadings (unit vectors in feature space) of the two leading axes.
    let axes: Vec<Vec<f64>> = if n.min(d) > DENSE_MAX {
        leading_axes(top2_singular(&x, n, d))
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
    };

    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, mut v) in axes.into_iter().enumerate() {
        orient(&mut v);
        for (c, r) in coords[axis].iter_mut().zip(x.chunks_exact(d)) {
            *c = finite_or_clamped(dot(r, &v) * scale);
        }
    }
    to_points(coords)
}

/// [`pca_2d`] of sparse vectors of dimension `d` without a dense copy: the two
/// leading right singular vectors of the centred data by faer's partial SVD of
/// [`CentredSparse`], O(non-zeros + n + d) per Lanczos step and O((n + d)·64)
/// extra memory. Same scaling, start vector, tolerance and orientation as the
/// dense partial-SVD path, so the axes agree with it up to round-off.
fn sparse_pca_2d(vectors: &[&SparseVector], d: usize) -> Vec<Point> {
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

/// Classical (Torgerson) MDS to 2-D: double-centres the squared dissimilarities and
/// scales the two leading eigenvectors by the square roots of their eigenvalues; above
/// 512 points, landmark MDS (see below).
///
/// Used when nodes only have a similarity (`dissimilarity = 1 − similarity`). The function
/// is called only with `i < j` (at most once per unordered pair): it is assumed
/// symmetric, and the diagonal is taken as 0. NaN and infinite values count as the largest
/// finite dissimilarity ("unknown" reads as "far"); the sign is ignored because only squares
/// enter. Negative eigenvalues (non-Euclidean input) give zeros on that axis, as does
/// an eigenvalue that is round-off. Axis orientation: the largest-magnitude coordinate
/// (ties: lowest index) is positive. The output is always finite, one point per index.
///
/// Cost up to 512 points: n(n−1)/2 calls, O(n²) memory, faer's dense EVD (O(n³)). Above:
/// landmark MDS with 128 landmarks chosen by MaxMin from a fixed-seed first one
/// (de Silva & Tenenbaum, "Sparse multidimensional scaling using landmark points", 2004):
/// about 128·n calls, a 128×n distance table (O(n) memory), a 128×128 EVD, and each point
/// placed by distance-based triangulation from its distances to the landmarks. On
/// Euclidean input of rank ≤ 2 that is exact; otherwise it approximates classical MDS
/// (figures in BENCHMARKS.md, "Projections").
pub fn classical_mds_2d(dissimilarity: impl Fn(usize, usize) -> f64, n: usize) -> Vec<Point> {
    if n < 2 {
        return vec![Point::ZERO; n];
    }
    if n > MDS_EXACT_MAX {
        return landmark_mds_2d(&dissimilarity, n, LANDMARKS);
    }
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
fn double_center(b: &mut [f64], n: usize) {
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

/// Landmark MDS of `n` points with up to `k` landmarks (see [`classical_mds_2d`]).
///
/// Landmarks: the first from a fixed seed, then MaxMin (each next one the point farthest
/// from all chosen so far; ties: lowest index; non-finite counts as farthest), which
/// spreads them over the data and needs the k·n distances the triangulation reads anyway.
/// Stops early when every remaining point duplicates a landmark.
fn landmark_mds_2d(dissimilarity: &impl Fn(usize, usize) -> f64, n: usize, k: usize) -> Vec<Point> {
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

fn to_points([xs, ys]: [Vec<f64>; 2]) -> Vec<Point> {
    xs.into_iter()
        .zip(ys)
        .map(|(a, b)| Point::new(a, b))
        .collect()
}

/// Rescales points per axis (min–max) into the box with corners `lo` and `hi`
/// (method-reference §4.1 step 3, without the prototype's halving of the y range).
///
/// On each axis the smallest coordinate maps to `lo` and the largest to `hi` (if
/// `lo > hi` the axis is mirrored). A single point, or a zero range on an axis, maps to the
/// box's midpoint on that axis. Non-finite coordinates are left out of the range and map to
/// the midpoint; non-finite box corners count as 0. The output is finite.
pub fn fit_into(points: &[Point], lo: Point, hi: Point) -> Vec<Point> {
    let xs = rescale_axis(
        points.iter().map(|p| p.x),
        finite_or_zero(lo.x),
        finite_or_zero(hi.x),
    );
    let ys = rescale_axis(
        points.iter().map(|p| p.y),
        finite_or_zero(lo.y),
        finite_or_zero(hi.y),
    );
    xs.into_iter()
        .zip(ys)
        .map(|(x, y)| Point::new(x, y))
        .collect()
}

/// One axis of [`fit_into`].
fn rescale_axis(values: impl Iterator<Item = f64> + Clone, lo: f64, hi: f64) -> Vec<f64> {
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.clone().filter(|v| v.is_finite()) {
        min = min.min(v);
        max = max.max(v);
    }
    // lo·(1−t) + hi·t is exact at both ends and cannot overflow for finite corners.
    let lerp = |t: f64| lo * (1.0 - t) + hi * t;
    let mid = lerp(0.5);
    // Halving before subtracting keeps the range finite even for ±f64::MAX.
    let half_range = 0.5 * max - 0.5 * min;
    values
        .map(|v| {
            if !v.is_finite() || half_range.is_nan() || half_range <= 0.0 {
                mid
            } else {
                lerp(((0.5 * v - 0.5 * min) / half_range).clamp(0.0, 1.0))
            }
        })
        .collect()
}

/// The eigenpairs worth keeping as axes: positive, and not round-off relative to the first.
fn leading_axes(pairs: Vec<(f64, Vec<f64>)>) -> Vec<(f64, Vec<f64>)> {
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
fn top2_dense(a: &[f64], m: usize) -> Vec<(f64, Vec<f64>)> {
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

/// The two leading right singular vectors of the centred n×d data `x` (row-major) as
/// (σ², v) pairs, descending: the covariance's top eigenpairs without forming it, by
/// faer's restarted Lanczos bidiagonalisation from a fixed start vector.
fn top2_singular(x: &[f64], n: usize, d: usize) -> Vec<(f64, Vec<f64>)> {
    top2_singular_of(&MatRef::from_row_major_slice(x, n, d), dot(x, x).sqrt())
}

/// [`top2_singular`] of any operator (`frob`: its Frobenius norm, for the
/// stopping tolerance): the dense data or the implicitly centred sparse rows.
fn top2_singular_of(op: &dyn BiLinOp<f64>, frob: f64) -> Vec<(f64, Vec<f64>)> {
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
fn normalize(x: &mut [f64]) -> bool {
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
fn orient(v: &mut [f64]) {
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
fn mirror_upper(a: &mut [f64], n: usize) {
    for i in 0..n {
        for j in i + 1..n {
            a[j * n + i] = a[i * n + j];
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The largest power of two not above `x` (finite, > 0); dividing by it is exact.
fn pow2_floor(x: f64) -> f64 {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    if x >= f64::MIN_POSITIVE {
        f64::from_bits(x.to_bits() & EXPONENT)
    } else {
        // Subnormal: lift into the normal range first.
        f64::from_bits((x * TWO_52).to_bits() & EXPONENT) / TWO_52
    }
}

fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// Overflow in the final unscaling (inputs near f64::MAX) saturates instead of going
/// infinite.
fn finite_or_clamped(x: f64) -> f64 {
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

    fn random_points(n: usize, seed: u64, sx: f64, sy: f64) -> Vec<Point> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| Point::new(sx * (rng.next_f64() - 0.5), sy * (rng.next_f64() - 0.5)))
            .collect()
    }

    /// A 5×5 orthogonal matrix (product of Givens rotations), rows as basis vectors.
    fn rotation5() -> [[f64; 5]; 5] {
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

    fn embed5(points: &[Point], offset: [f64; 5]) -> Vec<Vec<f64>> {
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

    fn assert_same_distances(a: &[Point], b: &[Point], tol: f64) {
        assert_eq!(a.len(), b.len());
        for i in 0..a.len() {
            for j in 0..a.len() {
                let (da, db) = (a[i].distance(a[j]), b[i].distance(b[j]));
                assert!((da - db).abs() <= tol, "pair ({i},{j}): {da} vs {db}");
            }
        }
    }

    fn variance(values: impl Iterator<Item = f64> + Clone) -> f64 {
        let n = values.clone().count() as f64;
        let mean = values.clone().sum::<f64>() / n;
        values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / n
    }

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

    fn euclidean(points: &[Point]) -> impl Fn(usize, usize) -> f64 + '_ {
        move |i, j| points[i].distance(points[j])
    }

    #[test]
    fn mds_reproduces_points_up_to_rigid_motion() {
        let pts = random_points(60, 5, 10.0, 4.0);
        let out = classical_mds_2d(euclidean(&pts), pts.len());
        assert_same_distances(&pts, &out, 1e-9);
        // Centred at the origin, first axis with the larger variance.
        let c = out.iter().copied().sum::<Point>() / out.len() as f64;
        assert!(c.length() < 1e-9);
        assert!(variance(out.iter().map(|p| p.x)) > variance(out.iter().map(|p| p.y)));
    }

    #[test]
    fn mds_landmark_path_reproduces_planar_points() {
        // n > MDS_EXACT_MAX: landmark MDS, exact on Euclidean input of rank 2, including
        // a repeated top eigenvalue (regular polygon).
        let n = MDS_EXACT_MAX + 88;
        let pts = random_points(n, 8, 10.0, 4.0);
        assert_same_distances(&pts, &classical_mds_2d(euclidean(&pts), n), 1e-9);
        let ring: Vec<Point> = (0..n)
            .map(|i| Point::from_angle(i as f64 * std::f64::consts::TAU / n as f64) * 3.0)
            .collect();
        assert_same_distances(&ring, &classical_mds_2d(euclidean(&ring), n), 1e-9);
    }

    #[test]
    fn mds_landmark_path_keeps_the_contract() {
        let n = MDS_EXACT_MAX * 3;
        let pts = random_points(n, 9, 10.0, 4.0);
        // Called only with i < j, and far fewer than n² times.
        let calls = std::cell::Cell::new(0usize);
        let d = |i: usize, j: usize| {
            assert!(i < j, "called with ({i}, {j})");
            calls.set(calls.get() + 1);
            pts[i].distance(pts[j])
        };
        let a = classical_mds_2d(d, n);
        assert!(calls.get() <= LANDMARKS * n, "{} calls", calls.get());
        assert_eq!(a, classical_mds_2d(euclidean(&pts), n));
        // Non-Euclidean input stays finite.
        let far = |i: usize, j: usize| {
            let z = |k: usize| ((k * 37) % 11) as f64;
            (pts[i].distance(pts[j]).powi(2) + (z(i) - z(j)).powi(2)).sqrt()
        };
        assert!(classical_mds_2d(far, n).iter().all(|p| p.is_finite()));
        // Degenerate inputs: all equal, all unknown, duplicates, huge values.
        assert!(classical_mds_2d(|_, _| 1.0, n)
            .iter()
            .all(|p| p.is_finite()));
        assert!(classical_mds_2d(|_, _| f64::NAN, n)
            .iter()
            .all(|p| p.is_finite()));
        assert_eq!(classical_mds_2d(|_, _| 0.0, n), vec![Point::ZERO; n]);
        let dup = |i: usize, j: usize| pts[i % 3].distance(pts[j % 3]);
        let p = classical_mds_2d(dup, n);
        assert!((p[0].distance(p[1]) - pts[0].distance(pts[1])).abs() < 1e-9);
        assert!(p[0].distance(p[3]) < 1e-9);
        let huge = |i: usize, j: usize| pts[i].distance(pts[j]) * 1e300;
        assert!(classical_mds_2d(huge, n).iter().all(|p| p.is_finite()));
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

    #[test]
    fn mds_degenerate_and_non_euclidean_inputs_are_finite() {
        let finite = |p: &[Point]| p.iter().all(|q| q.is_finite());
        assert!(classical_mds_2d(|_, _| 1.0, 0).is_empty());
        assert_eq!(classical_mds_2d(|_, _| 1.0, 1), vec![Point::ZERO]);
        assert_eq!(classical_mds_2d(|_, _| 0.0, 4), vec![Point::ZERO; 4]);
        let p = classical_mds_2d(|_, _| f64::NAN, 5);
        assert!(finite(&p));
        let p = classical_mds_2d(
            |i, j| {
                if (i + j) % 3 == 0 {
                    f64::INFINITY
                } else {
                    -2.0
                }
            },
            7,
        );
        assert!(finite(&p));
        let p = classical_mds_2d(|i, j| ((i * 7 + j * 3) % 5) as f64 * 1e300, 9);
        assert!(finite(&p));
        // Two points: a segment of the right length on the first axis.
        let p = classical_mds_2d(|_, _| 2.0, 2);
        assert!((p[0].distance(p[1]) - 2.0).abs() < 1e-12 && p[0].y == 0.0);
        let p1 = classical_mds_2d(|i, j| 1.0 - 1.0 / (1.0 + (i * j) as f64), 30);
        let p2 = classical_mds_2d(|i, j| 1.0 - 1.0 / (1.0 + (i * j) as f64), 30);
        assert_eq!(p1, p2);
    }

    #[test]
    fn fit_into_rescales_each_axis_independently() {
        let pts = [
            Point::new(-1.0, 10.0),
            Point::new(3.0, 20.0),
            Point::new(1.0, 15.0),
        ];
        let out = fit_into(&pts, Point::new(0.0, 0.0), Point::new(100.0, 50.0));
        assert_eq!(
            out,
            vec![
                Point::new(0.0, 0.0),
                Point::new(100.0, 50.0),
                Point::new(50.0, 25.0)
            ]
        );
    }

    #[test]
    fn fit_into_degenerate_axes_go_to_the_midpoint() {
        let lo = Point::new(10.0, 20.0);
        let hi = Point::new(30.0, 60.0);
        assert_eq!(
            fit_into(&[Point::new(5.0, 5.0)], lo, hi),
            vec![Point::new(20.0, 40.0)]
        );
        let out = fit_into(&[Point::new(1.0, 7.0), Point::new(2.0, 7.0)], lo, hi);
        assert_eq!(out, vec![Point::new(10.0, 40.0), Point::new(30.0, 40.0)]);
        let out = fit_into(
            &[
                Point::new(f64::NAN, 0.0),
                Point::new(-f64::MAX, f64::INFINITY),
                Point::new(f64::MAX, 1.0),
            ],
            lo,
            hi,
        );
        assert_eq!(
            out,
            vec![
                Point::new(20.0, 20.0),
                Point::new(10.0, 40.0),
                Point::new(30.0, 60.0)
            ]
        );
        assert!(fit_into(&[], lo, hi).is_empty());
        let out = fit_into(
            &[Point::new(1.0, 2.0)],
            Point::new(f64::NAN, 0.0),
            Point::new(4.0, 4.0),
        );
        assert_eq!(out, vec![Point::new(2.0, 2.0)]);
    }

    /// Issue 23 item 1: sets above [`DENSIFY_MAX`] values are projected by the
    /// sparse PCA without a dense copy, to the dense PCA's points up to
    /// round-off; small ones are densified, so they give its points bit for bit.
    #[test]
    fn sparse_pca_matches_the_dense_pca() {
        use nptreemap_formats::{Features, SparseVector};
        let (n, d) = (120usize, 40_000u32);
        assert!(n * d as usize > DENSIFY_MAX);
        let mut rng = crate::rng::Rng::new(7);
        // Three clusters of members plus noise, so the two axes are well separated.
        let sets: Vec<Features> = (0..n)
            .map(|i| {
                let base = (i % 3) as u32 * 100;
                let mut members: Vec<u32> =
                    (0..30).filter(|_| rng.next_u64() % 3 > 0).map(|k| base + k).collect();
                members.extend((0..5).map(|_| (rng.next_u64() % u64::from(d)) as u32));
                if i % 2 == 0 {
                    members.push(1000 + (i % 3) as u32);
                }
                SparseVector::set(d, members).expect("set").into()
            })
            .collect();
        let refs: Vec<Option<&Features>> = sets.iter().map(Some).collect();
        let sparse = pca_of_features(&refs).expect("uniform");
        let dense = pca_2d(&sets.iter().map(Features::to_dense).collect::<Vec<_>>());
        let spread = dense.iter().fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        for (s, t) in sparse.iter().zip(&dense) {
            assert!(
                (s.x - t.x).abs() < 1e-9 * spread && (s.y - t.y).abs() < 1e-9 * spread,
                "{s:?} {t:?}"
            );
        }
        // Small: densified, bit for bit.
        let small: Vec<Features> = sets[..10]
            .iter()
            .map(|f| SparseVector::set(1200, f.as_sparse().expect("set").indices().iter().copied().filter(|&k| k < 1200)).expect("set").into())
            .collect();
        let refs: Vec<Option<&Features>> = small.iter().map(Some).collect();
        assert_eq!(
            pca_of_features(&refs),
            Some(pca_2d(&small.iter().map(Features::to_dense).collect::<Vec<_>>()))
        );
        // Mixed kinds or lengths: no PCA (the caller uses MDS).
        let mixed = [Some(&sets[0]), Some(&small[0])];
        assert_eq!(pca_of_features(&mixed), None);
    }
}
