//! The raw text of a hierarchy JSON document, kept to turn the JSON path of an
//! offending value into a line and column; the errors at such a value, and
//! the JSON path of a node.

use serde_json::Value;

use crate::dataset::ModelError;
use crate::error::FormatError;
use crate::json_path::{line_column, locate, Step};
use crate::limits::{Limit, Limits};

/// The raw text, kept to turn JSON paths into positions.
pub(super) struct Reader<'t> {
    pub(super) text: &'t [u8],
}

/// Where a node sits: its parent's spec index and its index in the parent's
/// `children` array. Enough to rebuild its JSON path for error positions.
#[derive(Clone, Copy, Debug)]
pub(super) struct Origin {
    pub(super) parent: Option<(usize, usize)>,
}

impl Reader<'_> {
    /// A field error at the value `path` leads to.
    pub(super) fn field_error(
        &self,
        node: Option<&str>,
        path: &[Step<'_>],
        field: &str,
        message: String,
    ) -> FormatError {
        let (line, column) = self.position(path);
        FormatError::Field {
            line,
            column,
            node: node.map(str::to_owned),
            field: field.to_owned(),
            message,
        }
    }

    /// A structure error (a node that is not an object) at the value `path` leads to.
    pub(super) fn structure_error(&self, path: &[Step<'_>], message: String) -> FormatError {
        let (line, column) = self.position(path);
        FormatError::Structure {
            line,
            column,
            message,
        }
    }

    /// Line and column of the value at `path`, if the scanner finds it.
    pub(super) fn position(&self, path: &[Step<'_>]) -> (Option<usize>, Option<usize>) {
        match locate(self.text, path) {
            Some(offset) => {
                let (line, column) = line_column(self.text, offset);
                (Some(line), Some(column))
            }
            None => (None, None),
        }
    }

    /// Wraps a model error with the position of the node it names. For a duplicate
    /// id that is the second node with the id (the first one is not the problem).
    pub(super) fn model_error(
        &self,
        source: ModelError,
        ids: &[String],
        origins: &[Origin],
    ) -> FormatError {
        let skip = usize::from(matches!(source, ModelError::DuplicateId { .. }));
        let node = source
            .node_id()
            .and_then(|id| ids.iter().enumerate().filter(|(_, x)| *x == id).nth(skip))
            .map(|(index, _)| index);
        let (line, column) = match node {
            Some(index) => self.position(&node_path(index, origins)),
            None => (None, None),
        };
        FormatError::Model {
            line,
            column,
            source,
        }
    }
}

/// A refusal by `limit`, at the node `path` leads to.
pub(super) fn over_limit(
    reader: &Reader<'_>,
    path: &[Step<'_>],
    limits: &Limits,
    limit: Limit,
    what: String,
) -> FormatError {
    let (line, column) = reader.position(path);
    FormatError::Model {
        line,
        column,
        source: ModelError::TooLarge(limits.exceeded(limit, what)),
    }
}

/// The JSON path of node `index`: `children`, i, `children`, j, ... from the root.
pub(super) fn node_path(index: usize, origins: &[Origin]) -> Vec<Step<'static>> {
    let mut steps = Vec::new();
    let mut current = origins.get(index).and_then(|origin| origin.parent);
    // Parents always have smaller indices than their children, so this ends.
    while let Some((parent, child_index)) = current {
        steps.push(Step::Index(child_index));
        steps.push(Step::Key("children"));
        current = origins.get(parent).and_then(|origin| origin.parent);
    }
    steps.reverse();
    steps
}

/// "a string", "an array", ... for error messages.
pub(super) fn kind(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_paths_are_rebuilt_from_origins() {
        let origins = [
            Origin { parent: None },
            Origin {
                parent: Some((0, 0)),
            },
            Origin {
                parent: Some((1, 3)),
            },
        ];
        let path = node_path(2, &origins);
        let rendered: Vec<String> = path
            .iter()
            .map(|step| match step {
                Step::Key(key) => (*key).to_owned(),
                Step::Index(i) => i.to_string(),
            })
            .collect();
        assert_eq!(rendered, ["children", "0", "children", "3"]);
    }
}
