//! The stage views (`bins::stage_view`, all that Stages A and C read) of dense
//! cosine and Pearson rows through a single-precision filter: every pair's
//! similarity is first computed in f32 from unit vectors, and the exact f64
//! similarity ([`pair_similarity`]) is computed only where the f32 value could
//! change a decision (a score near an integer step, a candidate that might be
//! among the row's best). The views come out bit for bit as the all-pairs f64
//! scan's bins give them (`bin_row` of `bins`); the unit test checks it.
//!
//! Why: the all-pairs scan is the one `O(n²·d)` step of the method. On a
//! 100,000-leaf level it took 44.8 s of the whole method's 75 s, most of it not in
//! the dot products but in storing each f64 row (0.8 MB per row) and reading it
//! back to bin it. Here a row is binned as it is computed: AVX2 turns each block
//! of 16 f32 dot products into scores and a mask of the pairs that need a closer
//! look; the rest only move the row's lowest and highest score, and only the
//! few candidates that may still be among the row's 12 best are kept
//! (`row_best`); their exact similarities are computed at the end. The rare row
//! whose view needs more (a top bin of fewer than 4 over crowded following
//! bins: 13 of 20,063 rows on h20000) is scanned again keeping the best entries
//! of every score, as the filter did for every row before (issue 34: a
//! histogram and per-score candidates cost 3× the kernel itself; BENCHMARKS.md,
//! "Issue 34 item 4"). The kernel (`kernels`, shared with the exact rows) does
//! twice the pairs per instruction in f32 (BENCHMARKS.md, "Constraints through
//! an f32 filter"). Written by hand: no crate does filtered exact binning.

use super::bins::{bin_table, stage_view, Bin, Bins, Candidate, BIN_HEAD};
use super::kernels::{dot_tile, KERNEL_ROWS};
use super::row_best::{view_from_best, RowBest};
use super::similarity::{pair_similarity, score, NodeFeatures, SimilarityKind};

/// Lanes per column block: two AVX registers of f32.
const LANES: usize = 16;
/// Possible scores, 0..=100 (§3.2).
const SCORES: usize = 101;
/// Norms outside this range could overflow or underflow the exact path's
/// `dot / (|a|·|b|)` in f64, where the unit vectors of the filter would not; such
/// nodes are always computed exactly.
const NORM_RANGE: std::ops::RangeInclusive<f64> = 1e-100..=1e100;

/// A level's unit vectors in f32, rows and transposed column blocks.
pub(super) struct Filter {
    d: usize,
    /// `rows[i·d + k]`: coordinate `k` of node `i`'s unit vector.
    rows: Vec<f32>,
    /// `blocks[(block·d + k)·LANES + lane]`: coordinate `k` of node
    /// `block·LANES + lane`; padding lanes are zero.
    blocks: Vec<f32>,
    /// Nodes computed exactly, never through the filter (zero or extreme norms).
    exact: Vec<bool>,
    /// Per column block: true when one of its nodes is in `exact`.
    exact_in_block: Vec<bool>,
    /// Bound on |rescaled f32 cosine − exact rescaled cosine|.
    eps: f64,
}

