//! CSV/TSV bytes → records with positions ([`Row`](crate::table::Row)), and
//! tables with a header row ([`Table`](crate::table::Table)). Shared by every
//! table format; what a node table's columns mean is [`crate::node_table`]'s.
//!
//! # Reading
//!
//! A UTF-8 byte order mark is skipped and CRLF line ends are read like LF. Empty
//! lines are skipped. Fields are trimmed of surrounding whitespace. Quoting follows
//! RFC 4180 strictly: a quote may only open a field or be doubled inside a quoted
//! field, and a closing quote must end the field; anything else is an error rather
//! than a silent guess. Positions: lines are 1-based; the column of a field is its
//! 1-based field number (the first field is column 1), which is what people look for
//! in a spreadsheet.
//!
//! # Bounds
//!
//! Records are read field by field, so every bound holds before memory is spent:
//! a table's data row is refused at its first field past the header's width (the
//! rest of it is counted for the message, not kept), rows without a header and
//! headers stop at a [`Cap`](crate::table::Cap) on fields, and a `Cap` on
//! records stops at a record count. Checking the header
//! for repeated names is one pass with a map.

use std::collections::hash_map::Entry;
use std::collections::HashMap;

use crate::dataset::ModelError;
use crate::error::FormatError;
use crate::limits::{Limit, Limits};
use crate::warning::{Warning, WarningKind, Warnings};

/// One record of a CSV/TSV input, fields trimmed.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// 1-based line the record starts on.
    pub line: usize,
    /// The fields, in order.
    pub fields: Vec<String>,
}

/// A CSV/TSV input with a header row; every row has as many fields as the header.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The column names, trimmed.
    pub header: Vec<String>,
    /// 1-based line of the header row.
    pub header_line: usize,
    /// The data rows.
    pub rows: Vec<Row>,
    /// Repeated column names (the first of each is the one used), as
    /// warnings without a role: [`Table::warnings_in`] gives them one.
    pub warnings: Warnings,
}

impl Table {
    /// The table's warnings, as warnings about input `role`.
    pub fn warnings_in(&self, role: &str) -> Warnings {
        self.warnings.clone().with_role(role)
    }

    /// Index of the column called `name` (ASCII case-insensitive), if any.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header
            .iter()
            .position(|column| column.eq_ignore_ascii_case(name))
    }

    /// Index of the column named by an option, or an error at the header naming the
    /// option when the table has no such column.
    pub fn required_column(&self, name: &str, option: &str) -> Result<usize, FormatError> {
        self.column(name).ok_or_else(|| FormatError::Structure {
            line: Some(self.header_line),
            column: None,
            message: format!(
                "no column {name:?} ({option}){}; the header has: {}",
                crate::suggest::did_you_mean(name, self.header.iter().map(String::as_str)),
                self.header.join(", ")
            ),
        })
    }

    /// The column named by `option` when given (then it must exist), else the first
    /// of `defaults` present.
    pub fn optional_column(
        &self,
        option: Option<&str>,
        option_name: &str,
        defaults: &[&str],
    ) -> Result<Option<usize>, FormatError> {
        match option {
            Some(name) => self.required_column(name, option_name).map(Some),
            None => Ok(defaults.iter().find_map(|name| self.column(name))),
        }
    }
}

/// The delimiter to use: the given one, else comma when the first non-empty line
/// (the header) has a comma, else the first of tab, `;` and `|` it has (spreadsheets
/// in many locales save `;`), else comma.
pub fn detect_delimiter(bytes: &[u8], given: Option<u8>) -> u8 {
    if let Some(delimiter) = given {
        return delimiter;
    }
    let bytes = strip_bom(bytes);
    let first_line = bytes
        .split(|&b| b == b'\n')
        .find(|line| !line.iter().all(u8::is_ascii_whitespace))
        .unwrap_or(&[]);
    if first_line.contains(&b',') {
        return b',';
    }
    [b'\t', b';', b'|']
        .into_iter()
        .find(|d| first_line.contains(d))
        .unwrap_or(b',')
}

/// The bytes without a leading UTF-8 byte order mark.
fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

/// A bound on what a reader keeps, from one of the [`Limits`]: past `max`
/// records of an input (a cap on rows) or `max` fields of one record (a cap on
/// fields) it stops with `limit`'s error, naming what they are (`rows`,
/// `dates`, `values`), so an oversized input costs memory for `max` of them
/// only. (A table's data rows are bounded by its header anyway; a cap on
/// fields bounds rows with no header to compare with, and headers.)
#[derive(Clone, Copy, Debug)]
pub struct Cap {
    /// Most records kept (a header row included), or most fields kept of one
    /// record.
    pub max: usize,
    /// The limit this enforces.
    pub limit: Limit,
    /// The limits (for the error's figures).
    pub limits: Limits,
    /// What a record is, or what the fields past the first `extra` are, for
    /// the message.
    pub what: &'static str,
}

