//! The border-list format: a node table (see [`crate::node_table`]) plus a pair list
//! saying which nodes are neighbours, e.g. countries that share a land border.
//! Owns the pair-list columns and how pairs become symmetric relations.
//!
//! # Pair list
//!
//! CSV or TSV with a header. The two node columns are `a` and `b` when the header has
//! them, else the first two columns. An optional strength column
//! ([`FormatOptions::strength`], else `strength` when present) holds a finite number
//! `>= 0`; a pair with strength 0 is dropped. The model keeps no per-pair weight, so
//! any other strength just means "related". Pairs are symmetric: `a,b` relates `b` to
//! `a` too, and repeats collapse (a repeat with another strength is a warning). A
//! pair of a node with itself is ignored, with a warning. Every id must be a node
//! of the table (a row or a group id).
//!
//! The dataset's similarity hint is [`SimilarityHint::NeighborList`].

use std::collections::HashMap;

use crate::dataset::{Dataset, SimilarityHint};
use crate::error::FormatError;
use crate::format::{Format, FormatOptions, InputError, Inputs, OnUnknownId, Role};
use crate::node_table::{parse_with_input, TableTree, NODES_ROLE};
use crate::table::{read_table_bounded, Cap, Row, Table};
use crate::warning::{Warning, WarningKind};

/// The border-list [`Format`] (name `border-list`, inputs `nodes` and `pairs`).
#[derive(Clone, Copy, Debug, Default)]
pub struct BorderList;

/// The inputs of [`BorderList`].
const ROLES: &[Role] = &[
    NODES_ROLE,
    Role {
        name: "pairs",
        required: true,
        description: "pair list CSV/TSV with a header: a,b and an optional strength",
    },
];

impl Format for BorderList {
    fn name(&self) -> &'static str {
        "border-list"
    }

    fn roles(&self) -> &'static [Role] {
        ROLES
    }

    #[allow(clippy::result_large_err)] // InputError's shape is the Format API's
    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let in_pairs = |error| InputError::new("pairs", error);
        let hint = SimilarityHint::NeighborList;
        parse_with_input(inputs, options, "pairs", hint, |tree, pairs| {
            let columns = Cap::columns(options.limits);
            let pair_table = read_table_bounded(pairs, options.delimiter, None, Some(columns))
                .map_err(in_pairs)?;
            tree.warnings.append(pair_table.warnings_in("pairs"));
            add_pairs(tree, &pair_table, options).map_err(in_pairs)
        })
    }
}

/// The first line and strength of each unordered pair read so far.
type Seen = HashMap<(usize, usize), (usize, Option<f64>)>;

/// Adds each pair of the pair list as a relation on both of its nodes.
fn add_pairs(
    tree: &mut TableTree,
    pairs: &Table,
    options: &FormatOptions,
) -> Result<(), FormatError> {
    let (a, b) = id_columns(pairs)?;
    let strength = pairs.optional_column(
        options.strength.as_deref(),
        "the strength column",
        &["strength"],
    )?;
    // To warn about a repeat that says something else (the model keeps no
    // strengths).
    let mut seen = Seen::new();
    for row in &pairs.rows {
        let Some((first, second)) = pair_nodes(tree, pairs, row, [a, b], options.on_unknown_id)?
        else {
            continue;
        };
        let given = match strength {
            Some(column) => Some(parse_strength(pairs, row, column)?),
            None => None,
        };
        // A self pair is ignored (the model would drop it anyway).
        if first == second {
            tree.warnings.push(Warning::new(
                WarningKind::SelfPair,
                "pairs",
                Some(row.line),
                format!(
                    "the pair ({0}, {0}) joins a node to itself; it is ignored",
                    tree.specs[first].id
                ),
            ));
            continue;
        }
        note_repeat(tree, &mut seen, row.line, (first, second), given);
        if given == Some(0.0) {
            continue;
        }
        let (first_id, second_id) = (tree.specs[first].id.clone(), tree.specs[second].id.clone());
        tree.specs[first].relations.push(second_id);
        tree.specs[second].relations.push(first_id);
    }
    Ok(())
}

/// The two id columns: `a` and `b` when the header has them, else the first two.
fn id_columns(pairs: &Table) -> Result<(usize, usize), FormatError> {
    match (pairs.column("a"), pairs.column("b")) {
        (Some(a), Some(b)) => Ok((a, b)),
        _ if pairs.header.len() >= 2 => Ok((0, 1)),
        _ => Err(FormatError::Structure {
            line: Some(pairs.header_line),
            column: None,
            message: format!(
                "a pair list needs two id columns (a,b); the header has: {}",
                pairs.header.join(", ")
            ),
        }),
    }
}

/// The nodes (indices into the tree's specs) the pair of `row` joins; `None`
/// when an id names no node and `on_unknown` says to skip the pair (with a
/// warning), an error when it says so.
fn pair_nodes(
    tree: &mut TableTree,
    pairs: &Table,
    row: &Row,
    columns: [usize; 2],
    on_unknown: OnUnknownId,
) -> Result<Option<(usize, usize)>, FormatError> {
    let unknown = columns
        .into_iter()
        .find(|&column| tree.find(&row.fields[column]).is_none());
    if let Some(column) = unknown {
        let id = &row.fields[column];
        if on_unknown == OnUnknownId::Error {
            return Err(FormatError::Field {
                line: Some(row.line),
                column: Some(column + 1),
                node: None,
                field: pairs.header[column].clone(),
                message: format!("unknown id {id:?}: no node of the node table has it"),
            });
        }
        tree.warnings.push(Warning::new(
            WarningKind::UnknownId,
            "pairs",
            Some(row.line),
            format!(
                "unknown id {id:?} in field {:?}: no node of the node table has it; \
                 the pair is skipped (fields.on_unknown_id: error makes this an error)",
                pairs.header[column]
            ),
        ));
        return Ok(None);
    }
    let node = |column: usize| tree.find(&row.fields[column]).unwrap_or_default();
    Ok(Some((node(columns[0]), node(columns[1]))))
}

/// The pair's strength in `column`: a finite number `>= 0`.
fn parse_strength(pairs: &Table, row: &Row, column: usize) -> Result<f64, FormatError> {
    let text = &row.fields[column];
    text.parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| FormatError::Field {
            line: Some(row.line),
            column: Some(column + 1),
            node: None,
            field: pairs.header[column].clone(),
            message: format!("expected a finite number >= 0, found {text:?}"),
        })
}

/// Records the pair `(first, second)` of `line` with its strength `given`, or
/// warns when it repeats an earlier line with another strength.
fn note_repeat(
    tree: &mut TableTree,
    seen: &mut Seen,
    line: usize,
    (first, second): (usize, usize),
    given: Option<f64>,
) {
    let key = (first.min(second), first.max(second));
    match seen.get(&key) {
        Some(&(earlier, before)) if before != given => {
            let say = |s: Option<f64>| s.map_or_else(|| "none".to_owned(), |v| v.to_string());
            tree.warnings.push(Warning::new(
                WarningKind::RepeatedPair,
                "pairs",
                Some(line),
                format!(
                    "the pair ({}, {}) repeats line {earlier} with another strength ({} there, {} here); \
                     strengths only say whether two nodes are related",
                    tree.specs[first].id,
                    tree.specs[second].id,
                    say(before),
                    say(given)
                ),
            ));
        }
        Some(_) => {}
        None => {
            seen.insert(key, (line, given));
        }
    }
}
