//! The bins of a large dense cosine or Pearson level from an exact
//! nearest-neighbour search (`cap_index`) instead of all pairs: per row, what
//! Stages A and C read ([`stage_view`]), bit for bit as the all-pairs scan
//! gives it, or the all-pairs row where the search cannot settle it.
//!
//! A row needs its best entries in exact order, its highest score, and its
//! lowest score only as far as it moves a threshold across one of those
//! entries (`row_best`). The search gives:
//! - `best`: every entry whose exact similarity is at least a bound `floor`,
//!   sorted as the bins' heads are (similarity descending, level order), at
//!   least `row_best::WANTED` of them: the caps are visited best bound first, members
//!   in reach of the current `floor` only, until no cap can hold a better one;
//! - the lowest score, between a lower bound (the caps' bounds) and an upper
//!   one (the lowest entry seen, the farthest cap being always visited).
//! The row is settled when every lowest score in that range gives the same
//! view from `best`, each bin of which `best` holds in full or to its first
//! `bins::BIN_HEAD` entries. Otherwise (a small top bin over a crowded second bin,
//! or a lowest score that moves a threshold across a best entry) the row is
//! binned over all pairs through the filter.
//!
//! Why: the all-pairs scan is O(n²·d): 10¹⁰ pairs on a 100,000-leaf level.
//! Whether the search pays depends on the data (clustered vectors prune, noise
//! in 64 dimensions does not), so a sample of rows decides it by the vectors
//! they visit, a count, not a clock: the result is the same either way.
//!
//! Levels of [`APPROXIMATE_FROM`] rows and more that the exact search does not
//! serve (many dimensions, where no angle bound prunes: 384-d sentence-like
//! vectors) take an approximate search instead of the scan (issue 34 item 4):
//! √n caps of √n members, a row visiting the caps of its nearest centres and
//! its farthest one, as an inverted-file index does, O(n^1.5) for the level.
//! A row's view is then built from what it saw. It is used only where a
//! sample of rows, scanned too, finds at least [`MIN_RECALL`] of the nodes the
//! scan's views name; on noise it does not, and the scan runs. The difference
//! from the scan is measured per dataset in BENCHMARKS.md. Hand-written for the
//! same reason as the caps: the graph-based indexes of crates (HNSW) are built
//! one insertion at a time, in parallel only nondeterministically, and compare
//! vectors one pair at a time, where this search reuses the caps and the
//! four-row f32 kernel.

use rayon::prelude::*;

use super::bins::{stage_view, Bins};
use super::cap_index::{CapIndex, CAP_SIZE, LANES};
use super::filtered_rows::{Filter, Scratch};
use super::kernels::{dot_tile, KERNEL_ROWS};
use super::row_best::{view_from_best, RowBest};
use super::similarity::{pair_similarity, score, NodeFeatures, SimilarityKind};

/// Levels smaller than this are scanned over all pairs: the caps and the
/// sample cost about a tenth of the filter's scan where the search is then
/// refused (64-d noise, 10,000 rows), and the scan of a smaller level takes
/// under a second (BENCHMARKS.md, "Nearest-neighbour constraints").
pub(super) const MIN_LEVEL: usize = 8_000;
/// The search is used when a sample of rows visits at most this share of the
/// level per row (centres and members); above it the filter's scan, which
/// needs no bounds and whose pairs cost 2–6 times less at 8 and 64
/// dimensions, is faster: at 0.146 (64-d clustered) the search wins by 1.1×,
/// at 0.25 (8-d, 20,000 rows) it loses by 1.4× (BENCHMARKS.md, issue 34 item
/// 4).
const MAX_VISITED_SHARE: f64 = 0.2;
/// One query tile in this many makes the sample.
const SAMPLE_EVERY: usize = 64;
/// Levels of at least this many rows whose exact search does not pay take the
/// approximate one ([`Reach::Probes`]) instead of the all-pairs scan: from
/// here the scan costs seconds (about 1.5 s at 64 dimensions, 7.5 s at 384,
/// on two cores) and grows with n²; below it every level is binned exactly
/// (BENCHMARKS.md, issue 34 item 4, approximate rows).
pub(super) const APPROXIMATE_FROM: usize = 30_000;
/// Caps an approximate row visits whole, nearest centre first, beside its
/// farthest one (for its lowest score), tried in turn until a sample's recall
/// reaches [`MIN_RECALL`]. With caps of √n members a row visits about
/// (probes + 2)·√n vectors: O(n^1.5) for the level.
const PROBES: [usize; 2] = [8, 32];
/// A probe count is tried only while a row visits at most this share of the
/// level (its centres and the largest caps it may probe): a visited pair
/// costs the search about 3.5 times what the scan pays for one (384-d,
/// 50,000 rows), so beyond about a quarter the scan is faster.
const MAX_PROBED_SHARE: f64 = 0.15;
/// The approximate search is used when a sample of rows finds at least this
/// share of the nodes the scan's views name (recall). Where a level is noise a
/// row's best entries are scattered over every cap and the probes miss most
/// of them (64-d noise: 0.24), and the scan runs instead.
const MIN_RECALL: f64 = 0.95;
/// Rows of that sample, at most: the scan of them costs a share of the
/// level's scan that falls as the level grows.
const RECALL_ROWS: usize = 256;