impl Filter {
    /// The filter for a level, or `None` when the measure is not a dot product,
    /// a vector is missing or of another length, or more than an eighth of the
    /// nodes need the exact path anyway.
    pub(super) fn new(kind: SimilarityKind, features: &[NodeFeatures<'_>]) -> Option<Self> {
        if !matches!(kind, SimilarityKind::Cosine | SimilarityKind::Pearson) {
            return None;
        }
        let n = features.len();
        let d = features.first()?.values()?.len();
        let mut rows = vec![0.0f32; n * d];
        let mut blocks = vec![0.0f32; n.div_ceil(LANES) * d * LANES];
        let mut exact = vec![false; n];
        for (j, f) in features.iter().enumerate() {
            let v = f.values().filter(|v| v.len() == d)?;
            let norm = super::similarity::norm_of(f);
            if !NORM_RANGE.contains(&norm) || v.iter().any(|x| !x.is_finite()) {
                exact[j] = true;
                continue;
            }
            let (block, lane) = (j / LANES, j % LANES);
            for (k, &x) in v.iter().enumerate() {
                let u = (x / norm) as f32;
                rows[j * d + k] = u;
                blocks[(block * d + k) * LANES + lane] = u;
            }
        }
        if exact.iter().filter(|&&e| e).count() * 8 > n {
            return None;
        }
        // Unit vectors rounded to f32 (each coordinate within u = 2⁻²⁴ relative)
        // and summed left to right in f32: |Σ ûᵢûⱼ − cos| ≤ (d + 2)·u·(1 + O(u))
        // (the standard bound for recursive summation, with Σ|uᵢ||uⱼ| ≤ 1); the
        // exact path's own f64 error is ~d·2⁻⁵³. Rescaling halves it; (d + 8)·u
        // leaves more than a factor of two.
        let eps = (d as f64 + 8.0) * f64::from(f32::EPSILON) / 2.0;
        let exact_in_block = exact.chunks(LANES).map(|c| c.contains(&true)).collect();
        Some(Filter {
            d,
            rows,
            blocks,
            exact,
            exact_in_block,
            eps,
        })
    }

    /// The length of the level's vectors.
    pub(super) fn dim(&self) -> usize {
        self.d
    }

    /// Node `i`'s unit vector in f32 (zeros for a [`Filter::is_exact`] node).
    pub(super) fn unit(&self, i: usize) -> &[f32] {
        &self.rows[i * self.d..(i + 1) * self.d]
    }

    /// Bound on |(f32 dot of two unit vectors + 1)/2 − exact similarity|, the
    /// dot summed by the kernels of `kernels` (k ascending from zero).
    pub(super) fn eps(&self) -> f64 {
        self.eps
    }

    /// True when node `i` of the level is always computed exactly.
    pub(super) fn is_exact(&self, i: usize) -> bool {
        self.exact[i]
    }

    /// The stage views (`bins::stage_view`) of rows `rows` (none of them
    /// [`Filter::is_exact`]), as the all-pairs f64 scan's bins give them: one
    /// pass keeps each row's extreme scores and best entries (`row_best`);
    /// the rows whose view needs more than those (a small top bin over
    /// crowded following bins) are scanned again for the best entries of
    /// every score.
    pub(super) fn bin_rows(
        &self,
        kind: SimilarityKind,
        features: &[NodeFeatures<'_>],
        level: &[usize],
        rows: &[usize],
        scratch: &mut Scratch,
    ) -> Vec<Bins> {
        let n = level.len();
        let exact =
            |i: usize, j: usize| pair_similarity(kind, &features[i], &features[j], level[j]);
        let mut views = std::mem::take(&mut scratch.views);
        views.clear();
        views.resize_with(rows.len(), ViewState::new);
        self.scan(rows, &mut views, |row, i, j, dot| self.pair_view(row, i, j, dot, &exact));
        let mut out: Vec<Option<Bins>> = rows
            .iter()
            .zip(&mut views)
            .map(|(&i, row)| row.view(n, level, self.eps, |j| exact(i, j)))
            .collect();
        scratch.views = views;
        let open: Vec<usize> = (0..rows.len()).filter(|&r| out[r].is_none()).collect();
        if !open.is_empty() {
            let again: Vec<usize> = open.iter().map(|&r| rows[r]).collect();
            let full = self.full_bins(n, level, &again, &mut scratch.full, &exact);
            for (r, bins) in open.into_iter().zip(full) {
                out[r] = Some(stage_view(&bins));
            }
        }
        out.into_iter()
            .map(|v| v.expect("invariant: every row has its view"))
            .collect()
    }

    /// Every pair `(i, j)` of `rows` × the level through the f32 kernel, in
    /// blocks of [`LANES`] columns: `visit(state of i, i, j, f32 dot)` for
    /// each pair other than `(i, i)`, except that a clean block (16 columns,
    /// none exact, not `i`) is handed whole to `block(state, dots)`, which
    /// returns the mask of the lanes still to visit (all of them where AVX2
    /// is missing).
    fn scan<S: Classify>(
        &self,
        rows: &[usize],
        states: &mut [S],
        mut visit: impl FnMut(&mut S, usize, usize, f32),
    ) {
        let n = self.exact.len();
        let margin = MARGIN_STEPS * self.eps;
        let simd = avx2();
        for block in 0..n.div_ceil(LANES) {
            let columns = &self.blocks[block * self.d * LANES..(block + 1) * self.d * LANES];
            let first = block * LANES;
            let last = (first + LANES).min(n);
            for (group, states) in rows.chunks(KERNEL_ROWS).zip(states.chunks_mut(KERNEL_ROWS)) {
                let vectors: [&[f32]; KERNEL_ROWS] = std::array::from_fn(|r| {
                    let i = group[r.min(group.len() - 1)];
                    &self.rows[i * self.d..(i + 1) * self.d]
                });
                let dots = dot_tile::<f32, LANES>(&vectors, columns);
                for ((&i, row), dots) in group.iter().zip(states.iter_mut()).zip(&dots) {
                    let clean = last - first == LANES
                        && !self.exact_in_block[block]
                        && !(first..last).contains(&i);
                    if clean && simd {
                        let mut attention = row.classify(dots, margin);
                        while attention != 0 {
                            let lane = attention.trailing_zeros() as usize;
                            attention &= attention - 1;
                            visit(row, i, first + lane, dots[lane]);
                        }
                        continue;
                    }
                    for (j, &dot) in (first..last).zip(dots) {
                        if j != i {
                            visit(row, i, j, dot);
                        }
                    }
                }
            }
        }
    }

    /// The full bins of `rows` from the best entries of every score (the
    /// fallback of [`Filter::bin_rows`]).
    fn full_bins(
        &self,
        n: usize,
        level: &[usize],
        rows: &[usize],
        state: &mut Vec<RowState>,
        exact: &impl Fn(usize, usize) -> f64,
    ) -> Vec<Bins> {
        state.resize_with(rows.len(), RowState::default);
        for s in state.iter_mut() {
            s.reset(self.eps);
        }
        let states = &mut state[..rows.len()];
        self.scan(rows, states, |row, i, j, dot| {
            let (score, similarity) = self.pair(i, j, dot, exact);
            row.take(score, similarity, j);
        });
        states
            .iter()
            .zip(rows)
            .map(|(row, &i)| row.bins(n, level, |j| exact(i, j)))
            .collect()
    }

    /// One pair `(i, j)` from its f32 dot product: its exact score, and a
    /// similarity within `eps` of the exact one (the exact one near a score
    /// step, where the f32 value could have the wrong score).
    #[inline]
    fn pair(&self, i: usize, j: usize, dot: f32, exact: &impl Fn(usize, usize) -> f64) -> (u8, f64) {
        let approx = (f64::from(dot) + 1.0) / 2.0;
        let scaled = 100.0 * approx;
        // The nearest step by truncation (scaled > −1 for unit vectors, so the
        // shifted value is positive): no libm call.
        let nearest = ((scaled + 1.5) as i64 - 1) as f64;
        if self.exact[j] || (scaled - nearest).abs() < MARGIN_STEPS * self.eps {
            let s = exact(i, j);
            (score(s), s)
        } else {
            // Not near a step: the f32 value has the exact score.
            (score(approx), approx)
        }
    }

    /// One pair of the view pass: its score moves the row's extremes, its
    /// similarity goes to the row's best entries.
    #[inline]
    fn pair_view(
        &self,
        row: &mut ViewState,
        i: usize,
        j: usize,
        dot: f32,
        exact: &impl Fn(usize, usize) -> f64,
    ) {
        let (score, similarity) = self.pair(i, j, dot, exact);
        row.lo = row.lo.min(score);
        row.hi = row.hi.max(score);
        row.best.take(similarity, j, self.eps);
        row.floor32 = (row.best.floor - self.eps) as f32;
    }
}

/// Scores are steps of 1/100 of the similarity: a value farther than
/// `MARGIN_STEPS · eps` from a step (in units of score) has the same score in
/// f32 as in f64.
const MARGIN_STEPS: f64 = 100.0;

/// Scratch space of [`Filter::bin_rows`], kept across calls by a thread.
#[derive(Default)]
pub(super) struct Scratch {
    views: Vec<ViewState>,
    full: Vec<RowState>,
}

/// What a block of 16 pairs of one row needs from the AVX2 classifier.
trait Classify {
    /// The mask of the lanes of `dots` that need a closer look; the others
    /// are accounted for here.
    fn classify(&mut self, dots: &[f32; LANES], margin: f64) -> u32;
}

/// One row of the view pass: its lowest and highest score, and its best
/// entries.
struct ViewState {
    best: RowBest,
    lo: u8,
    hi: u8,
    /// Per lane of the AVX2 classifier: lowest scores (first 8) and highest
    /// (last 8) of the pairs it settled.
    range: [i32; 2 * LANES / 2],
    /// `best.floor − eps` in f32: pairs below it cannot be kept.
    floor32: f32,
}

impl ViewState {
    fn new() -> Self {
        let mut range = [0i32; LANES];
        range[..LANES / 2].fill(100);
        ViewState {
            best: RowBest::new(),
            lo: 100,
            hi: 0,
            range,
            floor32: f32::NEG_INFINITY,
        }
    }

    /// The row's stage view, or `None` when it needs more than the best
    /// entries kept.
    fn view(
        &mut self,
        n: usize,
        level: &[usize],
        eps: f64,
        exact: impl Fn(usize) -> f64,
    ) -> Option<Bins> {
        if n < 2 {
            return Some(Bins::default());
        }
        let (mins, maxes) = self.range.split_at(LANES / 2);
        let lo = mins.iter().fold(i32::from(self.lo), |a, &b| a.min(b));
        let hi = maxes.iter().fold(i32::from(self.hi), |a, &b| a.max(b));
        self.best.prune(eps);
        let best = self.best.exact_best(eps, exact);
        view_from_best(&best, self.best.floor, lo as u8, hi as u8, level)
    }
}

impl Classify for ViewState {
    #[inline]
    fn classify(&mut self, dots: &[f32; LANES], margin: f64) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: `scan` classifies only when the CPU has AVX2.
            unsafe { classify_view_avx2(dots, self.floor32, margin as f32, &mut self.range) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (dots, margin);
            u32::MAX
        }
    }
}

impl Classify for RowState {
    #[inline]
    fn classify(&mut self, dots: &[f32; LANES], margin: f64) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            let mut scores = [0i32; LANES];
            // SAFETY: `scan` classifies only when the CPU has AVX2.
            let attention =
                unsafe { classify_avx2(dots, &self.floor32, margin as f32, &mut scores) };
            for &sc in &scores {
                self.counts[sc as usize] += 1;
            }
            // The lanes to visit are counted there.
            let mut rest = attention;
            while rest != 0 {
                let lane = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                self.counts[scores[lane] as usize] -= 1;
            }
            attention
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (dots, margin);
            u32::MAX
        }
    }
}

