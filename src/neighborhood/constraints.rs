//! The constraint pipeline of the prototype (method-reference §3.1–3.6): per-node
//! similarity lists over a whole level, min–max binning, the capped top bin
//! (Stage A), propagation to parents (Stage B), one extra link per following bin
//! (Stage C) and symmetrisation (Stage D), ending in the unordered pairs with
//! score > 1 that the paper counts. Stage E (the optimiser's per-round reordering)
//! is left to the optimiser; it can be derived from `ConstraintLists`.

use std::collections::BTreeMap;

use nptreemap_formats::Dataset;
use rayon::prelude::*;

use super::dot_kernel::kernel;
use super::bins::{bin_table, push_head, Bin, Bins, Candidate};
use super::filtered_rows::{Filter, RowState};
use super::similarity::{
    clamp_unit, cosine_from_parts, norm_of, pair_similarity, score, NodeFeatures, SimilarityKind,
};
use super::sparse_rows::{SparseLevel, SparseRow};

/// Stage A keeps at most this many links from the top bin (`slice(0, 6)`, §3.3).
const TOP_BIN_CAP: usize = 6;
/// Stage C stops once a node holds more than this many links (§3.5).
const STAGE_C_STOP_ABOVE: usize = 3;
/// A pair is a constraint when its score exceeds this (§3.6: `s > 1`).
const MIN_PAIR_SCORE: u8 = 1;

/// One undirected constraint between two nodes at the same depth of a prepared
/// dataset (one with virtual nodes for a uniform leaf depth).
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Index of the first node in the prepared dataset; `a < b`.
    pub a: usize,
    /// Index of the second node, at the same depth as `a`.
    pub b: usize,
    /// The pipeline's integer score in 2..=100: the larger of the scores the two
    /// directed lists hold for the pair (a propagated link carries its child
    /// link's score, §3.4).
    pub score: u8,
    /// The raw similarity of the two nodes in [0, 1], recomputed from the measure
    /// (for the directed neighbour flag, the larger of both directions).
    pub similarity: f64,
    /// 1..=3 for the layout JSON: 3 when the link came from a node's top bin or
    /// has score 100, 2 when it came from the second bin, 1 for later bins and
    /// for weaker links propagated from children; the larger of both directions.
    pub strength: u8,
}

/// One entry of a node's constraint list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListEntry {
    /// Index of the linked node (same depth) in the prepared dataset.
    pub target: usize,
    /// Integer score 1..=100 (never 0: such links are not created, §3.5).
    pub score: u8,
    /// Strength 1..=3, as for [`Constraint::strength`].
    pub strength: u8,
}

/// Per-node ordered constraint lists, indexed like the prepared dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintLists {
    /// After Stage C: what each node asked for itself (top bin, propagation,
    /// one per following bin), in the order added.
    pub directed: Vec<Vec<ListEntry>>,
    /// After Stage D: `directed` plus the reverse of every link the node lacked,
    /// appended in level order. Undirected from here on; may exceed the caps.
    pub symmetric: Vec<Vec<ListEntry>>,
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
            let sums = kernel_dispatch(tile, columns);
            acc[r..r + KERNEL_ROWS].copy_from_slice(&sums);
            r += KERNEL_ROWS;
        }
        for (a, row) in acc[r..].iter_mut().zip(&rows[r..]) {
            *a = kernel::<f64, 1, LANES>(&[row], columns)[0];
        }
    }
}

/// Rows one kernel call sums at once: 4 rows × 8 lanes are 8 AVX registers.
const KERNEL_ROWS: usize = 4;


/// [`kernel`] compiled for AVX where the CPU has it (checked once per call by
/// the standard library's cached detection), else for the baseline. AVX's
/// multiplies and adds round exactly as SSE2's, so the choice changes no bit.
fn kernel_dispatch(rows: &[&[f64]; KERNEL_ROWS], columns: &[f64]) -> [[f64; LANES]; KERNEL_ROWS] {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX, checked just above.
            return unsafe { kernel_avx(rows, columns) };
        }
    }
    kernel::<f64, KERNEL_ROWS, LANES>(rows, columns)
}