/// How far a level's rows search.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reach {
    /// Exactly, when a sample of rows visits at most this share of the level.
    Exact { max_share: f64 },
    /// Approximately: with the first of these probe counts (caps of about √n
    /// members, the nearest by their centres, and the farthest) whose
    /// sampled recall reaches [`MIN_RECALL`] and whose rows visit at most
    /// `max_share` of the level; a row settles on what it saw.
    Probes {
        steps: &'static [usize],
        max_share: f64,
    },
}

/// The stage views of every row of `level`, or `None` where the search would
/// not pay (then the caller scans all pairs).
pub(super) fn knn_level_bins(
    kind: SimilarityKind,
    filter: &Filter,
    features: &[NodeFeatures<'_>],
    level: &[usize],
) -> Option<Vec<Bins>> {
    if level.len() < MIN_LEVEL {
        return None;
    }
    let exact = Reach::Exact {
        max_share: MAX_VISITED_SHARE,
    };
    let searched = match search_level(kind, filter, features, level, exact) {
        Some(searched) => searched,
        None if level.len() >= APPROXIMATE_FROM => {
            let approximate = Reach::Probes {
                steps: &PROBES,
                max_share: MAX_PROBED_SHARE,
            };
            search_level(kind, filter, features, level, approximate)?
        }
        None => return None,
    };
    tracing::debug!(
        n = level.len(),
        share = searched.share,
        open = searched.open,
        "nearest-neighbour rows: visited share, rows left to the scan"
    );
    Some(searched.bins)
}

/// A level's rows through the search.
struct Searched {
    /// Every row's stage view.
    bins: Vec<Bins>,
    /// Rows the search left to the scan.
    open: usize,
    /// Vectors a row visited (centres and members) as a share of the level:
    /// the sample's (exact search) or all rows' (approximate).
    share: f64,
}

/// [`knn_level_bins`] at any size: exactly when a sample of rows visits at
/// most `max_share` of the level ([`Reach::Exact`]), or approximately where
/// a sample's recall allows ([`Reach::Probes`]).
fn search_level(
    kind: SimilarityKind,
    filter: &Filter,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    reach: Reach,
) -> Option<Searched> {
    let n = level.len();
    let (points, exact): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| !filter.is_exact(i));
    let cap_size = match reach {
        Reach::Exact { .. } => CAP_SIZE,
        // √n caps of √n members: a row's centres and probed caps both grow
        // as √n.
        Reach::Probes { .. } => CAP_SIZE.max((points.len() as f64).sqrt() as usize),
    };
    let index = CapIndex::build(filter, &points, cap_size);
    // Queries cap by cap, so a tile's rows share their nearest caps.
    let mut tiles: Vec<Vec<usize>> = Vec::new();
    for cap in &index.caps {
        let first = cap.first_block * LANES;
        let members = &index.slots[first..first + cap.rho.len()];
        tiles.extend(members.chunks(KERNEL_ROWS).map(<[usize]>::to_vec));
    }
    let search = |probes: Option<usize>| Search {
        kind,
        filter,
        index: &index,
        features,
        level,
        exact: &exact,
        probes,
    };
    match reach {
        Reach::Exact { max_share } => {
            let search = search(None);
            let sample: Vec<usize> = (0..tiles.len()).step_by(SAMPLE_EVERY).collect();
            let visited: usize = sample
                .par_iter()
                .map(|&t| search.tile(&tiles[t]).1)
                .sum();
            let rows: usize = sample.iter().map(|&t| tiles[t].len()).sum();
            let share = visited as f64 / (rows.max(1) as f64 * n as f64);
            tracing::debug!(n, caps = index.caps.len(), share, "nearest-neighbour rows: visited share");
            (share <= max_share).then(|| search.level(&tiles, share))
        }
        Reach::Probes { steps, max_share } => {
            // The caps' sizes, largest first: a row visits at most the
            // largest few (duplicates gather in one cap, which would make the
            // search slower than the scan).
            // The scan's heads of the sampled rows, made once for every
            // probe count tried.
            let mut sample = None;
            let mut sizes: Vec<usize> = index.caps.iter().map(|c| c.rho.len()).collect();
            sizes.sort_unstable_by(|a, b| b.cmp(a));
            for &probes in steps {
                let largest: usize = sizes.iter().take(probes + 2).sum();
                let per_row = index.caps.len() + largest;
                if per_row as f64 > max_share * n as f64 {
                    break;
                }
                let search = search(Some(probes));
                let sample = sample.get_or_insert_with(|| scanned_sample(&search, &tiles));
                let recall = search.recall(sample);
                tracing::debug!(n, probes, recall, "approximate rows: recall of a sample");
                if recall >= MIN_RECALL {
                    // Said at `-v`: the one place the bins may differ from
                    // every pair's.
                    tracing::info!(
                        "constraints: a level of {n} nodes binned from approximate nearest \
                         neighbours ({probes} groups probed per node; a scanned sample found \
                         {:.1}% of its best pairs)",
                        100.0 * recall
                    );
                    return Some(search.level(&tiles, f64::NAN));
                }
            }
            None
        }
    }
}

