//! The embedding-matrix format: a node table (see [`crate::node_table`]) plus one feature
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
//!
//! # NumPy matrices
//!
//! The `vectors` input may instead be a `.npy` file (recognised by its magic bytes,
//! whatever its name; read by [`crate::npy`]): a float32 or float64 matrix with one
//! row per node. Row `i` belongs to the `i`-th row of the node table, or, when an
//! `ids` input is given, to the node named on its `i`-th line (one id per line, the
//! first field of a CSV/TSV row; a first line that is not a node id is a header).
//! The counts must match, and
//! the rules above (finite values, no zero vector, every leaf a vector) hold.

use crate::dataset::{Dataset, SimilarityHint};
use crate::dataset::{ModelError, FEATURE_BOUND};
use crate::error::FormatError;
use crate::format::{Format, FormatOptions, InputError, Inputs, OnUnknownId, Role};
use crate::limits::{Limit, Limits};
use crate::node_table::{parse_with_input, TableTree, NODES_ROLE};
use crate::npy::{is_npy, read_npy, Matrix};
use crate::table::{read_rows_bounded, Cap, Row};
use crate::warning::{Warning, WarningKind};

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
        description: "CSV/TSV rows id,v1..vd (header optional), one per leaf; or a .npy \
                      float32/float64 matrix, one row per node",
    },
    Role {
        name: "ids",
        required: false,
        description: "for a .npy matrix: the node id of each row, one per line \
                      (default: the node table's row order)",
    },
];

impl Format for EmbeddingMatrix {
    fn name(&self) -> &'static str {
        "embedding-matrix"
    }

    fn roles(&self) -> &'static [Role] {
        ROLES
    }

    #[allow(clippy::result_large_err)] // InputError's shape is the Format API's
    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let in_vectors = |error| InputError::new("vectors", error);
        let hint = SimilarityHint::Cosine;
        parse_with_input(inputs, options, "vectors", hint, |tree, vectors| {
            if is_npy(vectors) {
                let matrix = read_npy(vectors, &options.limits).map_err(in_vectors)?;
                let owners = matrix_owners(tree, &matrix, inputs.get("ids"), options)?;
                add_matrix(tree, matrix, &owners).map_err(in_vectors)?;
            } else {
                read_vector_rows(tree, vectors, inputs, options)?;
            }
            // Every leaf of the table needs a vector.
            tree.check_leaf_features(None, "vector").map_err(in_vectors)
        })
    }
}

/// Reads the CSV/TSV `vectors` and sets them as features on the tree's nodes
/// (an `ids` input is for a `.npy` matrix only).
#[allow(clippy::result_large_err)] // InputError's shape is the Format API's
fn read_vector_rows(
    tree: &mut TableTree,
    vectors: &[u8],
    inputs: &Inputs<'_>,
    options: &FormatOptions,
) -> Result<(), InputError> {
    let in_vectors = |error| InputError::new("vectors", error);
    if inputs.get("ids").is_some() {
        return Err(InputError::new(
            "ids",
            FormatError::Structure {
                line: None,
                column: None,
                message: "ids are for a .npy vectors file; a CSV/TSV vectors file \
                          names each row's node in its first column"
                    .to_owned(),
            },
        ));
    }
    // One vector per node, plus an optional header row; an id and at
    // most max_dimensions values per row.
    let cap = Cap::new(options.limits, Limit::Nodes, 1, "vector rows");
    let width = Cap::new(options.limits, Limit::Dimensions, 1, "values");
    let rows = read_rows_bounded(vectors, options.delimiter, Some(cap), Some(width))
        .map_err(in_vectors)?;
    add_vectors(tree, &rows, &options.limits, options.on_unknown_id).map_err(in_vectors)
}

/// True when every field after the id parses as a number.
fn all_numbers(row: &Row) -> bool {
    row.fields[1..].iter().all(|f| f.parse::<f64>().is_ok())
}

