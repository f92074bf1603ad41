//! [`Warning`]: something in an input that is read but probably not what the
//! user meant (a header without rows, a repeated column name, a pair of a
//! node with itself, a pair repeated with another strength). The dataset is
//! still valid; `check`, `build` and `watch` report the warnings it carries.

use std::fmt;

/// One warning about an input, with its role and line like an error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// The role of the input (a [`crate::Role::name`]); the caller maps it to a path.
    pub role: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What looks wrong, and what the reader did about it.
    pub message: String,
}

impl Warning {
    /// A warning about input `role` at `line`.
    pub fn new(role: impl Into<String>, line: Option<usize>, message: impl Into<String>) -> Self {
        Warning {
            role: role.into(),
            line,
            message: message.into(),
        }
    }
}

/// `line L: message` (or the message alone); the caller puts the file first.
impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "line {line}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}
