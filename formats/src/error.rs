//! `FormatError`: why input bytes could not be read as a dataset, with the 1-based
//! line and column of the problem when known. It never holds a file path: the caller
//! knows the path and adds it (`path:line:column: message`).

use std::fmt;

use crate::dataset::ModelError;

/// An input that could not be turned into a [`crate::Dataset`].
///
/// Lines and columns are 1-based; columns count characters (not bytes), as editors do.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    /// The bytes are not well-formed (for example JSON cut short or not UTF-8).
    #[error("line {line}, column {column}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// 1-based column (0 when the parser reports the very start of a line, e.g.
        /// an empty input).
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// The input is well-formed but its overall shape is not what the format needs
    /// (for example a top-level array where a hierarchy object belongs).
    #[error("{}{message}", Position(*.line, *.column))]
    Structure {
        /// 1-based line, when known.
        line: Option<usize>,
        /// 1-based column, when known.
        column: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A field of a node has the wrong type or value, or is missing.
    #[error("{}{}field {field:?}: {message}", Position(*.line, *.column), NodePrefix(.node.as_deref()))]
    Field {
        /// 1-based line, when known.
        line: Option<usize>,
        /// 1-based column, when known.
        column: Option<usize>,
        /// Id of the node the field belongs to, when known.
        node: Option<String>,
        /// The field's name.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// The nodes were read but do not form a valid dataset.
    #[error("{}{source}", Position(*.line, *.column))]
    Model {
        /// 1-based line of the node the error is about, when known.
        line: Option<usize>,
        /// 1-based column of that node, when known.
        column: Option<usize>,
        /// The model's complaint (it names the node).
        #[source]
        source: ModelError,
    },
}

impl FormatError {
    /// The 1-based line of the problem, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            FormatError::Syntax { line, .. } => Some(*line),
            FormatError::Structure { line, .. }
            | FormatError::Field { line, .. }
            | FormatError::Model { line, .. } => *line,
        }
    }

    /// The 1-based column of the problem, when known.
    pub fn column(&self) -> Option<usize> {
        match self {
            FormatError::Syntax { column, .. } => Some(*column),
            FormatError::Structure { column, .. }
            | FormatError::Field { column, .. }
            | FormatError::Model { column, .. } => *column,
        }
    }
}

/// Formats `line L, column C: ` (or `line L: `), or nothing when the line is unknown.
struct Position(Option<usize>, Option<usize>);

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.0, self.1) {
            (Some(line), Some(column)) => write!(f, "line {line}, column {column}: "),
            (Some(line), None) => write!(f, "line {line}: "),
            _ => Ok(()),
        }
    }
}

/// Formats `node "ID": `, or nothing when no node is known.
struct NodePrefix<'a>(Option<&'a str>);

impl fmt::Display for NodePrefix<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(id) => write!(f, "node {id:?}: "),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_error_reads_like_the_house_example() {
        let error = FormatError::Field {
            line: Some(12),
            column: Some(5),
            node: Some("CN".into()),
            field: "Population".into(),
            message: "expected a number, found a string".into(),
        };
        assert_eq!(
            error.to_string(),
            "line 12, column 5: node \"CN\": field \"Population\": expected a number, found a string"
        );
        assert_eq!((error.line(), error.column()), (Some(12), Some(5)));
    }

    #[test]
    fn unknown_positions_are_left_out() {
        let error = FormatError::Model {
            line: None,
            column: None,
            source: ModelError::NoRoot,
        };
        assert_eq!(error.to_string(), "no root: every node has a parent");
        let error = FormatError::Field {
            line: None,
            column: None,
            node: None,
            field: "weightAttribute".into(),
            message: "expected a string".into(),
        };
        assert_eq!(
            error.to_string(),
            "field \"weightAttribute\": expected a string"
        );
    }
}
