//! 2-D projections for the geometric initialisation (method-reference §4.1): Euclidean
//! PCA of feature vectors, classical (Torgerson) MDS of a dissimilarity, and the
//! per-axis min–max rescale into a box. Pure and deterministic: no randomness (start
//! vectors come from a fixed-seed generator), fixed iteration caps, no I/O.

use crate::geom::Point;

/// Symmetric matrices up to this order are tridiagonalised densely (about m³ flops);
/// larger ones go through Lanczos, which needs only matrix–vector products.
const DENSE_MAX: usize = 512;

/// Lanczos step cap per eigenpair. The top eigenvalue of the matrices we see (a
/// covariance, a double-centred distance matrix) converges in tens of steps; the cap
/// only bounds time and memory (`LANCZOS_MAX_STEPS × m` floats) in pathological cases.
const LANCZOS_MAX_STEPS: usize = 400;

/// Lanczos stops once the Ritz residual is below this fraction of ‖A‖_F: a few hundred
/// ulps, the best full reorthogonalisation can reach, so the result matches the dense path.
const LANCZOS_REL_TOL: f64 = 1e-13;

/// Eigenvalues at most this many ulps of the largest one (times the order) are round-off,
/// not variance: their eigenvectors are arbitrary, so the axis is set to zero instead.
const ZERO_EIG_ULPS: f64 = 16.0;

/// Fixed seeds for the start vectors; any constant works, these make runs repeatable.
const SEED_INVERSE_ITERATION: u64 = 0x6e70_7472_6565_6d61;
const SEED_LANCZOS: u64 = 0x9e37_79b9_7f4a_7c15;

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
/// Cost: O(n·d·min(n, d)) to form the smaller of the covariance (d×d) and Gram (n×n)
/// matrices, then O(m³) with m = min(n, d) for the eigen-decomposition (Householder
/// tridiagonalisation, bisection, inverse iteration), or Lanczos when m > 512.
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
    let axes: Vec<Vec<f64>> = if d <= n {
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
        leading_axes(top2_symmetric(cov, d))
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
        leading_axes(top2_symmetric(gram, n))
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
    coords[0]
        .iter()
        .zip(&coords[1])
        .map(|(&a, &b)| Point::new(a, b))
        .collect()
}