impl Cap {
    /// A cap of `limit`'s value plus `extra` records (a header) or fields (an
    /// id before the values).
    pub fn new(limits: Limits, limit: Limit, extra: usize, what: &'static str) -> Self {
        Cap {
            max: usize::try_from(limits.get(limit))
                .unwrap_or(usize::MAX)
                .saturating_add(extra),
            limit,
            limits,
            what,
        }
    }

    /// The bound on a table's header: one column per node (a time series'
    /// header names every node) plus the first. No table format reads more.
    pub fn columns(limits: Limits) -> Self {
        Cap::new(limits, Limit::Nodes, 1, "columns after the first")
    }

    /// The error for a record past the cap on records, on `line`.
    fn too_many_records(&self, line: usize) -> FormatError {
        self.error(line, "")
    }

    /// The error for a record past the cap on fields, on `line`.
    fn too_many_fields(&self, line: usize) -> FormatError {
        self.error(line, "a row of ")
    }

    fn error(&self, line: usize, prefix: &str) -> FormatError {
        let allowed = self.limits.get(self.limit);
        FormatError::Model {
            line: Some(line),
            column: None,
            source: ModelError::TooLarge(self.limits.exceeded(
                self.limit,
                format_args!("{prefix}more than {allowed} {}", self.what),
            )),
        }
    }
}

/// Reads every record of a CSV/TSV input, without interpreting a header. Records may
/// have different lengths; callers check. An input without any record is an error.
pub fn read_rows(bytes: &[u8], delimiter: Option<u8>) -> Result<Vec<Row>, FormatError> {
    read_rows_bounded(bytes, delimiter, None, None)
}

/// [`read_rows`], stopping with an error past `rows`' records or at a record
/// with more than `fields`' fields.
pub fn read_rows_bounded(
    bytes: &[u8],
    delimiter: Option<u8>,
    rows: Option<Cap>,
    fields: Option<Cap>,
) -> Result<Vec<Row>, FormatError> {
    let mut records = Records::new(bytes, delimiter)?;
    let mut out = Vec::new();
    let max_fields = fields.map_or(usize::MAX, |cap| cap.max);
    while let Some(record) = records.next(max_fields)? {
        let row = match record {
            Record::Row(row) => row,
            Record::TooWide { line, .. } => {
                return Err(fields.map_or_else(
                    // Unreachable: without a cap no record is too wide.
                    || FormatError::Structure {
                        line: Some(line),
                        column: None,
                        message: "the row has too many fields".to_owned(),
                    },
                    |cap| cap.too_many_fields(line),
                ));
            }
        };
        if let Some(cap) = &rows {
            if out.len() >= cap.max {
                return Err(cap.too_many_records(row.line));
            }
        }
        out.push(row);
    }
    if out.is_empty() {
        return Err(empty_input());
    }
    Ok(out)
}

fn empty_input() -> FormatError {
    FormatError::Structure {
        line: Some(1),
        column: None,
        message: "the input is empty: expected at least one CSV/TSV row".to_owned(),
    }
}

/// Reads a CSV/TSV input whose first row is a header; every row must have as many
/// fields as the header.
pub fn read_table(bytes: &[u8], delimiter: Option<u8>) -> Result<Table, FormatError> {
    read_table_bounded(bytes, delimiter, None, None)
}

/// [`read_table`], stopping with an error past `cap`'s data rows (the header
/// does not count) and at a header of more than [`Cap::columns`].
pub fn read_table_capped(
    bytes: &[u8],
    delimiter: Option<u8>,
    cap: Option<Cap>,
) -> Result<Table, FormatError> {
    let header = cap.map(|c| Cap::columns(c.limits));
    read_table_bounded(bytes, delimiter, cap, header)
}

