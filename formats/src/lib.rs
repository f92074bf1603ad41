//! nptreemap-formats: the dataset model and the readers that turn input bytes into it.
//!
//! [`Dataset`] is the model every later step (layout, rendering, evaluation) works
//! on: a tree in breadth-first order with weights, values, feature vectors and
//! relations, valid by construction because only [`DatasetBuilder::build`] makes one.
//! Readers take bytes, never paths, and report problems as [`FormatError`]s with the
//! line and column of the offending value; the caller adds the file name.
//!
//! Each input format implements [`Format`] (its name, the inputs it reads, and
//! bytes + [`FormatOptions`] → [`Dataset`], errors as [`InputError`] naming the input);
//! [`registry::formats`] lists them and [`registry::find`] looks one up by name. See
//! `formats/README.md` for adding one.
//!
//! ```
//! use nptreemap_formats::{parse_hierarchy_json, HierarchyJsonOptions};
//!
//! let json = br#"{"name": "root", "children": [
//!     {"name": "a", "weight": 2},
//!     {"name": "b", "weight": 3}
//! ]}"#;
//! let dataset = parse_hierarchy_json(json, &HierarchyJsonOptions::default())?;
//! assert_eq!(dataset.len(), 3);
//! assert_eq!(dataset.node(dataset.root()).value, 5.0);
//! # Ok::<(), nptreemap_formats::FormatError>(())
//! ```

/// Border lists: a node table plus a pair list.
pub mod border_list;
/// [`Rgb`]: colours parsed once from `#rgb` / `#rrggbb`.
pub mod color;
/// The model: [`Dataset`], [`Node`], and [`DatasetBuilder`] with its checks.
pub mod dataset;
/// Embedding matrices: a node table plus one vector per leaf.
pub mod embedding;
/// [`FormatError`]: reader errors with line and column.
pub mod error;
/// [`Features`]: dense vectors and sparse ones (sets), shared between copies.
pub mod features;
/// The [`Format`] trait, its inputs, options and errors.
pub mod format;
/// Genre tables: a node table whose rows list genres, compared by Jaccard.
pub mod genre_table;
/// The paper's hierarchy JSON and d3-hierarchy style JSON.
pub mod hierarchy_json;
/// Positions in JSON text, for the hierarchy JSON reader's errors.
mod json_path;
/// [`Limits`]: how large an input the readers accept.
pub mod limits;
/// Node tables → hierarchies (grouping, path or parent columns).
pub mod node_table;
/// NumPy `.npy` matrices (embedding vectors saved by `numpy.save`).
pub mod npy;
/// The list of formats, looked up by name.
pub mod registry;
/// "Did you mean" hints for misspelt names.
pub mod suggest;
/// CSV/TSV rows with positions, and tables with a header.
pub mod table;
/// Time series: a node table plus values by date, compared by Pearson correlation.
pub mod time_series;
/// [`Warning`]: a suspicious but readable input.
pub mod warning;

pub use border_list::BorderList;
pub use color::{ColorError, Rgb};
pub use dataset::{Dataset, DatasetBuilder, ModelError, Node, NodeSpec, SimilarityHint};
pub use embedding::EmbeddingMatrix;
pub use error::FormatError;
pub use features::{Features, SparseVector};
pub use format::{Carry, Format, FormatOptions, InputError, Inputs, OnUnknownId, Role};
pub use genre_table::GenreTable;
pub use hierarchy_json::{parse_hierarchy_json, HierarchyJson, HierarchyJsonOptions};
pub use limits::{Limit, LimitError, Limits};
pub use time_series::TimeSeries;
pub use warning::{Warning, WarningKind, Warnings};
