//! Similarity between two nodes of a dataset (method-reference §1.4) and the integer
//! score the constraint pipeline works on (§1.5). Owns the floating-point form of
//! every measure, because the golden constraint counts depend on it bit for bit.
//!
//! Sparse features (sets and their means, [`nptreemap_formats::SparseVector`])
//! are read as they are stored: their cosine, Jaccard and binary similarities
//! are those of the dense vectors they stand for, bit for bit (the dense sums
//! only add exact zeros between the non-zero terms); Pearson, whose centring
//! makes every coordinate non-zero, is the same correlation summed in another
//! order (equal up to the last bits). A dense and a sparse vector are never
//! compared (no reader mixes them): like vectors of different lengths, they
//! give 0.

use std::borrow::Cow as Borrowed;

use nptreemap_formats::{Dataset, Features, SimilarityHint, SparseVector};

/// How the similarity of two nodes is measured. Every measure gives a value in
/// [0, 1]; undefined cases (zero vectors, two empty supports, a missing vector,
/// vectors of different lengths, constant series) give 0 (method-reference §10 #3).
///
/// Named in configs (`similarity:`) and on the command line (`--similarity`)
/// as `cosine`, `jaccard`, `binary`, `neighbors` and `pearson`.
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum SimilarityKind {
    /// Cosine of the feature vectors, rescaled from [-1, 1] to [0, 1].
    Cosine,
    /// Jaccard index of the feature vectors' non-zero supports.
    Jaccard,
    /// 1 when the two feature vectors are equal element by element, else 0.
    Binary,
    /// 1 when the second node is among the first node's relations, else 0.
    /// Directed, as the prototype's `useNeighborLeafs` flag (§1.4); the constraint
    /// pipeline symmetrises later (§3.6).
    #[serde(rename = "neighbors")]
    #[cfg_attr(feature = "cli", value(name = "neighbors"))]
    NeighborList,
    /// Pearson correlation of the feature vectors (for example rows of a time
    /// series), rescaled from [-1, 1] to [0, 1].
    Pearson,
}

impl SimilarityKind {
    /// The measure a dataset's own hint asks for.
    pub fn from_hint(hint: SimilarityHint) -> Self {
        match hint {
            SimilarityHint::Cosine => SimilarityKind::Cosine,
            SimilarityHint::Jaccard => SimilarityKind::Jaccard,
            SimilarityHint::Binary => SimilarityKind::Binary,
            SimilarityHint::NeighborList => SimilarityKind::NeighborList,
            SimilarityHint::Pearson => SimilarityKind::Pearson,
        }
    }

    /// The measure for `dataset`: its hint, else cosine (the prototype's default
    /// `similarityMeasure`, §1.1).
    pub fn for_dataset(dataset: &Dataset) -> Self {
        dataset
            .similarity_hint()
            .map_or(SimilarityKind::Cosine, SimilarityKind::from_hint)
    }
}

/// The similarity of nodes `a` and `b` of `dataset`, in [0, 1].
///
/// For [`SimilarityKind::NeighborList`] this is directed: 1 when `b` is in the
/// relations of `a`. Indices must come from `dataset` (panics otherwise, like slice
/// indexing). Undefined cases give 0.
pub fn similarity(kind: SimilarityKind, dataset: &Dataset, a: usize, b: usize) -> f64 {
    let fa = NodeFeatures::new(kind, dataset, a);
    let fb = NodeFeatures::new(kind, dataset, b);
    clamp_unit(pair_similarity(kind, &fa, &fb, b))
}

/// The integer score of a similarity, `floor(100·s)` clamped to 0..=100
/// (method-reference §1.5); NaN gives 0.
pub fn score(s: f64) -> u8 {
    let scaled = 100.0 * s;
    // NaN is caught first. For values in (0, 100) the cast truncates, which is
    // `floor` for positive numbers (and avoids a libm call per pair).
    if scaled.is_nan() || scaled <= 0.0 {
        0
    } else if scaled >= 100.0 {
        100
    } else {
        scaled as u8
    }
}

/// Clamps to [0, 1] for callers; the pipeline sorts on the unclamped value so that,
/// like the prototype, a cosine of 1 + 1 ulp still sorts ahead of an exact 1.
pub(crate) fn clamp_unit(s: f64) -> f64 {
    if s.is_nan() {
        0.0
    } else {
        s.clamp(0.0, 1.0)
    }
}

