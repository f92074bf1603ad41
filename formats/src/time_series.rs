//! The time-series format: a node table (see [`crate::node_table`]) plus a table of values
//! by date and id, compared by Pearson correlation (the paper's stock example). Owns
//! the series table's layout, missing values and the checks that make correlation
//! defined.
//!
//! # Series
//!
//! A CSV/TSV table with a header row; the delimiter is detected per input as for
//! node tables. The first column holds the dates (any header name; the dates are
//! labels and are not interpreted: the rows' order is the time order). Every other
//! header cell is the id of a node of the node table, at most once. Each following
//! row is one date with a number per id; an empty cell is a missing value.
//!
//! Each id's column becomes its node's feature vector, one value per date. There
//! must be at least 3 dates, because a correlation of fewer points says nothing.
//! Every leaf of the node table needs a column; a row that has children may have
//! one. A missing value is an error unless [`FormatOptions::fill_missing`] is set:
//! then it takes the previous date's value (carried forward), and missing values
//! before an id's first value take that first value (back-filled). A column with no
//! value at all is an error either way. A constant series is allowed; Pearson
//! correlation is undefined for it and its similarity to every node is 0.
//!
//! The dataset's similarity hint is [`SimilarityHint::Pearson`].

use crate::dataset::FEATURE_BOUND;
use crate::dataset::{Dataset, SimilarityHint};
use crate::error::FormatError;
use crate::format::{Format, FormatOptions, InputError, Inputs, OnUnknownId, Role};
use crate::limits::Limit;
use crate::node_table::{node_tree, TableTree, NODES_ROLE};
use crate::table::{read_table_capped, Cap, Table};
use crate::warning::{Warning, WarningKind};

/// The time-series [`Format`] (name `time-series`, inputs `nodes` and `series`).
#[derive(Clone, Copy, Debug, Default)]
pub struct TimeSeries;

/// The inputs of [`TimeSeries`].
const ROLES: &[Role] = &[
    NODES_ROLE,
    Role {
        name: "series",
        required: true,
        description: "CSV/TSV: header date,id1,id2,..; one row per date, a value per id",
    },
];

/// Fewest dates a series may have: correlation needs at least 3 points.
const MIN_DATES: usize = 3;

impl Format for TimeSeries {
    fn name(&self) -> &'static str {
        "time-series"
    }

    fn roles(&self) -> &'static [Role] {
        ROLES
    }

    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let series = inputs.require("series")?;
        let in_nodes = |error| InputError::new("nodes", error);
        let in_series = |error| InputError::new("series", error);
        let mut tree = node_tree(inputs, options)?;
        // One row per date, and the dates are each node's dimensions.
        let cap = Cap::new(options.limits, Limit::Dimensions, 0, "dates");
        let series = read_table_capped(series, options.delimiter, Some(cap)).map_err(in_series)?;
        tree.warnings.append(series.warnings_in("series"));
        add_series(
            &mut tree,
            &series,
            options.fill_missing,
            options.on_unknown_id,
        )
        .map_err(in_series)?;
        tree.build(Some(SimilarityHint::Pearson)).map_err(in_nodes)
    }
}

/// Reads each id's column of `series` and sets it as the features of its
/// node; a column naming no node is skipped with a warning or is an error,
/// as `on_unknown` says.
fn add_series(
    tree: &mut TableTree,
    series: &Table,
    fill: bool,
    on_unknown: OnUnknownId,
) -> Result<(), FormatError> {
    if series.header.len() < 2 {
        return Err(FormatError::Structure {
            line: Some(series.header_line),
            column: None,
            message: "the header needs a date column and at least one id column".to_owned(),
        });
    }
    if series.rows.len() < MIN_DATES {
        return Err(FormatError::Structure {
            line: Some(
                series
                    .rows
                    .last()
                    .map_or(series.header_line, |row| row.line),
            ),
            column: None,
            message: format!(
                "{} date(s); a correlation needs at least {MIN_DATES}",
                series.rows.len()
            ),
        });
    }
    let date_name = &series.header[0];
    // Column (0-based) that gave each spec its series, to report repeats.
    let mut seen: Vec<Option<usize>> = vec![None; tree.specs.len()];
    for (column, id) in series.header.iter().enumerate().skip(1) {
        let header_error = |message: String| FormatError::Field {
            line: Some(series.header_line),
            column: Some(column + 1),
            node: None,
            field: id.clone(),
            message,
        };
        let Some(index) = tree.find(id) else {
            if on_unknown == OnUnknownId::Warn {
                tree.warnings.push(Warning::new(
                    WarningKind::UnknownId,
                    "series",
                    Some(series.header_line),
                    format!(
                        "column {}: unknown id {id:?}: no node of the node table has it; the \
                         column is skipped (fields.on_unknown_id: error makes this an error)",
                        column + 1
                    ),
                ));
                continue;
            }
            return Err(header_error(format!(
                "unknown id {id:?}: no node of the node table has it"
            )));
        };
        if let Some(previous) = seen[index] {
            return Err(header_error(format!(
                "id {id:?} has a second column (the first is column {})",
                previous + 1
            )));
        }
        seen[index] = Some(column);

        let mut values: Vec<Option<f64>> = Vec::with_capacity(series.rows.len());
        for row in &series.rows {
            let text = row.fields.get(column).map_or("", String::as_str);
            let date = row.fields.first().map_or("", String::as_str);
            let cell_error = |message: String| FormatError::Field {
                line: Some(row.line),
                column: Some(column + 1),
                node: Some(id.clone()),
                field: id.clone(),
                message,
            };
            if text.is_empty() {
                if !fill {
                    return Err(cell_error(format!(
                        "missing value for {date_name} {date:?} (set fill_missing to carry \
                         the previous value forward)"
                    )));
                }
                values.push(None);
                continue;
            }
            match text.parse::<f64>().ok().filter(|v| v.is_finite()) {
                Some(value) if value.abs() > FEATURE_BOUND => {
                    return Err(cell_error(format!(
                        "{text}: values must lie within ±{FEATURE_BOUND:e} (sums of their squares would overflow)"
                    )))
                }
                Some(value) => values.push(Some(value)),
                None => {
                    return Err(cell_error(format!(
                        "expected a finite number for {date_name} {date:?}, found {text:?}"
                    )))
                }
            }
        }
        let Some(first) = values.iter().flatten().next().copied() else {
            return Err(header_error(format!("id {id:?} has no value on any date")));
        };
        // Leading gaps take the first value; later gaps the value before them.
        let mut last = first;
        let vector: Vec<f64> = values
            .into_iter()
            .map(|value| {
                last = value.unwrap_or(last);
                last
            })
            .collect();
        tree.specs[index].features = Some(vector.into());
    }
    let leaves = tree.leaf_flags();
    for (index, spec) in tree.specs.iter().enumerate() {
        if leaves[index] && spec.features.is_none() {
            let place =
                tree.lines[index].map_or_else(String::new, |line| format!(" (nodes line {line})"));
            return Err(FormatError::Structure {
                line: Some(series.header_line),
                column: None,
                message: format!(
                    "node {:?}{place} has no column; every leaf needs one",
                    spec.id
                ),
            });
        }
    }
    Ok(())
}
