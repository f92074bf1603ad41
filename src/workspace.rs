//! The one reader of input files: turns a path into a validated [`Dataset`],
//! attaching the path to every parse error so messages read `file:line:column`.

use std::path::{Path, PathBuf};

use nptreemap_formats::{parse_hierarchy_json, Dataset, FormatError, HierarchyJsonOptions};

/// Reading or parsing an input file failed.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
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
}

/// How to read a hierarchy file.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// Leaf field holding the weight; `None` uses the file's own flags.
    pub weight_field: Option<String>,
}

/// Reads a file's bytes, naming it in the error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, InputError> {
    std::fs::read(path).map_err(|source| InputError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads and validates a hierarchy JSON file.
pub fn read_dataset(path: &Path, options: &ReadOptions) -> Result<Dataset, InputError> {
    let bytes = std::fs::read(path).map_err(|source| InputError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let opts = HierarchyJsonOptions {
        weight_field: options.weight_field.clone(),
    };
    parse_hierarchy_json(&bytes, &opts).map_err(|source| InputError::Parse {
        path: path.to_path_buf(),
        source: Box::new(source),
    })
}