/// What one node contributes to a similarity, computed once per node so that the
/// all-pairs loop of the constraint pipeline allocates nothing per pair.
#[derive(Clone, Debug)]
pub(crate) struct NodeFeatures<'a> {
    /// The number of coordinates, when the node has features.
    len: Option<usize>,
    /// The dense vector (centred for Pearson, rescaled for cosine); `None` when
    /// missing or sparse.
    values: Option<Cow<'a>>,
    /// The sparse vector (values rescaled for cosine); `None` when missing or dense.
    sparse: Option<Sparse<'a>>,
    /// Euclidean norm of the vector (centred for Pearson), summed left to right
    /// from 0 (cosine, Pearson).
    norm: f64,
    /// Mean of all coordinates of a sparse vector (Pearson).
    mean: f64,
    /// Sorted positions of the non-zero values (Jaccard; a sparse vector's own).
    support: Borrowed<'a, [u32]>,
    /// Sorted relation targets (neighbour list).
    relations: &'a [usize],
}

/// A sparse vector as one similarity reads it.
#[derive(Clone, Debug)]
struct Sparse<'a> {
    indices: &'a [u32],
    /// `None`: every value is 1 (a set).
    values: Option<Cow<'a>>,
}

impl Sparse<'_> {
    /// The value of the `k`-th stored entry.
    fn value(&self, k: usize) -> f64 {
        self.values.as_ref().map_or(1.0, |v| v.as_slice()[k])
    }
}

/// A borrowed vector, or an owned one when it had to be transformed (centred).
#[derive(Clone, Debug)]
enum Cow<'a> {
    Borrowed(&'a [f64]),
    Owned(Vec<f64>),
}

impl Cow<'_> {
    fn as_slice(&self) -> &[f64] {
        match self {
            Cow::Borrowed(values) => values,
            Cow::Owned(values) => values,
        }
    }
}

/// Sum of squares, left to right from 0 (§1.4: the order matters for the goldens).
fn squared_norm(values: &[f64]) -> f64 {
    let mut sum = 0.0;
    for &v in values {
        sum += v * v;
    }
    sum
}

/// Largest components a vector keeps as it is (2⁻²⁰⁰ to 2²⁰⁰): their squares,
/// sums of up to a million of them and products of two norms stay far from
/// f64's underflow (2⁻¹⁰²²) and overflow (2¹⁰²⁴), so cosine and Pearson come
/// out as the literal formula gives them, bit for bit (§1.4).
const PLAIN_SCALE: std::ops::RangeInclusive<f64> = 6.223_015_277_861_142e-61..=1.606_938_044_258_990_3e60;

/// `values` times the power of two that brings its largest component into
/// [0.5, 1), when that component lies outside [`PLAIN_SCALE`]; `None` when
/// the vector is fine as it is (or all zeros, which has no direction at any
/// scale). Cosine and Pearson do not depend on a vector's scale, and a power
/// of two changes no bit of a value, so this gives the similarities of the
/// unscaled vectors; without it the squared norm of a vector of 1e-200s
/// underflowed to 0 and the vector counted as a zero vector (issue 21).
fn rescaled(values: &[f64]) -> Option<Vec<f64>> {
    let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if largest == 0.0 || !largest.is_finite() || PLAIN_SCALE.contains(&largest) {
        return None;
    }
    // Two factors, each a power of two within f64's range: the one factor for
    // the smallest subnormals (2⁻¹⁰⁷⁴) would overflow.
    let exponent = largest.log2().floor() as i32 + 1;
    let first = -exponent / 2;
    let (a, b) = (2f64.powi(first), 2f64.powi(-exponent - first));
    Some(values.iter().map(|v| v * a * b).collect())
}

impl<'a> NodeFeatures<'a> {
    /// Precomputes what `kind` needs from node `index`.
    pub(crate) fn new(kind: SimilarityKind, dataset: &'a Dataset, index: usize) -> Self {
        let node = dataset.node(index);
        let mut result = NodeFeatures {
            len: None,
            values: None,
            sparse: None,
            norm: 0.0,
            mean: 0.0,
            support: Borrowed::Borrowed(&[]),
            relations: &node.relations,
        };
        match &node.features {
            None => {}
            Some(Features::Dense(values)) => result.dense(kind, values),
            Some(Features::Sparse(sparse)) => result.sparse(kind, sparse),
        }
        result
    }