/// One row's histogram of scores and, per score, the candidates that may still be
/// among its best: every one whose similarity may reach the eighth best's.
#[derive(Default)]
pub(super) struct RowState {
    counts: Vec<u32>,
    /// Per score: (similarity within `eps` of the exact one, level position).
    kept: Vec<Vec<(f64, usize)>>,
    /// Per score: a candidate below this is surely beaten by eight kept ones.
    floor: Vec<f64>,
    /// `floor` rounded to f32, for [`classify_avx2`].
    floor32: Vec<f32>,
    /// Per score: the length at which `kept` is pruned next.
    prune_at: Vec<usize>,
    eps: f64,
}

/// Kept candidates of one score before the first pruning.
const PRUNE_FROM: usize = 2 * BIN_HEAD;

impl RowState {
    fn reset(&mut self, eps: f64) {
        self.eps = eps;
        self.counts.clear();
        self.counts.resize(SCORES, 0);
        self.floor.clear();
        self.floor.resize(SCORES, f64::NEG_INFINITY);
        self.floor32.clear();
        self.floor32.resize(SCORES, f32::NEG_INFINITY);
        self.prune_at.clear();
        self.prune_at.resize(SCORES, PRUNE_FROM);
        self.kept.resize_with(SCORES, Vec::new);
        for kept in &mut self.kept {
            kept.clear();
        }
    }