/// [`kernel`] in AVX intrinsics: the four rows' eight sums stay in eight
/// registers (the compiler's own vectorisation of [`kernel`] spilled them to the
/// stack every step). Multiplies and adds in the same order as [`kernel`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn kernel_avx(rows: &[&[f64]; KERNEL_ROWS], columns: &[f64]) -> [[f64; LANES]; KERNEL_ROWS] {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_setzero_pd,
        _mm256_storeu_pd,
    };
    let d = columns.len() / LANES;
    let rows: [&[f64]; KERNEL_ROWS] = rows.map(|row| &row[..d]);
    let mut acc = [[_mm256_setzero_pd(); 2]; KERNEL_ROWS];
    for k in 0..d {
        let column = &columns[k * LANES..(k + 1) * LANES];
        // SAFETY: `column` holds LANES = 8 values, two loads of four.
        let (lo, hi) = unsafe {
            (
                _mm256_loadu_pd(column.as_ptr()),
                _mm256_loadu_pd(column.as_ptr().add(4)),
            )
        };
        for r in 0..KERNEL_ROWS {
            let x = _mm256_set1_pd(rows[r][k]);
            acc[r][0] = _mm256_add_pd(acc[r][0], _mm256_mul_pd(x, lo));
            acc[r][1] = _mm256_add_pd(acc[r][1], _mm256_mul_pd(x, hi));
        }
    }
    let mut out = [[0.0f64; LANES]; KERNEL_ROWS];
    for (o, a) in out.iter_mut().zip(&acc) {
        // SAFETY: `o` holds 8 values, two stores of four.
        unsafe {
            _mm256_storeu_pd(o.as_mut_ptr(), a[0]);
            _mm256_storeu_pd(o.as_mut_ptr().add(4), a[1]);
        }
    }
    out
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
    rows: std::ops::Range<usize>,
    out: &mut [Vec<f64>],
) {
    let vectors: Option<Vec<&[f64]>> = transposed.and_then(|_| {
        rows.clone()
            .map(|i| features[i].values())
            .collect::<Option<_>>()
    });
    let (Some(t), Some(vectors)) = (transposed, vectors) else {
        for (i, row) in rows.zip(out.iter_mut()) {
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
        for ((i, row), dots) in rows.clone().zip(out.iter_mut()).zip(&acc) {
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
            i..i + 1,
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

/// The bins of node `level[i]` (§3.1–3.2; the neighbour-list variant has one bin,
/// the nodes it lists, all at score 100) from its filled similarity `row`.
fn bin_row(
    kind: SimilarityKind,
    level: &[usize],
    i: usize,
    row: &[f64],
    scores: &mut Vec<u8>,
) -> Bins {
    if level.len() < 2 {
        return Bins::default();
    }
    // Scores once per pair; `u8::MAX` marks the node itself.
    scores.clear();
    scores.extend(row.iter().map(|&s| score(s)));
    scores[i] = u8::MAX;
    let candidate = |j: usize| Candidate {
        similarity: row[j],
        node: level[j],
        score: scores[j],
    };
    if kind == SimilarityKind::NeighborList {
        let mut bin = Bin::default();
        for j in (0..level.len()).filter(|&j| j != i && scores[j] > 0) {
            bin.len += 1;
            push_head(&mut bin.head, candidate(j));
        }
        return Bins { bins: vec![bin] };
    }
    let (mut lo, mut hi) = (u8::MAX, 0u8);
    for (j, &s) in scores.iter().enumerate() {
        if j != i {
            lo = lo.min(s);
            hi = hi.max(s);
        }
    }
    let bin_of = bin_table(lo, hi);
    let mut bins = vec![Bin::default(); usize::from(bin_of[usize::from(lo)]) + 1];
    for (j, &s) in scores.iter().enumerate() {
        if j != i {
            let bin = &mut bins[usize::from(bin_of[usize::from(s)])];
            bin.len += 1;
            push_head(&mut bin.head, candidate(j));
        }
    }
    Bins { bins }
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

/// The bins of the rows `span` of a level through the f32 [`Filter`]; its exact
/// nodes get the full exact row (`row` and `scores` are scratch space).
fn filtered_tile(
    kind: SimilarityKind,
    filter: &Filter,
    features: &[NodeFeatures<'_>],
    level: &[usize],
    span: std::ops::Range<usize>,
    (row, scores, state): (&mut Vec<f64>, &mut Vec<u8>, &mut Vec<RowState>),
) -> Vec<Bins> {
    let filtered: Vec<usize> = span.clone().filter(|&i| !filter.is_exact(i)).collect();
    let mut fast = filter
        .bin_rows(kind, features, level, &filtered, state)
        .into_iter();
    span.map(|i| {
        if filter.is_exact(i) {
            similarity_row(kind, features, None, level, i, row);
            bin_row(kind, level, i, row, scores)
        } else {
            fast.next()
                .expect("invariant: one bin set per filtered row")
        }
    })
    .collect()
}

/// The bins of a node from its sparse row (the measures of [`SparseLevel`]): the same
/// bins as [`bin_row`] gives from the full row, bit for bit. Entries go in level order,
/// shown ones before the zeros; they never tie (shown similarities are non-zero), so
/// every head gets the order of the full scan.
fn bin_sparse(kind: SimilarityKind, row: &SparseRow, level: &[usize]) -> Bins {
    if level.len() < 2 {
        return Bins::default();
    }
    let candidate = |j: usize, similarity: f64| Candidate {
        similarity,
        node: level[j],
        score: score(similarity),
    };
    if kind == SimilarityKind::NeighborList {
        let mut bin = Bin::default();
        for &(j, s) in row.shown.iter().filter(|&&(_, s)| score(s) > 0) {
            bin.len += 1;
            push_head(&mut bin.head, candidate(j, s));
        }
        return Bins { bins: vec![bin] };
    }
    let (mut lo, mut hi) = (u8::MAX, 0u8);
    let scores = row
        .shown
        .iter()
        .map(|&(_, s)| score(s))
        .chain(row.hidden.filter(|h| h.1 > 0).map(|h| score(h.0)))
        .chain((row.zeros > 0).then_some(0));
    for s in scores {
        lo = lo.min(s);
        hi = hi.max(s);
    }
    let bin_of = bin_table(lo, hi);
    let mut bins = vec![Bin::default(); usize::from(bin_of[usize::from(lo)]) + 1];
    for &(j, s) in &row.shown {
        let bin = &mut bins[usize::from(bin_of[usize::from(score(s))])];
        bin.len += 1;
        push_head(&mut bin.head, candidate(j, s));
    }
    if let Some((s, count)) = row.hidden {
        bins[usize::from(bin_of[usize::from(score(s))])].len += count;
    }
    if row.zeros > 0 {
        let bin = &mut bins[usize::from(bin_of[0])];
        bin.len += row.zeros;
        for &j in &row.zero_head {
            push_head(&mut bin.head, candidate(j, 0.0));
        }
    }
    Bins { bins }
}

/// Strength of a link taken from bin `bin` (0 = top) with this score.
fn strength_for(bin: usize, score: u8) -> u8 {
    if score == 100 || bin == 0 {
        3
    } else if bin == 1 {
        2
    } else {
        1
    }
}

/// True when `list` already links to `target`.
fn has(list: &[ListEntry], target: usize) -> bool {
    list.iter().any(|e| e.target == target)
}

/// Runs Stages A to D (method-reference §3.1–3.6) on a prepared dataset (uniform
/// leaf depth, vectors aggregated: [`super::prepare::prepare`]) and returns every
/// node's list after Stage C and after Stage D.
///
/// Similarities are computed level by level, rows in parallel (results independent
/// of the thread count): neighbour lists, binary and Jaccard from sparse rows
/// (`SparseLevel`: the relations, groups of equal vectors, an inverted index of
/// supports; O(n + pairs that share a coordinate) per level), cosine and Pearson over
/// all pairs (`O(n²·d)` per level), through the f32 filter of `filtered_rows` where
/// the level allows it (same bins, bit for bit).
pub fn constraint_lists(prepared: &Dataset, kind: SimilarityKind) -> ConstraintLists {
    constraint_lists_with(prepared, kind, true)
}

/// [`constraint_lists`], with the sparse rows allowed or not (the all-pairs scan is
/// the reference the sparse rows are tested against).
fn constraint_lists_with(
    prepared: &Dataset,
    kind: SimilarityKind,
    sparse: bool,
) -> ConstraintLists {
    let nodes = prepared.nodes();

    // Levels in breadth-first order: the tie-break order of §2.1.
    let mut levels: Vec<Vec<usize>> = vec![Vec::new(); prepared.max_depth() + 1];
    for (index, node) in nodes.iter().enumerate() {
        levels[node.depth].push(index);
    }

    // §3.1–3.2: bins per non-root node.
    let mut bins: Vec<Bins> = vec![Bins::default(); nodes.len()];
    for level in levels.iter().skip(1) {
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
        let transposed = match (&sparse_level, &filter) {
            (None, None) => Transposed::new(kind, &level_features),
            _ => None,
        };
        let level_bins: Vec<Bins> = match &sparse_level {
            Some(index) => (0..level.len())
                .into_par_iter()
                .map_init(Vec::new, |counts, i| {
                    let row = index.row(&level_features, level, i, counts);
                    bin_sparse(kind, &row, level)
                })
                .collect(),
            None => {
                let tiles: Vec<Vec<Bins>> = (0..level.len().div_ceil(TILE_ROWS))
                    .into_par_iter()
                    .map_init(
                        || (vec![Vec::new(); TILE_ROWS], Vec::new(), Vec::new()),
                        |(rows, scores, filter_state), tile| {
                            let span = tile * TILE_ROWS..((tile + 1) * TILE_ROWS).min(level.len());
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
                                span.clone(),
                                rows,
                            );
                            span.zip(rows.iter())
                                .map(|(i, row)| bin_row(kind, level, i, row, scores))
                                .collect()
                        },
                    )
                    .collect();
                tiles.into_iter().flatten().collect()
            }
        };
        for (&node, node_bins) in level.iter().zip(level_bins) {
            bins[node] = node_bins;
        }
    }

    // Stage A (§3.3): the top bin, capped; nothing when the best score is 0.
    let mut lists: Vec<Vec<ListEntry>> = vec![Vec::new(); nodes.len()];
    for (node, node_bins) in bins.iter().enumerate() {
        let Some(top) = node_bins.bins.first() else {
            continue;
        };
        if top.head.first().is_none_or(|c| c.score == 0) {
            continue;
        }
        lists[node] = top
            .head
            .iter()
            .take(TOP_BIN_CAP)
            .map(|c| ListEntry {
                target: c.node,
                score: c.score,
                strength: strength_for(0, c.score),
            })
            .collect();
    }

    // Stage B (§3.4): children's links become links between their parents. Children
    // come after their parent in breadth-first order, so the reverse sweep sees
    // every child's list complete, as the prototype's post-order walk does.
    for d in (0..nodes.len()).rev() {
        for &p in &nodes[d].children {
            for k in 0..lists[p].len() {
                let link = lists[p][k];
                let parent = nodes[link.target].parent.unwrap_or(0);
                if parent == d || has(&lists[d], parent) {
                    continue;
                }
                // A perfect child link always propagates; a weaker one only gives
                // the parent its first link.
                if link.score == 100 || lists[d].is_empty() {
                    lists[d].push(ListEntry {
                        target: parent,
                        score: link.score,
                        strength: strength_for(usize::MAX, link.score),
                    });
                }
            }
        }
    }

    // Stage C (§3.5): one more link from each following non-empty bin while the
    // node holds at most 3, stopping at the first empty bin. Skipped when the top
    // bin is empty; score-0 links are never created (§3.5, §10 #2).
    for (node, node_bins) in bins.iter().enumerate() {
        if node_bins.bins.first().is_none_or(|top| top.len == 0) {
            continue;
        }
        for (b, bin) in node_bins.bins.iter().enumerate() {
            if lists[node].len() > STAGE_C_STOP_ABOVE || bin.len == 0 {
                break;
            }
            if let Some(c) = bin.head.iter().find(|c| !has(&lists[node], c.node)) {
                if c.score > 0 {
                    lists[node].push(ListEntry {
                        target: c.node,
                        score: c.score,
                        strength: strength_for(b, c.score),
                    });
                }
            }
        }
    }
    let directed = lists.clone();

    // Stage D (§3.6): per level, parents in order and their children in order,
    // i.e. breadth-first order; links only join nodes of one level, so one sweep
    // over all nodes is the same as one sweep per level.
    for c in 0..nodes.len() {
        for k in 0..lists[c].len() {
            let link = lists[c][k];
            if !has(&lists[link.target], c) {
                lists[link.target].push(ListEntry {
                    target: c,
                    score: link.score,
                    strength: link.strength,
                });
            }
        }
    }

    ConstraintLists {
        directed,
        symmetric: lists,
    }
}

/// The unordered pairs with score > 1 (§3.6) of every level of a prepared dataset,
/// sorted by (depth, a, b). See [`Constraint`] for score, similarity and strength.
pub fn build_constraints(prepared: &Dataset, kind: SimilarityKind) -> Vec<Constraint> {
    pairs(prepared, kind, &constraint_lists(prepared, kind))
}

/// The pairs of [`build_constraints`] from lists already computed with
/// [`constraint_lists`] for the same dataset and measure.
pub fn pairs(prepared: &Dataset, kind: SimilarityKind, lists: &ConstraintLists) -> Vec<Constraint> {
    // A BTreeMap keyed by (a, b) gives the (depth, a, b) order directly: indices
    // are breadth-first, so a deeper node always has a larger index.
    let mut best: BTreeMap<(usize, usize), (u8, u8)> = BTreeMap::new();
    for (c, list) in lists.symmetric.iter().enumerate() {
        for link in list {
            let key = (c.min(link.target), c.max(link.target));
            let entry = best.entry(key).or_insert((0, 0));
            entry.0 = entry.0.max(link.score);
            entry.1 = entry.1.max(link.strength);
        }
    }
    best.into_iter()
        .filter(|&(_, (score, _))| score > MIN_PAIR_SCORE)
        .map(|((a, b), (score, strength))| {
            let fa = NodeFeatures::new(kind, prepared, a);
            let fb = NodeFeatures::new(kind, prepared, b);
            let s = pair_similarity(kind, &fa, &fb, b).max(pair_similarity(kind, &fb, &fa, a));
            Constraint {
                a,
                b,
                score,
                similarity: clamp_unit(s),
                strength: if score == 100 { 3 } else { strength },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::prepare::prepare;
    use super::*;

    fn paper(name: &str) -> (Dataset, SimilarityKind) {
        let dataset = super::super::prepare::test_data::dataset(name);
        let prepared = prepare(&dataset);
        let kind = SimilarityKind::for_dataset(&prepared);
        (prepared, kind)
    }

    /// Pair counts per depth 1..=D.
    fn counts_per_level(name: &str) -> Vec<usize> {
        let (p, kind) = paper(name);
        let pairs = build_constraints(&p, kind);
        (1..=p.max_depth())
            .map(|depth| pairs.iter().filter(|c| p.node(c.a).depth == depth).count())
            .collect()
    }

    #[test]
    fn golden_counts_per_level() {
        // Method-reference §3.9; leaf-level values are Table 2's.
        assert_eq!(counts_per_level("country_pop_50M_AUS.json"), [1, 18]);
        assert_eq!(counts_per_level("imdb_100_genre_sim_2child.json"), [25, 42]);
        assert_eq!(
            counts_per_level("syntheticPoints_10nodes_2components.json"),
            [11]
        );
        assert_eq!(
            counts_per_level("2_level_4_cousin_constraints.json"),
            [4, 24]
        );
        assert_eq!(counts_per_level("cifar10.json"), [1, 12, 19]);
        assert_eq!(counts_per_level("flare.json"), [14, 209, 488, 547]);
    }

    fn id_pair(p: &Dataset, c: &Constraint) -> String {
        let (a, b) = (&p.node(c.a).id, &p.node(c.b).id);
        if a < b {
            format!("{a}-{b}")
        } else {
            format!("{b}-{a}")
        }
    }

    #[test]
    fn golden_country_pairs() {
        let (p, kind) = paper("country_pop_50M_AUS.json");
        assert_eq!(kind, SimilarityKind::NeighborList);
        let pairs = build_constraints(&p, kind);
        let mut leaf: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 2)
            .map(|c| id_pair(&p, c))
            .collect();
        leaf.sort();
        let expected = [
            "BD-IN", "BD-MM", "CD-TZ", "CN-IN", "CN-MM", "CN-PK", "CN-RU", "CN-VN", "DE-FR",
            "ET-KE", "FR-IT", "IN-MM", "IN-PK", "IR-PK", "IR-TR", "KE-TZ", "MM-TH", "MX-US",
        ];
        assert_eq!(leaf, expected);
        for c in &pairs {
            assert_eq!(c.score, 100);
            assert_eq!(c.strength, 3);
            // Leaves share a border; the continents' link is propagated (§3.4) and
            // continents list no neighbours, so their own similarity is 0.
            let expected = if p.node(c.a).depth == 2 { 1.0 } else { 0.0 };
            assert_eq!(c.similarity, expected, "{}", id_pair(&p, c));
        }
        let level1: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 1)
            .map(|c| id_pair(&p, c))
            .collect();
        assert_eq!(level1, ["Cont_AS-Cont_EU"]);
    }

    #[test]
    fn synthetic_two_level_lists() {
        let (p, kind) = paper("2_level_4_cousin_constraints.json");
        let lists = constraint_lists(&p, kind);
        let ids = |node: &str| -> Vec<String> {
            let index = p.find(node).expect("exists");
            let mut v: Vec<String> = lists.directed[index]
                .iter()
                .map(|e| p.node(e.target).id.clone())
                .collect();
            v.sort();
            v
        };
        assert_eq!(ids("P13"), ["P1", "P14", "P15", "P16", "P17"]);
        assert_eq!(ids("P2"), ["P3"]);
        // Level 1: P21 linked to P22..P25 (through Stage B), nothing else.
        let pairs = build_constraints(&p, kind);
        let level1: Vec<String> = pairs
            .iter()
            .filter(|c| p.node(c.a).depth == 1)
            .map(|c| id_pair(&p, c))
            .collect();
        assert_eq!(level1, ["P21-P25", "P21-P24", "P21-P23", "P21-P22"]);
    }

    #[test]
    fn pairs_are_sorted_symmetric_and_never_weak() {
        for name in [
            "flare.json",
            "cifar10.json",
            "imdb_100_genre_sim_2child.json",
            "country_pop_50M_AUS.json",
        ] {
            let (p, kind) = paper(name);
            let lists = constraint_lists(&p, kind);
            let pairs = pairs(&p, kind, &lists);
            for w in pairs.windows(2) {
                let key = |c: &Constraint| (p.node(c.a).depth, c.a, c.b);
                assert!(key(&w[0]) < key(&w[1]), "{name}");
            }
            for c in &pairs {
                assert!(c.a < c.b);
                assert_eq!(p.node(c.a).depth, p.node(c.b).depth);
                assert!(p.node(c.a).depth >= 1);
                assert!(c.score > 1 && c.score <= 100);
                assert!((1..=3).contains(&c.strength));
                assert!((0.0..=1.0).contains(&c.similarity));
            }
            for (n, list) in lists.symmetric.iter().enumerate() {
                for e in list {
                    assert!(e.score > 0, "{name}: score-0 link");
                    assert!(lists.symmetric[e.target].iter().any(|r| r.target == n));
                }
            }
            // Deterministic.
            assert_eq!(pairs, build_constraints(&p, kind), "{name}");
        }
    }

    #[test]
    fn all_zero_similarities_give_no_links() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for i in 0..4 {
            builder.add(NodeSpec::new(format!("n{i}")).parent("r").weight(1.0));
        }
        let p = prepare(&builder.build().expect("valid"));
        let lists = constraint_lists(&p, SimilarityKind::Cosine);
        assert!(lists.symmetric.iter().all(Vec::is_empty));
        assert!(build_constraints(&p, SimilarityKind::Cosine).is_empty());
        // A single node: nothing to compare with.
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add(NodeSpec::new("x").parent("r").features(vec![1.0]));
        let p = prepare(&builder.build().expect("valid"));
        assert!(build_constraints(&p, SimilarityKind::Cosine).is_empty());
    }

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
                    let span = first..first + len;
                    similarity_rows(
                        kind,
                        &features,
                        transposed.as_ref(),
                        &level,
                        span.clone(),
                        &mut rows,
                    );
                    for (i, row) in span.zip(&rows) {
                        for j in (0..level.len()).filter(|&j| j != i) {
                            let slow = pair_similarity(kind, &features[i], &features[j], level[j]);
                            assert_eq!(row[j].to_bits(), slow.to_bits(), "tile {len} at {first}");
                        }
                    }
                }
            }
        }
    }

    /// Random two- and three-level datasets for the sparse measures: short 0/1-ish
    /// vectors (many equal, many disjoint), some missing, some of another length, some
    /// with −0, and relations to any node (own level or not, itself, repeated).
    fn sparse_case(seed: u64, leaves: usize) -> Dataset {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut rng = crate::rng::Rng::new(seed);
        let mut below = |n: u64| (rng.next_u64() % n) as usize;
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        let groups = 1 + below(5);
        for g in 0..groups {
            builder.add(NodeSpec::new(format!("g{g}")).parent("r"));
        }
        let total = groups + leaves + 1;
        for i in 0..leaves {
            let parent = format!("g{}", below(groups as u64));
            let mut spec = NodeSpec::new(format!("n{i}")).parent(parent).weight(1.0);
            match below(12) {
                0 => {}
                1 => spec = spec.features(vec![1.0; 3]),
                2 => spec = spec.features(vec![0.0, 1.0]),
                3 => spec = spec.features(vec![-0.0, 1.0, 0.0, 0.0]),
                _ => {
                    let v: Vec<f64> = (0..4).map(|_| (below(3) == 0) as u8 as f64).collect();
                    spec = spec.features(v);
                }
            }
            for _ in 0..below(4) {
                let t = below(total as u64);
                let id = match t {
                    0 => "r".to_string(),
                    t if t <= groups => format!("g{}", t - 1),
                    t => format!("n{}", (t - groups - 1).min(leaves - 1)),
                };
                spec = spec.relation(id);
            }
            builder.add(spec);
        }
        builder.build().expect("valid")
    }

    #[test]
    fn sparse_rows_match_the_all_pairs_scan() {
        for seed in 0..60 {
            let leaves = [2, 3, 9, 17, 40, 120][seed as usize % 6];
            let d = sparse_case(seed, leaves);
            let p = prepare(&d);
            for kind in [
                SimilarityKind::NeighborList,
                SimilarityKind::Binary,
                SimilarityKind::Jaccard,
            ] {
                let sparse = constraint_lists_with(&p, kind, true);
                let dense = constraint_lists_with(&p, kind, false);
                assert_eq!(sparse, dense, "seed {seed}, {kind:?}");
            }
        }
        // Paper data through both paths (Flare is Jaccard, Country neighbour lists).
        for name in [
            "flare.json",
            "country_pop_50M_AUS.json",
            "imdb_100_genre_sim_2child.json",
        ] {
            let (p, kind) = paper(name);
            assert_eq!(
                constraint_lists_with(&p, kind, true),
                constraint_lists_with(&p, kind, false),
                "{name}"
            );
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
