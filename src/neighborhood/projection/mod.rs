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
//! centred sparse matrix (`CentredSparse`), never a dense n×d copy (issue 23).
//!
//! One algorithm per file: this entry chooses; `pca.rs` (dense PCA),
//! `sparse_svd.rs` (sparse PCA), `mds.rs` (exact classical MDS), `landmark.rs`
//! (landmark MDS); `linalg.rs` holds the solvers they share, `fit.rs` the
//! rescale into a box.

use nptreemap_formats::{Features, SparseVector};

use crate::geom::Point;

/// The linear algebra every projection shares: faer's eigen-solvers, the axes.
mod linalg;
/// PCA of dense vectors.
mod pca;
/// PCA of sparse vectors by a partial SVD, never densified.
mod sparse_svd;
/// Classical MDS, exact.
mod mds;
/// Landmark MDS, for more points than the exact one takes.
mod landmark;
/// The per-axis rescale into a box.
mod fit;

#[cfg(test)]
mod test_support;

pub use fit::fit_into;
pub use pca::pca_2d;

use landmark::landmark_mds_2d;
use linalg::DENSE_MAX;
use mds::exact_mds_2d;
use sparse_svd::sparse_pca_2d;

/// Classical MDS is exact (an n×n matrix, dense EVD) up to this many points; above it,
/// landmark MDS (de Silva & Tenenbaum 2004) with [`LANDMARKS`] MaxMin landmarks keeps
/// memory and dissimilarity calls at O(n·k). 512 keeps the exact matrix at 2 MB and its
/// EVD near 0.1 s; the paper's datasets all have vectors (PCA), so none takes this path.
const MDS_EXACT_MAX: usize = DENSE_MAX;

/// Landmarks of landmark MDS. The projection only seeds the matching (method-reference
/// §4.3), and two axes are stable with far fewer landmarks; 128 keeps the n·k distance
/// table at 100 MB for 100,000 nodes (see BENCHMARKS.md for the stress against exact MDS).
const LANDMARKS: usize = 128;

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
    exact_mds_2d(dissimilarity, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    use test_support::{assert_same_distances, euclidean, random_points, variance};

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