    /// Counts a pair with its (exact) score and keeps it while it may be among
    /// that score's best. `similarity` is exact or within `eps` of it.
    #[inline]
    fn take(&mut self, score: u8, similarity: f64, j: usize) {
        let s = usize::from(score);
        self.counts[s] += 1;
        if similarity < self.floor[s] {
            return;
        }
        let kept = &mut self.kept[s];
        kept.push((similarity, j));
        if kept.len() >= self.prune_at[s] {
            // The eighth best kept value T: eight candidates have exact values
            // ≥ T − eps, so one below T − 2·eps is exactly below eight others
            // (strictly: no tie can bring it back).
            let (_, &mut (eighth, _), _) =
                kept.select_nth_unstable_by(BIN_HEAD - 1, |a, b| b.0.total_cmp(&a.0));
            self.floor[s] = eighth - 2.0 * self.eps;
            let floor = self.floor[s];
            self.floor32[s] = floor as f32;
            kept.retain(|&(v, _)| v >= floor);
            // Doubling keeps the work linear when many values tie.
            self.prune_at[s] = (2 * kept.len()).max(PRUNE_FROM);
        }
    }

    /// The bins of the row: thresholds from the lowest and highest score, each
    /// bin's count from the histogram, and its head from its highest scores: a
    /// bin's best entries come from the fewest top scores holding eight entries,
    /// whose kept candidates get their exact similarity here (`exact(j)`).
    fn bins(&self, level_len: usize, level: &[usize], exact: impl Fn(usize) -> f64) -> Bins {
        if level_len < 2 {
            return Bins::default();
        }
        let counts = &self.counts;
        let present = || (0..SCORES).filter(|&s| counts[s] > 0);
        let (Some(lo), Some(hi)) = (present().next(), present().next_back()) else {
            return Bins::default();
        };
        let bin_of = bin_table(lo as u8, hi as u8);
        let mut bins = vec![Bin::default(); usize::from(bin_of[lo]) + 1];
        for s in present().rev() {
            let bin = &mut bins[usize::from(bin_of[s])];
            let needed = bin.len < BIN_HEAD;
            bin.len += counts[s] as usize;
            if needed {
                bin.head
                    .extend(self.kept[s].iter().map(|&(_, j)| Candidate {
                        similarity: exact(j),
                        node: level[j],
                        score: s as u8,
                    }));
            }
        }
        for bin in &mut bins {
            // Similarity descending, then level order: `push_head`'s stable order
            // (its `>=` treats −0 and 0 as equal, as `partial_cmp` does).
            bin.head.sort_by(|a, b| {
                b.similarity
                    .partial_cmp(&a.similarity)
                    .unwrap_or(std::cmp::Ordering::Equal)
                    .then(a.node.cmp(&b.node))
            });
            bin.head.truncate(BIN_HEAD);
        }
        Bins { bins }
    }
}