/// Gives each leaf its vector from the rows; a row naming no node is skipped
/// with a warning or is an error, as `on_unknown` says.
fn add_vectors(
    tree: &mut TableTree,
    rows: &[Row],
    limits: &Limits,
    on_unknown: OnUnknownId,
) -> Result<(), FormatError> {
    // A first row that is not all numbers is a header, unless its first field is a
    // node id: then it is a data row with a bad value, reported as such below.
    let header = rows
        .first()
        .filter(|row| !all_numbers(row) && tree.find(&row.fields[0]).is_none());
    let data = &rows[usize::from(header.is_some())..];
    let (first, width) = first_row(header, data, limits)?;
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
        let Some(index) = row_owner(tree, header, row, on_unknown, &mut seen)? else {
            continue;
        };
        let vector = row_vector(header, row)?;
        tree.specs[index].features = Some(vector.into());
    }
    Ok(())
}

/// The first data row and its width (the id and the values), which every
/// row must have: at least one value, at most `limits.max_dimensions`.
fn first_row<'r>(
    header: Option<&Row>,
    data: &'r [Row],
    limits: &Limits,
) -> Result<(&'r Row, usize), FormatError> {
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
    Ok((first, width))
}

/// The node (index into the tree's specs) `row` gives a vector to; `None`
/// when its id names no node and `on_unknown` says to skip the row (with a
/// warning). A second vector for a node is an error; `seen` holds the line
/// of each node's vector.
fn row_owner(
    tree: &mut TableTree,
    header: Option<&Row>,
    row: &Row,
    on_unknown: OnUnknownId,
    seen: &mut [Option<usize>],
) -> Result<Option<usize>, FormatError> {
    let id = &row.fields[0];
    let Some(index) = tree.find(id) else {
        if on_unknown == OnUnknownId::Warn {
            tree.warnings.push(Warning::new(
                WarningKind::UnknownId,
                "vectors",
                Some(row.line),
                format!(
                    "unknown id {id:?}: no node of the node table has it; the row is \
                     skipped (fields.on_unknown_id: error makes this an error)"
                ),
            ));
            return Ok(None);
        }
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
            message: format!("node {id:?} has a second vector (the first is on line {previous})"),
        });
    }
    seen[index] = Some(row.line);
    Ok(Some(index))
}

/// The values of `row` after its id: finite numbers within
/// [`FEATURE_BOUND`], not all zero. Errors name the value's header cell, or
/// `v1`, `v2`, ... without a header.
fn row_vector(header: Option<&Row>, row: &Row) -> Result<Vec<f64>, FormatError> {
    let id = &row.fields[0];
    let value_name = |index: usize| -> String {
        header
            .and_then(|h| h.fields.get(index))
            .cloned()
            .unwrap_or_else(|| format!("v{index}"))
    };
    let mut vector = Vec::with_capacity(row.fields.len() - 1);
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
        return Err(zero_vector(Some(row.line), &format!("node {id:?}")));
    }
    Ok(vector)
}

fn zero_vector(line: Option<usize>, what: &str) -> FormatError {
    FormatError::Structure {
        line,
        column: None,
        message: format!(
            "{what}: the vector is all zeros, and cosine similarity is undefined for a zero \
             vector"
        ),
    }
}

