//! A level's similarity rows, binned (method-reference §3.1–3.2): sparse rows
//! for the set and relation measures (`sparse_rows`), the f32 filter for dense
//! cosine and Pearson levels it can serve (`filtered_rows`), else exact dense
//! rows over all pairs, tiled through [`dot_tile`]; large dense levels through
//! the nearest-neighbour search of `knn_rows` where it pays. Every path gives
//! the same bins as the plain scan of [`pair_similarity`], bit for bit (the
//! search: their stage views, all the stages read).

use rayon::prelude::*;

use super::bins::{bin_row, bin_sparse, stage_view, Bins};
use super::duplicate_rows;
use super::filtered_rows::{Filter, Scratch};
use super::kernels::{dot_tile, kernel, KERNEL_ROWS};
use super::knn_rows::knn_level_bins;
use super::similarity::{cosine_from_parts, norm_of, pair_similarity, NodeFeatures, SimilarityKind};
use super::sparse_rows::SparseLevel;
use nptreemap_formats::Dataset;

/// The bins of every node of `level` (indices of `prepared`, in breadth-first
/// order), one per node in level order; `sparse` allows the sparse rows (the
/// all-pairs scan is the reference they are tested against).
pub(super) fn level_bins(
    prepared: &Dataset,
    kind: SimilarityKind,
    level: &[usize],
    sparse: bool,
) -> Vec<Bins> {
    level_rows_bins(prepared, kind, level, None, sparse)
}

/// [`level_bins`] for the rows at positions `only` (ascending) of `level`, one
/// per position in that order, each over the whole level; `None` is every row.
/// A subset never goes through the nearest-neighbour search, which indexes and
/// samples the level for all of its rows: its rows are scanned.
pub(super) fn level_rows_bins(
    prepared: &Dataset,
    kind: SimilarityKind,
    level: &[usize],
    only: Option<&[usize]>,
    sparse: bool,
) -> Vec<Bins> {
    // Norms, supports and centred vectors once per node, not per pair.
    let level_features: Vec<NodeFeatures<'_>> = level
        .iter()
        .map(|&n| NodeFeatures::new(kind, prepared, n))
        .collect();
    let sparse_level = SparseLevel::new(kind, &level_features).filter(|_| sparse);
    let filter = match sparse_level {
        Some(_) => None,
        None => Filter::new(kind, &level_features),
    };
    // Large levels: the nearest-neighbour search, where a sample shows it pays.
    if let Some(bins) = filter
        .as_ref()
        .filter(|_| only.is_none())
        .and_then(|f| knn_level_bins(kind, f, &level_features, level))
    {
        return bins;
    }
    let all: Vec<usize>;
    let rows: &[usize] = match only {
        Some(rows) => rows,
        None => {
            all = (0..level.len()).collect();
            &all
        }
    };
    let transposed = match (&sparse_level, &filter) {
        (None, None) => Transposed::new(kind, &level_features),
        _ => None,
    };
    if let Some(index) = &sparse_level {
        return rows
            .par_iter()
            .map_init(Vec::new, |counts, &i| {
                let row = index.row(&level_features, level, i, counts);
                bin_sparse(kind, &row, level)
            })
            .collect();
    }
    // Rows of identical vectors once (`duplicate_rows`).
    let firsts = duplicate_rows::firsts(kind, &level_features, rows);
    let computed: Vec<usize>;
    let unique: &[usize] = match &firsts {
        Some(firsts) => {
            computed = (0..rows.len()).filter(|&k| firsts[k] == k).map(|k| rows[k]).collect();
            &computed
        }
        None => rows,
    };
    let tiles: Vec<Vec<Bins>> = unique
        .par_chunks(TILE_ROWS)
        .map_init(
            || (vec![Vec::new(); TILE_ROWS], Vec::new(), Scratch::default()),
            |(rows, scores, filter_state), span| {
                if let Some(filter) = &filter {
                    return filtered_tile(
                        kind,
                        filter,
                        &level_features,
                        level,
                        span,
                        (&mut rows[0], scores, filter_state),
                    );
                }
                similarity_rows(
                    kind,
                    &level_features,
                    transposed.as_ref(),
                    level,
                    span,
                    rows,
                );
                span.iter()
                    .zip(rows.iter())
                    .map(|(&i, row)| bin_row(kind, level, i, row, scores))
                    .collect()
            },
        )
        .collect();
    let binned: Vec<Bins> = tiles.into_iter().flatten().collect();
    let Some(firsts) = firsts else {
        return binned;
    };
    // Each first row's bins, by its index into `rows`.
    let mut of_first: Vec<Option<Bins>> = vec![None; rows.len()];
    for (k, bins) in (0..rows.len()).filter(|&k| firsts[k] == k).zip(binned) {
        of_first[k] = Some(bins);
    }
    (0..rows.len())
        .into_par_iter()
        .map(|k| {
            let first = of_first[firsts[k]]
                .as_ref()
                .expect("invariant: every first row was binned");
            if firsts[k] == k {
                first.clone()
            } else {
                let r = rows[firsts[k]];
                duplicate_rows::derive(kind, &level_features, level, (r, first), rows[k])
            }
        })
        .collect()
}

