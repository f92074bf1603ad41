//! CSV/TSV bytes → rows with positions, and a node table → the [`NodeSpec`]s of a
//! hierarchy. Shared by the table formats (border list, embedding matrix); owns the
//! rules for ids, labels, weights and the hierarchy columns of a node table.
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
//! # Node tables
//!
//! A node table has a header row. Columns (names match ASCII case-insensitively):
//!
//! - **id**: [`FormatOptions::id`], default `id`. Required unless a path column
//!   gives the ids.
//! - **label**: [`FormatOptions::label`], else `label`, else `name`, else the id.
//! - **weight**: [`FormatOptions::weight`], else the first of `weight`, `value`,
//!   `size` present. With no weight column every row weighs 1. A weight must be a
//!   finite number `>= 0`.
//! - **color**: [`FormatOptions::color`], else `color` when present; `#rgb`/`#rrggbb`.
//!
//! The hierarchy comes from at most one of:
//!
//! - **grouping columns** ([`FormatOptions::groups`], outermost first): each distinct
//!   value becomes a group node with id `group:` + the values joined by `/`
//!   (`group:Asia`, `group:Asia/EastAsia`; a `/` or `\` inside a value is escaped
//!   with `\`, so `Asia/East` is `group:Asia\/East`) and the value as its label;
//!   the row's node hangs under its innermost group.
//! - **a path column** ([`FormatOptions::path`], segments split by
//!   [`FormatOptions::path_separator`], default `/`): without an id column the last
//!   segment is the row's node (id = the whole path, label = the last segment) and
//!   the segments before it are groups; with an id column every segment is a group
//!   and the row's node hangs under the last one. Groups get ids as for grouping
//!   columns and are created as needed.
//! - **a parent-id column** ([`FormatOptions::parent`]): an empty cell means "no
//!   parent". When exactly one row has no parent it is the root; otherwise the rows
//!   without parent hang under a synthetic root.
//!
//! With none of them the rows hang flat under a synthetic root. The synthetic root
//! has id `root` and the label [`FormatOptions::root_label`] (default `root`).
//! Group and root nodes have no own weight: their value is the sum of their
//! children's.

use std::collections::HashMap;

use crate::color::Rgb;
use crate::dataset::{
    is_valid_weight, Dataset, DatasetBuilder, ModelError, NodeSpec, SimilarityHint,
};
use crate::error::FormatError;
use crate::format::{FormatOptions, InputError, Inputs, Role};
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

/// The node specs of a table's hierarchy, ready for [`DatasetBuilder`], with the
/// line each came from so that model errors can point at the input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TableTree {
    /// The nodes: synthetic root and groups first where they appear, then rows.
    pub specs: Vec<NodeSpec>,
    /// Parallel to `specs`: the line of the row that made the node (for groups, the
    /// first row in the group; `None` for a synthetic root).
    pub lines: Vec<Option<usize>>,
    /// Parallel to `specs`: true for nodes that are a row of the table (not groups or
    /// the synthetic root).
    pub from_row: Vec<bool>,
    /// What the readers found suspicious, carried into the dataset.
    pub warnings: Vec<Warning>,
    /// The limits the tree is built within (node count here; depth by the builder).
    pub limits: Limits,
    // Lookup by id only; never iterated, so its order cannot reach results.
    index: HashMap<String, usize>,
}

impl TableTree {
    /// Index into `specs` of the node with this id.
    pub fn find(&self, id: &str) -> Option<usize> {
        self.index.get(id).copied()
    }

    /// True when no spec names spec `index` as its parent.
    pub fn leaf_flags(&self) -> Vec<bool> {
        let mut leaf = vec![true; self.specs.len()];
        for spec in &self.specs {
            if let Some(parent) = spec.parent.as_deref().and_then(|p| self.find(p)) {
                leaf[parent] = false;
            }
        }
        leaf
    }

