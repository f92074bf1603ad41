//! The format plugin interface: the [`Format`] trait every input adapter implements,
//! the named inputs ([`Inputs`], [`Role`]) it reads, the options a caller may pass
//! ([`FormatOptions`]) and [`InputError`], which says which input an error is in.
//! Bytes in, [`Dataset`] out: a format never sees a path.

use std::collections::BTreeMap;

use crate::dataset::Dataset;
use crate::error::FormatError;

/// One input a format reads, for example the node table of a border list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Role {
    /// The role's name, the key used in [`Inputs`] (e.g. `"nodes"`).
    pub name: &'static str,
    /// True when [`Format::parse`] fails without this input.
    pub required: bool,
    /// One line for people: what the input holds.
    pub description: &'static str,
}

/// The bytes of each input, by role name. The caller reads the files; the format
/// only sees bytes.
#[derive(Clone, Debug, Default)]
pub struct Inputs<'a> {
    // A BTreeMap so that anything listing the inputs sees them in a fixed order.
    by_role: BTreeMap<&'a str, &'a [u8]>,
}

impl<'a> Inputs<'a> {
    /// No inputs yet.
    pub fn new() -> Self {
        Inputs::default()
    }

    /// Adds (or replaces) the bytes for `role`.
    pub fn with(mut self, role: &'a str, bytes: &'a [u8]) -> Self {
        self.by_role.insert(role, bytes);
        self
    }

    /// The bytes given for `role`, if any.
    pub fn get(&self, role: &str) -> Option<&'a [u8]> {
        self.by_role.get(role).copied()
    }

    /// The bytes for a required role, or an [`InputError`] saying it is missing.
    // InputError is a plain struct by the agreed API (role + FormatError, ~130 bytes);
    // it is built once per failed parse, so boxing would buy nothing measurable.
    #[allow(clippy::result_large_err)]
    pub fn require(&self, role: &str) -> Result<&'a [u8], InputError> {
        self.get(role).ok_or_else(|| {
            InputError::new(
                role,
                FormatError::Structure {
                    line: None,
                    column: None,
                    message: format!("the input {role:?} is required but was not given"),
                },
            )
        })
    }
}

/// What a format does with a reference to an id that no node has
/// (`fields.on_unknown_id`).
#[derive(serde::Serialize, Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OnUnknownId {
    /// Skip it with a warning. The default, for the daemon's sake: a row
    /// removed from the node table while `watch` runs leaves its pairs
    /// behind until the pairs file is edited too, and the picture should
    /// follow the node table meanwhile, not stop at an error.
    #[default]
    Warn,
    /// Fail, naming the file, line and id.
    Error,
}

