//! The features of a hierarchy JSON document: each node's array as read
//! (`RawFeatures`), then, once the whole file is known, dense vectors, or
//! sets numbered over the file's distinct strings.

use std::collections::{BTreeMap, BTreeSet};

use crate::dataset::{ModelError, NodeSpec};
use crate::error::FormatError;
use crate::features::{Features, SparseVector};
use crate::json_path::{extend, Step};
use crate::limits::{Limit, Limits};

use super::flags::Flags;
use super::reader::{node_path, Origin, Reader};

/// A node's feature array as read, before the file's kind is known.
#[derive(Debug)]
pub(super) enum RawFeatures {
    /// Numbers: a vector (an empty array is this too).
    Numbers(Vec<f64>),
    /// Strings: the names of a set's members.
    Names(Vec<String>),
}

impl Reader<'_> {
    /// Turns every node's feature array into [`Features`] on its spec: sets
    /// when the file lists strings (numbered over all its distinct strings,
    /// sorted) or declares Jaccard, dense vectors otherwise. Returns whether
    /// the file lists strings.
    pub(super) fn set_features(
        &self,
        specs: &mut [NodeSpec],
        raw: Vec<Option<RawFeatures>>,
        flags: &Flags,
        origins: &[Origin],
        limits: &Limits,
    ) -> Result<bool, FormatError> {
        let field = flags.feature_field.as_str();
        if !self.lists_names(specs, &raw, field, origins)? {
            let jaccard = flags.jaccard();
            for (spec, raw) in specs.iter_mut().zip(raw) {
                spec.features = raw.map(|raw| match raw {
                    RawFeatures::Numbers(v) if jaccard => SparseVector::from_dense(&v).into(),
                    RawFeatures::Numbers(v) => v.into(),
                    // Only empty name lists reach here, in a file of vectors.
                    RawFeatures::Names(_) => Vec::new().into(),
                });
            }
            return Ok(false);
        }
        let sets = numbered_sets(&raw, field, limits)?;
        for (spec, features) in specs.iter_mut().zip(sets) {
            spec.features = features;
        }
        Ok(true)
    }

    /// Whether the file's features are strings (sets), from its first
    /// non-empty array. A file mixing numbers and strings is an error at the
    /// first node (in `field`) whose kind differs from the first node's.
    fn lists_names(
        &self,
        specs: &[NodeSpec],
        raw: &[Option<RawFeatures>],
        field: &str,
        origins: &[Origin],
    ) -> Result<bool, FormatError> {
        let is_names = |r: &RawFeatures| matches!(r, RawFeatures::Names(_));
        let non_empty = |r: &&RawFeatures| match r {
            RawFeatures::Numbers(v) => !v.is_empty(),
            RawFeatures::Names(v) => !v.is_empty(),
        };
        let mut kinds = raw.iter().enumerate().filter_map(|(i, r)| {
            r.as_ref()
                .filter(|r| non_empty(r))
                .map(|r| (i, is_names(r)))
        });
        let first = kinds.next();
        let names = first.is_some_and(|(_, names)| names);
        if let (Some((first, _)), Some((other, _))) = (first, kinds.find(|&(_, n)| n != names)) {
            let what = |n: bool| {
                if n {
                    "strings (a set)"
                } else {
                    "numbers (a vector)"
                }
            };
            let path = extend(&node_path(other, origins), Step::Key(field));
            return Err(self.field_error(
                Some(&specs[other].id),
                &path,
                field,
                format!(
                    "{} here, but node {:?} has {}: a file's features are all vectors or all sets",
                    what(!names),
                    specs[first].id,
                    what(names)
                ),
            ));
        }
        Ok(names)
    }
}

/// Each node's set of names (in `field`) as the numbers of its names among
/// the file's distinct names, sorted by bytes; their count is bounded by
/// `limits.max_set_members`.
fn numbered_sets(
    raw: &[Option<RawFeatures>],
    field: &str,
    limits: &Limits,
) -> Result<Vec<Option<Features>>, FormatError> {
    let all: BTreeSet<&str> = raw
        .iter()
        .flatten()
        .filter_map(|r| match r {
            RawFeatures::Names(names) => Some(names.iter().map(String::as_str)),
            RawFeatures::Numbers(_) => None,
        })
        .flatten()
        .collect();
    let too_many = |what: String| FormatError::Model {
        line: None,
        column: None,
        source: ModelError::TooLarge(limits.exceeded(Limit::SetMembers, what)),
    };
    let count = all.len();
    let described = format!("field {field:?}: {count} distinct names in lists");
    limits
        .check_set_members(count, &format!("names in the lists of field {field:?}"))
        .map_err(|e| FormatError::Model {
            line: None,
            column: None,
            source: ModelError::TooLarge(e),
        })?;
    let len = u32::try_from(count).map_err(|_| too_many(described))?;
    let number: BTreeMap<&str, u32> = all
        .iter()
        .enumerate()
        .map(|(i, &name)| (name, i as u32))
        .collect();
    Ok(raw
        .iter()
        .map(|r| {
            r.as_ref().map(|r| {
                let members: Vec<u32> = match r {
                    RawFeatures::Names(names) => names
                        .iter()
                        .filter_map(|n| number.get(n.as_str()).copied())
                        .collect(),
                    RawFeatures::Numbers(_) => Vec::new(),
                };
                // Every number is below `len`: the fallback is never taken.
                SparseVector::set(len, members)
                    .unwrap_or_else(|| SparseVector::from_dense(&[]))
                    .into()
            })
        })
        .collect())
}
