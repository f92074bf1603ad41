//! The embedding-matrix format: a node table (see [`crate::table`]) plus one feature
//! vector per leaf, compared by cosine similarity. Owns the vector file's layout,
//! header detection and the checks that make cosine defined.
//!
//! # Vectors
//!
//! CSV or TSV rows `id, v1, .., vd`; the delimiter is detected per input as for
//! tables. The header is optional: the first row is a header when any of its fields
//! after the id is not a number. Every row must have the same number of values
//! (`d >= 1`), each a finite number. (A first row whose id is a node of the table
//! is data, so a typo in the first vector is reported, not taken as a header.) A vector of all zeros is an error, because
//! cosine similarity is undefined for it. Each id must be a node of the table and
//! appear once; every leaf of the table needs a vector, and a table row that has
//! children may have one. The dataset's similarity hint is [`SimilarityHint::Cosine`].

use crate::dataset::{Dataset, SimilarityHint};
use crate::dataset::{ModelError, FEATURE_BOUND};
use crate::error::FormatError;
use crate::format::{Format, FormatOptions, InputError, Inputs, Role};
use crate::limits::{Limit, Limits};
use crate::table::{node_tree, read_rows_capped, Row, RowCap, TableTree, NODES_ROLE};

/// The embedding-matrix [`Format`] (name `embedding-matrix`, inputs `nodes` and
/// `vectors`).
#[derive(Clone, Copy, Debug, Default)]
pub struct EmbeddingMatrix;

/// The inputs of [`EmbeddingMatrix`].
const ROLES: &[Role] = &[
    NODES_ROLE,
    Role {
        name: "vectors",
        required: true,
        description: "CSV/TSV rows id,v1..vd (header optional), one per leaf",
    },
];

impl Format for EmbeddingMatrix {
    fn name(&self) -> &'static str {
        "embedding-matrix"
    }

    fn roles(&self) -> &'static [Role] {
        ROLES
    }

    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let vectors = inputs.require("vectors")?;
        let in_nodes = |error| InputError::new("nodes", error);
        let in_vectors = |error| InputError::new("vectors", error);
        let mut tree = node_tree(inputs, options)?;
        // One vector per node, plus an optional header row.
        let cap = RowCap::new(options.limits, Limit::Nodes, 1, "vector rows");
        let rows = read_rows_capped(vectors, options.delimiter, Some(cap)).map_err(in_vectors)?;
        add_vectors(&mut tree, &rows, &options.limits).map_err(in_vectors)?;
        tree.build(Some(SimilarityHint::Cosine)).map_err(in_nodes)
    }
}

/// True when every field after the id parses as a number.
fn all_numbers(row: &Row) -> bool {
    row.fields[1..].iter().all(|f| f.parse::<f64>().is_ok())
}

/// Reads the vector rows and sets them as features on the tree's nodes.
fn add_vectors(tree: &mut TableTree, rows: &[Row], limits: &Limits) -> Result<(), FormatError> {
    // A first row that is not all numbers is a header, unless its first field is a
    // node id: then it is a data row with a bad value, reported as such below.
    let header = rows
        .first()
        .filter(|row| !all_numbers(row) && tree.find(&row.fields[0]).is_none());
    let data = &rows[usize::from(header.is_some())..];
    let Some(first) = data.first() else {
        return Err(FormatError::Structure {
            line: header.map(|h| h.line),
            column: None,
            message: "no vectors: the input has only a header row".to_owned(),
        });
    };
    let width = first.fields.len();
    if width < 2 {
        return Err(FormatError::Structure {
            line: Some(first.line),
            column: None,
            message: "a vector row needs an id and at least one value".to_owned(),
        });
    }
    limits
        .check_dimensions(width - 1, "the vectors")
        .map_err(|e| FormatError::Model {
            line: Some(first.line),
            column: None,
            source: ModelError::TooLarge(e),
        })?;
    let value_name = |index: usize| -> String {
        header
            .and_then(|h| h.fields.get(index))
            .cloned()
            .unwrap_or_else(|| format!("v{index}"))
    };
    // Line of the vector given for each spec, to report repeats.
    let mut seen: Vec<Option<usize>> = vec![None; tree.specs.len()];
    for row in data {
        if row.fields.len() != width {
            return Err(FormatError::Structure {
                line: Some(row.line),
                column: None,
                message: format!(
                    "the row has {} values, the first row (line {}) has {}",
                    row.fields.len() - 1,
                    first.line,
                    width - 1
                ),
            });
        }
        let id = &row.fields[0];
        let Some(index) = tree.find(id) else {
            return Err(FormatError::Field {
                line: Some(row.line),
                column: Some(1),
                node: None,
                field: header
                    .and_then(|h| h.fields.first())
                    .cloned()
                    .unwrap_or_else(|| "id".to_owned()),
                message: format!("unknown id {id:?}: no node of the node table has it"),
            });
        };
        if let Some(previous) = seen[index] {
            return Err(FormatError::Structure {
                line: Some(row.line),
                column: Some(1),
                message: format!(
                    "node {id:?} has a second vector (the first is on line {previous})"
                ),
            });
        }
        seen[index] = Some(row.line);
        let mut vector = Vec::with_capacity(width - 1);
        for (offset, text) in row.fields[1..].iter().enumerate() {
            let column = offset + 1;
            let value = text.parse::<f64>().ok().filter(|v| v.is_finite());
            let Some(value) = value else {
                return Err(FormatError::Field {
                    line: Some(row.line),
                    column: Some(column + 1),
                    node: Some(id.clone()),
                    field: value_name(column),
                    message: format!("expected a finite number, found {text:?}"),
                });
            };
            if value.abs() > FEATURE_BOUND {
                return Err(FormatError::Field {
                    line: Some(row.line),
                    column: Some(column + 1),
                    node: Some(id.clone()),
                    field: value_name(column),
                    message: format!(
                        "{text}: vector values must lie within ±{FEATURE_BOUND:e} (sums of their squares would overflow)"
                    ),
                });
            }
            vector.push(value);
        }
        if vector.iter().all(|&v| v == 0.0) {
            return Err(FormatError::Structure {
                line: Some(row.line),
                column: None,
                message: format!(
                    "node {id:?}: the vector is all zeros, and cosine similarity is undefined \
                     for a zero vector"
                ),
            });
        }
        tree.specs[index].features = Some(vector);
    }
    let leaves = tree.leaf_flags();
    for (index, spec) in tree.specs.iter().enumerate() {
        if leaves[index] && spec.features.is_none() {
            let place =
                tree.lines[index].map_or_else(String::new, |line| format!(" (nodes line {line})"));
            return Err(FormatError::Structure {
                line: None,
                column: None,
                message: format!(
                    "node {:?}{place} has no vector; every leaf needs one",
                    spec.id
                ),
            });
        }
    }
    Ok(())
}