    /// Fills in what `kind` needs from a dense vector.
    fn dense(&mut self, kind: SimilarityKind, values: &'a [f64]) {
        self.len = Some(values.len());
        match kind {
            SimilarityKind::Cosine => {
                let values = match rescaled(values) {
                    Some(scaled) => Cow::Owned(scaled),
                    None => Cow::Borrowed(values),
                };
                self.norm = squared_norm(values.as_slice()).sqrt();
                self.values = Some(values);
            }
            SimilarityKind::Jaccard => {
                self.support = Borrowed::Owned(
                    values
                        .iter()
                        .enumerate()
                        .filter(|(_, &v)| v != 0.0)
                        .map(|(i, _)| i as u32)
                        .collect(),
                );
                self.values = Some(Cow::Borrowed(values));
            }
            SimilarityKind::Binary => self.values = Some(Cow::Borrowed(values)),
            SimilarityKind::NeighborList => {}
            SimilarityKind::Pearson => {
                let mut sum = 0.0;
                for &v in values {
                    sum += v;
                }
                let mean = if values.is_empty() {
                    0.0
                } else {
                    sum / values.len() as f64
                };
                let centered: Vec<f64> = values.iter().map(|&v| v - mean).collect();
                let centered = rescaled(&centered).unwrap_or(centered);
                self.norm = squared_norm(&centered).sqrt();
                self.values = Some(Cow::Owned(centered));
            }
        }
    }

    /// Fills in what `kind` needs from a sparse vector, without densifying it.
    fn sparse(&mut self, kind: SimilarityKind, sparse: &'a SparseVector) {
        let len = sparse.len();
        self.len = Some(len);
        let stored = sparse.values().map(Cow::Borrowed);
        let mut view = Sparse {
            indices: sparse.indices(),
            values: stored,
        };
        match kind {
            SimilarityKind::Cosine => {
                // The dense sum of squares adds exact zeros between these terms.
                if let Some(scaled) = sparse.values().and_then(rescaled) {
                    view.values = Some(Cow::Owned(scaled));
                }
                self.norm = match &view.values {
                    Some(values) => squared_norm(values.as_slice()).sqrt(),
                    None => (view.indices.len() as f64).sqrt(),
                };
            }
            SimilarityKind::Jaccard => self.support = Borrowed::Borrowed(sparse.indices()),
            SimilarityKind::Binary | SimilarityKind::NeighborList => {}
            SimilarityKind::Pearson => {
                let mut sum = 0.0;
                for k in 0..view.indices.len() {
                    sum += view.value(k);
                }
                self.mean = if len == 0 { 0.0 } else { sum / len as f64 };
                let mut squares = 0.0;
                for k in 0..view.indices.len() {
                    let c = view.value(k) - self.mean;
                    squares += c * c;
                }
                let zeros = (len - view.indices.len()) as f64;
                self.norm = (squares + zeros * self.mean * self.mean).sqrt();
            }
        }
        self.sparse = Some(view);
    }

    /// The dense vector, when present.
    pub(crate) fn values(&self) -> Option<&[f64]> {
        self.values.as_ref().map(Cow::as_slice)
    }

    /// The number of coordinates, when the node has features.
    pub(crate) fn len(&self) -> Option<usize> {
        self.len
    }

    /// Sorted positions of the non-zero values (computed for Jaccard only).
    pub(crate) fn support(&self) -> &[u32] {
        &self.support
    }

    /// Sorted relation targets (dataset indices).
    pub(crate) fn relations(&self) -> &[usize] {
        self.relations
    }