/// True when [`classify_avx2`] can run on this CPU.
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The scores of one block's 16 pairs of a row, computed in f32, and a mask of
/// the pairs that need [`Filter::pair`]: those within `margin` (plus f32 slack)
/// of a score step, and those that may reach their score's `floor` (minus
/// slack). For every other pair the f32 score is the exact one and the pair
/// cannot be among its score's best, so counting it is all there is to do.
/// The slacks cover this function's own f32 rounding of (dot + 1)/2·100 (a few
/// units of 2⁻²⁴·100) and of the floors (2⁻²⁴).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn classify_avx2(
    dots: &[f32; LANES],
    floors: &[f32],
    margin: f32,
    scores: &mut [i32; LANES],
) -> u32 {
    use std::arch::x86_64::{
        __m256i, _mm256_add_ps, _mm256_andnot_ps, _mm256_cmp_ps, _mm256_cvttps_epi32,
        _mm256_i32gather_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps, _mm256_movemask_ps,
        _mm256_mul_ps, _mm256_or_ps, _mm256_round_ps, _mm256_set1_ps, _mm256_setzero_ps,
        _mm256_storeu_si256, _mm256_sub_ps, _CMP_GE_OQ, _CMP_LT_OQ, _MM_FROUND_NO_EXC,
        _MM_FROUND_TO_NEAREST_INT,
    };
    assert!(floors.len() >= SCORES, "invariant: a floor per score");
    let half = _mm256_set1_ps(0.5);
    let hundred = _mm256_set1_ps(100.0);
    let near_margin = _mm256_set1_ps(margin + 1e-4);
    let floor_slack = _mm256_set1_ps(1e-6);
    let sign = _mm256_set1_ps(-0.0);
    let mut mask = 0u32;
    for part in 0..2 {
        // SAFETY: `dots` and `scores` hold 16 values, two halves of eight.
        let dot = unsafe { _mm256_loadu_ps(dots.as_ptr().add(8 * part)) };
        let approx = _mm256_add_ps(_mm256_mul_ps(dot, half), half);
        let scaled = _mm256_mul_ps(approx, hundred);
        let nearest = _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(scaled);
        let distance = _mm256_andnot_ps(sign, _mm256_sub_ps(scaled, nearest));
        let near = _mm256_cmp_ps::<_CMP_LT_OQ>(distance, near_margin);
        let clamped = _mm256_min_ps(_mm256_max_ps(scaled, _mm256_setzero_ps()), hundred);
        let score = _mm256_cvttps_epi32(clamped);
        // SAFETY: every score lane is in 0..=100 and `floors` has 101 values.
        let floor = unsafe { _mm256_i32gather_ps::<4>(floors.as_ptr(), score) };
        let may_enter = _mm256_cmp_ps::<_CMP_GE_OQ>(approx, _mm256_sub_ps(floor, floor_slack));
        mask |= (_mm256_movemask_ps(_mm256_or_ps(near, may_enter)) as u32) << (8 * part);
        // SAFETY: see above.
        unsafe {
            _mm256_storeu_si256(scores.as_mut_ptr().add(8 * part).cast::<__m256i>(), score);
        }
    }
    mask
}


