//! The one reader of files: input data, previous layouts and the layouts
//! stored beside the outputs. Attaches the path to every error, so messages
//! read `file: line L, column C: problem`. Parsing is the formats' (see
//! [`crate::pipeline::parse_inputs`]); writing is [`crate::store`]'s.

use std::path::{Path, PathBuf};

use nptreemap_formats::FormatError;

/// An input file could not be read, or its content is not valid.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file was read but its content is not valid.
    #[error("{path}: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong and where (boxed: it is large and errors are rare).
        source: Box<FormatError>,
    },
    /// The file is not UTF-8 text where text is expected.
    #[error("{path}: not UTF-8 text: {source}")]
    Text {
        /// The file.
        path: PathBuf,
        /// Where the first bad byte is.
        source: std::string::FromUtf8Error,
    },
}

/// Reads a file's bytes, naming it in the error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).map_err(|source| FileError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a UTF-8 text file, naming it in the error.
pub fn read_text(path: &Path) -> Result<String, FileError> {
    String::from_utf8(read_bytes(path)?).map_err(|source| FileError::Text {
        path: path.to_path_buf(),
        source,
    })
}

/// The text of a stored layout (see [`crate::pipeline::state_path`]), or
/// `None` when there is none or it cannot be read: a missing stored layout
/// only means a cold start.
pub fn read_state(path: &Path) -> Option<String> {
    std::fs::read_to_string(path).ok()
}