    /// What decides binary equality, as words: equal keys, equal vectors
    /// (−0 folded into 0; lengths and kinds, dense or sparse, included).
    /// `None` when the node has no vector or a NaN, which equals nothing.
    pub(crate) fn binary_key(&self) -> Option<Vec<u64>> {
        let bits = |x: f64| if x == 0.0 { 0 } else { x.to_bits() };
        if let Some(v) = self.values() {
            if v.iter().any(|x| x.is_nan()) {
                return None;
            }
            let mut key = Vec::with_capacity(v.len() + 2);
            key.extend([0, v.len() as u64]);
            key.extend(v.iter().map(|&x| bits(x)));
            return Some(key);
        }
        let sparse = self.sparse.as_ref()?;
        let mut key = Vec::with_capacity(2 * sparse.indices.len() + 2);
        key.extend([1, self.len.unwrap_or(0) as u64]);
        for (k, &index) in sparse.indices.iter().enumerate() {
            key.extend([u64::from(index), bits(sparse.value(k))]);
        }
        Some(key)
    }
}

/// Dot product, left to right from 0 (§1.4).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut sum = 0.0;
    for (x, y) in a.iter().zip(b) {
        sum += x * y;
    }
    sum
}

/// The cosine-type rescaling `(c − (−1)) / (1 − (−1))`, written literally (§1.4).
fn rescale(c: f64) -> f64 {
    (c - (-1.0)) / (1.0 - (-1.0))
}

/// The rescaled cosine from a dot product and two norms; NaN (a zero norm) gives 0.
pub(crate) fn cosine_from_parts(dot: f64, norm_a: f64, norm_b: f64) -> f64 {
    let s = rescale(dot / (norm_a * norm_b));
    if s.is_nan() {
        0.0
    } else {
        s
    }
}

/// Norm used by [`cosine_from_parts`] for this node (the Euclidean norm).
pub(crate) fn norm_of(features: &NodeFeatures<'_>) -> f64 {
    features.norm
}

/// A vector measure before clamping, NaN already mapped to 0 (the neighbour flag,
/// which needs node indices, is [`neighbor_flag`]).
fn vector_similarity(kind: SimilarityKind, a: &NodeFeatures<'_>, b: &NodeFeatures<'_>) -> f64 {
    if kind == SimilarityKind::NeighborList || a.len.is_none() || a.len != b.len {
        // Missing vectors and different lengths have no defined similarity;
        // treat as unrelated.
        return 0.0;
    }
    if let (Some(sa), Some(sb)) = (&a.sparse, &b.sparse) {
        return sparse_similarity(kind, a, sa, b, sb);
    }
    let (Some(va), Some(vb)) = (a.values(), b.values()) else {
        // A dense and a sparse vector are unrelated (module docs).
        return 0.0;
    };
    match kind {
        SimilarityKind::Cosine | SimilarityKind::Pearson => {
            cosine_from_parts(dot(va, vb), a.norm, b.norm)
        }
        SimilarityKind::Jaccard => jaccard(&a.support, &b.support),
        SimilarityKind::Binary => {
            // `==` on f64 treats -0 and 0 as equal, as the prototype's JSON-string
            // comparison does (JSON.stringify(-0) is "0").
            if va.iter().zip(vb).all(|(x, y)| x == y) {
                1.0
            } else {
                0.0
            }
        }
        SimilarityKind::NeighborList => 0.0,
    }
}

/// [`vector_similarity`] of two sparse vectors of one length (module docs).
fn sparse_similarity(
    kind: SimilarityKind,
    a: &NodeFeatures<'_>,
    sa: &Sparse<'_>,
    b: &NodeFeatures<'_>,
    sb: &Sparse<'_>,
) -> f64 {
    match kind {
        SimilarityKind::Cosine => {
            // Products in ascending index order: the dense sum with its zero
            // terms left out, which changes no bit.
            let mut sum = 0.0;
            merge(sa.indices, sb.indices, |i, j| {
                if let (Some(i), Some(j)) = (i, j) {
                    sum += sa.value(i) * sb.value(j);
                }
            });
            cosine_from_parts(sum, a.norm, b.norm)
        }
        SimilarityKind::Pearson => {
            let (ma, mb) = (a.mean, b.mean);
            let (mut sum, mut union) = (0.0, 0usize);
            merge(sa.indices, sb.indices, |i, j| {
                union += 1;
                let x = i.map_or(0.0, |i| sa.value(i)) - ma;
                let y = j.map_or(0.0, |j| sb.value(j)) - mb;
                sum += x * y;
            });
            let len = a.len.unwrap_or(0);
            sum += (len - union) as f64 * (ma * mb);
            cosine_from_parts(sum, a.norm, b.norm)
        }
        SimilarityKind::Jaccard => jaccard(sa.indices, sb.indices),
        SimilarityKind::Binary => {
            let same = sa.indices == sb.indices
                && (0..sa.indices.len()).all(|k| sa.value(k) == sb.value(k));
            if same {
                1.0
            } else {
                0.0
            }
        }
        SimilarityKind::NeighborList => 0.0,
    }
}