/// The view pass's [`classify_avx2`]: one floor for every score (the row's
/// best entries, `floor` being their floor less `eps`), and instead of a
/// histogram the lowest and highest scores of the lanes it settles, per lane,
/// into `range` (8 lowest, then 8 highest). Lanes near a score step are left
/// out of `range`: their f32 score may be wrong, and they are visited.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn classify_view_avx2(
    dots: &[f32; LANES],
    floor: f32,
    margin: f32,
    range: &mut [i32; LANES],
) -> u32 {
    use std::arch::x86_64::{
        __m256i, _mm256_add_ps, _mm256_andnot_ps, _mm256_blendv_epi8, _mm256_castps_si256,
        _mm256_cmp_ps, _mm256_cvttps_epi32, _mm256_loadu_ps, _mm256_loadu_si256, _mm256_max_epi32,
        _mm256_max_ps, _mm256_min_epi32, _mm256_min_ps, _mm256_movemask_ps, _mm256_mul_ps,
        _mm256_or_ps, _mm256_round_ps, _mm256_set1_epi32, _mm256_set1_ps, _mm256_setzero_ps,
        _mm256_setzero_si256, _mm256_storeu_si256, _mm256_sub_ps, _CMP_GE_OQ, _CMP_LT_OQ,
        _MM_FROUND_NO_EXC, _MM_FROUND_TO_NEAREST_INT,
    };
    let half = _mm256_set1_ps(0.5);
    let hundred = _mm256_set1_ps(100.0);
    let near_margin = _mm256_set1_ps(margin + 1e-4);
    // The f32 rounding of `approx` and of the floor (see `classify_avx2`).
    let floor = _mm256_set1_ps(floor - 1e-6);
    let sign = _mm256_set1_ps(-0.0);
    let top = _mm256_set1_epi32(100);
    // SAFETY: `range` holds 16 values, two halves of eight.
    let (mut lowest, mut highest) = unsafe {
        (
            _mm256_loadu_si256(range.as_ptr().cast::<__m256i>()),
            _mm256_loadu_si256(range.as_ptr().add(8).cast::<__m256i>()),
        )
    };
    let mut mask = 0u32;
    for part in 0..2 {
        // SAFETY: `dots` holds 16 values, two halves of eight.
        let dot = unsafe { _mm256_loadu_ps(dots.as_ptr().add(8 * part)) };
        let approx = _mm256_add_ps(_mm256_mul_ps(dot, half), half);
        let scaled = _mm256_mul_ps(approx, hundred);
        let nearest = _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(scaled);
        let distance = _mm256_andnot_ps(sign, _mm256_sub_ps(scaled, nearest));
        let near = _mm256_cmp_ps::<_CMP_LT_OQ>(distance, near_margin);
        let clamped = _mm256_min_ps(_mm256_max_ps(scaled, _mm256_setzero_ps()), hundred);
        let score = _mm256_cvttps_epi32(clamped);
        let near_bits = _mm256_castps_si256(near);
        lowest = _mm256_min_epi32(lowest, _mm256_blendv_epi8(score, top, near_bits));
        highest = _mm256_max_epi32(highest, _mm256_blendv_epi8(score, _mm256_setzero_si256(), near_bits));
        let may_enter = _mm256_cmp_ps::<_CMP_GE_OQ>(approx, floor);
        mask |= (_mm256_movemask_ps(_mm256_or_ps(near, may_enter)) as u32) << (8 * part);
    }
    // SAFETY: see above.
    unsafe {
        _mm256_storeu_si256(range.as_mut_ptr().cast::<__m256i>(), lowest);
        _mm256_storeu_si256(range.as_mut_ptr().add(8).cast::<__m256i>(), highest);
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::super::rows::exact_bins;
    use super::*;
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

    /// A root with one child per vector.
    fn level_of(vectors: &[Vec<f64>]) -> Dataset {
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for (i, v) in vectors.iter().enumerate() {
            builder.add(
                NodeSpec::new(format!("n{i}"))
                    .parent("r")
                    .weight(1.0)
                    .features(v.clone()),
            );
        }
        builder.build().expect("valid")
    }

    /// Vectors that stress every decision of the filter: 2-d unit vectors whose
    /// cosines with the first one fall exactly on score steps and on either side
    /// of them, exact duplicates (ties broken by level order) and scaled copies,
    /// a crowd of 40 identical vectors (pruning among ties), a zero vector and
    /// one of norm 1e-150 (the zero vector exact-only, the tiny one rescaled), then pseudo-random vectors so that
    /// every score holds far more than a head.
    fn hard_vectors(random: usize) -> Vec<Vec<f64>> {
        let mut vectors = vec![vec![1.0, 0.0]];
        // Random vectors first, so the first row's heads are full (and pruned)
        // when the vectors on the steps arrive.
        let mut state = 99u64;
        for _ in 0..random {
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 33) as f64) / f64::from(u32::MAX) - 0.5
            };
            vectors.push(vec![next(), next()]);
        }
        for k in 0..=100 {
            // cos θ = 2·(k/100) − 1: the rescaled similarity is k/100, and the
            // shifts put it just below or above the step, closer than f32 sees.
            let c = 2.0 * (f64::from(k) / 100.0) - 1.0;
            for shift in [0.0, 1e-9, -1e-9, -3e-8, 1e-7, -1e-7, 1e-5] {
                let c = (c + shift).clamp(-1.0, 1.0);
                vectors.push(vec![c, (1.0 - c * c).sqrt()]);
            }
        }
        for _ in 0..40 {
            vectors.push(vec![0.6, 0.8]);
        }
        vectors.push(vec![3.0, 4.0]);
        vectors.push(vec![0.0, 0.0]);
        vectors.push(vec![1e-150, 2e-150]);
        vectors
    }

    /// Every row's bins through the filter equal the exact scan's, bit for bit,
    /// for both dot-product measures, on 2-d and 37-d vectors (2-d puts hundreds
    /// of pairs on each score, so heads fill, prune and tie).
    #[test]
    fn filtered_bins_equal_the_exact_scan() {
        let wide: Vec<Vec<f64>> = hard_vectors(300)
            .iter()
            .enumerate()
            .map(|(i, v)| {
                // Scaled by the vector's own size, so the zero and the tiny
                // vector stay what they are.
                let size = v[0].abs().max(v[1].abs());
                let mut w = v.clone();
                w.extend((0..35).map(|k| size * (((i * 7 + k * 13) % 17) as f64 / 17.0 - 0.4)));
                w
            })
            .collect();
        for vectors in [hard_vectors(3000), wide] {
            let p = level_of(&vectors);
            let level: Vec<usize> = (1..p.len()).collect();
            for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson] {
                let features: Vec<NodeFeatures<'_>> = level
                    .iter()
                    .map(|&n| NodeFeatures::new(kind, &p, n))
                    .collect();
                let filter = Filter::new(kind, &features).expect("a filter for this level");
                let rows: Vec<usize> = (0..level.len()).filter(|&i| !filter.is_exact(i)).collect();
                // The zero vector takes the exact path; the tiny one is
                // rescaled before its norm (issue 21) and is filtered like
                // any other.
                assert!(
                    rows.len() < level.len(),
                    "{kind:?}: the zero vector is exact"
                );
                let mut state = Scratch::default();
                // Tiles of 5 rows (groups of the 4-row kernel and a remainder):
                // the first rows, and every 41st row after them.
                let sample: Vec<usize> = rows
                    .iter()
                    .copied()
                    .filter(|&i| i < 10 || i % 41 == 0)
                    .collect();
                for tile in sample.chunks(5) {
                    let fast = filter.bin_rows(kind, &features, &level, tile, &mut state);
                    for (&i, bins) in tile.iter().zip(&fast) {
                        let slow = stage_view(&exact_bins(kind, &features, &level, i));
                        assert_eq!(bins, &slow, "{kind:?} row {i}");
                    }
                }
            }
        }
    }

    /// A row whose view needs more than its 12 best entries: one duplicate
    /// (score 100) alone in the top bin, over four crowded bins that Stage C
    /// reads. Its view comes from the second scan, and equals the exact
    /// scan's, as every other row's does.
    #[test]
    fn a_small_top_bin_over_crowded_bins_is_scanned_again() {
        let mut vectors = vec![vec![1.0, 0.0], vec![1.0, 0.0]];
        for k in 0..300 {
            // Similarities spread over [0, 0.78): scores 0 to 77.
            let c = 2.0 * (0.78 * f64::from(k) / 300.0) - 1.0;
            vectors.push(vec![c, (1.0 - c * c).sqrt()]);
        }
        let p = level_of(&vectors);
        let level: Vec<usize> = (1..p.len()).collect();
        let kind = SimilarityKind::Cosine;
        let features: Vec<NodeFeatures<'_>> =
            level.iter().map(|&n| NodeFeatures::new(kind, &p, n)).collect();
        let filter = Filter::new(kind, &features).expect("a filter for this level");
        let rows: Vec<usize> = (0..level.len()).collect();
        let views = filter.bin_rows(kind, &features, &level, &rows, &mut Scratch::default());
        for (&i, view) in rows.iter().zip(&views) {
            assert_eq!(view, &stage_view(&exact_bins(kind, &features, &level, i)), "row {i}");
        }
        let needed: usize = views[0].bins.iter().map(|b| b.head.len()).sum();
        assert!(
            needed > super::super::row_best::WANTED && views[0].bins.len() == 5,
            "row 0 reads {needed} entries in {} bins",
            views[0].bins.len()
        );
    }

    /// Only cosine and Pearson levels of equal-length vectors get a filter, and
    /// not one where most nodes would need the exact path.
    #[test]
    fn filters_only_levels_it_can_serve() {
        let p = level_of(&[vec![1.0, 0.0], vec![0.0, 1.0], vec![1.0, 1.0]]);
        let features = |kind| {
            (1..p.len())
                .map(|n| NodeFeatures::new(kind, &p, n))
                .collect::<Vec<_>>()
        };
        assert!(Filter::new(SimilarityKind::Cosine, &features(SimilarityKind::Cosine)).is_some());
        assert!(Filter::new(SimilarityKind::Jaccard, &features(SimilarityKind::Jaccard)).is_none());
        let zeros = level_of(&[vec![0.0, 0.0], vec![0.0, 0.0], vec![1.0, 1.0]]);
        let features: Vec<_> = (1..zeros.len())
            .map(|n| NodeFeatures::new(SimilarityKind::Cosine, &zeros, n))
            .collect();
        assert!(Filter::new(SimilarityKind::Cosine, &features).is_none());
    }
}