/// The node (index into the tree's specs) of each row of a `.npy` matrix: from
/// the `ids` input when given, else the node table's rows in order.
#[allow(clippy::result_large_err)] // InputError's shape is the Format API's
fn matrix_owners(
    tree: &TableTree,
    matrix: &Matrix<'_>,
    ids: Option<&[u8]>,
    options: &FormatOptions,
) -> Result<Vec<usize>, InputError> {
    let shape = format!("shape ({}, {})", matrix.rows, matrix.cols);
    let Some(ids) = ids else {
        let rows: Vec<usize> = (0..tree.specs.len())
            .filter(|&i| tree.from_row[i])
            .collect();
        if rows.len() != matrix.rows {
            return Err(InputError::new(
                "vectors",
                FormatError::Structure {
                    line: None,
                    column: None,
                    message: format!(
                        "the matrix has {} rows ({shape}) but the node table has {} rows; \
                         row i of the matrix is the vector of the table's row i, unless an \
                         `ids` file names the node of each matrix row",
                        matrix.rows,
                        rows.len()
                    ),
                },
            ));
        }
        return Ok(rows);
    };
    let in_ids = |error| InputError::new("ids", error);
    // One id per matrix row, plus an optional header.
    let cap = Cap::new(options.limits, Limit::Nodes, 1, "ids");
    let width = Cap::new(options.limits, Limit::Dimensions, 1, "fields after the id");
    let rows = read_rows_bounded(ids, options.delimiter, Some(cap), Some(width)).map_err(in_ids)?;
    // A first line that names no node is a header (`id`); a typo there shows in
    // the count, and the message says it was taken for one.
    let header = rows
        .first()
        .filter(|row| tree.find(&row.fields[0]).is_none());
    let data = &rows[usize::from(header.is_some())..];
    if data.len() != matrix.rows {
        let note = header.map_or_else(String::new, |h| {
            format!(
                " (line {}, {:?}, names no node and was taken for a header)",
                h.line, h.fields[0]
            )
        });
        return Err(in_ids(FormatError::Structure {
            line: None,
            column: None,
            message: format!(
                "{} ids for a matrix of {} rows ({shape}): give one node id per matrix \
                 row{note}",
                data.len(),
                matrix.rows
            ),
        }));
    }
    let mut seen: Vec<Option<usize>> = vec![None; tree.specs.len()];
    data.iter()
        .map(|row| {
            let id = &row.fields[0];
            let index = tree.find(id).ok_or_else(|| {
                in_ids(FormatError::Field {
                    line: Some(row.line),
                    column: Some(1),
                    node: None,
                    field: "id".to_owned(),
                    message: format!("unknown id {id:?}: no node of the node table has it"),
                })
            })?;
            if let Some(first) = seen[index].replace(row.line) {
                return Err(in_ids(FormatError::Structure {
                    line: Some(row.line),
                    column: Some(1),
                    message: format!("node {id:?} is named twice (first on line {first})"),
                }));
            }
            Ok(index)
        })
        .collect()
}

/// Sets row `i` of the matrix as the features of node `owners[i]`, with the
/// checks of a CSV row (finite values within [`FEATURE_BOUND`], not all zero).
/// The rows are decoded once, into the vectors the nodes keep.
fn add_matrix(
    tree: &mut TableTree,
    matrix: Matrix<'_>,
    owners: &[usize],
) -> Result<(), FormatError> {
    for (i, (row, &index)) in matrix.into_rows().into_iter().zip(owners).enumerate() {
        let what = || format!("matrix row {} (node {:?})", i + 1, tree.specs[index].id);
        if let Some(j) = row.iter().position(|v| !v.is_finite()) {
            return Err(FormatError::Structure {
                line: None,
                column: None,
                message: format!(
                    "{}, column {}: {}; every value must be a finite number",
                    what(),
                    j + 1,
                    row[j]
                ),
            });
        }
        if let Some(j) = row.iter().position(|v| v.abs() > FEATURE_BOUND) {
            return Err(FormatError::Structure {
                line: None,
                column: None,
                message: format!(
                    "{}, column {}: {:e}: vector values must lie within ±{FEATURE_BOUND:e} \
                     (sums of their squares would overflow)",
                    what(),
                    j + 1,
                    row[j]
                ),
            });
        }
        if row.iter().all(|&v| v == 0.0) {
            return Err(zero_vector(None, &what()));
        }
        tree.specs[index].features = Some(row.into());
    }
    Ok(())
}
