//! An exact nearest-neighbour index over a level's unit vectors (the f32 unit
//! vectors of the `filtered_rows` filter): the vectors grouped into spherical
//! caps, each a centre direction and its members sorted by their cosine to it,
//! so that a query's cosine to every member of a cap is bounded from its one
//! cosine to the centre (angles on the sphere obey the triangle inequality:
//! |∠(u,c) − ∠(x,c)| ≤ ∠(u,x) ≤ ∠(u,c) + ∠(x,c)). A query then visits the caps
//! that may hold its best entries, and in each only the members whose angle to
//! the centre is close enough to its own; the bounds also give every row's
//! lowest similarity from below. Every bound is widened by the rounding of the
//! f32 dot products it comes from ([`CapIndex::slack`]), so a member the bounds
//! skip is surely below them.
//!
//! The caps come from a few rounds of spherical k-means (Lloyd's assignment to
//! the nearest centre, centres re-normalised), seeded with evenly spaced nodes
//! of the level: deterministic, and any grouping gives exact bounds, only
//! tighter or looser ones. Written here rather than taken from a crate: the
//! crates with exact search (k-d trees) prune nothing in 64 dimensions, those
//! for high dimensions (HNSW, random-projection forests) are approximate and
//! give no bound for the entries they skip, which the exact bins need.

use rayon::prelude::*;

use super::filtered_rows::Filter;
use super::kernels::{dot_tile, KERNEL_ROWS};

/// Lanes per block: two AVX registers of f32, as the filter's kernel.
pub(super) const LANES: usize = 16;
/// Mean members per cap of the exact search. Smaller caps bound tighter but
/// cost a query more centres: at 64 a query's centres are 1.6% of the level.
pub(super) const CAP_SIZE: usize = 64;
/// Rounds of assignment to the nearest centre.
const ROUNDS: usize = 3;

/// One cap: a range of member slots and the members' cosines to the centre.
pub(super) struct Cap {
    /// First block of the cap's members in [`CapIndex::member_blocks`].
    pub(super) first_block: usize,
    /// Members' cosines to the centre (as measured in f32), descending.
    pub(super) rho: Vec<f64>,
}

/// The caps of a level (see the module documentation).
pub(super) struct CapIndex {
    d: usize,
    /// Centres, unit f32, transposed in blocks of [`LANES`] (padding: zeros).
    pub(super) centre_blocks: Vec<f32>,
    pub(super) caps: Vec<Cap>,
    /// Members' unit vectors cap by cap (in `rho` order), each cap padded to
    /// whole blocks, transposed in blocks of [`LANES`].
    pub(super) member_blocks: Vec<f32>,
    /// The level position of every member slot; `usize::MAX` for padding.
    pub(super) slots: Vec<usize>,
    /// Bound on |cosine measured in f32 − cosine of the directions| for any
    /// two of the index's vectors (query, member or centre).
    slack: f64,
}

