//! The genre-table format: one node table (see [`crate::node_table`]) whose rows also list
//! genres, turned into 0/1 feature vectors compared by Jaccard similarity. Owns the
//! two ways of writing genres (a multi-valued column or one-hot columns) and their
//! encoding.
//!
//! # Genres
//!
//! Either (not both):
//!
//! - **a multi-valued column**: [`FormatOptions::genres`], default `genres` when the
//!   table has it. Values are split at [`FormatOptions::separator`] (default `|`,
//!   as in `Drama|Crime`) and trimmed; empty pieces are skipped, so an empty cell
//!   means "no genres" and a repeated genre counts once.
//! - **one-hot columns**: [`FormatOptions::genre_columns`]; the header of each is the
//!   genre's name. A cell is `1`, `true` or `yes` (has the genre), `0`, `false`, `no`
//!   or empty (has not), ASCII case-insensitive; anything else is an error.
//!
//! Naming both a genres column and one-hot columns is an error. At least one row
//! must have a genre. Every row's node gets a feature vector over the genres that
//! some row has, sorted by name (byte order, so the result depends on neither column
//! nor row order): 1 when the row has the genre, else 0. A one-hot column no row
//! uses adds no dimension, so the same data written either way gives the same
//! dataset. A row without genres gets an all-zero vector, whose Jaccard similarity
//! to anything is 0.
//!
//! The dataset's similarity hint is [`SimilarityHint::Jaccard`] (shared genres over
//! all genres of the pair). The paper's IMDB example instead uses `binary` (1 only
//! for identical genre sets); choose that in the configuration to override the hint.

use std::collections::{BTreeMap, BTreeSet};

use crate::dataset::ModelError;
use crate::dataset::{Dataset, SimilarityHint};
use crate::error::FormatError;
use crate::format::{Format, FormatOptions, InputError, Inputs, Role};
use crate::limits::Limits;
use crate::node_table::{read_node_table, tree_from_table, TableTree};
use crate::table::Table;

/// The genre-table [`Format`] (name `genre-table`, one input `nodes`).
#[derive(Clone, Copy, Debug, Default)]
pub struct GenreTable;

/// The input of [`GenreTable`].
const ROLES: &[Role] = &[Role {
    name: "nodes",
    required: true,
    description: "node table CSV/TSV: id, label, weight, hierarchy columns and genres \
                  (a multi-valued column or one-hot columns)",
}];

impl Format for GenreTable {
    fn name(&self) -> &'static str {
        "genre-table"
    }

    fn roles(&self) -> &'static [Role] {
        ROLES
    }

    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let in_nodes = |error| InputError::new("nodes", error);
        let table = read_node_table(inputs.require("nodes")?, options).map_err(in_nodes)?;
        let mut tree = tree_from_table(&table, options).map_err(in_nodes)?;
        // Row nodes are pushed one per row, in row order, so the k-th spec made from
        // a row belongs to the k-th row.
        let row_specs: Vec<usize> = (0..tree.specs.len())
            .filter(|&i| tree.from_row[i])
            .collect();
        let ids: Vec<&str> = row_specs
            .iter()
            .map(|&i| tree.specs[i].id.as_str())
            .collect();
        let genres = read_genres(&table, &ids, options).map_err(in_nodes)?;
        set_features(&mut tree, &row_specs, &table, &genres, &options.limits).map_err(in_nodes)?;
        tree.build(Some(SimilarityHint::Jaccard)).map_err(in_nodes)
    }
}

