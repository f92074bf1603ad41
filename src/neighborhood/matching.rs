//! Minimum-cost assignment (Kuhn–Munkres / Hungarian algorithm) and its use for the
//! initial layout: matching CVT sites to nodes' projected positions (method-reference
//! §4.3). Pure and deterministic: fixed tie-breaking, no randomness, no I/O.
//!
//! Groups of up to `EXACT_MAX` are matched exactly. Larger ones (issue 12 item 3:
//! Kuhn–Munkres is O(k³), 20 s at 3,000 siblings) use recursive bisection matching:
//! sites and points are split at the same rank along the longer side of the sites'
//! bounding box until a block holds at most `BLOCK` of each, and each block is
//! matched exactly: O(k log k + k·BLOCK²) time, O(BLOCK²) memory. Quality against exact
//! KM on groups of 200 and 500 (total distance; measured by
//! `cargo run --release --example matching_quality`, figures in BENCHMARKS.md,
//! "Matching"): the bisected total is within a few per cent of the optimum on
//! projections spread like the sites, and the split being by rank, it does not depend
//! on the two sets' scales (the projections fill the root box, the sites one parent cell).
//! Written by hand: no maintained crate offers an assignment solver of this shape.

use crate::geom::Point;
use crate::neighborhood::pow2::pow2_floor;

/// Marks a row that has no column (only when there are more rows than columns).
const UNASSIGNED: usize = usize::MAX;

/// Groups with at most this many sites and points are matched exactly (Kuhn–Munkres:
/// 12 ms at 200, but 190–280 ms at 500, most of a cold 500-leaf layout's 300 ms
/// budget). Bisection into blocks of 128 matches 500 in 22 ms at a total 0.8% above
/// the optimum (BENCHMARKS.md, "Matching"), and the finished layouts realise as many
/// constraints (flat 500, seeds 1–3: median 420 against 380 with exact matching).
/// Every paper dataset's groups are far below it.
const EXACT_MAX: usize = 256;

/// Largest block the bisection matches exactly: 128³ operations per block keeps 100,000
/// siblings near a second, and blocks this size lose little against the optimum.
const BLOCK: usize = 128;

/// Solves the rectangular assignment problem: for each row of the `rows × cols` cost
/// matrix (`cost`, row-major) a distinct column, minimising the total cost.
///
/// Algorithm: shortest augmenting paths with row and column potentials (the O(n²·m)
/// Hungarian algorithm in Jonker–Volgenant form), one row added per phase. Ties are
/// broken deterministically: among equally cheap columns an unassigned one is preferred,
/// then the lowest index. So equal costs give the identity (row `i` → column `i`).
///
/// Contract and degenerate input:
/// - `rows ≤ cols` is expected. With more rows than columns the transposed problem is
///   solved and the `rows − cols` rows left without a column get `usize::MAX`.
/// - NaN, +∞ and entries missing from a too-short `cost` count as a "large" cost, larger
///   than the total of any assignment that avoids them, so they are used only when no
///   assignment avoids them; −∞ counts as the same magnitude, negative.
/// - Costs may be negative. All costs are scaled by one power of two (exact) so that any
///   finite magnitude works without overflow.
///
/// Cost: O(rows²·cols) time, O(rows·cols) extra memory for the sanitised copy.
pub fn min_cost_assignment(cost: &[f64], rows: usize, cols: usize) -> Vec<usize> {
    if rows == 0 {
        return Vec::new();
    }
    if rows > cols {
        let mut transposed = vec![f64::NAN; rows * cols];
        for r in 0..rows {
            for c in 0..cols {
                transposed[c * rows + r] = cost.get(r * cols + c).copied().unwrap_or(f64::NAN);
            }
        }
        let mut out = vec![UNASSIGNED; rows];
        for (c, r) in hungarian(&sanitize(&transposed, cols, rows), cols, rows)
            .into_iter()
            .enumerate()
        {
            out[r] = c;
        }
        return out;
    }
    hungarian(&sanitize(cost, rows, cols), rows, cols)
}

