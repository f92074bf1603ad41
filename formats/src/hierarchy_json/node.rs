//! One node object of a hierarchy JSON document, read field by field (label,
//! children, weight, features, neighbours, colour, carried fields): each
//! error names the node and points at the field.

use serde_json::{Map, Value};

use crate::color::Rgb;
use crate::dataset::is_valid_weight;
use crate::error::FormatError;
use crate::json_path::{extend, Step};
use crate::limits::{Limit, Limits};

use super::flags::WeightRule;
use super::reader::{kind, over_limit, Reader};
use super::sets::RawFeatures;

/// One node object being read, once its id is known: each field has its own
/// step, and every error names the node and points at the field.
pub(super) struct NodeObject<'a, 't> {
    pub(super) reader: &'a Reader<'t>,
    pub(super) object: &'a Map<String, Value>,
    pub(super) path: Vec<Step<'static>>,
    pub(super) id: String,
}

impl<'a> NodeObject<'a, '_> {
    /// The property `name` as a carried field: strings as they are, numbers
    /// and booleans as their JSON text; `None` when absent, null, empty or
    /// structured.
    pub(super) fn carried(&self, name: &str) -> Option<(String, String)> {
        let text = match self.object.get(name)? {
            Value::Bool(b) => b.to_string(),
            value => id_text(value)?,
        };
        (!text.is_empty()).then(|| (name.to_owned(), text))
    }

    /// The path to `field` of this node.
    fn at<'f>(&self, field: &'f str) -> Vec<Step<'f>> {
        extend(&self.path, Step::Key(field))
    }

    /// A field error of this node at `steps`.
    fn error(&self, field: &str, steps: &[Step<'_>], message: String) -> FormatError {
        self.reader
            .field_error(Some(&self.id), steps, field, message)
    }

    /// `name`, else `Name` (else the id, later).
    pub(super) fn label(&self) -> Result<Option<String>, FormatError> {
        for field in ["name", "Name"] {
            let found = text_field(self.object, field)
                .map_err(|found| self.error(field, &self.at(field), found))?;
            if found.is_some() {
                return Ok(found);
            }
        }
        Ok(None)
    }

    /// The `children` array (absent or null: none).
    pub(super) fn children(&self) -> Result<&'a [Value], FormatError> {
        match self.object.get("children") {
            None | Some(Value::Null) => Ok(&[]),
            Some(Value::Array(children)) => Ok(children.as_slice()),
            Some(other) => Err(self.error(
                "children",
                &self.at("children"),
                format!("expected an array of nodes, found {}", kind(other)),
            )),
        }
    }

    /// The node's own weight by `rule`; a leaf must have one.
    pub(super) fn weight(
        &self,
        rule: &WeightRule,
        is_leaf: bool,
    ) -> Result<Option<f64>, FormatError> {
        let field = match rule {
            WeightRule::EveryNodeOne => return Ok(Some(1.0)),
            WeightRule::LeafOne => return Ok(is_leaf.then_some(1.0)),
            WeightRule::Field(field) => field.as_str(),
        };
        match self.object.get(field) {
            None | Some(Value::Null) if is_leaf => Err(self.error(
                field,
                &self.path,
                "missing; every leaf needs a weight".to_owned(),
            )),
            None | Some(Value::Null) => Ok(None),
            Some(Value::Number(number)) => {
                let weight = number.as_f64().unwrap_or(f64::NAN);
                if is_valid_weight(weight) {
                    return Ok(Some(weight));
                }
                let problem = if weight < 0.0 {
                    "is negative"
                } else {
                    "is not a finite number"
                };
                Err(self.error(field, &self.at(field), format!("weight {number} {problem}")))
            }
            Some(other) => Err(self.error(
                field,
                &self.at(field),
                format!("expected a number, found {}", kind(other)),
            )),
        }
    }

    /// The feature array in `field`: numbers (possibly wrapped once as `[[..]]`)
    /// or strings, at most `limits.max_dimensions` numbers (`max_set_members`
    /// when they are a Jaccard file's sets).
    pub(super) fn features(
        &self,
        field: &str,
        limits: &Limits,
        jaccard: bool,
    ) -> Result<Option<RawFeatures>, FormatError> {
        let outer = match self.object.get(field) {
            None | Some(Value::Null) => return Ok(None),
            Some(Value::Array(outer)) => outer,
            Some(other) => {
                return Err(self.error(
                    field,
                    &self.at(field),
                    format!(
                        "expected an array of numbers or of strings, found {}",
                        kind(other)
                    ),
                ))
            }
        };
        let mut steps = self.at(field);
        // The prototype unwraps a one-element list holding a list (`[[..]]`).
        let entries = match outer.as_slice() {
            [Value::Array(inner)] => {
                steps.push(Step::Index(0));
                inner
            }
            _ => outer,
        };
        if entries.first().is_some_and(Value::is_string) {
            let mut names = Vec::with_capacity(entries.len());
            for (k, entry) in entries.iter().enumerate() {
                let Some(name) = entry.as_str() else {
                    return Err(self.error(
                        field,
                        &extend(&steps, Step::Index(k)),
                        format!(
                            "entry {k}: expected a string like the entries before it, found {}",
                            kind(entry)
                        ),
                    ));
                };
                names.push(name.to_owned());
            }
            return Ok(Some(RawFeatures::Names(names)));
        }
        let (limit, allowed) = if jaccard {
            (Limit::SetMembers, limits.max_set_members)
        } else {
            (Limit::Dimensions, limits.max_dimensions)
        };
        if entries.len() > allowed {
            return Err(over_limit(
                self.reader,
                &self.path,
                limits,
                limit,
                format!(
                    "node {:?}: a feature vector of {} values",
                    self.id,
                    entries.len()
                ),
            ));
        }
        let mut features = Vec::with_capacity(entries.len());
        for (k, entry) in entries.iter().enumerate() {
            let Some(x) = entry.as_f64() else {
                return Err(self.error(
                    field,
                    &extend(&steps, Step::Index(k)),
                    format!("entry {k}: expected a number, found {}", kind(entry)),
                ));
            };
            features.push(x);
        }
        Ok(Some(RawFeatures::Numbers(features)))
    }

    /// The ids listed in `neighbors`.
    pub(super) fn relations(&self) -> Result<Vec<String>, FormatError> {
        let entries = match self.object.get("neighbors") {
            None | Some(Value::Null) => return Ok(Vec::new()),
            Some(Value::Array(entries)) => entries,
            Some(other) => {
                return Err(self.error(
                    "neighbors",
                    &self.at("neighbors"),
                    format!("expected an array of ids, found {}", kind(other)),
                ))
            }
        };
        entries
            .iter()
            .enumerate()
            .map(|(k, entry)| {
                id_text(entry).ok_or_else(|| {
                    self.error(
                        "neighbors",
                        &extend(&self.at("neighbors"), Step::Index(k)),
                        format!("entry {k}: expected an id, found {}", kind(entry)),
                    )
                })
            })
            .collect()
    }

    /// `color`, a `#rgb` or `#rrggbb` string.
    pub(super) fn color(&self) -> Result<Option<Rgb>, FormatError> {
        match self.object.get("color") {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(text)) => Rgb::from_hex(text).map(Some).ok_or_else(|| {
                self.error(
                    "color",
                    &self.at("color"),
                    format!("{text:?} is not a hex color like #rgb or #rrggbb"),
                )
            }),
            Some(other) => Err(self.error(
                "color",
                &self.at("color"),
                format!("expected a hex color string, found {}", kind(other)),
            )),
        }
    }
}

/// A string or a number as text (ids may be written either way); `Err` describes
/// any other value, `Ok(None)` means absent or null.
pub(super) fn text_field(
    object: &Map<String, Value>,
    field: &str,
) -> Result<Option<String>, String> {
    match object.get(field) {
        None | Some(Value::Null) => Ok(None),
        Some(value) => id_text(value)
            .map(Some)
            .ok_or_else(|| format!("expected a string or a number, found {}", kind(value))),
    }
}

/// A string as is, a number as its JSON text; `None` for other values.
fn id_text(value: &Value) -> Option<String> {
    match value {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    }
}