/// Lanes per block of the transposed layout: eight dot products advance together,
/// each still its own left-to-right sum, so the CPU can vectorise across pairs
/// without changing a single bit of any result (§1.4).
const LANES: usize = 8;

/// A level's vectors for the dot-product measures, transposed in blocks of
/// [`LANES`] nodes: `blocks[(block · d + k) · LANES + lane]` is coordinate `k` of
/// node `block · LANES + lane`. Built only when every node of the level has a
/// vector of the same length `d`; padding lanes are zero.
struct Transposed {
    d: usize,
    blocks: Vec<f64>,
    norms: Vec<f64>,
}

impl Transposed {
    /// The layout for these nodes, or `None` when a vector is missing, lengths
    /// differ, or the measure is not a dot product.
    fn new(kind: SimilarityKind, features: &[NodeFeatures<'_>]) -> Option<Self> {
        if !matches!(kind, SimilarityKind::Cosine | SimilarityKind::Pearson) {
            return None;
        }
        let d = features.first()?.values()?.len();
        let block_count = features.len().div_ceil(LANES);
        let mut blocks = vec![0.0; block_count * d * LANES];
        for (j, f) in features.iter().enumerate() {
            let v = f.values().filter(|v| v.len() == d)?;
            let (block, lane) = (j / LANES, j % LANES);
            for (k, &x) in v.iter().enumerate() {
                blocks[(block * d + k) * LANES + lane] = x;
            }
        }
        let norms = features.iter().map(norm_of).collect();
        Some(Transposed { d, blocks, norms })
    }

    /// Dot products of each vector of `rows` (length `d`) with the nodes of block
    /// `block`, into `acc[r]`. Every sum still runs over `k` in order from 0.0, as
    /// one row alone would, with a multiply and an add (never a fused
    /// multiply-add), so tiling and the vector width change no bit. Tiles keep
    /// their sums in registers: the one-row loop stored every partial sum to
    /// memory and ran scalar (a 20,000-leaf level's constraints: 14.6 s before,
    /// 3.8 s after; BENCHMARKS.md, "Scale after tiled constraints").
    fn dot_block_tile(&self, rows: &[&[f64]], block: usize, acc: &mut [[f64; LANES]]) {
        let columns = &self.blocks[block * self.d * LANES..(block + 1) * self.d * LANES];
        let mut r = 0;
        while r + KERNEL_ROWS <= rows.len() {
            let tile: &[&[f64]; KERNEL_ROWS] = rows[r..r + KERNEL_ROWS]
                .try_into()
                .expect("invariant: the slice has KERNEL_ROWS rows");
            let sums = dot_tile::<f64, LANES>(tile, columns);
            acc[r..r + KERNEL_ROWS].copy_from_slice(&sums);
            r += KERNEL_ROWS;
        }
        for (a, row) in acc[r..].iter_mut().zip(&rows[r..]) {
            *a = kernel::<f64, 1, LANES>(&[row], columns)[0];
        }
    }
}

/// Rows of similarities computed together (see [`Transposed::dot_block_tile`]).
const TILE_ROWS: usize = 64;

/// Similarities of `level[i]` for every `i` of `rows` (at most [`TILE_ROWS`]) to
/// every node of the level, into `out[0..rows.len()]` (`out[r][i]` is unused), as
/// [`pair_similarity`] gives them, bit for bit.
fn similarity_rows(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    transposed: Option<&Transposed>,
    level: &[usize],
    rows: &[usize],
    out: &mut [Vec<f64>],
) {
    let vectors: Option<Vec<&[f64]>> = transposed.and_then(|_| {
        rows.iter()
            .map(|&i| features[i].values())
            .collect::<Option<_>>()
    });
    let (Some(t), Some(vectors)) = (transposed, vectors) else {
        for (&i, row) in rows.iter().zip(out.iter_mut()) {
            similarity_row(kind, features, None, level, i, row);
        }
        return;
    };
    for row in out.iter_mut().take(vectors.len()) {
        row.clear();
        row.resize(level.len(), 0.0);
    }
    let mut acc = vec![[0.0f64; LANES]; vectors.len()];
    for block in 0..level.len().div_ceil(LANES) {
        t.dot_block_tile(&vectors, block, &mut acc);
        let first = block * LANES;
        let last = (first + LANES).min(level.len());
        for ((&i, row), dots) in rows.iter().zip(out.iter_mut()).zip(&acc) {
            let norm_a = t.norms[i];
            for (j, &d) in (first..last).zip(dots) {
                row[j] = cosine_from_parts(d, norm_a, t.norms[j]);
            }
        }
    }
}

/// Similarities of `level[i]` to every node of the level (`out[i]` is unused),
/// as [`pair_similarity`] gives them, bit for bit.
fn similarity_row(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    transposed: Option<&Transposed>,
    level: &[usize],
    i: usize,
    out: &mut Vec<f64>,
) {
    if let Some(t) = transposed.filter(|_| features[i].values().is_some()) {
        similarity_rows(
            kind,
            features,
            Some(t),
            level,
            &[i],
            std::slice::from_mut(out),
        );
        return;
    }
    out.clear();
    out.resize(level.len(), 0.0);
    for (j, &node) in level.iter().enumerate() {
        if j != i {
            out[j] = pair_similarity(kind, &features[i], &features[j], node);
        }
    }
}

/// The bins of `level[i]` from its exact similarity row (the reference the
/// filter is tested against).
#[cfg(test)]
pub(super) fn exact_bins(
    kind: SimilarityKind,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    i: usize,
) -> Bins {
    let mut row = Vec::new();
    similarity_row(kind, features, None, level, i, &mut row);
    bin_row(kind, level, i, &row, &mut Vec::new())
}

/// The stage views of the rows `span` of a level through the f32 [`Filter`];
/// its exact nodes' from their full exact row (`row` and `scores` are scratch
/// space).
fn filtered_tile(
    kind: SimilarityKind,
    filter: &Filter,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    span: &[usize],
    (row, scores, state): (&mut Vec<f64>, &mut Vec<u8>, &mut Scratch),
) -> Vec<Bins> {
    let filtered: Vec<usize> = span.iter().copied().filter(|&i| !filter.is_exact(i)).collect();
    let mut fast = filter
        .bin_rows(kind, features, level, &filtered, state)
        .into_iter();
    span.iter()
        .map(|&i| {
        if filter.is_exact(i) {
            similarity_row(kind, features, None, level, i, row);
            stage_view(&bin_row(kind, level, i, row, scores))
        } else {
            fast.next()
                .expect("invariant: one bin set per filtered row")
        }
    })
    .collect()
}

#[cfg(test)]
mod tests {
    use super::super::constraints::build_constraints;
    use super::*;

