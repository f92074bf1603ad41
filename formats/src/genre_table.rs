//! The genre-table format: one node table (see [`crate::node_table`]) whose rows also list
//! genres, kept as sets of genres ([`SparseVector::set`]) compared by Jaccard similarity. Owns the
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
//! must have a genre. Every row's node gets the set of its genres, numbered over the
//! genres that some row has, sorted by name (byte order, so the result depends on
//! neither column nor row order): as a vector, 1 when the row has the genre, else 0,
//! but stored as the genres' numbers only, so a table of 100,000 distinct genres
//! costs what its rows list. A one-hot column no row uses adds no member, so the same
//! data written either way gives the same dataset. A row without genres gets the
//! empty set, whose Jaccard similarity to anything is 0. The distinct genres are
//! bounded by [`Limits::max_set_members`] (not `max_dimensions`, which caps dense
//! vectors).
//!
//! The dataset's similarity hint is [`SimilarityHint::Jaccard`] (shared genres over
//! all genres of the pair). The paper's IMDB example instead uses `binary` (1 only
//! for identical genre sets); choose that in the configuration to override the hint.

use std::collections::{BTreeMap, BTreeSet};

use crate::dataset::ModelError;
use crate::dataset::{Dataset, SimilarityHint};
use crate::error::FormatError;
use crate::features::SparseVector;
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

/// Sets every row's genres, numbered over all genres sorted by name, on the row's
/// node (`row_specs[k]` is the spec of row `k`).
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
    let too_many = |e| FormatError::Model {
        line: Some(table.header_line),
        column: None,
        source: ModelError::TooLarge(e),
    };
    limits
        .check_set_members(all.len(), "genres")
        .map_err(too_many)?;
    // Within the limit, which fits a u32 (a larger limit fails here instead).
    let len = u32::try_from(all.len()).map_err(|_| {
        too_many(limits.exceeded(
            crate::limits::Limit::SetMembers,
            format_args!("{} distinct genres", all.len()),
        ))
    })?;
    let position: BTreeMap<&str, u32> = all
        .iter()
        .enumerate()
        .map(|(i, &g)| (g, i as u32))
        .collect();
    for (&spec, set) in row_specs.iter().zip(genres) {
        let members = set
            .iter()
            .filter_map(|genre| position.get(genre.as_str()).copied());
        // Every member is a position in `all`, below `len`.
        let features = SparseVector::set(len, members).ok_or_else(|| FormatError::Structure {
            line: Some(table.header_line),
            column: None,
            message: "internal error: a genre outside the genres found".to_owned(),
        })?;
        tree.specs[spec].features = Some(features.into());
    }
    Ok(())
}