/// About [`RECALL_ROWS`] rows in whole tiles spread over the level, each
/// with the nodes its scanned view names, per row.
fn scanned_sample<'t>(search: &Search<'_>, tiles: &'t [Vec<usize>]) -> Vec<(&'t [usize], Vec<Vec<usize>>)> {
    let every = SAMPLE_EVERY.max(tiles.len() * KERNEL_ROWS / RECALL_ROWS);
    let sample: Vec<&[usize]> = tiles.iter().step_by(every).map(Vec::as_slice).collect();
    sample
        .into_par_iter()
        .map_init(Scratch::default, |scratch: &mut Scratch, tile| {
            let scanned =
                search
                    .filter
                    .bin_rows(search.kind, search.features, search.level, tile, scratch);
            (tile, scanned.iter().map(|bins| heads(&stage_view(bins))).collect())
        })
        .collect()
}

/// The nodes a view names (its bins' heads, the entries the stages link).
fn heads(view: &Bins) -> Vec<usize> {
    view.bins
        .iter()
        .flat_map(|b| b.head.iter().map(|c| c.node))
        .collect()
}

/// The bins of an exact node's row from its exact similarities.
fn exact_row(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    i: usize,
) -> Bins {
    let row: Vec<f64> = (0..level.len())
        .map(|j| {
            if j == i {
                0.0
            } else {
                pair_similarity(kind, &features[i], &features[j], level[j])
            }
        })
        .collect();
    super::bins::bin_row(kind, level, i, &row, &mut Vec::new())
}

/// The similarity of two vectors from the f32 cosine of their directions.
fn similarity_of(dot: f32) -> f64 {
    (f64::from(dot) + 1.0) / 2.0
}

/// [`RowBest::take`] over one block of members: `dots` the f32 cosines to the
/// members `slots` (`usize::MAX`: padding), skipping the row's own node `own`;
/// `masked` when the block holds padding or `own`. The same state as taking
/// lane by lane, with the lowest entry and the floor test once per block: the
/// similarity rises with the cosine, and the floor only rises within the block.
/// Why: lane by lane, the per-entry minimum and test were most of the search's
/// own time (a store and a compare per pair).
#[inline]
fn take_block(
    row: &mut RowBest,
    dots: &[f32; LANES],
    slots: &[usize],
    masked: bool,
    own: usize,
    eps: f64,
) {
    let valid = |j: usize| j != usize::MAX && j != own;
    let (lo, hi) = if masked {
        dots.iter()
            .zip(slots)
            .filter(|&(_, &j)| valid(j))
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), (&d, _)| {
                (lo.min(d), hi.max(d))
            })
    } else {
        dots.iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &d| {
                (lo.min(d), hi.max(d))
            })
    };
    if lo > hi {
        return;
    }
    row.lowest = row.lowest.min(similarity_of(lo) + eps);
    if similarity_of(hi) + eps < row.floor {
        return;
    }
    for (&dot, &j) in dots.iter().zip(slots) {
        if valid(j) {
            row.take(similarity_of(dot), j, eps);
        }
    }
}

/// What [`Search::bounds`] gives a tile.
struct TileBounds {
    /// Per cap, the cosine of each row to its centre.
    gamma: Vec<[f64; KERNEL_ROWS]>,
    /// Per cap, the highest similarity each row can reach in it.
    upper: Vec<[f64; KERNEL_ROWS]>,
    /// Per row, the lowest lower bound over the caps, and its cap.
    lowest_bound: [f64; KERNEL_ROWS],
    farthest: [usize; KERNEL_ROWS],
}

/// What a tile's search needs, shared by all tiles.
struct Search<'a> {
    kind: SimilarityKind,
    filter: &'a Filter,
    index: &'a CapIndex,
    features: &'a [NodeFeatures<'a>],
    level: &'a [usize],
    /// Level positions of the exact nodes (not in the index).
    exact: &'a [usize],
    /// Caps visited per tile beside the farthest ([`Reach::Probes`]); `None`
    /// for the exact search.
    probes: Option<usize>,
}