    /// Adds a node, rejecting a repeated id with the line of the repeat.
    fn push(
        &mut self,
        spec: NodeSpec,
        line: Option<usize>,
        column: Option<usize>,
        from_row: bool,
    ) -> Result<(), FormatError> {
        if let Some(&first) = self.index.get(&spec.id) {
            let first_line = match self.lines[first] {
                Some(line) => format!("line {line}"),
                None => "the synthetic root".to_owned(),
            };
            return Err(FormatError::Structure {
                line,
                column,
                message: format!("duplicate id {:?}: already used by {first_line}", spec.id),
            });
        }
        if self.specs.len() >= self.limits.max_nodes {
            return Err(FormatError::Model {
                line,
                column,
                source: ModelError::TooLarge(self.limits.exceeded(
                    Limit::Nodes,
                    format_args!("more than {} nodes", self.limits.max_nodes),
                )),
            });
        }
        self.index.insert(spec.id.clone(), self.specs.len());
        self.specs.push(spec);
        self.lines.push(line);
        self.from_row.push(from_row);
        Ok(())
    }

    /// Validates the specs into a [`Dataset`]; a model error points at the line of
    /// the node it names.
    pub fn build(self, hint: Option<SimilarityHint>) -> Result<Dataset, FormatError> {
        let TableTree {
            specs,
            lines,
            index,
            warnings,
            limits,
            ..
        } = self;
        let mut builder = DatasetBuilder::new();
        builder.limits(limits);
        for spec in specs {
            builder.add(spec);
        }
        for warning in warnings {
            builder.warn(warning);
        }
        if let Some(hint) = hint {
            builder.similarity_hint(hint);
        }
        builder.build().map_err(|source| {
            let line = source
                .node_id()
                .and_then(|id| index.get(id))
                .and_then(|&i| lines[i]);
            FormatError::Model {
                line,
                column: None,
                source,
            }
        })
    }
}

/// The id of the synthetic root of a table.
pub const ROOT_ID: &str = "root";