/// [`read_table`], stopping with an error past `rows`' data rows and at a
/// header of more than `header`'s fields. A data row is read only up to the
/// header's width: one field more is an error, and the rest of that row is
/// counted for the message, not kept.
pub fn read_table_bounded(
    bytes: &[u8],
    delimiter: Option<u8>,
    rows: Option<Cap>,
    header: Option<Cap>,
) -> Result<Table, FormatError> {
    let mut records = Records::new(bytes, delimiter)?;
    let header_row = match records.next(header.map_or(usize::MAX, |cap| cap.max))? {
        None => return Err(empty_input()),
        Some(Record::Row(row)) => row,
        Some(Record::TooWide { line, .. }) => {
            return Err(header.map_or_else(empty_input, |cap| cap.too_many_fields(line)))
        }
    };
    for (index, name) in header_row.fields.iter().enumerate() {
        if name.is_empty() {
            return Err(FormatError::Structure {
                line: Some(header_row.line),
                column: Some(index + 1),
                message: format!("header column {} has no name", index + 1),
            });
        }
    }
    let warnings = repeated_names(&header_row);
    let width = header_row.fields.len();
    let wrong_width = |line: usize, found: usize| FormatError::Structure {
        line: Some(line),
        column: None,
        message: format!(
            "wrong number of fields: found {found}, the header (line {}) has {width}",
            header_row.line
        ),
    };
    let mut data = Vec::new();
    while let Some(record) = records.next(width)? {
        let row = match record {
            Record::TooWide { line, fields } => return Err(wrong_width(line, fields)),
            Record::Row(row) if row.fields.len() != width => {
                return Err(wrong_width(row.line, row.fields.len()))
            }
            Record::Row(row) => row,
        };
        if let Some(cap) = &rows {
            if data.len() >= cap.max {
                return Err(cap.too_many_records(row.line));
            }
        }
        data.push(row);
    }
    Ok(Table {
        header: header_row.fields,
        header_line: header_row.line,
        rows: data,
        warnings,
    })
}

/// A warning for each header name that repeats an earlier one (ASCII
/// case-insensitively), naming both columns. One pass with a map of the names
/// seen: comparing every name with every earlier one took 16 s for 100,000
/// names.
fn repeated_names(header: &Row) -> Warnings {
    let mut first_of: HashMap<String, usize> = HashMap::with_capacity(header.fields.len());
    let mut warnings = Warnings::new();
    for (index, name) in header.fields.iter().enumerate() {
        match first_of.entry(name.to_ascii_lowercase()) {
            Entry::Vacant(slot) => {
                slot.insert(index);
            }
            Entry::Occupied(first) => {
                let first = *first.get() + 1;
                warnings.push(Warning::new(
                    WarningKind::RepeatedColumn,
                    "",
                    Some(header.line),
                    format!(
                        "column {} repeats the name {name:?} of column {first}; only column \
                         {first} is read",
                        index + 1,
                    ),
                ));
            }
        }
    }
    warnings
}

/// What [`Records::next`] read.
enum Record {
    /// A record within the bound on its fields (blank records are skipped).
    Row(Row),
    /// A record with more fields than the bound: `fields` were counted, the
    /// bound's worth kept and dropped.
    TooWide { line: usize, fields: usize },
}

/// The records of a CSV/TSV input, one at a time, read field by field with
/// `csv_core` (the csv crate's own parser) so that a record can be given up at
/// any field: the csv crate's `ByteRecord` holds a record whole (a row of 100
/// million commas took 3.5 GB before its length could be checked).
struct Records<'a> {
    bytes: &'a [u8],
    core: csv_core::Reader,
    /// Bytes of `bytes` consumed.
    at: usize,
    /// The line of byte `counted_to`, both moving forward only, so lines are
    /// counted once per byte.
    line_at: usize,
    counted_to: usize,
    /// The current field's bytes (unquoted by `csv_core`).
    field: Vec<u8>,
}

impl<'a> Records<'a> {
    /// Checks the text (see [`check_text`]) and starts reading it with
    /// `delimiter` (or the detected one).
    fn new(bytes: &'a [u8], delimiter: Option<u8>) -> Result<Self, FormatError> {
        let delimiter = detect_delimiter(bytes, delimiter);
        let bytes = strip_bom(bytes);
        check_text(bytes, delimiter)?;
        Ok(Records {
            bytes,
            core: csv_core::ReaderBuilder::new().delimiter(delimiter).build(),
            at: 0,
            line_at: 1,
            counted_to: 0,
            field: vec![0; 256],
        })
    }

    /// The 1-based line of the record starting at byte `start`.
    fn line_of(&mut self, mut start: usize) -> usize {
        // csv_core consumes a record's line end in the call that reads the next
        // record, and skips empty lines there too: a record never starts with a
        // line-end byte, so skip them to find its first line.
        while matches!(self.bytes.get(start), Some(b'\r' | b'\n')) {
            start += 1;
        }
        if start > self.counted_to {
            self.line_at += self.bytes[self.counted_to..start]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            self.counted_to = start;
        }
        self.line_at
    }