/// Walks two ascending index lists together, calling `visit` once per index of
/// either, with its position in each list (`None` where it is absent).
fn merge(a: &[u32], b: &[u32], mut visit: impl FnMut(Option<usize>, Option<usize>)) {
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        match (a.get(i), b.get(j)) {
            (Some(x), Some(y)) if x == y => {
                visit(Some(i), Some(j));
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x < y => {
                visit(Some(i), None);
                i += 1;
            }
            (Some(_), None) => {
                visit(Some(i), None);
                i += 1;
            }
            _ => {
                visit(None, Some(j));
                j += 1;
            }
        }
    }
}

/// 1 when `b` is among the relations of the node described by `a` (directed,
/// method-reference §1.4).
pub(crate) fn neighbor_flag(a: &NodeFeatures<'_>, b: usize) -> f64 {
    if a.relations.binary_search(&b).is_ok() {
        1.0
    } else {
        0.0
    }
}

/// Jaccard similarity of two sorted supports, in the literal form
/// `1 − (nz − eq)/nz` that reproduces Flare's 547 (§1.4: `eq/nz` rounds
/// differently, e.g. 1/5 gives 0.2 instead of 0.19999…). Two empty supports: 0.
pub(crate) fn jaccard(a: &[u32], b: &[u32]) -> f64 {
    let (mut i, mut j, mut eq) = (0, 0, 0usize);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                eq += 1;
                i += 1;
                j += 1;
            }
        }
    }
    let nz = a.len() + b.len() - eq;
    if nz == 0 {
        return 0.0;
    }
    1.0 - (nz - eq) as f64 / nz as f64
}