/// Assigns each of `points` (nodes' projected positions) to a distinct site of `sites`
/// (CVT sites), minimising the total Euclidean distance (method-reference §4.3; call it
/// once per parent, or pass the prototype's level-wide 10⁶ penalty in your own cost
/// matrix to [`min_cost_assignment`]). Exact up to 256 sites and points; above, recursive
/// bisection into exactly matched blocks of at most 128 (see the module header).
///
/// Returns, for each point, the index of its site: a permutation when the counts are
/// equal. With more points than sites the surplus points get `usize::MAX`. Non-finite
/// coordinates make their distances "large" (see [`min_cost_assignment`]).
pub fn match_points(sites: &[Point], points: &[Point]) -> Vec<usize> {
    if sites.len().max(points.len()) <= EXACT_MAX {
        return match_exact(sites, points);
    }
    bisection_match(sites, points, BLOCK)
}

/// Exact minimum total distance assignment of `points` to `sites`.
fn match_exact(sites: &[Point], points: &[Point]) -> Vec<usize> {
    let cost: Vec<f64> = points
        .iter()
        .flat_map(|p| sites.iter().map(move |s| p.distance(*s)))
        .collect();
    min_cost_assignment(&cost, points.len(), sites.len())
}

/// Recursive bisection matching with exact blocks of at most `block` sites and points
/// (see the module header). Same contract as [`match_points`], which calls it with
/// `block` = 128 above 256; public for the quality benchmark (`examples/matching_quality.rs`).
pub fn bisection_match(sites: &[Point], points: &[Point], block: usize) -> Vec<usize> {
    let mut out = vec![UNASSIGNED; points.len()];
    let mut site_ids: Vec<usize> = (0..sites.len()).collect();
    let mut point_ids: Vec<usize> = (0..points.len()).collect();
    for (p, s) in bisect(sites, points, &mut site_ids, &mut point_ids, block.max(1)) {
        out[p] = s;
    }
    out
}

/// One step of [`bisection_match`] on the sites `site_ids` and points `point_ids`:
/// the (point, site) pairs it assigns. The two halves run in parallel; each writes
/// only its own pairs, so the result does not depend on the thread count.
fn bisect(
    sites: &[Point],
    points: &[Point],
    site_ids: &mut [usize],
    point_ids: &mut [usize],
    block: usize,
) -> Vec<(usize, usize)> {
    if point_ids.is_empty() || site_ids.is_empty() {
        return Vec::new();
    }
    if site_ids.len().max(point_ids.len()) <= block {
        let s: Vec<Point> = site_ids.iter().map(|&i| sites[i]).collect();
        let p: Vec<Point> = point_ids.iter().map(|&i| points[i]).collect();
        return point_ids
            .iter()
            .zip(match_exact(&s, &p))
            .filter(|&(_, si)| si != UNASSIGNED)
            .map(|(&pi, si)| (pi, site_ids[si]))
            .collect();
    }
    // Split along the longer side of the sites' bounding box (finite coordinates), so
    // blocks of sites stay compact; points are split at the same rank on that axis.
    let (mut lo, mut hi) = (Point::INFINITY, Point::NEG_INFINITY);
    for p in site_ids.iter().map(|&i| sites[i]).filter(|p| p.is_finite()) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let along_x = (hi.y - lo.y).partial_cmp(&(hi.x - lo.x)) != Some(std::cmp::Ordering::Greater);
    let key = |p: Point| if along_x { p.x } else { p.y };
    // Total order (NaN last), ties by index: deterministic.
    site_ids.sort_by(|&a, &b| key(sites[a]).total_cmp(&key(sites[b])).then(a.cmp(&b)));
    point_ids.sort_by(|&a, &b| key(points[a]).total_cmp(&key(points[b])).then(a.cmp(&b)));
    let (s, p) = (site_ids.len(), point_ids.len());
    let s_left = s / 2;
    // Points in proportion; when there are no more points than sites, each half keeps
    // at least as many sites as points, so nobody is left out.
    let mut p_left = (p * s_left + s / 2) / s;
    if p <= s {
        p_left = p_left.clamp(p.saturating_sub(s - s_left), s_left);
    }
    let (sl, sr) = site_ids.split_at_mut(s_left);
    let (pl, pr) = point_ids.split_at_mut(p_left);
    let (mut left, right) = rayon::join(
        || bisect(sites, points, sl, pl, block),
        || bisect(sites, points, sr, pr, block),
    );
    left.extend(right);
    left
}