/// Classical (Torgerson) MDS to 2-D: double-centres the squared dissimilarities and
/// scales the two leading eigenvectors by the square roots of their eigenvalues.
///
/// Used when nodes only have a similarity (`dissimilarity = 1 − similarity`). The function
/// is called once per unordered pair as `dissimilarity(i, j)` with `i < j`: it is assumed
/// symmetric, and the diagonal is taken as 0. NaN and infinite values count as the largest
/// finite dissimilarity ("unknown" reads as "far"); the sign is ignored because only squares
/// enter. Negative eigenvalues (non-Euclidean input) give zeros on that axis, as does
/// an eigenvalue that is round-off. Axis orientation: the largest-magnitude coordinate
/// (ties: lowest index) is positive. The output is always finite, one point per index.
///
/// Cost: n(n−1)/2 calls and O(n²) memory; O(n³) dense eigen-decomposition for n ≤ 512,
/// otherwise Lanczos with full reorthogonalisation, O(n²) per step, run once for each axis
/// (the second run deflates the first axis, so a double top eigenvalue is still found).
pub fn classical_mds_2d(dissimilarity: impl Fn(usize, usize) -> f64, n: usize) -> Vec<Point> {
    if n < 2 {
        return vec![Point::ZERO; n];
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

    // B = −½ J D² J, via row means (= column means, D² is symmetric) and the grand mean.
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
    // Row i and column i were computed by the same formula in a different order of
    // operands; force exact symmetry so both eigen paths see a symmetric matrix.
    for i in 0..n {
        for j in i + 1..n {
            b[j * n + i] = b[i * n + j];
        }
    }

    let mut coords = [vec![0.0; n], vec![0.0; n]];
    for (axis, (value, mut u)) in leading_axes(top2_symmetric(b, n)).into_iter().enumerate() {
        orient(&mut u);
        let s = value.max(0.0).sqrt() * scale;
        for (c, ui) in coords[axis].iter_mut().zip(&u) {
            *c = finite_or_clamped(ui * s);
        }
    }
    coords[0]
        .iter()
        .zip(&coords[1])
        .map(|(&a, &b)| Point::new(a, b))
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
/// m×m matrix `a` (row-major, both triangles filled). Vectors have unit length.
fn top2_symmetric(mut a: Vec<f64>, m: usize) -> Vec<(f64, Vec<f64>)> {
    if m == 0 {
        return Vec::new();
    }
    if m <= DENSE_MAX {
        let (diag, off, reflectors) = tridiagonalize(&mut a, m);
        let mut out: Vec<(f64, Vec<f64>)> = Vec::new();
        for t in 0..m.min(2) {
            let value = tridiag_eigenvalue(&diag, &off, m - 1 - t);
            let previous: Vec<&[f64]> = out.iter().map(|p| p.1.as_slice()).collect();
            let z = tridiag_eigenvector(&diag, &off, value, &previous);
            out.push((value, z));
        }
        // Back to the original basis: y = H₀ H₁ ⋯ z, innermost reflector first.
        for (_, y) in &mut out {
            for (start, v, beta) in reflectors.iter().rev() {
                let tail = &mut y[*start..];
                let f = beta * dot(v, tail);
                for (yi, vi) in tail.iter_mut().zip(v) {
                    *yi -= f * vi;
                }
            }
            normalize(y);
        }
        out
    } else {
        let frob = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let matvec = |x: &[f64], y: &mut [f64]| {
            for (yi, row) in y.iter_mut().zip(a.chunks_exact(m)) {
                *yi = dot(row, x);
            }
        };
        let first = lanczos_top1(&matvec, m, &[], frob, SEED_LANCZOS);
        let second = lanczos_top1(
            &matvec,
            m,
            std::slice::from_ref(&first.1),
            frob,
            SEED_LANCZOS ^ 1,
        );
        vec![first, second]
    }
}

/// A Householder reflector `I − β v vᵀ` acting on indices `start..`.
type Reflector = (usize, Vec<f64>, f64);

/// Householder reduction of the symmetric m×m `a` (overwritten) to tridiagonal form
/// T = Qᵀ A Q. Returns T's diagonal, its off-diagonal (`off[k]` couples k and k+1)
/// and the reflectors whose product is Q.
fn tridiagonalize(a: &mut [f64], m: usize) -> (Vec<f64>, Vec<f64>, Vec<Reflector>) {
    let mut off = vec![0.0; m.saturating_sub(1)];
    let mut reflectors = Vec::new();
    let mut p = vec![0.0; m];
    for k in 0..m.saturating_sub(2) {
        let start = k + 1;
        let r = m - start;
        // Column k below the diagonal equals row k right of it (symmetry): contiguous.
        let x = &a[k * m + start..(k + 1) * m];
        let x0 = x[0];
        let sigma: f64 = x[1..].iter().map(|v| v * v).sum();
        if sigma == 0.0 {
            // Already tridiagonal in this column; a reflector would divide by zero.
            off[k] = x0;
            continue;
        }
        let norm = (x0 * x0 + sigma).sqrt();
        let alpha = if x0 >= 0.0 { -norm } else { norm };
        let mut v = x.to_vec();
        v[0] = x0 - alpha;
        let beta = 2.0 / (v[0] * v[0] + sigma);
        off[k] = alpha;

        // A' ← H A' H with H = I − β v vᵀ on the trailing block, as the rank-2 update
        // A' − v wᵀ − w vᵀ where p = β A' v and w = p − (β/2)(vᵀp) v.
        let p = &mut p[..r];
        for (i, pi) in p.iter_mut().enumerate() {
            let row = &a[(start + i) * m + start..(start + i + 1) * m];
            *pi = beta * dot(row, &v);
        }
        let kf = 0.5 * beta * dot(&v, p);
        for (pi, vi) in p.iter_mut().zip(&v) {
            *pi -= kf * vi;
        }
        for i in 0..r {
            let (vi, wi) = (v[i], p[i]);
            let row = &mut a[(start + i) * m + start..(start + i + 1) * m];
            for ((aij, vj), wj) in row.iter_mut().zip(&v).zip(p.iter()) {
                *aij -= vi * wj + wi * vj;
            }
        }
        reflectors.push((start, v, beta));
    }
    if m >= 2 {
        off[m - 2] = a[(m - 2) * m + m - 1];
    }
    let diag = (0..m).map(|i| a[i * m + i]).collect();
    (diag, off, reflectors)
}

/// Largest absolute row sum of the tridiagonal matrix (a bound on its spectral radius).
fn tridiag_norm(diag: &[f64], off: &[f64]) -> f64 {
    (0..diag.len())
        .map(|i| {
            let left = if i > 0 { off[i - 1].abs() } else { 0.0 };
            let right = off.get(i).map_or(0.0, |v| v.abs());
            diag[i].abs() + left + right
        })
        .fold(0.0, f64::max)
}

/// Eigenvalue number `idx` (ascending, 0-based) of the symmetric tridiagonal matrix, by
/// Sturm-sequence bisection: robust, deterministic, absolutely accurate to a few ulps of
/// ‖T‖ whatever the clustering.
fn tridiag_eigenvalue(diag: &[f64], off: &[f64], idx: usize) -> f64 {
    let off2: Vec<f64> = off.iter().map(|v| v * v).collect();
    // Keeps every pivot away from zero without perturbing the count (LAPACK's pivmin).
    let pivmin = f64::MIN_POSITIVE * off2.iter().copied().fold(1.0, f64::max);
    let count_below = |x: f64| {
        let mut count = 0;
        let mut q = 1.0;
        for i in 0..diag.len() {
            q = diag[i] - x - if i > 0 { off2[i - 1] / q } else { 0.0 };
            if q.abs() < pivmin {
                q = -pivmin;
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    let norm = tridiag_norm(diag, off);
    let margin = 4.0 * f64::EPSILON * norm + 4.0 * pivmin;
    // Gershgorin bounds contain every eigenvalue.
    let mut lo = -norm - margin;
    let mut hi = norm + margin;
    let tol = 2.0 * f64::EPSILON * norm + pivmin;
    // 2‖T‖ halved 64 times is below the tolerance; the cap only bounds the loop.
    for _ in 0..128 {
        let mid = lo + 0.5 * (hi - lo);
        if hi - lo <= tol || mid <= lo || mid >= hi {
            break;
        }
        if count_below(mid) > idx {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo + 0.5 * (hi - lo)
}

/// Unit eigenvector of the tridiagonal matrix for the eigenvalue `lambda`, by inverse
/// iteration (LU with partial pivoting of T − λI, tiny pivots replaced by ε‖T‖), kept
/// orthogonal to `previous` so that a repeated eigenvalue yields a second, independent
/// vector.
fn tridiag_eigenvector(diag: &[f64], off: &[f64], lambda: f64, previous: &[&[f64]]) -> Vec<f64> {
    let m = diag.len();
    let norm = tridiag_norm(diag, off);
    let tiny = if norm > 0.0 {
        f64::EPSILON * norm
    } else {
        f64::MIN_POSITIVE
    };
    let guard = |p: f64| {
        if p.abs() < tiny {
            if p < 0.0 {
                -tiny
            } else {
                tiny
            }
        } else {
            p
        }
    };

    // Factor P(T − λI) = L U; U has up to two super-diagonals (u1, u2) after row swaps.
    let mut u0 = vec![0.0; m];
    let mut u1 = vec![0.0; m];
    let mut u2 = vec![0.0; m];
    let mut l = vec![0.0; m.saturating_sub(1)];
    let mut swapped = vec![false; m.saturating_sub(1)];
    let mut d = diag[0] - lambda;
    let mut e = off.first().copied().unwrap_or(0.0);
    for i in 0..m - 1 {
        let sub = off[i];
        let nd = diag[i + 1] - lambda;
        let ne = off.get(i + 1).copied().unwrap_or(0.0);
        if sub.abs() > d.abs() {
            swapped[i] = true;
            let li = d / sub;
            (u0[i], u1[i], u2[i]) = (sub, nd, ne);
            l[i] = li;
            (d, e) = (e - li * nd, -li * ne);
        } else {
            let dg = guard(d);
            let li = sub / dg;
            (u0[i], u1[i], u2[i]) = (dg, e, 0.0);
            l[i] = li;
            (d, e) = (nd - li * e, ne);
        }
    }
    u0[m - 1] = d;
    for p in &mut u0 {
        *p = guard(*p);
    }

    let solve = |rhs: &[f64]| -> Vec<f64> {
        let mut y = rhs.to_vec();
        for i in 0..m - 1 {
            if swapped[i] {
                y.swap(i, i + 1);
            }
            y[i + 1] -= l[i] * y[i];
        }
        let mut x = vec![0.0; m];
        for i in (0..m).rev() {
            let mut s = y[i];
            if i + 1 < m {
                s -= u1[i] * x[i + 1];
            }
            if i + 2 < m {
                s -= u2[i] * x[i + 2];
            }
            x[i] = s / u0[i];
        }
        x
    };

    // A different start per vector: reusing the first one would make its projection
    // on a repeated eigenvalue's eigenspace exactly the previous vector, which the
    // orthogonalisation then removes, leaving only round-off to grow from.
    let mut x = start_vector(
        m,
        SEED_INVERSE_ITERATION.wrapping_add(previous.len() as u64),
    );
    orthogonalize(&mut x, previous);
    normalize(&mut x);
    // λ is accurate to a few ulps, so each solve multiplies the wanted component by
    // ~1/ε against the rest: two steps suffice, four leave a wide margin.
    for _ in 0..4 {
        let mut next = solve(&x);
        orthogonalize(&mut next, previous);
        let len = dot(&next, &next).sqrt();
        if !(len.is_finite() && len > 0.0) {
            // Overflow or a vanished vector: keep the last good iterate.
            break;
        }
        for v in &mut next {
            *v /= len;
        }
        x = next;
    }
    x
}

/// The largest eigenpair of the symmetric m×m operator `matvec`, restricted to the
/// orthogonal complement of `deflate` (unit, mutually orthogonal vectors): Lanczos from a
/// fixed start vector with full reorthogonalisation, stopped when the Ritz residual is
/// below `LANCZOS_REL_TOL · frob` or after `LANCZOS_MAX_STEPS` steps (then the best Ritz
/// pair so far is returned). A start vector exactly orthogonal to the top eigenvector would
/// miss it; the pseudo-random fixed start makes that practically impossible.
fn lanczos_top1(
    matvec: &dyn Fn(&[f64], &mut [f64]),
    m: usize,
    deflate: &[Vec<f64>],
    frob: f64,
    seed: u64,
) -> (f64, Vec<f64>) {
    let tol = LANCZOS_REL_TOL * frob;
    let room = m.saturating_sub(deflate.len());
    let steps = room.min(LANCZOS_MAX_STEPS);
    let mut q = start_vector(m, seed);
    let deflate_refs: Vec<&[f64]> = deflate.iter().map(Vec::as_slice).collect();
    orthogonalize(&mut q, &deflate_refs);
    if steps == 0 || !normalize(&mut q) {
        return (0.0, vec![0.0; m]);
    }
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(steps);
    let mut alphas = Vec::with_capacity(steps);
    let mut betas: Vec<f64> = Vec::with_capacity(steps);
    let mut w = vec![0.0; m];
    let mut ritz = (0.0, vec![1.0]);
    for _ in 0..steps {
        matvec(&q, &mut w);
        alphas.push(dot(&q, &w));
        basis.push(q.clone());
        // Full reorthogonalisation (twice is enough, Kahan–Parlett) replaces the
        // three-term recurrence and keeps the basis orthonormal to working precision.
        let mut against: Vec<&[f64]> = deflate_refs.clone();
        against.extend(basis.iter().map(Vec::as_slice));
        orthogonalize(&mut w, &against);
        let b = dot(&w, &w).sqrt();

        let k = alphas.len();
        let value = tridiag_eigenvalue(&alphas, &betas, k - 1);
        let s = tridiag_eigenvector(&alphas, &betas, value, &[]);
        let residual = b * s[k - 1].abs();
        ritz = (value, s);
        if residual.is_nan() || residual <= tol || k == steps {
            break;
        }
        betas.push(b);
        for (qi, wi) in q.iter_mut().zip(&w) {
            *qi = wi / b;
        }
    }
    let mut y = vec![0.0; m];
    for (si, qi) in ritz.1.iter().zip(&basis) {
        for (yj, qj) in y.iter_mut().zip(qi) {
            *yj += si * qj;
        }
    }
    normalize(&mut y);
    (ritz.0, y)
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
fn orient(v: &mut [f64]) {
    let mut best = 0;
    for (i, x) in v.iter().enumerate() {
        if x.abs() > v[best].abs() {
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
    fn mds_lanczos_path_reproduces_points() {
        // n > DENSE_MAX: Lanczos, including a repeated top eigenvalue (regular polygon).
        let n = DENSE_MAX + 88;
        let pts = random_points(n, 8, 10.0, 4.0);
        assert_same_distances(&pts, &classical_mds_2d(euclidean(&pts), n), 1e-9);
        let ring: Vec<Point> = (0..n)
            .map(|i| Point::from_angle(i as f64 * std::f64::consts::TAU / n as f64) * 3.0)
            .collect();
        assert_same_distances(&ring, &classical_mds_2d(euclidean(&ring), n), 1e-9);
    }

    #[test]
    fn lanczos_matches_dense_on_a_full_spectrum() {
        // A random symmetric matrix with negative and close eigenvalues.
        let m = 150;
        let mut rng = Rng::new(21);
        let mut a = vec![0.0; m * m];
        for i in 0..m {
            for j in i..m {
                a[i * m + j] = rng.next_f64() - 0.5;
            }
        }
        mirror_upper(&mut a, m);
        let dense = top2_symmetric(a.clone(), m);
        let frob = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let matvec = |x: &[f64], y: &mut [f64]| {
            for (yi, row) in y.iter_mut().zip(a.chunks_exact(m)) {
                *yi = dot(row, x);
            }
        };
        let first = lanczos_top1(&matvec, m, &[], frob, 1);
        let second = lanczos_top1(&matvec, m, std::slice::from_ref(&first.1), frob, 2);
        for ((dv, dvec), (lv, lvec)) in dense.iter().zip([&first, &second]) {
            assert!((dv - lv).abs() < 1e-10, "{dv} vs {lv}");
            assert!(dot(dvec, lvec).abs() > 1.0 - 1e-8);
        }
        assert!(dense[0].0 >= dense[1].0);
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
        for (value, v) in top2_symmetric(a.clone(), m) {
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
}