/// Column names and reading choices shared by the table formats. Every field is
/// optional; each format documents its defaults. Formats ignore fields that do not
/// apply to them. Deserialises from a config's `fields:` mapping (unknown keys
/// are errors), so the config and the formats share this one type.
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FormatOptions {
    /// The id column (default `id`).
    pub id: Option<String>,
    /// The label column (default `label`, else `name`, else the id).
    pub label: Option<String>,
    /// The weight column (default: the first of `weight`, `value`, `size` present;
    /// with none, every row weighs 1). For hierarchy JSON, the weight field.
    pub weight: Option<String>,
    /// The colour column (default `color` when present).
    pub color: Option<String>,
    /// A parent-id column that gives the hierarchy.
    pub parent: Option<String>,
    /// A path column (`Asia/China`) that gives the hierarchy, segments split by
    /// [`FormatOptions::path_separator`].
    pub path: Option<String>,
    /// Separator of path segments; default `/`.
    pub path_separator: Option<char>,
    /// Grouping columns that give the hierarchy, outermost first.
    pub groups: Vec<String>,
    /// Pair lists: the strength column (default `strength` when present).
    pub strength: Option<String>,
    /// Field delimiter; default `,` when the input's first line has a comma, else
    /// the first of tab, `;` and `|` it has. In a config: a one-byte string such
    /// as `";"` or `"\t"`.
    #[serde(deserialize_with = "one_byte")]
    pub delimiter: Option<u8>,
    /// Label of the synthetic root of a table (default `root`).
    pub root_label: Option<String>,
    /// Genre tables: the multi-valued genres column (`Drama|Crime`); default
    /// `genres` when present and no [`FormatOptions::genre_columns`] are given.
    pub genres: Option<String>,
    /// Genre tables: separator of the values in the genres column; default `|`.
    pub separator: Option<char>,
    /// Genre tables: one-hot genre columns (cells 0/1, true/false, yes/no or empty),
    /// each column's header being the genre's name. Not together with
    /// [`FormatOptions::genres`].
    pub genre_columns: Vec<String>,
    /// Time series: fill a missing value with the previous date's value (and leading
    /// missing values with the first value given) instead of failing.
    pub fill_missing: bool,
    /// What to do with a pair, vector row or series column whose id is in no
    /// row of the node table. Default [`OnUnknownId::Warn`].
    pub on_unknown_id: OnUnknownId,
    /// How large an input may be. Not a `fields:` key: a config sets it for
    /// every dataset in its `limits:` section.
    #[serde(skip)]
    pub limits: crate::limits::Limits,
    /// Further columns (hierarchy JSON: node properties) to carry into
    /// [`crate::Node::fields`] as text, for a picture's own use (a tooltip
    /// field, a link, a colour scale). Each must exist; the error names what
    /// asked for it. Not a `fields:` key: a config fills it from its `page:`
    /// and `render:` sections.
    #[serde(skip)]
    pub carry: Vec<Carry>,
}

/// A column to carry into the model (see [`FormatOptions::carry`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Carry {
    /// The column (or property) name.
    pub column: String,
    /// What asked for it, for errors (`page.fields, config line 12`).
    pub asked_by: String,
}

/// An input format: reads the bytes of its inputs into a validated [`Dataset`].
///
/// Implementations are unit structs listed once in [`crate::registry::formats`].
pub trait Format: Sync {
    /// The name users select the format by, e.g. `"border-list"`.
    fn name(&self) -> &'static str;
    /// The inputs the format reads.
    fn roles(&self) -> &'static [Role];
    /// Reads the inputs. Never panics on user data; every error names the input.
    // InputError is a plain struct by the agreed API (role + FormatError, ~130 bytes);
    // it is built once per failed parse, so boxing would buy nothing measurable.
    #[allow(clippy::result_large_err)]
    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError>;
}

/// A [`FormatError`] together with the role of the input it is in; the caller maps
/// the role to a file path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{role}: {error}")]
pub struct InputError {
    /// The role of the input (a [`Role::name`]).
    pub role: String,
    /// What is wrong, with line and column.
    pub error: FormatError,
}

impl InputError {
    /// Wraps `error` as being in the input `role`.
    pub fn new(role: impl Into<String>, error: FormatError) -> Self {
        InputError {
            role: role.into(),
            error,
        }
    }
}

/// A delimiter given as a string of exactly one byte (`";"`, `"\t"`).
fn one_byte<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u8>, D::Error> {
    let text: Option<String> = serde::Deserialize::deserialize(d)?;
    match text.as_deref().map(str::as_bytes) {
        None => Ok(None),
        Some([b]) => Ok(Some(*b)),
        Some(_) => Err(serde::de::Error::custom(format!(
            "delimiter {:?}: expected a single one-byte character such as \";\"",
            text.unwrap_or_default()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_by_role() {
        let inputs = Inputs::new().with("nodes", b"id\n").with("pairs", b"a,b\n");
        assert_eq!(inputs.get("nodes"), Some(&b"id\n"[..]));
        assert_eq!(inputs.get("vectors"), None);
        let error = inputs.require("vectors").expect_err("missing");
        assert_eq!(
            error.to_string(),
            "vectors: the input \"vectors\" is required but was not given"
        );
    }
}
