//! The root's flags of a hierarchy JSON document (`weightAttribute`,
//! `simAttribute`, `useNeighborLeafs`, `similarityMeasure`), resolved once
//! with the options into how the walk reads every node.

use serde_json::{Map, Value};

use crate::dataset::SimilarityHint;
use crate::error::FormatError;
use crate::json_path::Step;

use super::reader::{kind, Reader};

/// How weights are read, decided once from the options and the root's flags.
#[derive(Debug)]
pub(super) enum WeightRule {
    /// `weightAttribute: "none"`: every node, internal ones too, weighs 1.
    EveryNodeOne,
    /// Leaves must have this numeric field; internal nodes may.
    Field(String),
    /// No weight field anywhere: every leaf weighs 1.
    LeafOne,
}

/// The root's flags, resolved.
#[derive(Debug)]
pub(super) struct Flags {
    pub(super) weight: WeightRule,
    pub(super) feature_field: String,
    /// `useNeighborLeafs`, when given.
    pub(super) neighbor_lists: Option<bool>,
    /// `similarityMeasure`, when given, with its name.
    pub(super) measure: Option<(SimilarityHint, &'static str)>,
}

/// The weight-field names tried on leaves when neither the options nor the file say.
const WEIGHT_FIELD_GUESSES: [&str; 3] = ["value", "weight", "size"];

impl Flags {
    /// Whether the file declares Jaccard similarity (its vectors are then sets).
    pub(super) fn jaccard(&self) -> bool {
        matches!(self.measure, Some((SimilarityHint::Jaccard, _)))
    }
}

impl Reader<'_> {
    /// Resolves the root flags that steer the whole read; `weight_field`,
    /// when given, overrides `weightAttribute`.
    pub(super) fn read_flags(
        &self,
        root: &Map<String, Value>,
        weight_field: Option<&str>,
    ) -> Result<Flags, FormatError> {
        let flag_error = |field: &str, message: String| {
            self.field_error(None, &[Step::Key(field)], field, message)
        };
        let string_flag = |field: &str| -> Result<Option<&str>, FormatError> {
            match root.get(field) {
                None | Some(Value::Null) => Ok(None),
                Some(Value::String(s)) => Ok(Some(s.as_str())),
                Some(other) => Err(flag_error(
                    field,
                    format!("expected a string, found {}", kind(other)),
                )),
            }
        };

        let weight_field = match weight_field {
            Some(field) => Some(field.to_owned()),
            None => string_flag("weightAttribute")?.map(str::to_owned),
        };
        let weight = match weight_field {
            Some(field) if field == "none" => WeightRule::EveryNodeOne,
            Some(field) => WeightRule::Field(field),
            None => WEIGHT_FIELD_GUESSES
                .iter()
                .find(|field| any_leaf_has(root, field))
                .map_or(WeightRule::LeafOne, |field| {
                    WeightRule::Field((*field).to_owned())
                }),
        };

        let feature_field = string_flag("simAttribute")?
            .unwrap_or("embeddings")
            .to_owned();

        let neighbor_lists = match root.get("useNeighborLeafs") {
            None | Some(Value::Null) => None,
            Some(Value::Bool(b)) => Some(*b),
            Some(other) => {
                return Err(flag_error(
                    "useNeighborLeafs",
                    format!("expected true or false, found {}", kind(other)),
                ))
            }
        };
        // Checked even when `useNeighborLeafs` wins, so a typo never goes unnoticed.
        let measure = match string_flag("similarityMeasure")? {
            None => None,
            Some("cosine") => Some((SimilarityHint::Cosine, "cosine")),
            Some("jaccard") => Some((SimilarityHint::Jaccard, "jaccard")),
            Some("binary") => Some((SimilarityHint::Binary, "binary")),
            Some(other) => {
                return Err(flag_error(
                    "similarityMeasure",
                    format!("unknown similarity measure {other:?}; expected \"cosine\", \"jaccard\" or \"binary\""),
                ))
            }
        };
        Ok(Flags {
            weight,
            feature_field,
            neighbor_lists,
            measure,
        })
    }
}

/// True when any leaf below (or at) `node` has a non-null `field`. Malformed
/// `children` are ignored here; the walk reports them with a position.
fn any_leaf_has(node: &Map<String, Value>, field: &str) -> bool {
    match node.get("children") {
        Some(Value::Array(children)) if !children.is_empty() => children
            .iter()
            .filter_map(Value::as_object)
            .any(|child| any_leaf_has(child, field)),
        _ => node.get(field).is_some_and(|value| !value.is_null()),
    }
}