/// Builds the hierarchy of a node table (see the module docs for the rules).
pub fn tree_from_table(table: &Table, options: &FormatOptions) -> Result<TableTree, FormatError> {
    let hierarchy_kinds = usize::from(options.parent.is_some())
        + usize::from(options.path.is_some())
        + usize::from(!options.groups.is_empty());
    if hierarchy_kinds > 1 {
        return Err(FormatError::Structure {
            line: None,
            column: None,
            message: "give only one of a parent column, a path column or grouping columns"
                .to_owned(),
        });
    }
    let path_column = match &options.path {
        Some(name) => Some(table.required_column(name, "the path column")?),
        None => None,
    };
    let id_column = match (&options.id, path_column) {
        (Some(name), _) => Some(table.required_column(name, "the id column")?),
        (None, Some(_)) => table.column("id"),
        (None, None) => Some(table.required_column("id", "the id column")?),
    };
    let label_column = table.optional_column(
        options.label.as_deref(),
        "the label column",
        &["label", "name"],
    )?;
    let weight_column = table.optional_column(
        options.weight.as_deref(),
        "the weight column",
        &["weight", "value", "size"],
    )?;
    let color_column =
        table.optional_column(options.color.as_deref(), "the color column", &["color"])?;
    let parent_column = match &options.parent {
        Some(name) => Some(table.required_column(name, "the parent column")?),
        None => None,
    };
    let group_columns = options
        .groups
        .iter()
        .map(|name| table.required_column(name, "a grouping column"))
        .collect::<Result<Vec<_>, _>>()?;
    let separator = options.path_separator.unwrap_or('/');

    let mut tree = TableTree {
        limits: options.limits,
        ..TableTree::default()
    };
    tree.warnings.extend(table.warnings_in(NODES_ROLE.name));
    if table.rows.is_empty() {
        tree.warnings.push(Warning::new(
            NODES_ROLE.name,
            Some(table.header_line),
            "the table has a header but no rows: the picture is empty",
        ));
    } else if weight_column.is_none() {
        // Equal cells are rarely what a table of sizes meant, so say so.
        tree.warnings.push(Warning::new(
            NODES_ROLE.name,
            Some(table.header_line),
            "no weight column (set fields.weight, or name a column weight, value or size): \
             every row weighs 1",
        ));
    }
    let root_label = options
        .root_label
        .clone()
        .unwrap_or_else(|| "root".to_owned());

    // With a parent column, a single parentless row is the root; otherwise (or with
    // several) a synthetic root collects the top-level nodes.
    let parentless = parent_column.map(|column| {
        table
            .rows
            .iter()
            .filter(|row| row.fields.get(column).is_none_or(String::is_empty))
            .count()
    });
    let synthetic_root = parentless != Some(1);
    if synthetic_root {
        tree.push(NodeSpec::new(ROOT_ID).label(root_label), None, None, false)?;
    }

    for row in &table.rows {
        // `get`, not indexing: a hand-made Table may have short rows; read as empty.
        let field = |column: usize| row.fields.get(column).map_or("", String::as_str);
        // Groups of this row, outermost first, as (value, column).
        let mut groups: Vec<(String, usize)> = group_columns
            .iter()
            .map(|&column| (field(column).to_owned(), column))
            .collect();
        let mut path_leaf: Option<String> = None;
        let mut id = id_column.map(|column| field(column).to_owned());
        if let Some(column) = path_column {
            let mut segments: Vec<String> = field(column)
                .split(separator)
                .map(|segment| segment.trim().to_owned())
                .collect();
            if id_column.is_none() {
                path_leaf = segments.pop();
                // The whole path is the id: the last segment alone may repeat.
                id = Some(field(column).to_owned());
            }
            groups = segments
                .into_iter()
                .map(|segment| (segment, column))
                .collect();
        }
        let id = id.unwrap_or_default();
        let id_col = id_column.or(path_column).map(|c| c + 1);
        if id.is_empty() || path_leaf.as_deref() == Some("") {
            return Err(FormatError::Field {
                line: Some(row.line),
                column: id_col,
                node: None,
                field: id_column
                    .or(path_column)
                    .map_or_else(|| "id".to_owned(), |c| table.header[c].clone()),
                message: "the id is empty".to_owned(),
            });
        }

        // Create the row's groups as needed; the parent is the innermost.
        let mut parent = synthetic_root.then(|| ROOT_ID.to_owned());
        let mut joined = String::new();
        for (value, column) in &groups {
            if value.is_empty() {
                return Err(FormatError::Field {
                    line: Some(row.line),
                    column: Some(column + 1),
                    node: Some(id.clone()),
                    field: table.header[*column].clone(),
                    message: "the group value is empty".to_owned(),
                });
            }
            if !joined.is_empty() {
                joined.push('/');
            }
            push_escaped(&mut joined, value);
            let group_id = format!("group:{joined}");
            if tree.find(&group_id).is_none() {
                let mut spec = NodeSpec::new(group_id.clone()).label(value.clone());
                spec.parent = parent.clone();
                tree.push(spec, Some(row.line), Some(column + 1), false)?;
            }
            parent = Some(group_id);
        }
        if let Some(column) = parent_column {
            let value = field(column);
            if !value.is_empty() {
                parent = Some(value.to_owned());
            } else if !synthetic_root {
                parent = None;
            }
        }

        let mut spec = NodeSpec::new(id.clone());
        spec.parent = parent;
        spec.label = match (label_column, &path_leaf) {
            (Some(column), _) if !field(column).is_empty() => Some(field(column).to_owned()),
            (_, Some(leaf)) => Some(leaf.clone()),
            _ => None,
        };
        spec.weight = Some(match weight_column {
            Some(column) => {
                parse_weight(field(column), row.line, column, &table.header[column], &id)?
            }
            None => 1.0,
        });
        if let Some(column) = color_column {
            let text = field(column);
            if !text.is_empty() {
                spec.color = Some(Rgb::from_hex(text).ok_or_else(|| FormatError::Field {
                    line: Some(row.line),
                    column: Some(column + 1),
                    node: Some(id.clone()),
                    field: table.header[column].clone(),
                    message: format!("{text:?} is not a hex color like #rgb or #rrggbb"),
                })?);
            }
        }
        tree.push(spec, Some(row.line), id_col, true)?;
    }
    check_parent_cycles(&tree)?;
    Ok(tree)
}

