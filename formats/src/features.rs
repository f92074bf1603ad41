//! [`Features`]: what a node's similarity is measured on, a dense vector or a
//! [`SparseVector`] (a set of members is a sparse vector whose values are all 1).
//! Both are shared (`Arc`), so copies of a node (the virtual nodes of paper §4)
//! cost a pointer, not a row.
//!
//! A set stays a set from the reader to the constraints (issue 23): a genre
//! table's genres, a hierarchy JSON list of strings, or a Jaccard file's 0/1
//! vectors are kept as sorted member ids, never as a one-hot row over every
//! member. The similarities and projections read them without densifying and
//! give what the dense 0/1 vector over the same members would give.

use std::sync::Arc;

/// The feature data of one node ([`crate::Node::features`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Features {
    /// A dense vector: embedding rows, time series. Every value is finite.
    Dense(Arc<[f64]>),
    /// A sparse vector: sets of members (genres, included names) and their
    /// bottom-up means (paper §4).
    Sparse(SparseVector),
}

impl Features {
    /// The number of coordinates: a dense vector's length, a sparse vector's
    /// dimension (for a set, the number of distinct members of the dataset).
    pub fn len(&self) -> usize {
        match self {
            Features::Dense(values) => values.len(),
            Features::Sparse(sparse) => sparse.len(),
        }
    }

    /// True when there are no coordinates at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The dense vector, when this is one.
    pub fn as_dense(&self) -> Option<&[f64]> {
        match self {
            Features::Dense(values) => Some(values),
            Features::Sparse(_) => None,
        }
    }

    /// The sparse vector, when this is one.
    pub fn as_sparse(&self) -> Option<&SparseVector> {
        match self {
            Features::Dense(_) => None,
            Features::Sparse(sparse) => Some(sparse),
        }
    }

    /// Every coordinate as a dense vector (zeros included): for small data and
    /// tests; a set over many members is long.
    pub fn to_dense(&self) -> Vec<f64> {
        match self {
            Features::Dense(values) => values.to_vec(),
            Features::Sparse(sparse) => sparse.to_dense(),
        }
    }
}

impl From<Vec<f64>> for Features {
    fn from(values: Vec<f64>) -> Self {
        Features::Dense(values.into())
    }
}

impl From<SparseVector> for Features {
    fn from(sparse: SparseVector) -> Self {
        Features::Sparse(sparse)
    }
}

/// A vector of `len` coordinates stored as its non-zero entries: indices
/// ascending without repeats, each below `len`, values non-zero. A set is the
/// case where every value is 1 ([`SparseVector::set`]), stored without values.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseVector {
    len: u32,
    indices: Arc<[u32]>,
    // `None`: every value is 1 (a set). Never `Some` of all ones, so that
    // equal vectors compare equal.
    values: Option<Arc<[f64]>>,
}

impl SparseVector {
    /// The set of `members` (in any order, repeats allowed) among `len`
    /// members numbered from 0; `None` when a member is `len` or more.
    pub fn set(len: u32, members: impl IntoIterator<Item = u32>) -> Option<Self> {
        let mut indices: Vec<u32> = members.into_iter().collect();
        indices.sort_unstable();
        indices.dedup();
        if indices.last().is_some_and(|&last| last >= len) {
            return None;
        }
        Some(SparseVector {
            len,
            indices: indices.into(),
            values: None,
        })
    }

    /// The vector of `len` coordinates with `entries` (index, value), indices
    /// ascending without repeats; zero values are dropped (so `-0.0` and `0.0`
    /// are both absent). `None` when indices are not ascending or reach `len`.
    pub fn from_entries(len: u32, entries: impl IntoIterator<Item = (u32, f64)>) -> Option<Self> {
        let mut indices = Vec::new();
        let mut values = Vec::new();
        for (index, value) in entries {
            if indices.last().is_some_and(|&last| last >= index) || index >= len {
                return None;
            }
            if value != 0.0 {
                indices.push(index);
                values.push(value);
            }
        }
        let values = (!values.iter().all(|&v| v == 1.0)).then(|| values.into());
        Some(SparseVector {
            len,
            indices: indices.into(),
            values,
        })
    }

    /// The non-zero entries of a dense vector (lossless: the dense vector is
    /// [`SparseVector::to_dense`] of the result, up to the sign of zeros).
    pub fn from_dense(values: &[f64]) -> Self {
        let len = u32::try_from(values.len()).unwrap_or(u32::MAX);
        let entries = values
            .iter()
            .take(len as usize)
            .enumerate()
            .map(|(k, &v)| (k as u32, v));
        // Ascending and below `len` by construction.
        SparseVector::from_entries(len, entries).unwrap_or(SparseVector {
            len: 0,
            indices: Arc::from([]),
            values: None,
        })
    }

    /// The number of coordinates.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when the vector has no coordinates at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The indices of the non-zero entries, ascending (a set's members).
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The non-zero values, parallel to [`SparseVector::indices`]; `None` for a
    /// set (every value 1).
    pub fn values(&self) -> Option<&[f64]> {
        self.values.as_deref()
    }

    /// True when every value is 1.
    pub fn is_set(&self) -> bool {
        self.values.is_none()
    }

    /// The non-zero entries (index, value), indices ascending.
    pub fn entries(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.indices.iter().enumerate().map(move |(k, &index)| {
            let value = self.values.as_ref().map_or(1.0, |values| values[k]);
            (index, value)
        })
    }

    /// Every coordinate, zeros included.
    pub fn to_dense(&self) -> Vec<f64> {
        let mut dense = vec![0.0; self.len()];
        for (index, value) in self.entries() {
            dense[index as usize] = value;
        }
        dense
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_are_sorted_without_repeats_and_bounded() {
        let set = SparseVector::set(5, [3, 1, 3, 0]).expect("valid");
        assert_eq!(set.indices(), [0, 1, 3]);
        assert!(set.is_set());
        assert_eq!(set.to_dense(), [1.0, 1.0, 0.0, 1.0, 0.0]);
        assert_eq!(SparseVector::set(3, [3]), None);
        assert_eq!(Features::from(set.clone()).len(), 5);
    }

    #[test]
    fn dense_round_trips_and_ones_are_a_set() {
        let dense = [0.0, 0.5, -0.0, 2.0];
        let sparse = SparseVector::from_dense(&dense);
        assert_eq!(sparse.indices(), [1, 3]);
        assert_eq!(sparse.values(), Some(&[0.5, 2.0][..]));
        assert_eq!(sparse.to_dense(), [0.0, 0.5, 0.0, 2.0]);
        let ones = SparseVector::from_dense(&[1.0, 0.0, 1.0]);
        assert_eq!(ones, SparseVector::set(3, [0, 2]).expect("valid"));
        assert_eq!(SparseVector::from_entries(3, [(2, 1.0), (1, 1.0)]), None);
    }
}