/// The genres of each row (parallel to `table.rows`, whose node ids are `ids`), as
/// read from whichever source the options select.
fn read_genres(
    table: &Table,
    ids: &[&str],
    options: &FormatOptions,
) -> Result<Vec<BTreeSet<String>>, FormatError> {
    if options.genres.is_some() && !options.genre_columns.is_empty() {
        return Err(FormatError::Structure {
            line: Some(table.header_line),
            column: None,
            message: "give either a genres column or one-hot genre columns, not both".to_owned(),
        });
    }
    if !options.genre_columns.is_empty() {
        return read_one_hot(table, ids, &options.genre_columns);
    }
    let column = match &options.genres {
        Some(name) => table.required_column(name, "the genres column")?,
        None => table
            .column("genres")
            .ok_or_else(|| FormatError::Structure {
                line: Some(table.header_line),
                column: None,
                message: format!(
                    "no genres: the table has no \"genres\" column and no one-hot genre columns \
                 were given; the header has: {}",
                    table.header.join(", ")
                ),
            })?,
    };
    let separator = options.separator.unwrap_or('|');
    Ok(table
        .rows
        .iter()
        .map(|row| {
            row.fields
                .get(column)
                .map_or("", String::as_str)
                .split(separator)
                .map(str::trim)
                .filter(|genre| !genre.is_empty())
                .map(str::to_owned)
                .collect()
        })
        .collect())
}

/// The genres of each row (node ids `ids`) from the one-hot columns named in `names`.
fn read_one_hot(
    table: &Table,
    ids: &[&str],
    names: &[String],
) -> Result<Vec<BTreeSet<String>>, FormatError> {
    let columns = names
        .iter()
        .map(|name| table.required_column(name, "a one-hot genre column"))
        .collect::<Result<Vec<_>, _>>()?;
    // The same column named twice would be one genre counted as two dimensions.
    for (position, &column) in columns.iter().enumerate() {
        if columns[..position].contains(&column) {
            return Err(FormatError::Structure {
                line: Some(table.header_line),
                column: Some(column + 1),
                message: format!(
                    "the one-hot genre column {:?} is named twice",
                    table.header[column]
                ),
            });
        }
    }
    let mut genres = Vec::with_capacity(table.rows.len());
    for (number, row) in table.rows.iter().enumerate() {
        let mut set = BTreeSet::new();
        for &column in &columns {
            let cell = row.fields.get(column).map_or("", String::as_str);
            let has = match cell.to_ascii_lowercase().as_str() {
                "1" | "true" | "yes" => true,
                "" | "0" | "false" | "no" => false,
                _ => {
                    return Err(FormatError::Field {
                        line: Some(row.line),
                        column: Some(column + 1),
                        node: ids.get(number).map(|&id| id.to_owned()),
                        field: table.header[column].clone(),
                        message: format!(
                            "expected 0/1, true/false, yes/no or an empty cell, found {cell:?}"
                        ),
                    })
                }
            };
            if has {
                set.insert(table.header[column].clone());
            }
        }
        genres.push(set);
    }
    Ok(genres)
}

/// Encodes every row's genres as a 0/1 vector over all genres, sorted, and sets it on
/// the row's node (`row_specs[k]` is the spec of row `k`).
fn set_features(
    tree: &mut TableTree,
    row_specs: &[usize],
    table: &Table,
    genres: &[BTreeSet<String>],
    limits: &Limits,
) -> Result<(), FormatError> {
    let all: BTreeSet<&str> = genres.iter().flatten().map(String::as_str).collect();
    if all.is_empty() {
        return Err(FormatError::Structure {
            line: Some(table.header_line),
            column: None,
            message: "no row has a genre, so there is nothing to compare".to_owned(),
        });
    }
    // Every row gets a vector over all genres: bound them before allocating
    // rows × genres values (a column of unique genres would be quadratic).
    limits
        .check_dimensions(all.len(), "the genres")
        .map_err(|e| FormatError::Model {
            line: Some(table.header_line),
            column: None,
            source: ModelError::TooLarge(e),
        })?;
    let position: BTreeMap<&str, usize> = all.iter().enumerate().map(|(i, &g)| (g, i)).collect();
    for (&spec, set) in row_specs.iter().zip(genres) {
        let mut vector = vec![0.0; all.len()];
        for genre in set {
            if let Some(&index) = position.get(genre.as_str()) {
                vector[index] = 1.0;
            }
        }
        tree.specs[spec].features = Some(vector);
    }
    Ok(())
}
