//! Neighbourhood preservation, the data side: similarity between nodes, the
//! preparation of a hierarchy (virtual nodes, aggregation), the constraint
//! pipeline of the paper (method-reference §3), 2-D projections and assignment
//! (Kuhn–Munkres). Knows datasets, not layouts (adjacency of cells is
//! [`crate::geom::adjacency`]'s, the paper's metrics [`crate::measure`]'s).
//! Pure: no I/O.
/// A node's similarity bins (§3.1–3.2).
mod bins;
/// An exact nearest-neighbour index of unit vectors: spherical caps.
mod cap_index;
/// The virtual copies' bins, derived from their leaves' similarities.
mod copies;
/// The constraint pipeline's results and its order (stages A to E).
pub mod constraints;
/// Rows of identical vectors binned once, the others derived.
mod duplicate_rows;
/// The dot-product kernels of the dense similarity rows (one AVX dispatch).
mod kernels;
/// Exact bins of dense cosine and Pearson rows through an f32 filter.
mod filtered_rows;
/// Stage views of large dense levels from the nearest-neighbour index.
mod knn_rows;
/// Assignment: Kuhn–Munkres, and recursive bisection for large groups.
pub mod matching;
/// Exact rescaling by the largest power of two below a value.
mod pow2;
/// Virtual nodes for uniform depth and bottom-up aggregation (paper §4).
pub mod prepare;
/// 2-D projections: PCA of feature vectors, classical (landmark) MDS of a dissimilarity.
pub mod projection;
/// Similarity functions between two nodes.
pub mod similarity;
/// A level's similarity rows, binned: sparse, filtered or exact dense.
mod rows;
/// A row's best entries, kept as it is scanned, and the stage view they give.
mod row_best;
/// A row over some columns reduced to what binning reads; rows from parts.
mod score_tops;
/// Exact similarity rows without all-pairs work for the sparse measures.
mod sparse_rows;
/// Stages A to D: from bins to directed and symmetric lists.
mod stages;

pub use constraints::{build_constraints, Constraint};
pub use prepare::prepare;
#[cfg(any(feature = "cli", feature = "watch", feature = "internals"))]
pub use prepare::reweigh;
pub use similarity::SimilarityKind;