    /// The next record that is not blank (one field of only whitespace), its
    /// fields trimmed, keeping at most `max_fields` of them; `None` at the end.
    fn next(&mut self, max_fields: usize) -> Result<Option<Record>, FormatError> {
        use csv_core::ReadFieldResult as Read;
        loop {
            let line = self.line_of(self.at);
            let mut fields: Vec<String> = Vec::new();
            // Fields ended in this record, and bytes of the current one.
            let (mut count, mut len) = (0usize, 0usize);
            loop {
                let (result, read, written) = self
                    .core
                    .read_field(&self.bytes[self.at..], &mut self.field[len..]);
                self.at += read;
                len += written;
                match result {
                    // The whole rest was given: the next call (with no input)
                    // ends the field.
                    Read::InputEmpty => {}
                    // Past the bound the field's bytes are only skipped.
                    Read::OutputFull if count >= max_fields => len = 0,
                    Read::OutputFull => {
                        let grown = self.field.len().saturating_mul(2);
                        self.field.resize(grown, 0);
                    }
                    Read::Field { record_end } => {
                        count += 1;
                        if count <= max_fields {
                            let text = std::str::from_utf8(&self.field[..len]).map_err(|_| {
                                FormatError::Syntax {
                                    line,
                                    column: count,
                                    message: "the field is not valid UTF-8 text".to_owned(),
                                }
                            })?;
                            fields.push(text.trim().to_owned());
                        }
                        len = 0;
                        if record_end {
                            break;
                        }
                    }
                    Read::End => return Ok(None),
                }
            }
            if count > max_fields {
                return Ok(Some(Record::TooWide {
                    line,
                    fields: count,
                }));
            }
            // A line of only whitespace reads as one empty field; treat it as empty.
            if fields.len() == 1 && fields[0].is_empty() {
                continue;
            }
            return Ok(Some(Record::Row(Row { line, fields })));
        }
    }
}

/// Rejects bytes that are not CSV text before they are parsed: NUL bytes
/// (binary data) and quoting `csv_core` would silently accept and reinterpret
/// (an unterminated quoted field swallows the rest of the file; a stray quote is
/// kept as text). Positions as in the module docs.
fn check_text(bytes: &[u8], delimiter: u8) -> Result<(), FormatError> {
    #[derive(PartialEq)]
    enum State {
        FieldStart,
        Unquoted,
        Quoted,
        // Just saw a quote inside a quoted field: either a doubled quote or the end.
        QuoteInQuoted,
    }
    let mut state = State::FieldStart;
    let mut line = 1;
    let mut field = 1;
    let mut quote_start = (1, 1);
    for &byte in bytes {
        if byte == 0 {
            return Err(FormatError::Syntax {
                line,
                column: field,
                message: "binary data (a NUL byte): this is not CSV/TSV text".to_owned(),
            });
        }
        state = match (state, byte) {
            (State::Quoted, b'"') => State::QuoteInQuoted,
            (State::Quoted, b'\n') => {
                line += 1;
                State::Quoted
            }
            (State::Quoted, _) => State::Quoted,
            (State::QuoteInQuoted, b'"') => State::Quoted,
            (State::FieldStart, b'"') => {
                quote_start = (line, field);
                State::Quoted
            }
            (State::Unquoted, b'"') => {
                return Err(FormatError::Syntax {
                    line,
                    column: field,
                    message: "bad quoting: a quote inside an unquoted field (quote the whole \
                              field and double the inner quote)"
                        .to_owned(),
                })
            }
            (_, b'\n') => {
                line += 1;
                field = 1;
                State::FieldStart
            }
            (_, b'\r') => State::FieldStart,
            (_, b) if b == delimiter => {
                field += 1;
                State::FieldStart
            }
            (State::QuoteInQuoted, _) => {
                return Err(FormatError::Syntax {
                    line,
                    column: field,
                    message: "bad quoting: text after the closing quote of a quoted field"
                        .to_owned(),
                })
            }
            // Leading spaces are allowed before a field's text (it is trimmed later).
            (State::FieldStart, b' ') => State::FieldStart,
            (State::FieldStart | State::Unquoted, _) => State::Unquoted,
        };
    }
    if state == State::Quoted {
        return Err(FormatError::Syntax {
            line: quote_start.0,
            column: quote_start.1,
            message: "bad quoting: a quoted field is never closed".to_owned(),
        });
    }
    Ok(())
}