/// The similarity of two precomputed nodes before clamping, NaN mapped to 0; `b`
/// is at dataset index `b_index` (the directed neighbour flag needs it). The
/// pipeline sorts on this value (§3.1).
pub(crate) fn pair_similarity(
    kind: SimilarityKind,
    a: &NodeFeatures<'_>,
    b: &NodeFeatures<'_>,
    b_index: usize,
) -> f64 {
    if kind == SimilarityKind::NeighborList {
        neighbor_flag(a, b_index)
    } else {
        vector_similarity(kind, a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// A root with one child per vector (`None` = no vector), ids "n0", "n1", ...
    fn dataset(vectors: &[Option<Vec<f64>>]) -> Dataset {
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("r"));
        for (i, v) in vectors.iter().enumerate() {
            let mut spec = NodeSpec::new(format!("n{i}")).parent("r").weight(1.0);
            if let Some(v) = v {
                spec = spec.features(v.clone());
            }
            builder.add(spec);
        }
        builder.build().expect("valid")
    }

    fn sim(kind: SimilarityKind, a: Vec<f64>, b: Vec<f64>) -> f64 {
        let d = dataset(&[Some(a), Some(b)]);
        similarity(kind, &d, 1, 2)
    }

    #[test]
    fn cosine_is_rescaled_to_unit_interval() {
        assert_eq!(
            sim(SimilarityKind::Cosine, vec![1.0, 0.0], vec![1.0, 0.0]),
            1.0
        );
        assert_eq!(
            sim(SimilarityKind::Cosine, vec![1.0, 0.0], vec![0.0, 2.0]),
            0.5
        );
        assert_eq!(
            sim(SimilarityKind::Cosine, vec![1.0, 0.0], vec![-3.0, 0.0]),
            0.0
        );
        let s = sim(SimilarityKind::Cosine, vec![1.0, 1.0], vec![1.0, 0.0]);
        assert!((s - (1.0 + 0.5f64.sqrt()) / 2.0).abs() < 1e-15);
    }

    #[test]
    fn cosine_follows_the_literal_formula_bit_for_bit() {
        let a = vec![0.8, 0.3, 0.3, 1.0, 0.5];
        let b = vec![0.3, 0.5, 1.0, 0.3, 0.3];
        let mut dot = 0.0;
        let (mut na, mut nb) = (0.0f64, 0.0f64);
        for k in 0..a.len() {
            dot += a[k] * b[k];
            na += a[k] * a[k];
            nb += b[k] * b[k];
        }
        let expected = (dot / (na.sqrt() * nb.sqrt()) - (-1.0)) / (1.0 - (-1.0));
        assert_eq!(
            sim(SimilarityKind::Cosine, a, b).to_bits(),
            expected.to_bits()
        );
    }

    #[test]
    fn nan_cases_are_zero() {
        // A zero vector (Australia's is all zeros).
        assert_eq!(
            sim(SimilarityKind::Cosine, vec![0.0, 0.0], vec![1.0, 0.0]),
            0.0
        );
        // Two empty supports (Flare's MergeEdge).
        assert_eq!(
            sim(SimilarityKind::Jaccard, vec![0.0, 0.0], vec![0.0, 0.0]),
            0.0
        );
        // Constant series.
        assert_eq!(
            sim(
                SimilarityKind::Pearson,
                vec![2.0, 2.0, 2.0],
                vec![1.0, 2.0, 3.0]
            ),
            0.0
        );
        // Different lengths.
        assert_eq!(sim(SimilarityKind::Cosine, vec![1.0], vec![1.0, 0.0]), 0.0);
        // Missing vectors, for every kind.
        let d = dataset(&[None, Some(vec![1.0, 2.0])]);
        for kind in [
            SimilarityKind::Cosine,
            SimilarityKind::Jaccard,
            SimilarityKind::Binary,
            SimilarityKind::NeighborList,
            SimilarityKind::Pearson,
        ] {
            assert_eq!(similarity(kind, &d, 1, 2), 0.0, "{kind:?}");
            assert_eq!(similarity(kind, &d, 2, 1), 0.0, "{kind:?}");
        }
        // Empty vectors.
        assert_eq!(sim(SimilarityKind::Cosine, vec![], vec![]), 0.0);
        assert_eq!(sim(SimilarityKind::Pearson, vec![], vec![]), 0.0);
    }

    #[test]
    fn jaccard_uses_the_literal_form() {
        // eq = 1, nz = 5: 1 − 4/5 is 0.19999…, score 19, not 20 (§1.4).
        let s = sim(
            SimilarityKind::Jaccard,
            vec![1.0, 1.0, 1.0, 0.0, 0.0],
            vec![1.0, 0.0, 0.0, 1.0, 1.0],
        );
        assert_eq!(s.to_bits(), (1.0 - 4.0f64 / 5.0).to_bits());
        assert!(s < 0.2);
        assert_eq!(score(s), 19);
        assert_eq!(score(1.0 / 5.0), 20);
        // Means of 0/1 vectors: only the support counts.
        let s = sim(
            SimilarityKind::Jaccard,
            vec![0.5, 0.25, 0.0],
            vec![1.0, 0.0, 3.0],
        );
        assert_eq!(s.to_bits(), (1.0 - 2.0f64 / 3.0).to_bits());
        assert_eq!(
            sim(SimilarityKind::Jaccard, vec![0.0, 2.0], vec![0.0, 1.0]),
            1.0
        );
        assert_eq!(
            sim(SimilarityKind::Jaccard, vec![2.0, 0.0], vec![0.0, 1.0]),
            0.0
        );
        // One empty support against a non-empty one: nz > 0, eq = 0.
        assert_eq!(
            sim(SimilarityKind::Jaccard, vec![0.0, 0.0], vec![0.0, 1.0]),
            0.0
        );
    }

    #[test]
    fn binary_is_exact_equality() {
        assert_eq!(
            sim(SimilarityKind::Binary, vec![1.0, 0.0], vec![1.0, 0.0]),
            1.0
        );
        assert_eq!(
            sim(SimilarityKind::Binary, vec![1.0, 0.0], vec![1.0, 1e-12]),
            0.0
        );
        assert_eq!(
            sim(SimilarityKind::Binary, vec![-0.0, 1.0], vec![0.0, 1.0]),
            1.0
        );
        assert_eq!(
            sim(SimilarityKind::Binary, vec![0.0, 0.0], vec![0.0, 0.0]),
            1.0
        );
    }

    #[test]
    fn pearson_is_rescaled_correlation() {
        let up = vec![1.0, 2.0, 3.0, 4.0];
        let s = sim(
            SimilarityKind::Pearson,
            up.clone(),
            vec![2.0, 4.0, 6.0, 8.0],
        );
        assert!((s - 1.0).abs() < 1e-15);
        let s = sim(
            SimilarityKind::Pearson,
            up.clone(),
            vec![4.0, 3.0, 2.0, 1.0],
        );
        assert!(s.abs() < 1e-15);
        let s = sim(SimilarityKind::Pearson, up, vec![1.0, -1.0, -1.0, 1.0]);
        assert!((s - 0.5).abs() < 1e-15);
    }

    #[test]
    fn neighbor_list_is_directed() {
        let mut builder = DatasetBuilder::new();
        builder
            .add(NodeSpec::new("r"))
            .add(NodeSpec::new("a").parent("r").relation("b"))
            .add(NodeSpec::new("b").parent("r"));
        let d = builder.build().expect("valid");
        assert_eq!(similarity(SimilarityKind::NeighborList, &d, 1, 2), 1.0);
        assert_eq!(similarity(SimilarityKind::NeighborList, &d, 2, 1), 0.0);
    }

    #[test]
    fn score_floors_and_clamps() {
        assert_eq!(score(1.0), 100);
        assert_eq!(score(0.999_999), 99);
        assert_eq!(score(0.5), 50);
        assert_eq!(score(0.0), 0);
        assert_eq!(score(-0.3), 0);
        assert_eq!(score(1.5), 100);
        assert_eq!(score(f64::NAN), 0);
        assert_eq!(score(0.0099), 0);
        assert_eq!(score(0.01), 1);
    }

    #[test]
    fn from_hint_maps_every_hint() {
        assert_eq!(
            SimilarityKind::from_hint(SimilarityHint::Cosine),
            SimilarityKind::Cosine
        );
        assert_eq!(
            SimilarityKind::from_hint(SimilarityHint::Jaccard),
            SimilarityKind::Jaccard
        );
        assert_eq!(
            SimilarityKind::from_hint(SimilarityHint::Binary),
            SimilarityKind::Binary
        );
        assert_eq!(
            SimilarityKind::from_hint(SimilarityHint::NeighborList),
            SimilarityKind::NeighborList
        );
        assert_eq!(
            SimilarityKind::for_dataset(&dataset(&[])),
            SimilarityKind::Cosine
        );
    }
    /// Issue 21, item 8: vectors scaled by 1e-200 lost every constraint (66 to
    /// 0 on the probe's data) because their squared norms underflowed to 0,
    /// which the zero-vector rule then took for "no direction". Cosine and
    /// Pearson do not depend on the scale: every scale gives the constraints
    /// of the unscaled vectors (a power of two bit for bit, any other up to
    /// the last bits of the similarities), and a true zero vector stays
    /// unrelated.
    #[test]
    fn constraints_do_not_depend_on_the_scale_of_the_vectors() {
        use crate::neighborhood::{build_constraints, prepare};
        let mut rng = crate::rng::Rng::new(21);
        let base: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                if i == 7 {
                    vec![0.0; 6]
                } else {
                    (0..6).map(|_| rng.next_f64() - 0.3).collect()
                }
            })
            .collect();
        let tree = |scale: f64| {
            let mut b = DatasetBuilder::new();
            b.add(NodeSpec::new("r"));
            for g in 0..4 {
                b.add(NodeSpec::new(format!("g{g}")).parent("r"));
            }
            for (i, v) in base.iter().enumerate() {
                let spec = NodeSpec::new(format!("n{i}"))
                    .parent(format!("g{}", i % 4))
                    .weight(1.0 + i as f64)
                    .features(v.iter().map(|x| x * scale).collect::<Vec<f64>>());
                b.add(spec);
            }
            b.build().expect("valid")
        };
        for kind in [SimilarityKind::Cosine, SimilarityKind::Pearson] {
            let of = |scale: f64| build_constraints(&prepare(&tree(scale)), kind);
            let reference = of(1.0);
            assert!(reference.len() > 20, "{kind:?}: {}", reference.len());
            let n7 = prepare(&tree(1.0)).find("n7").expect("n7");
            let zero = reference.iter().filter(|c| c.a == n7 || c.b == n7);
            assert!(
                zero.clone().all(|c| c.similarity == 0.0),
                "{kind:?}: the zero vector is unrelated"
            );
            let exact = 2f64.powi(-664);
            for scale in [exact, 1e-200, 1e-300, 1e90, 3.7] {
                let scaled = of(scale);
                let key = |c: &crate::neighborhood::Constraint| (c.a, c.b, c.score, c.strength);
                assert_eq!(
                    scaled.iter().map(key).collect::<Vec<_>>(),
                    reference.iter().map(key).collect::<Vec<_>>(),
                    "{kind:?} at scale {scale:e}"
                );
                for (s, r) in scaled.iter().zip(&reference) {
                    if scale == exact {
                        assert_eq!(s.similarity.to_bits(), r.similarity.to_bits());
                    } else {
                        assert!((s.similarity - r.similarity).abs() < 1e-12);
                    }
                }
            }
        }
    }

    /// Issue 23 item 1: a set (member ids) gives the constraints of its dense
    /// 0/1 vector, similarities bit for bit, for Jaccard, cosine and binary, on
    /// three levels (so the sparse means of §2.4 are compared too); Pearson's
    /// sparse sum is the same correlation up to round-off.
    #[test]
    fn sets_give_the_constraints_of_their_dense_vectors() {
        use crate::neighborhood::{build_constraints, prepare, Constraint};
        use nptreemap_formats::SparseVector;
        let width = 9u32;
        let mut rng = crate::rng::Rng::new(23);
        let members: Vec<Vec<u32>> = (0..60)
            .map(|i| {
                if i % 17 == 0 {
                    Vec::new()
                } else {
                    (0..width).filter(|_| rng.next_u64() % 4 == 0).collect()
                }
            })
            .collect();
        let tree = |sparse: bool| {
            let mut b = DatasetBuilder::new();
            b.add(NodeSpec::new("r"));
            for g in 0..3 {
                b.add(NodeSpec::new(format!("g{g}")).parent("r"));
                for h in 0..3 {
                    b.add(NodeSpec::new(format!("g{g}h{h}")).parent(format!("g{g}")));
                }
            }
            for (i, set) in members.iter().enumerate() {
                // Some leaves one level up, so that virtual copies carry them down.
                let parent = if i % 5 == 0 {
                    format!("g{}", i % 3)
                } else {
                    format!("g{}h{}", i % 3, i % 7 % 3)
                };
                let spec = NodeSpec::new(format!("n{i}")).parent(parent).weight(1.0);
                let spec = if sparse {
                    spec.features(SparseVector::set(width, set.iter().copied()).expect("set"))
                } else {
                    let mut dense = vec![0.0; width as usize];
                    for &k in set {
                        dense[k as usize] = 1.0;
                    }
                    spec.features(dense)
                };
                b.add(spec);
            }
            prepare(&b.build().expect("valid"))
        };
        let (dense, sparse) = (tree(false), tree(true));
        assert!(sparse.nodes().iter().all(|n| n.features.as_ref().is_some_and(|f| f.as_sparse().is_some())));
        let key = |c: &Constraint| (c.a, c.b, c.score, c.strength, c.similarity.to_bits());
        for kind in [SimilarityKind::Jaccard, SimilarityKind::Cosine, SimilarityKind::Binary] {
            let want: Vec<_> = build_constraints(&dense, kind).iter().map(key).collect();
            let got: Vec<_> = build_constraints(&sparse, kind).iter().map(key).collect();
            assert!(want.len() > 10, "{kind:?}: {}", want.len());
            assert_eq!(got, want, "{kind:?}");
            for (a, b) in [(1, 2), (4, 30), (40, 41), (0, 3)] {
                assert_eq!(
                    similarity(kind, &sparse, a, b).to_bits(),
                    similarity(kind, &dense, a, b).to_bits(),
                    "{kind:?} {a} {b}"
                );
            }
        }
        for a in 0..dense.len() {
            for b in [1, 5, 17, 33, 60] {
                let (s, d) = (
                    similarity(SimilarityKind::Pearson, &sparse, a, b),
                    similarity(SimilarityKind::Pearson, &dense, a, b),
                );
                assert!((s - d).abs() < 1e-12, "pearson {a} {b}: {s} {d}");
            }
        }
    }
}