/// A `rows × cols` copy of `cost` with every entry finite and of magnitude < 2, except
/// the stand-ins for NaN/±∞/missing, which are ±`large`.
fn sanitize(cost: &[f64], rows: usize, cols: usize) -> Vec<f64> {
    let len = rows * cols;
    let cost = &cost[..cost.len().min(len)];
    let max = cost
        .iter()
        .filter(|c| c.is_finite())
        .fold(0.0_f64, |m, c| m.max(c.abs()));
    // Dividing by a power of two is exact, so ties and the optimum are unchanged; after
    // it, potentials (sums of at most `rows` costs) cannot overflow.
    let scale = if max > 0.0 { pow2_floor(max) } else { 1.0 };
    // Any assignment total of finite entries lies in (−2·rows, 2·rows): one "large" entry
    // outweighs every difference between such totals.
    let large = 4.0 * rows as f64 + 4.0;
    let mut out: Vec<f64> = cost
        .iter()
        .map(|&c| {
            if c.is_finite() {
                c / scale
            } else if c == f64::NEG_INFINITY {
                -large
            } else {
                large
            }
        })
        .collect();
    out.resize(len, large);
    out
}

/// The shortest-augmenting-path Hungarian algorithm on a sanitised matrix, rows ≤ cols.
/// Index 0 of the column arrays is a virtual column holding the row being inserted;
/// real columns are 1-based there.
fn hungarian(cost: &[f64], rows: usize, cols: usize) -> Vec<usize> {
    let mut u = vec![0.0; rows + 1];
    let mut v = vec![0.0; cols + 1];
    // Row (1-based) assigned to each column, 0 for none.
    let mut owner = vec![0usize; cols + 1];
    // Previous column on the shortest path tree.
    let mut way = vec![0usize; cols + 1];
    let mut minv = vec![f64::INFINITY; cols + 1];
    let mut used = vec![false; cols + 1];
    for i in 1..=rows {
        owner[0] = i;
        let mut j0 = 0;
        minv.fill(f64::INFINITY);
        used.fill(false);
        // Each round marks one more column used (`j1` is always an unused
        // one), so a free column is reached within `cols` rounds.
        for _ in 0..=cols {
            used[j0] = true;
            let i0 = owner[j0];
            let row = &cost[(i0 - 1) * cols..i0 * cols];
            let ui = u[i0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0;
            for j in 1..=cols {
                if used[j] {
                    continue;
                }
                let cur = row[j - 1] - ui - v[j];
                if cur < minv[j] {
                    minv[j] = cur;
                    way[j] = j0;
                }
                // Prefer a free column on ties: it ends the search, and with equal costs
                // it keeps every row on its own column.
                if j1 == 0
                    || minv[j] < delta
                    || (minv[j] == delta && owner[j] == 0 && owner[j1] != 0)
                {
                    delta = minv[j];
                    j1 = j;
                }
            }
            if j1 == 0 {
                // Unreachable while rows ≤ cols (a free column always remains); stop
                // rather than index out of bounds.
                break;
            }
            for j in 0..=cols {
                if used[j] {
                    u[owner[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if owner[j0] == 0 {
                break;
            }
        }
        // Flip the alternating path back to the virtual column.
        while j0 != 0 {
            let prev = way[j0];
            owner[j0] = owner[prev];
            j0 = prev;
        }
    }
    let mut out = vec![UNASSIGNED; rows];
    for (j, &r) in owner.iter().enumerate().skip(1) {
        if r != 0 {
            out[r - 1] = j - 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rng::Rng;

    fn below(rng: &mut Rng, n: u64) -> u64 {
        rng.next_u64() % n
    }

    fn total(cost: &[f64], cols: usize, assignment: &[usize]) -> f64 {
        assignment
            .iter()
            .enumerate()
            .map(|(r, &c)| cost[r * cols + c])
            .sum()
    }

    /// Minimum total over all injective row → column maps, by exhaustive search.
    fn brute_force(cost: &[f64], rows: usize, cols: usize) -> f64 {
        fn go(cost: &[f64], cols: usize, row: usize, rows: usize, taken: &mut [bool]) -> f64 {
            if row == rows {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for c in 0..cols {
                if !taken[c] {
                    taken[c] = true;
                    best = best.min(cost[row * cols + c] + go(cost, cols, row + 1, rows, taken));
                    taken[c] = false;
                }
            }
            best
        }
        go(cost, cols, 0, rows, &mut vec![false; cols])
    }

    fn assert_valid(assignment: &[usize], rows: usize, cols: usize) {
        assert_eq!(assignment.len(), rows);
        let mut seen = vec![false; cols];
        for &c in assignment {
            assert!(c < cols && !seen[c], "{assignment:?}");
            seen[c] = true;
        }
    }

    #[test]
    fn matches_brute_force_on_random_square_matrices() {
        let mut rng = Rng::new(2024);
        for case in 0..200 {
            let n = 1 + below(&mut rng, 7) as usize;
            // Mix continuous costs with small integers, which produce many ties.
            let integer = case % 2 == 0;
            let cost: Vec<f64> = (0..n * n)
                .map(|_| {
                    if integer {
                        below(&mut rng, 5) as f64
                    } else {
                        rng.next_f64() * 100.0
                    }
                })
                .collect();
            let a = min_cost_assignment(&cost, n, n);
            assert_valid(&a, n, n);
            let best = brute_force(&cost, n, n);
            assert!(
                (total(&cost, n, &a) - best).abs() < 1e-9,
                "case {case}: {cost:?}"
            );
        }
    }

    #[test]
    fn matches_brute_force_on_rectangular_matrices() {
        let mut rng = Rng::new(7);
        for case in 0..100 {
            let rows = 1 + below(&mut rng, 5) as usize;
            let cols = rows + below(&mut rng, 3) as usize;
            let cost: Vec<f64> = (0..rows * cols).map(|_| rng.next_f64()).collect();
            let a = min_cost_assignment(&cost, rows, cols);
            assert_valid(&a, rows, cols);
            let best = brute_force(&cost, rows, cols);
            assert!((total(&cost, cols, &a) - best).abs() < 1e-12, "case {case}");
        }
    }

    #[test]
    fn known_three_by_three() {
        // Optimum 1 + 2 + 2 = 5 (row 0 → 1, row 1 → 0, row 2 → 2), unique.
        let cost = [4.0, 1.0, 3.0, 2.0, 0.0, 5.0, 3.0, 2.0, 2.0];
        assert_eq!(min_cost_assignment(&cost, 3, 3), vec![1, 0, 2]);
    }

    #[test]
    fn equal_costs_give_the_identity() {
        for n in [1, 2, 5, 30] {
            let identity: Vec<usize> = (0..n).collect();
            assert_eq!(min_cost_assignment(&vec![3.5; n * n], n, n), identity);
            assert_eq!(
                min_cost_assignment(&vec![0.0; n * (n + 3)], n, n + 3),
                identity
            );
        }
        assert_eq!(min_cost_assignment(&[7.0], 1, 1), vec![0]);
        assert_eq!(min_cost_assignment(&[3.0, 1.0, 2.0], 1, 3), vec![1]);
    }

    #[test]
    fn non_finite_and_missing_costs_are_avoided() {
        // Diagonal is NaN / +inf: the off-diagonal assignment must win despite its size.
        let cost = [f64::NAN, 1e9, 1e9, f64::INFINITY];
        assert_eq!(min_cost_assignment(&cost, 2, 2), vec![1, 0]);
        // Missing tail (only 3 of 4 entries): entry (1,1) is "large".
        assert_eq!(min_cost_assignment(&[0.0, 0.0, 0.0], 2, 2), vec![1, 0]);
        // −inf is the most attractive.
        let cost = [0.0, f64::NEG_INFINITY, 0.0, 0.0];
        assert_eq!(min_cost_assignment(&cost, 2, 2), vec![1, 0]);
        // All NaN still yields a valid assignment.
        let a = min_cost_assignment(&[f64::NAN; 9], 3, 3);
        assert_valid(&a, 3, 3);
        // Huge and tiny magnitudes do not overflow.
        let cost = [f64::MAX, 0.0, 0.0, f64::MAX];
        assert_eq!(min_cost_assignment(&cost, 2, 2), vec![1, 0]);
        let cost = [5e-324, 0.0, 0.0, 1e-320];
        assert_eq!(min_cost_assignment(&cost, 2, 2), vec![1, 0]);
        assert!(min_cost_assignment(&[], 0, 4).is_empty());
    }

    #[test]
    fn more_rows_than_columns_leaves_the_worst_rows_unassigned() {
        // Three rows, two columns: row 1 is expensive everywhere.
        let cost = [1.0, 5.0, 9.0, 9.0, 5.0, 1.0];
        assert_eq!(min_cost_assignment(&cost, 3, 2), vec![0, UNASSIGNED, 1]);
        assert_eq!(min_cost_assignment(&[1.0, 2.0], 2, 0), vec![UNASSIGNED; 2]);
    }

    #[test]
    fn match_points_minimizes_total_distance() {
        let sites = [
            Point::new(0.0, 0.0),
            Point::new(10.0, 0.0),
            Point::new(0.0, 10.0),
        ];
        let points = [
            Point::new(1.0, 9.0),
            Point::new(0.5, 0.5),
            Point::new(9.0, 1.0),
        ];
        assert_eq!(match_points(&sites, &points), vec![2, 0, 1]);
        // Fewer points than sites.
        assert_eq!(match_points(&sites, &[Point::new(9.0, 0.0)]), vec![1]);
        // A NaN point takes whatever is left.
        let points = [Point::new(f64::NAN, 0.0), Point::new(0.1, 0.0)];
        assert_eq!(match_points(&sites[..2], &points), vec![1, 0]);
        assert!(match_points(&[], &[]).is_empty());
    }

    fn random_points(rng: &mut Rng, n: usize, w: f64, h: f64) -> Vec<Point> {
        (0..n)
            .map(|_| Point::new(w * rng.next_f64(), h * rng.next_f64()))
            .collect()
    }

    fn assignment_total(sites: &[Point], points: &[Point], a: &[usize]) -> f64 {
        a.iter()
            .zip(points)
            .map(|(&s, p)| p.distance(sites[s]))
            .sum()
    }

    #[test]
    fn bisection_is_a_valid_near_optimal_matching() {
        let mut rng = Rng::new(12);
        for (k, extra) in [(300usize, 0usize), (301, 7), (257, 0)] {
            let sites = random_points(&mut rng, k + extra, 1.0, 0.6);
            // Projections fill a larger box than the sites (as in the layout).
            let points = random_points(&mut rng, k, 3.0, 2.0);
            let exact = match_exact(&sites, &points);
            for block in [1, 16, 64] {
                let a = bisection_match(&sites, &points, block);
                assert_valid(&a, k, k + extra);
                let ratio = assignment_total(&sites, &points, &a)
                    / assignment_total(&sites, &points, &exact);
                assert!((1.0..1.25).contains(&ratio), "k {k} block {block}: {ratio}");
                assert_eq!(a, bisection_match(&sites, &points, block));
            }
            // A block as large as the group is the exact matching.
            assert_eq!(bisection_match(&sites, &points, k + extra), exact);
        }
        // More points than sites: the surplus is unassigned, the rest distinct.
        let sites = random_points(&mut rng, 40, 1.0, 1.0);
        let points = random_points(&mut rng, 45, 1.0, 1.0);
        let a = bisection_match(&sites, &points, 8);
        assert_eq!(a.iter().filter(|&&s| s == UNASSIGNED).count(), 5);
        let mut used: Vec<usize> = a.iter().copied().filter(|&s| s != UNASSIGNED).collect();
        used.sort_unstable();
        used.dedup();
        assert_eq!(used.len(), 40);
    }

    #[test]
    fn large_groups_take_the_bisection_and_survive_bad_coordinates() {
        let mut rng = Rng::new(3);
        let n = EXACT_MAX + 1;
        let sites = random_points(&mut rng, n, 1.0, 1.0);
        let mut points = random_points(&mut rng, n, 1.0, 1.0);
        assert_eq!(
            match_points(&sites, &points),
            bisection_match(&sites, &points, BLOCK)
        );
        points[3] = Point::new(f64::NAN, 0.0);
        points[9] = Point::new(f64::INFINITY, f64::NEG_INFINITY);
        assert_valid(&match_points(&sites, &points), n, n);
        // All points identical: still a permutation.
        assert_valid(&match_points(&sites, &vec![Point::ZERO; n]), n, n);
    }

    #[test]
    fn deterministic_on_a_larger_instance() {
        let mut rng = Rng::new(5);
        let n = 60;
        let cost: Vec<f64> = (0..n * n).map(|_| below(&mut rng, 4) as f64).collect();
        let a = min_cost_assignment(&cost, n, n);
        assert_valid(&a, n, n);
        assert_eq!(a, min_cost_assignment(&cost, n, n));
    }
}
