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
use crate::node_table::{parse_with_input, TableTree, NODES_ROLE};
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

    #[allow(clippy::result_large_err)] // InputError's shape is the Format API's
    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let in_series = |error| InputError::new("series", error);
        let hint = SimilarityHint::Pearson;
        parse_with_input(inputs, options, "series", hint, |tree, series| {
            // One row per date, and the dates are each node's dimensions.
            let cap = Cap::new(options.limits, Limit::Dimensions, 0, "dates");
            let series =
                read_table_capped(series, options.delimiter, Some(cap)).map_err(in_series)?;
            tree.warnings.append(series.warnings_in("series"));
            add_series(tree, &series, options.fill_missing, options.on_unknown_id)
                .map_err(in_series)
        })
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
    check_shape(series)?;
    // Column (0-based) that gave each spec its series, to report repeats.
    let mut seen: Vec<Option<usize>> = vec![None; tree.specs.len()];
    for column in 1..series.header.len() {
        let Some(index) = column_owner(tree, series, column, on_unknown, &mut seen)? else {
            continue;
        };
        let vector = column_values(series, column, fill)?;
        tree.specs[index].features = Some(vector.into());
    }
    tree.check_leaf_features(Some(series.header_line), "column")
}

/// A date column and at least one id column, and at least [`MIN_DATES`] dates.
fn check_shape(series: &Table) -> Result<(), FormatError> {
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
    Ok(())
}

/// The error at the header cell of `column`, which names an id.
fn header_error(series: &Table, column: usize, message: String) -> FormatError {
    FormatError::Field {
        line: Some(series.header_line),
        column: Some(column + 1),
        node: None,
        field: series.header[column].clone(),
        message,
    }
}

/// The node (index into the tree's specs) whose id heads `column`; `None`
/// when it names no node and `on_unknown` says to skip the column (with a
/// warning). A second column for a node is an error; `seen` holds the
/// column that gave each node its series.
fn column_owner(
    tree: &mut TableTree,
    series: &Table,
    column: usize,
    on_unknown: OnUnknownId,
    seen: &mut [Option<usize>],
) -> Result<Option<usize>, FormatError> {
    let id = &series.header[column];
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
            return Ok(None);
        }
        return Err(header_error(
            series,
            column,
            format!("unknown id {id:?}: no node of the node table has it"),
        ));
    };
    if let Some(previous) = seen[index] {
        return Err(header_error(
            series,
            column,
            format!(
                "id {id:?} has a second column (the first is column {})",
                previous + 1
            ),
        ));
    }
    seen[index] = Some(column);
    Ok(Some(index))
}

/// The series in `column`, one value per date: each cell a finite number
/// within [`FEATURE_BOUND`]; empty cells are an error, or with `fill` take
/// the value before them (leading ones the first value).
fn column_values(series: &Table, column: usize, fill: bool) -> Result<Vec<f64>, FormatError> {
    let id = &series.header[column];
    let date_name = &series.header[0];
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
        return Err(header_error(
            series,
            column,
            format!("id {id:?} has no value on any date"),
        ));
    };
    // Leading gaps take the first value; later gaps the value before them.
    let mut last = first;
    Ok(values
        .into_iter()
        .map(|value| {
            last = value.unwrap_or(last);
            last
        })
        .collect())
}