impl CapIndex {
    /// The caps of the nodes `points` (level positions, none of them exact) of
    /// the filter's level, `cap_size` members each on average.
    pub(super) fn build(filter: &Filter, points: &[usize], cap_size: usize) -> CapIndex {
        let d = filter.dim();
        let k = (points.len() / cap_size.max(1)).max(1);
        // Seeds: every (n/k)-th node, in level order.
        let mut centres: Vec<Vec<f64>> = (0..k)
            .map(|t| {
                let u = filter.unit(points[t * points.len() / k]);
                u.iter().map(|&x| f64::from(x)).collect()
            })
            .collect();
        let mut assignment = Vec::new();
        for round in 0..ROUNDS {
            let blocks = transpose(d, centres.iter().map(|c| to_f32(c)));
            assignment = nearest_centres(filter, points, &blocks, centres.len());
            if round + 1 == ROUNDS {
                break;
            }
            let mut sums = vec![vec![0.0f64; d]; centres.len()];
            for (&p, &c) in points.iter().zip(&assignment) {
                for (s, &x) in sums[c].iter_mut().zip(filter.unit(p)) {
                    *s += f64::from(x);
                }
            }
            for (centre, sum) in centres.iter_mut().zip(sums) {
                let norm = sum.iter().map(|x| x * x).sum::<f64>().sqrt();
                // A centre left without members, or whose members cancel out,
                // keeps its direction.
                if norm > 1e-9 {
                    *centre = sum.iter().map(|x| x / norm).collect();
                }
            }
        }
        // Members per centre, in level order; empty caps are dropped.
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); centres.len()];
        for (&p, &c) in points.iter().zip(&assignment) {
            members[c].push(p);
        }
        let mut kept_centres = Vec::new();
        let mut caps = Vec::new();
        let mut slots = Vec::new();
        let mut member_vectors: Vec<Vec<f32>> = Vec::new();
        for (centre, mut list) in centres.into_iter().zip(members) {
            if list.is_empty() {
                continue;
            }
            let centre32 = to_f32(&centre);
            let cosine = |p: usize| -> f64 {
                filter
                    .unit(p)
                    .iter()
                    .zip(&centre32)
                    .map(|(&x, &c)| f64::from(x) * f64::from(c))
                    .sum()
            };
            let mut with_rho: Vec<(f64, usize)> = list.drain(..).map(|p| (cosine(p), p)).collect();
            with_rho.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let first_block = slots.len() / LANES;
            for &(_, p) in &with_rho {
                slots.push(p);
                member_vectors.push(filter.unit(p).to_vec());
            }
            while slots.len() % LANES != 0 {
                slots.push(usize::MAX);
                member_vectors.push(vec![0.0; d]);
            }
            caps.push(Cap {
                first_block,
                rho: with_rho.iter().map(|&(r, _)| r).collect(),
            });
            kept_centres.push(centre32);
        }
        // The f32 dot of two vectors within 2⁻²⁴ relative of unit length,
        // summed in order over d terms: within (d + 2)·2⁻²⁴ of the cosine of
        // their directions (twice that, for room); the centres' cosines to
        // the members above are summed in f64, closer still.
        let slack = 2.0 * (d as f64 + 8.0) * f64::from(f32::EPSILON) / 2.0;
        CapIndex {
            d,
            centre_blocks: transpose(d, kept_centres.into_iter()),
            caps,
            member_blocks: transpose(d, member_vectors.into_iter()),
            slots,
            slack,
        }
    }

    /// See [`CapIndex::slack`].
    pub(super) fn slack(&self) -> f64 {
        self.slack
    }

    /// Column block `block` of `blocks` (centres or members).
    pub(super) fn block<'a>(&self, blocks: &'a [f32], block: usize) -> &'a [f32] {
        &blocks[block * self.d * LANES..(block + 1) * self.d * LANES]
    }

    /// Upper bound on the cosine of a query with any member of `cap`, from the
    /// query's measured cosine `gamma` to the centre: cos(max(θ − α, 0)), θ the
    /// query's angle to the centre, α the cap's widest member's.
    pub(super) fn upper(&self, cap: &Cap, gamma: f64) -> f64 {
        let g = (gamma + self.slack).min(1.0);
        let r = (cap.rho.last().copied().unwrap_or(1.0) - self.slack).max(-1.0);
        if g >= r {
            return 1.0;
        }
        (g * r + (1.0 - g * g).sqrt() * (1.0 - r * r).sqrt() + ROUNDING).min(1.0)
    }

    /// Lower bound on the cosine of a query with any member of `cap`:
    /// cos(min(θ + α, π)).
    pub(super) fn lower(&self, cap: &Cap, gamma: f64) -> f64 {
        let g = (gamma - self.slack).max(-1.0);
        let r = (cap.rho.last().copied().unwrap_or(1.0) - self.slack).max(-1.0);
        if g <= -r {
            return -1.0;
        }
        (g * r - (1.0 - g * g).sqrt() * (1.0 - r * r).sqrt() - ROUNDING).max(-1.0)
    }

    /// The member slots of `cap` (offsets into its `rho`) whose cosine with a
    /// query at measured cosine `gamma` to the centre may reach `threshold`:
    /// those whose angle to the centre is within arccos(threshold) of the
    /// query's.
    pub(super) fn reach(&self, cap: &Cap, gamma: f64, threshold: f64) -> std::ops::Range<usize> {
        if threshold <= -1.0 {
            return 0..cap.rho.len();
        }
        let beta = threshold.min(1.0).acos();
        let theta_lo = (gamma + self.slack).min(1.0).acos();
        let theta_hi = (gamma - self.slack).max(-1.0).acos();
        let rho_hi = (theta_lo - beta).max(0.0).cos() + self.slack + ROUNDING;
        let rho_lo = (theta_hi + beta).min(std::f64::consts::PI).cos() - self.slack - ROUNDING;
        // `rho` is descending.
        let first = cap.rho.partition_point(|&r| r > rho_hi);
        let last = cap.rho.partition_point(|&r| r >= rho_lo);
        first..last.max(first)
    }
}

/// Room for the rounding of the bounds' own f64 arithmetic and libm.
const ROUNDING: f64 = 1e-12;

/// `v` in f32.
fn to_f32(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// Vectors of length `d` transposed in blocks of [`LANES`]: value `k` of
/// vector `j` at `(j / LANES · d + k) · LANES + j % LANES`; padding zeros.
fn transpose(d: usize, vectors: impl ExactSizeIterator<Item = Vec<f32>>) -> Vec<f32> {
    let mut blocks = vec![0.0f32; vectors.len().div_ceil(LANES) * d * LANES];
    for (j, v) in vectors.enumerate() {
        let (block, lane) = (j / LANES, j % LANES);
        for (k, &x) in v.iter().enumerate() {
            blocks[(block * d + k) * LANES + lane] = x;
        }
    }
    blocks
}

/// The nearest of `k` centres (transposed in `blocks`) to each of `points`, by
/// f32 cosine; the first on ties. Rows in parallel, each independent, so the
/// thread count changes nothing.
fn nearest_centres(filter: &Filter, points: &[usize], blocks: &[f32], k: usize) -> Vec<usize> {
    let d = filter.dim();
    points
        .par_chunks(KERNEL_ROWS)
        .flat_map_iter(|group| {
            let rows: [&[f32]; KERNEL_ROWS] =
                std::array::from_fn(|r| filter.unit(group[r.min(group.len() - 1)]));
            let mut best = [(f32::NEG_INFINITY, 0usize); KERNEL_ROWS];
            for block in 0..k.div_ceil(LANES) {
                let columns = &blocks[block * d * LANES..(block + 1) * d * LANES];
                let dots = dot_tile::<f32, LANES>(&rows, columns);
                for (b, row) in best.iter_mut().zip(&dots) {
                    for (lane, &dot) in row.iter().enumerate() {
                        let c = block * LANES + lane;
                        if c < k && dot > b.0 {
                            *b = (dot, c);
                        }
                    }
                }
            }
            best.into_iter().take(group.len()).map(|(_, c)| c)
        })
        .collect()
}
