//! A node table → the [`NodeSpec`]s of a hierarchy
//! ([`TableTree`](crate::node_table::TableTree)). Shared by the table formats
//! (border list, embedding matrix, genre table, time series); owns the rules for
//! ids, labels, weights and the hierarchy columns of a node table, read by
//! [`crate::table`].
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
//! - **carried columns** ([`FormatOptions::carry`]): must exist; a row's
//!   non-empty cells become its node's [`crate::Node::fields`], as text.
//!
//! The hierarchy comes from at most one of:
//!
//! - **grouping columns** ([`FormatOptions::groups`], outermost first): each distinct
//!   value becomes a group node with id `group:` + the values joined by `/`
//!   (`group:Asia`, `group:Asia/EastAsia`; a `/` or `\` inside a value is escaped
//!   with `\`, so `Asia/East` is `group:Asia\/East`) and the value as its label;
//!   the row's node hangs under its innermost group. A row whose own id is a
//!   generated group's id is an error, whichever comes first.
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
use crate::table::{read_table_capped, Cap, Table};
use crate::warning::{Warning, WarningKind, Warnings};

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
    pub warnings: Warnings,
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
        builder.warnings(warnings);
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
    // Each carried column must exist; the error names what asked for it.
    let carried = options
        .carry
        .iter()
        .map(|c| {
            Ok((
                c.column.clone(),
                table.required_column(&c.column, &c.asked_by)?,
            ))
        })
        .collect::<Result<Vec<_>, FormatError>>()?;
    let separator = options.path_separator.unwrap_or('/');
    let id_field = id_column
        .or(path_column)
        .map_or_else(|| "id".to_owned(), |c| table.header[c].clone());

    let mut tree = TableTree {
        limits: options.limits,
        ..TableTree::default()
    };
    tree.warnings.append(table.warnings_in(NODES_ROLE.name));
    if table.rows.is_empty() {
        tree.warnings.push(Warning::new(
            WarningKind::EmptyTable,
            NODES_ROLE.name,
            Some(table.header_line),
            "the table has a header but no rows: the picture is empty",
        ));
    } else if weight_column.is_none() {
        // Equal cells are rarely what a table of sizes meant, so say so.
        tree.warnings.push(Warning::new(
            WarningKind::NoWeight,
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
                field: id_field.clone(),
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
            match tree.find(&group_id) {
                None => {
                    let mut spec = NodeSpec::new(group_id.clone()).label(value.clone());
                    spec.parent = parent.clone();
                    tree.push(spec, Some(row.line), Some(column + 1), false)?;
                }
                // A row took this id first: it must not become the group.
                Some(taken) if tree.from_row[taken] => {
                    return Err(group_id_taken(
                        tree.lines[taken].unwrap_or(row.line),
                        id_col,
                        &id_field,
                        &group_id,
                        value,
                        row.line,
                    ));
                }
                Some(_) => {}
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
        spec.fields = carried
            .iter()
            .filter(|(_, column)| !field(*column).is_empty())
            .map(|(name, column)| (name.clone(), field(*column).to_owned()))
            .collect();
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
        // A generated group took this id first (a synthetic root, line None,
        // is a plain duplicate for `push`).
        if let Some(group) = tree.find(&spec.id).filter(|&i| !tree.from_row[i]) {
            if let (Some(group_line), Some(value)) = (tree.lines[group], &tree.specs[group].label) {
                return Err(group_id_taken(
                    row.line, id_col, &id_field, &spec.id, value, group_line,
                ));
            }
        }
        tree.push(spec, Some(row.line), id_col, true)?;
    }
    check_parent_cycles(&tree)?;
    Ok(tree)
}

/// The error for the row on `row_line` whose id `id` is also the id of the
/// group generated for `value` from `group_line` (ids `group:` + the values):
/// whichever came first, taking the group's place would silently move the
/// group's rows under the row's parent, and a duplicate-id error would blame a
/// row that names no such id.
fn group_id_taken(
    row_line: usize,
    column: Option<usize>,
    field: &str,
    id: &str,
    value: &str,
    group_line: usize,
) -> FormatError {
    FormatError::Field {
        line: Some(row_line),
        column,
        node: Some(id.to_owned()),
        field: field.to_owned(),
        message: format!(
            "the id of the group {value:?} generated from line {group_line} (group ids are \
             `group:` and the grouping values); give the row another id"
        ),
    }
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
    let cap = Cap::new(options.limits, Limit::Nodes, 0, "rows");
    read_table_capped(bytes, options.delimiter, Some(cap))
}