    #[test]
    fn fast_path_matches_the_slow_path() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        // A pseudo-random level of 37 nodes (not a multiple of the 8 lanes),
        // checked against `pair_similarity` bit for bit.
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64) / f64::from(u32::MAX) - 0.25
        };
        for i in 0..37 {
            let v: Vec<f64> = (0..13).map(|_| next()).collect();
            builder.add(
                NodeSpec::new(format!("n{i}"))
                    .parent("r")
                    .weight(1.0)
                    .features(v),
            );
        }
        let p = builder.build().expect("valid");
        let level: Vec<usize> = (1..p.len()).collect();
        for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson] {
            let features: Vec<NodeFeatures<'_>> = level
                .iter()
                .map(|&n| NodeFeatures::new(kind, &p, n))
                .collect();
            let transposed = Transposed::new(kind, &features);
            assert!(transposed.is_some());
            let mut row = Vec::new();
            for i in 0..level.len() {
                similarity_row(kind, &features, transposed.as_ref(), &level, i, &mut row);
                for j in 0..level.len() {
                    if i != j {
                        let slow = pair_similarity(kind, &features[i], &features[j], level[j]);
                        assert_eq!(row[j].to_bits(), slow.to_bits());
                    }
                }
            }
            // Tiles of every length up to 9 rows (the 4-row kernel, its
            // remainder, and both together), from every start.
            let mut rows = vec![Vec::new(); 9];
            for len in 1..=9 {
                for first in 0..=level.len() - len {
                    let span: Vec<usize> = (first..first + len).collect();
                    similarity_rows(
                        kind,
                        &features,
                        transposed.as_ref(),
                        &level,
                        &span,
                        &mut rows,
                    );
                    for (&i, row) in span.iter().zip(&rows) {
                        for j in (0..level.len()).filter(|&j| j != i) {
                            let slow = pair_similarity(kind, &features[i], &features[j], level[j]);
                            assert_eq!(row[j].to_bits(), slow.to_bits(), "tile {len} at {first}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn mixed_lengths_use_the_pair_path() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add(NodeSpec::new("a").parent("r").features(vec![1.0, 0.0]))
            .add(NodeSpec::new("b").parent("r").features(vec![1.0, 0.1]))
            .add(NodeSpec::new("c").parent("r").features(vec![1.0]));
        let p = builder.build().expect("valid");
        let features: Vec<NodeFeatures<'_>> = (1..4)
            .map(|n| NodeFeatures::new(SimilarityKind::Cosine, &p, n))
            .collect();
        assert!(Transposed::new(SimilarityKind::Cosine, &features).is_none());
        let pairs = build_constraints(&p, SimilarityKind::Cosine);
        let ids: Vec<(usize, usize)> = pairs.iter().map(|c| (c.a, c.b)).collect();
        // a–b are similar; c has a different length, so similarity 0 to both.
        assert_eq!(ids, [(1, 2)]);
    }
}