/// Appends a group value to a group id, escaping the separator `/` (and the
/// escape `\` itself) so that the id is the tuple of values: the group
/// `Asia/East` is `group:Asia\/East`, never the group `East` inside `Asia`
/// (`group:Asia/East`). Values without either character are unchanged.
fn push_escaped(id: &mut String, value: &str) {
    for c in value.chars() {
        if c == '/' || c == '\\' {
            id.push('\\');
        }
        id.push(c);
    }
}

/// A weight cell: a finite number `>= 0`.
fn parse_weight(
    text: &str,
    line: usize,
    column: usize,
    name: &str,
    id: &str,
) -> Result<f64, FormatError> {
    let error = |message: String| FormatError::Field {
        line: Some(line),
        column: Some(column + 1),
        node: Some(id.to_owned()),
        field: name.to_owned(),
        message,
    };
    let value: f64 = text
        .parse()
        .map_err(|_| error(format!("expected a number, found {text:?}")))?;
    if !is_valid_weight(value) {
        return Err(error(format!(
            "the weight must be a finite number >= 0, found {text:?}"
        )));
    }
    Ok(value)
}

/// Reports a cycle in a parent column with the node and line where it closes, which
/// reads better than the model's later "not reachable" check. Parents that name no
/// node are left to the model (MissingParent).
fn check_parent_cycles(tree: &TableTree) -> Result<(), FormatError> {
    let parent_of: Vec<Option<usize>> = tree
        .specs
        .iter()
        .map(|spec| spec.parent.as_deref().and_then(|p| tree.find(p)))
        .collect();
    // 0 = unvisited, 1 = on the current walk, 2 = done (known to reach a root).
    let mut state = vec![0u8; parent_of.len()];
    for start in 0..parent_of.len() {
        let mut walk: Vec<usize> = Vec::new();
        let mut current = Some(start);
        while let Some(node) = current {
            match state[node] {
                2 => break,
                1 => {
                    let mut cycle: Vec<&str> = walk
                        .iter()
                        .skip_while(|&&n| n != node)
                        .map(|&n| tree.specs[n].id.as_str())
                        .collect();
                    cycle.push(&tree.specs[node].id);
                    return Err(FormatError::Structure {
                        line: tree.lines[node],
                        column: None,
                        message: format!(
                            "node {:?}: the parent column forms a cycle: {}",
                            tree.specs[node].id,
                            cycle.join(" -> ")
                        ),
                    });
                }
                _ => {
                    state[node] = 1;
                    walk.push(node);
                    current = parent_of[node];
                }
            }
        }
        for node in walk {
            state[node] = 2;
        }
    }
    Ok(())
}

/// The node table every table format reads: ids, labels, weights and the
/// hierarchy columns.
pub const NODES_ROLE: Role = Role {
    name: "nodes",
    required: true,
    description: "node table CSV/TSV: id, label, weight and the hierarchy columns",
};

/// Reads the `nodes` input and builds its hierarchy; errors name the role.
#[allow(clippy::result_large_err)] // InputError's shape is the Format API's
pub fn node_tree(inputs: &Inputs<'_>, options: &FormatOptions) -> Result<TableTree, InputError> {
    let in_nodes = |error| InputError::new(NODES_ROLE.name, error);
    let table = read_node_table(inputs.require(NODES_ROLE.name)?, options).map_err(in_nodes)?;
    tree_from_table(&table, options).map_err(in_nodes)
}

/// Reads a node table within `options.limits` (one row per node, so at most
/// `max_nodes` rows are kept).
pub fn read_node_table(bytes: &[u8], options: &FormatOptions) -> Result<Table, FormatError> {
    let cap = RowCap::new(options.limits, Limit::Nodes, 0, "rows");
    read_table_capped(bytes, options.delimiter, Some(cap))
}