impl Search<'_> {
    /// The settled rows of a tile (up to [`KERNEL_ROWS`] level positions) with
    /// their views, and the vectors the tile visited per row (centres and
    /// members) summed over its rows.
    fn tile(&self, tile: &[usize]) -> (Vec<(usize, Bins)>, usize) {
        let index = self.index;
        let eps = self.filter.eps();
        let slack = index.slack();
        let rows: [&[f32]; KERNEL_ROWS] =
            std::array::from_fn(|r| self.filter.unit(tile[r.min(tile.len() - 1)]));
        let caps = index.caps.len();
        let TileBounds {
            gamma,
            upper,
            lowest_bound,
            farthest,
        } = self.bounds(&rows, tile.len());
        let mut order: Vec<usize> = (0..caps).collect();
        let best_of = |of: &[[f64; KERNEL_ROWS]], c: usize| {
            of[c][..tile.len()]
                .iter()
                .fold(f64::NEG_INFINITY, |m, &u| m.max(u))
        };
        let best_upper = |c: usize| best_of(&upper, c);
        // The exact search takes caps best bound first (it stops at the first
        // that cannot matter); the approximate one nearest centre first, as an
        // inverted-file index probes, since in many dimensions most caps'
        // bounds are 1.
        let rank = |c: usize| match self.probes {
            None => best_upper(c),
            Some(_) => best_of(&gamma, c),
        };
        order.sort_by(|&a, &b| rank(b).total_cmp(&rank(a)).then(a.cmp(&b)));
        let mut probed = 0;

        let mut state = self.exact_rows(tile);
        // The cosine (of directions) an entry must reach to matter to a row.
        let threshold = |row: &RowBest| 2.0 * (row.floor - eps) - 1.0 - slack;
        let mut visited = caps * tile.len();
        let mut seen = vec![false; caps];
        let farthest_first = farthest[..tile.len()].to_vec();
        for c in farthest_first.into_iter().chain(order) {
            if std::mem::replace(&mut seen[c], true) {
                continue;
            }
            let is_farthest = farthest[..tile.len()].contains(&c);
            if !is_farthest {
                if self.probes.is_some_and(|p| probed == p) {
                    break;
                }
                probed += 1;
            }
            if !is_farthest && state.iter().all(|row| best_upper(c) < threshold(row)) {
                // Caps come best bound first and floors only rise: no later
                // cap matters to any row.
                break;
            }
            let cap = &index.caps[c];
            // The union of the rows' reaches (members are in `rho` order).
            let mut span: Option<(usize, usize)> = None;
            for (r, row) in state.iter().enumerate() {
                let reach = if is_farthest {
                    0..cap.rho.len()
                } else {
                    index.reach(cap, gamma[c][r], threshold(row))
                };
                if !reach.is_empty() {
                    span = Some(span.map_or((reach.start, reach.end), |(a, b)| {
                        (a.min(reach.start), b.max(reach.end))
                    }));
                }
            }
            let Some(span) = span.map(|(a, b)| a..b) else {
                continue;
            };
            for block in span.start / LANES..span.end.div_ceil(LANES) {
                let block = cap.first_block + block;
                let dots = dot_tile::<f32, LANES>(&rows, index.block(&index.member_blocks, block));
                visited += LANES * tile.len();
                let slots = &index.slots[block * LANES..(block + 1) * LANES];
                let padded = slots.contains(&usize::MAX);
                for ((&i, row), dots) in tile.iter().zip(state.iter_mut()).zip(&dots) {
                    take_block(row, dots, slots, padded || slots.contains(&i), i, eps);
                }
            }
        }
        (self.settled(tile, state, lowest_bound), visited)
    }

    /// Every row of the level from its tile (`tiles`: all of the level's
    /// rows), the rows this search leaves open, and the exact nodes' rows,
    /// through the scan. `share` is the sample's, for the exact search; the
    /// approximate one counts all rows'.
    fn level(&self, tiles: &[Vec<usize>], share: f64) -> Searched {
        let (kind, filter, features, level) = (self.kind, self.filter, self.features, self.level);
        let n = level.len();
        let settled: Vec<(Vec<(usize, Bins)>, usize)> =
            tiles.par_iter().map(|tile| self.tile(tile)).collect();
        let pairs: usize = settled.iter().map(|(_, v)| v).sum();
        let share = match self.probes {
            None => share,
            Some(_) => pairs as f64 / (n as f64 * n as f64),
        };
        tracing::debug!(n, pairs, probes = self.probes, "nearest-neighbour rows: vectors visited by all rows");
        let mut out: Vec<Option<Bins>> = vec![None; n];
        for (row, bins) in settled.into_iter().flat_map(|(rows, _)| rows) {
            out[row] = Some(bins);
        }
        let open: Vec<usize> = (0..n).filter(|&i| out[i].is_none()).collect();
        let scanned: Vec<(usize, Bins)> = open
            .par_chunks(KERNEL_ROWS)
            .map_init(Scratch::default, |state: &mut Scratch, group| {
                let (filtered, exact_rows): (Vec<usize>, Vec<usize>) =
                    group.iter().partition(|&&i| !filter.is_exact(i));
                let mut rows: Vec<(usize, Bins)> = filtered
                    .iter()
                    .copied()
                    .zip(filter.bin_rows(kind, features, level, &filtered, state))
                    .collect();
                rows.extend(exact_rows.into_iter().map(|i| (i, exact_row(kind, features, level, i))));
                rows
            })
            .flatten_iter()
            .collect();
        for (row, bins) in scanned {
            out[row] = Some(stage_view(&bins));
        }
        Searched {
            bins: out.into_iter().map(Option::unwrap_or_default).collect(),
            open: open.len(),
            share,
        }
    }

    /// Of the nodes the scan's views name for the rows of `sample` (whole
    /// tiles, each with those nodes per row: [`scanned_sample`]), the share
    /// this search's views name too.
    fn recall(&self, sample: &[(&[usize], Vec<Vec<usize>>)]) -> f64 {
        let (found, named) = sample
            .par_iter()
            .map(|(tile, wanted)| {
                let searched = self.tile(tile).0;
                let mut found = (0, 0);
                for (&i, want) in tile.iter().zip(wanted) {
                    let got = searched
                        .iter()
                        .find(|(j, _)| *j == i)
                        .map(|(_, view)| heads(view))
                        .unwrap_or_default();
                    found.0 += want.iter().filter(|n| got.contains(n)).count();
                    found.1 += want.len();
                }
                found
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        found as f64 / named.max(1) as f64
    }

    /// Per cap, the cosines of the tile's rows to its centre and its upper
    /// bound per row; per row, the cap of lowest lower bound (visited first,
    /// whole) and that bound.
    fn bounds(&self, rows: &[&[f32]; KERNEL_ROWS], len: usize) -> TileBounds {
        let index = self.index;
        let caps = index.caps.len();
        // Cosines to every centre.
        let mut gamma = vec![[0.0f64; KERNEL_ROWS]; caps];
        for block in 0..caps.div_ceil(LANES) {
            let dots = dot_tile::<f32, LANES>(rows, index.block(&index.centre_blocks, block));
            for (lane, g) in gamma.iter_mut().skip(block * LANES).take(LANES).enumerate() {
                *g = std::array::from_fn(|r| f64::from(dots[r][lane]));
            }
        }
        let upper: Vec<[f64; KERNEL_ROWS]> = index
            .caps
            .iter()
            .zip(&gamma)
            .map(|(cap, g)| std::array::from_fn(|r| index.upper(cap, g[r])))
            .collect();
        let mut lowest_bound = [f64::INFINITY; KERNEL_ROWS];
        let mut farthest = [0usize; KERNEL_ROWS];
        for (c, (cap, g)) in index.caps.iter().zip(&gamma).enumerate() {
            for r in 0..len {
                let lower = index.lower(cap, g[r]);
                if lower < lowest_bound[r] {
                    lowest_bound[r] = lower;
                    farthest[r] = c;
                }
            }
        }
        TileBounds {
            gamma,
            upper,
            lowest_bound,
            farthest,
        }
    }

    /// The tile's rows with the exact nodes (those not in the index) taken.
    fn exact_rows(&self, tile: &[usize]) -> Vec<RowBest> {
        let eps = self.filter.eps();
        let mut state: Vec<RowBest> = tile.iter().map(|_| RowBest::new()).collect();
        for (&i, row) in tile.iter().zip(state.iter_mut()) {
            for &j in self.exact {
                let s = pair_similarity(
                    self.kind,
                    &self.features[i],
                    &self.features[j],
                    self.level[j],
                );
                row.take(s, j, eps);
            }
        }
        state
    }

    /// The rows of the tile that settle, with their views.
    fn settled(
        &self,
        tile: &[usize],
        state: Vec<RowBest>,
        lowest_bound: [f64; KERNEL_ROWS],
    ) -> Vec<(usize, Bins)> {
        let eps = self.filter.eps();
        let slack = self.index.slack();
        tile.iter()
            .zip(state)
            .zip(lowest_bound)
            .filter_map(|((&i, mut row), bound)| {
                row.prune(eps);
                // Lowest similarity from below: the caps' bound in cosines of
                // directions, less the f32 and exact paths' differences.
                let below = (bound - slack + 1.0) / 2.0 - eps;
                let below = self
                    .exact
                    .iter()
                    .map(|&j| {
                        pair_similarity(self.kind, &self.features[i], &self.features[j], self.level[j])
                    })
                    .fold(below, f64::min);
                self.settle(i, row, below).map(|bins| (i, bins))
            })
            .collect()
    }

    /// The view of row `i` from its search, when every lowest score in range
    /// gives the same one. Where they differ, the approximate search takes
    /// the view of the lowest entry it saw (its farthest cap, visited whole,
    /// holds the row's lowest unless the caps mislead) and the exact one
    /// gives up.
    fn settle(&self, i: usize, row: RowBest, below: f64) -> Option<Bins> {
        let floor = row.floor;
        let best = row.exact_best(self.filter.eps(), |j| {
            pair_similarity(self.kind, &self.features[i], &self.features[j], self.level[j])
        });
        let hi = score(best.first()?.0);
        let lowest_best = best.iter().map(|&(s, _)| score(s)).min()?;
        let lo_to = score(row.lowest).min(lowest_best);
        let lo_from = score(below);
        if lo_from > lo_to && self.probes.is_none() {
            return None;
        }
        let seen = view_from_best(&best, floor, lo_to, hi, self.level)?;
        for lo in lo_from.min(lo_to)..lo_to {
            if view_from_best(&best, floor, lo, hi, self.level).as_ref() != Some(&seen) {
                return self.probes.map(|_| seen);
            }
        }
        Some(seen)
    }
}

#[cfg(test)]
mod tests {
    use super::super::rows::{exact_bins, level_bins};
    use super::super::stages::{self, ListEntry};
    use super::*;
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

    /// A seeded stream of values in [-0.5, 0.5).
    fn stream(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64) / f64::from(u32::MAX) - 0.5
        }
    }

    /// Leaves under `groups` × `subgroups` inner nodes, `per` each, with
    /// vectors that share their group's and subgroup's directions
    /// (`spread` = 0 gives noise alone). Every 7th leaf repeats the previous
    /// one's vector and every 11th is it times 3 (ties broken by level order),
    /// and the last three are a zero vector, another zero vector and one of
    /// norm 1e-150 (nodes of the exact path).
    fn tree(groups: usize, subgroups: usize, per: usize, d: usize, spread: f64, seed: u64) -> Dataset {
        let mut next = stream(seed);
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        let mut previous: Vec<f64> = vec![1.0; d];
        let mut leaf = 0;
        for g in 0..groups {
            let gc: Vec<f64> = (0..d).map(|_| spread * next()).collect();
            builder.add(NodeSpec::new(format!("g{g}")).parent("r"));
            for s in 0..subgroups {
                let sc: Vec<f64> = gc.iter().map(|x| x + spread * next()).collect();
                builder.add(NodeSpec::new(format!("g{g}s{s}")).parent(format!("g{g}")));
                for _ in 0..per {
                    let mut v: Vec<f64> = sc.iter().map(|x| x + next()).collect();
                    if leaf % 7 == 6 {
                        v.clone_from(&previous);
                    } else if leaf % 11 == 10 {
                        v = previous.iter().map(|x| 3.0 * x).collect();
                    }
                    previous.clone_from(&v);
                    builder.add(
                        NodeSpec::new(format!("l{leaf}"))
                            .parent(format!("g{g}s{s}"))
                            .weight(1.0)
                            .features(v),
                    );
                    leaf += 1;
                }
            }
        }
        let tail = [vec![0.0; d], vec![0.0; d], (0..d).map(|k| 1e-150 * (k as f64 + 1.0)).collect()];
        for v in tail {
            builder.add(
                NodeSpec::new(format!("l{leaf}"))
                    .parent("g0s0")
                    .weight(1.0)
                    .features(v),
            );
            leaf += 1;
        }
        super::super::prepare::prepare(&builder.build().expect("valid"))
    }

    /// The directed and symmetric lists of Stages A–D from per-node bins.
    fn lists(p: &Dataset, bins: &[Bins]) -> (Vec<Vec<ListEntry>>, Vec<Vec<ListEntry>>) {
        let mut lists = stages::top_bin(bins);
        stages::propagate(p.nodes(), &mut lists);
        stages::following_bins(bins, &mut lists);
        let directed = lists.clone();
        stages::symmetrise(&mut lists);
        (directed, lists)
    }

    /// A head entry as (similarity bits, node, score).
    type HeadBits = (u64, usize, u8);

    /// The exact search on every level, however much it visits.
    const EVERY_ROW: Reach = Reach::Exact {
        max_share: f64::INFINITY,
    };

    /// The approximate search with these probe counts, however much it
    /// visits.
    fn probes(steps: &'static [usize]) -> Reach {
        Reach::Probes {
            steps,
            max_share: f64::INFINITY,
        }
    }

    /// Bins with every similarity as its bits, so that the comparison is
    /// bit for bit (−0 and 0 differ).
    fn bits(bins: &Bins) -> Vec<(usize, Vec<HeadBits>)> {
        bins.bins
            .iter()
            .map(|b| {
                let head = b.head.iter().map(|c| (c.similarity.to_bits(), c.node, c.score));
                (b.len, head.collect())
            })
            .collect()
    }

    /// What [`compare`] found: rows the search settled itself, all rows, and
    /// the largest share of a level a sampled row visited.
    struct Compared {
        settled: usize,
        rows: usize,
        share: f64,
    }

    /// Every level through the search, through the filter's scan (`rows`,
    /// below the search's size) and through the exact all-pairs scan: the
    /// same view of every row, bit for bit, and the same lists.
    fn compare(p: &Dataset, kind: SimilarityKind) -> Compared {
        let nodes = p.nodes();
        let mut levels: Vec<Vec<usize>> = vec![Vec::new(); p.max_depth() + 1];
        for (index, node) in nodes.iter().enumerate() {
            levels[node.depth].push(index);
        }
        let mut full = vec![Bins::default(); nodes.len()];
        let mut searched = vec![Bins::default(); nodes.len()];
        let mut found = Compared {
            settled: 0,
            rows: 0,
            share: 0.0,
        };
        for level in levels.iter().skip(1) {
            let features: Vec<NodeFeatures<'_>> =
                level.iter().map(|&n| NodeFeatures::new(kind, p, n)).collect();
            let filter = Filter::new(kind, &features).expect("a filter for this level");
            let result =
                search_level(kind, &filter, &features, level, EVERY_ROW).expect("the search runs");
            found.settled += level.len() - result.open;
            found.rows += level.len();
            found.share = found.share.max(result.share);
            assert!(level.len() < MIN_LEVEL, "the scan below is the filter's");
            let scanned = level_bins(p, kind, level, true);
            for (i, &node) in level.iter().enumerate() {
                full[node] = exact_bins(kind, &features, level, i);
                searched[node] = result.bins[i].clone();
                let want = bits(&stage_view(&full[node]));
                let size = level.len();
                assert_eq!(bits(&searched[node]), want, "{kind:?}: row {i} of {size}, search");
                assert_eq!(bits(&scanned[i]), want, "{kind:?}: row {i} of {size}, filter");
            }
        }
        assert_eq!(lists(p, &searched), lists(p, &full), "{kind:?}: the lists");
        // The views alone give the lists the full bins give.
        let views: Vec<Bins> = full.iter().map(stage_view).collect();
        assert_eq!(lists(p, &views), lists(p, &full), "{kind:?}: the views' lists");
        found
    }

    /// Clustered vectors in three levels, with duplicates, scaled copies and
    /// exact-path nodes: the search's views and lists equal the all-pairs
    /// scan's, and the search settles most rows itself.
    #[test]
    fn clustered_levels_equal_the_all_pairs_scan() {
        for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson] {
            for (d, seed) in [(12, 1), (40, 2)] {
                let p = tree(10, 8, 25, d, 4.0, seed);
                let Compared { settled, rows, .. } = compare(&p, kind);
                assert!(
                    settled * 10 >= rows * 9,
                    "{kind:?} d={d}: only {settled} of {rows} rows settled by the search"
                );
            }
        }
    }

    /// Unclustered vectors (noise, in 3 and 24 dimensions), where the bounds
    /// prune little and more rows fall back: still the all-pairs scan's views.
    #[test]
    fn noise_equals_the_all_pairs_scan() {
        for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson] {
            for (d, seed) in [(3, 3), (24, 4)] {
                let p = tree(1, 1, 1500, d, 0.0, seed);
                compare(&p, kind);
            }
        }
    }

    /// Vectors on a circle, each twice: exact ties everywhere, and 2-d
    /// cosines that put many pairs on score steps.
    #[test]
    fn ties_on_a_circle_equal_the_all_pairs_scan() {
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for k in 0..1400 {
            let angle = (k / 2) as f64 * std::f64::consts::TAU / 700.0;
            builder.add(
                NodeSpec::new(format!("n{k}"))
                    .parent("r")
                    .weight(1.0)
                    .features(vec![angle.cos(), angle.sin()]),
            );
        }
        let p = super::super::prepare::prepare(&builder.build().expect("valid"));
        let Compared { settled, rows, .. } = compare(&p, SimilarityKind::Cosine);
        assert!(settled * 2 >= rows, "{settled} of {rows}");
    }

    /// `n` flat leaves around `clusters` random unit centres in `d` dimensions,
    /// each its centre plus noise of `spread` per dimension (roughly Gaussian),
    /// as `benches/gen_clustered.py` makes them.
    fn clustered(n: usize, d: usize, clusters: usize, spread: f64, seed: u64) -> Dataset {
        let mut rng = crate::rng::Rng::new(seed);
        // Irwin–Hall: the sum of 12 uniforms, less 6.
        let mut gauss = move || (0..12).map(|_| rng.next_f64()).sum::<f64>() - 6.0;
        let centres: Vec<Vec<f64>> = (0..clusters)
            .map(|_| {
                let c: Vec<f64> = (0..d).map(|_| gauss()).collect();
                let norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                c.iter().map(|x| x / norm).collect()
            })
            .collect();
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for i in 0..n {
            // Clusters interleaved in level order, not one after another.
            let c = &centres[(i * 7919) % clusters];
            let v: Vec<f64> = c.iter().map(|x| x + spread * gauss()).collect();
            builder.add(
                NodeSpec::new(format!("l{i}"))
                    .parent("r")
                    .weight(1.0)
                    .features(v),
            );
        }
        super::super::prepare::prepare(&builder.build().expect("valid"))
    }

    /// Embedding-like levels (issue 34 item 4): digits-like, 64-d around 10
    /// centres, and sentence-like, 384-d around 40, noise 0.05 per
    /// dimension. The search's views and the filter's equal the all-pairs
    /// scan's; in 64 dimensions the search settles nearly every row visiting
    /// well under half the level, while in 384, where the noise is as long as
    /// the centre, its bounds prune little (the filter's scan is what runs
    /// there).
    #[test]
    fn embeddings_at_64_and_384_dimensions_equal_the_all_pairs_scan() {
        let digits = clustered(1200, 64, 10, 0.05, 5);
        let found = compare(&digits, SimilarityKind::Cosine);
        assert!(found.settled * 10 >= found.rows * 9, "{} of {}", found.settled, found.rows);
        assert!(found.share < 0.5, "64-d: a row visits {} of the level", found.share);
        let sentences = clustered(800, 384, 40, 0.05, 6);
        compare(&sentences, SimilarityKind::Cosine);
    }

    /// The search (exact and approximate) and the filter give the same views
    /// whatever the thread count: every row is its own, the caps are built
    /// row by row.
    #[test]
    fn views_do_not_depend_on_the_thread_count() {
        let p = clustered(900, 64, 10, 0.05, 7);
        let level: Vec<usize> = (1..p.len()).collect();
        let kind = SimilarityKind::Cosine;
        let features: Vec<NodeFeatures<'_>> =
            level.iter().map(|&n| NodeFeatures::new(kind, &p, n)).collect();
        let filter = Filter::new(kind, &features).expect("a filter for this level");
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| {
                let searched = search_level(kind, &filter, &features, &level, EVERY_ROW)
                    .expect("the search runs");
                let probed = search_level(kind, &filter, &features, &level, probes(&[8]))
                    .expect("the search runs");
                let scanned = level_bins(&p, kind, &level, true);
                let all = [searched.bins, probed.bins, scanned];
                all.map(|bins| bins.iter().map(bits).collect::<Vec<_>>())
            })
        };
        assert_eq!(run(1), run(2));
        assert_eq!(run(1), run(3));
    }

    /// The approximate search (issue 34 item 4) on embedding-like levels of
    /// 3,000 rows, digits-like (64-d around 30 centres) and sentence-like
    /// (384-d around 60), where a row's best entries lie in its own cluster:
    /// each row visits well under half the level, and nearly every row's view
    /// and nearly every constraint of Stages A-D are the all-pairs scan's.
    #[test]
    fn approximate_rows_visit_a_fraction_and_keep_nearly_every_constraint() {
        let kind = SimilarityKind::Cosine;
        for (d, clusters, seed) in [(64, 30, 8), (384, 60, 9)] {
            let p = clustered(3000, d, clusters, 0.05, seed);
            let level: Vec<usize> = (1..p.len()).collect();
            let features: Vec<NodeFeatures<'_>> =
                level.iter().map(|&n| NodeFeatures::new(kind, &p, n)).collect();
            let filter = Filter::new(kind, &features).expect("a filter for this level");
            let probed = search_level(kind, &filter, &features, &level, probes(&PROBES[..1]))
                .expect("the recall of clustered vectors is high enough");
            assert!(probed.share < 0.4, "{d}-d: a row visits {} of the level", probed.share);
            let mut full = vec![Bins::default(); p.len()];
            let mut approximate = vec![Bins::default(); p.len()];
            let mut same = 0;
            for (i, &node) in level.iter().enumerate() {
                full[node] = exact_bins(kind, &features, &level, i);
                approximate[node] = probed.bins[i].clone();
                same += usize::from(bits(&approximate[node]) == bits(&stage_view(&full[node])));
            }
            assert!(same * 100 >= level.len() * 97, "{d}-d: {same} of {} views the scan's", level.len());
            let pairs = |bins: &[Bins]| -> std::collections::BTreeSet<(usize, usize)> {
                let (_, symmetric) = lists(&p, bins);
                symmetric
                    .iter()
                    .enumerate()
                    .flat_map(|(a, list)| list.iter().map(move |e| (a.min(e.target), a.max(e.target))))
                    .collect()
            };
            let (want, got) = (pairs(&full), pairs(&approximate));
            let kept = want.intersection(&got).count();
            assert!(!want.is_empty());
            assert!(kept * 100 >= want.len() * 97, "{d}-d: {kept} of {} constraints kept", want.len());
            assert!(got.len() * 100 <= want.len() * 103, "{d}-d: {} constraints for {}", got.len(), want.len());
        }
    }

    /// Noise (64-d, no clusters): a row's best entries lie in any cap, the
    /// probes find few of them, and the approximate search refuses the level
    /// (the scan runs) rather than bin it from what it saw.
    #[test]
    fn the_approximate_search_refuses_noise() {
        let kind = SimilarityKind::Cosine;
        let p = clustered(3000, 64, 1, 1.0, 10);
        let level: Vec<usize> = (1..p.len()).collect();
        let features: Vec<NodeFeatures<'_>> =
            level.iter().map(|&n| NodeFeatures::new(kind, &p, n)).collect();
        let filter = Filter::new(kind, &features).expect("a filter for this level");
        let searched = search_level(kind, &filter, &features, &level, probes(&PROBES));
        assert!(searched.is_none(), "noise binned approximately");
    }
}
