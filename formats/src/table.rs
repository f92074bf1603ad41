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

use crate::dataset::ModelError;
use crate::error::FormatError;
use crate::limits::{Limit, Limits};
use crate::warning::Warning;

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
    pub warnings: Vec<Warning>,
}

impl Table {
    /// The table's warnings, as warnings about input `role`.
    pub fn warnings_in(&self, role: &str) -> impl Iterator<Item = Warning> + '_ {
        let role = role.to_owned();
        self.warnings.iter().map(move |w| Warning {
            role: role.clone(),
            ..w.clone()
        })
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

/// A bound on the records a reader keeps: past `rows` records it stops with
/// `limit`'s error (naming what the records are, e.g. `rows`, `dates`), so an
/// oversized input costs memory for `rows` records only.
#[derive(Clone, Copy, Debug)]
pub struct RowCap {
    /// Most records kept (a header row included).
    pub rows: usize,
    /// The limit this enforces.
    pub limit: Limit,
    /// The limits (for the error's figures).
    pub limits: Limits,
    /// What a record is, for the message.
    pub what: &'static str,
}

impl RowCap {
    /// A cap of `limit`'s value plus `extra` records (a header).
    pub fn new(limits: Limits, limit: Limit, extra: usize, what: &'static str) -> Self {
        RowCap {
            rows: usize::try_from(limits.get(limit))
                .unwrap_or(usize::MAX)
                .saturating_add(extra),
            limit,
            limits,
            what,
        }
    }

    fn error(&self, line: usize) -> FormatError {
        let allowed = self.limits.get(self.limit);
        FormatError::Model {
            line: Some(line),
            column: None,
            source: ModelError::TooLarge(self.limits.exceeded(
                self.limit,
                format_args!("more than {allowed} {}", self.what),
            )),
        }
    }
}

/// Reads every record of a CSV/TSV input, without interpreting a header. Records may
/// have different lengths; callers check. An input without any record is an error.
pub fn read_rows(bytes: &[u8], delimiter: Option<u8>) -> Result<Vec<Row>, FormatError> {
    read_rows_capped(bytes, delimiter, None)
}

/// [`read_rows`], stopping with an error past `cap`'s records.
pub fn read_rows_capped(
    bytes: &[u8],
    delimiter: Option<u8>,
    cap: Option<RowCap>,
) -> Result<Vec<Row>, FormatError> {
    let delimiter = detect_delimiter(bytes, delimiter);
    let bytes = strip_bom(bytes);
    check_text(bytes, delimiter)?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delimiter)
        .from_reader(bytes);
    let mut rows = Vec::new();
    let mut record = csv::ByteRecord::new();
    let (mut line_at, mut counted_to) = (1, 0);
    loop {
        match reader.read_byte_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(error) => {
                // check_text rejects what the csv crate could complain about, so this is
                // a fallback; report it with the position the crate gives.
                let line = error.position().map_or(1, |p| p.line() as usize);
                return Err(FormatError::Syntax {
                    line,
                    column: 0,
                    message: error.to_string(),
                });
            }
        }
        // Lines from the byte offset, not csv's own line count, which goes wrong after
        // CRLF (it reports the record after `\r\n` at the `\n`, on the line before).
        // For the same reason skip line-end bytes at the reported offset: a record never
        // starts with one. Offsets only grow, so this visits every byte once.
        let mut start = record
            .position()
            .map_or(0, |p| usize::try_from(p.byte()).unwrap_or(usize::MAX))
            .min(bytes.len());
        while matches!(bytes.get(start), Some(b'\r' | b'\n')) {
            start += 1;
        }
        if start > counted_to {
            line_at += bytes[counted_to..start]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            counted_to = start;
        }
        let line = line_at;
        let mut fields = Vec::with_capacity(record.len());
        for (index, field) in record.iter().enumerate() {
            let text = std::str::from_utf8(field).map_err(|_| FormatError::Syntax {
                line,
                column: index + 1,
                message: "the field is not valid UTF-8 text".to_owned(),
            })?;
            fields.push(text.trim().to_owned());
        }
        // A line of only whitespace reads as one empty field; treat it as empty.
        if fields.len() == 1 && fields[0].is_empty() {
            continue;
        }
        if let Some(cap) = &cap {
            if rows.len() >= cap.rows {
                return Err(cap.error(line));
            }
        }
        rows.push(Row { line, fields });
    }
    if rows.is_empty() {
        return Err(FormatError::Structure {
            line: Some(1),
            column: None,
            message: "the input is empty: expected at least one CSV/TSV row".to_owned(),
        });
    }
    Ok(rows)
}

/// Reads a CSV/TSV input whose first row is a header; every row must have as many
/// fields as the header.
pub fn read_table(bytes: &[u8], delimiter: Option<u8>) -> Result<Table, FormatError> {
    read_table_capped(bytes, delimiter, None)
}

/// [`read_table`], stopping with an error past `cap`'s data rows (the header
/// does not count).
pub fn read_table_capped(
    bytes: &[u8],
    delimiter: Option<u8>,
    cap: Option<RowCap>,
) -> Result<Table, FormatError> {
    let cap = cap.map(|c| RowCap {
        rows: c.rows.saturating_add(1),
        ..c
    });
    let mut rows = read_rows_capped(bytes, delimiter, cap)?.into_iter();
    let Some(header_row) = rows.next() else {
        // read_rows never returns no rows; keep the error rather than a panic.
        return Err(FormatError::Structure {
            line: Some(1),
            column: None,
            message: "the input is empty: expected a header row".to_owned(),
        });
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
    let mut warnings = Vec::new();
    for (index, name) in header_row.fields.iter().enumerate() {
        if let Some(first) = header_row.fields[..index]
            .iter()
            .position(|earlier| earlier.eq_ignore_ascii_case(name))
        {
            warnings.push(Warning::new(
                "",
                Some(header_row.line),
                format!(
                    "column {} repeats the name {name:?} of column {}; only column {} is read",
                    index + 1,
                    first + 1,
                    first + 1
                ),
            ));
        }
    }
    let width = header_row.fields.len();
    let rows: Vec<Row> = rows.collect();
    for row in &rows {
        if row.fields.len() != width {
            return Err(FormatError::Structure {
                line: Some(row.line),
                column: None,
                message: format!(
                    "wrong number of fields: found {}, the header (line {}) has {width}",
                    row.fields.len(),
                    header_row.line
                ),
            });
        }
    }
    Ok(Table {
        header: header_row.fields,
        header_line: header_row.line,
        rows,
        warnings,
    })
}

/// Rejects bytes that are not CSV text before the csv crate reads them: NUL bytes
/// (binary data) and quoting the csv crate would silently accept and reinterpret
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
