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
use crate::table::{read_table_capped, Cap, Row, Table};
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

    /// An error for the first leaf without features, naming it and its line
    /// of the node table, at `line` of the input that should have given them
    /// (its `what`: a vector, a column).
    pub(crate) fn check_leaf_features(
        &self,
        line: Option<usize>,
        what: &str,
    ) -> Result<(), FormatError> {
        let leaves = self.leaf_flags();
        for (index, spec) in self.specs.iter().enumerate() {
            if leaves[index] && spec.features.is_none() {
                let place = self.lines[index]
                    .map_or_else(String::new, |line| format!(" (nodes line {line})"));
                return Err(FormatError::Structure {
                    line,
                    column: None,
                    message: format!(
                        "node {:?}{place} has no {what}; every leaf needs one",
                        spec.id
                    ),
                });
            }
        }
        Ok(())
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
    let columns = Columns::find(table, options)?;
    let mut tree = TableTree {
        limits: options.limits,
        ..TableTree::default()
    };
    tree.warnings.append(table.warnings_in(NODES_ROLE.name));
    warn_of_the_table(&mut tree, table, columns.weight);

    // With a parent column, a single parentless row is the root; otherwise (or with
    // several) a synthetic root collects the top-level nodes.
    let parentless = columns.parent.map(|column| {
        table
            .rows
            .iter()
            .filter(|row| row.fields.get(column).is_none_or(String::is_empty))
            .count()
    });
    let synthetic_root = parentless != Some(1);
    if synthetic_root {
        let root_label = options
            .root_label
            .clone()
            .unwrap_or_else(|| "root".to_owned());
        tree.push(NodeSpec::new(ROOT_ID).label(root_label), None, None, false)?;
    }

    for row in &table.rows {
        columns.add_row(&mut tree, table, row, synthetic_root)?;
    }
    check_parent_cycles(&tree)?;
    Ok(tree)
}

/// A table without rows makes an empty picture, and one without a weight
/// column equal cells, which a table of sizes rarely meant: both are said.
fn warn_of_the_table(tree: &mut TableTree, table: &Table, weight_column: Option<usize>) {
    if table.rows.is_empty() {
        tree.warnings.push(Warning::new(
            WarningKind::EmptyTable,
            NODES_ROLE.name,
            Some(table.header_line),
            "the table has a header but no rows: the picture is empty",
        ));
    } else if weight_column.is_none() {
        tree.warnings.push(Warning::new(
            WarningKind::NoWeight,
            NODES_ROLE.name,
            Some(table.header_line),
            "no weight column (set fields.weight, or name a column weight, value or size): \
             every row weighs 1",
        ));
    }
}

/// The columns of a node table the options name (or the defaults find),
/// looked up once, before any row is read.
struct Columns {
    id: Option<usize>,
    path: Option<usize>,
    label: Option<usize>,
    weight: Option<usize>,
    color: Option<usize>,
    parent: Option<usize>,
    groups: Vec<usize>,
    /// Each carried column's name and index.
    carried: Vec<(String, usize)>,
    path_separator: char,
    /// The name errors give the ids' column (`id` when no column has them).
    id_field: String,
}

/// Where a row's node goes, from its id, path and grouping cells.
struct Place {
    id: String,
    /// The groups the node hangs in, outermost first, as (value, column).
    groups: Vec<(String, usize)>,
    /// The last segment of the path, when it is the node (no id column).
    path_leaf: Option<String>,
}

impl Columns {
    /// Looks the columns up, in a fixed order, so that the same table always
    /// reports the same missing column.
    fn find(table: &Table, options: &FormatOptions) -> Result<Columns, FormatError> {
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
        let path = match &options.path {
            Some(name) => Some(table.required_column(name, "the path column")?),
            None => None,
        };
        let id = match (&options.id, path) {
            (Some(name), _) => Some(table.required_column(name, "the id column")?),
            (None, Some(_)) => table.column("id"),
            (None, None) => Some(table.required_column("id", "the id column")?),
        };
        let label = table.optional_column(
            options.label.as_deref(),
            "the label column",
            &["label", "name"],
        )?;
        let weight = table.optional_column(
            options.weight.as_deref(),
            "the weight column",
            &["weight", "value", "size"],
        )?;
        let color =
            table.optional_column(options.color.as_deref(), "the color column", &["color"])?;
        let parent = match &options.parent {
            Some(name) => Some(table.required_column(name, "the parent column")?),
            None => None,
        };
        let groups = options
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
        let id_field = id
            .or(path)
            .map_or_else(|| "id".to_owned(), |c| table.header[c].clone());
        Ok(Columns {
            id,
            path,
            label,
            weight,
            color,
            parent,
            groups,
            carried,
            path_separator: options.path_separator.unwrap_or('/'),
            id_field,
        })
    }

    /// The 1-based column of the row's id, for errors.
    fn id_column(&self) -> Option<usize> {
        self.id.or(self.path).map(|c| c + 1)
    }

    /// Adds the node of `row`, and the groups it hangs in that are new. The
    /// checks run in a fixed order (id, groups, fields, then the id against
    /// the groups'), so the same table always reports the same error.
    fn add_row(
        &self,
        tree: &mut TableTree,
        table: &Table,
        row: &Row,
        synthetic_root: bool,
    ) -> Result<(), FormatError> {
        let place = self.place(row)?;
        let mut parent = self.add_groups(tree, table, row, &place, synthetic_root)?;
        if let Some(column) = self.parent {
            let value = cell(row, column);
            if !value.is_empty() {
                parent = Some(value.to_owned());
            } else if !synthetic_root {
                parent = None;
            }
        }
        let spec = self.spec(table, row, place, parent)?;
        // A generated group took this id first (a synthetic root, line None,
        // is a plain duplicate for `push`).
        if let Some(group) = tree.find(&spec.id).filter(|&i| !tree.from_row[i]) {
            if let (Some(group_line), Some(value)) = (tree.lines[group], &tree.specs[group].label) {
                return Err(group_id_taken(
                    row.line,
                    self.id_column(),
                    &self.id_field,
                    &spec.id,
                    value,
                    group_line,
                ));
            }
        }
        tree.push(spec, Some(row.line), self.id_column(), true)
    }

    /// The row's id and groups: from the id and grouping columns, or from
    /// its path. An empty id is an error.
    fn place(&self, row: &Row) -> Result<Place, FormatError> {
        let mut groups: Vec<(String, usize)> = self
            .groups
            .iter()
            .map(|&column| (cell(row, column).to_owned(), column))
            .collect();
        let mut path_leaf: Option<String> = None;
        let mut id = self.id.map(|column| cell(row, column).to_owned());
        if let Some(column) = self.path {
            let mut segments: Vec<String> = cell(row, column)
                .split(self.path_separator)
                .map(|segment| segment.trim().to_owned())
                .collect();
            if self.id.is_none() {
                path_leaf = segments.pop();
                // The whole path is the id: the last segment alone may repeat.
                id = Some(cell(row, column).to_owned());
            }
            groups = segments
                .into_iter()
                .map(|segment| (segment, column))
                .collect();
        }
        let id = id.unwrap_or_default();
        if id.is_empty() || path_leaf.as_deref() == Some("") {
            return Err(FormatError::Field {
                line: Some(row.line),
                column: self.id_column(),
                node: None,
                field: self.id_field.clone(),
                message: "the id is empty".to_owned(),
            });
        }
        Ok(Place {
            id,
            groups,
            path_leaf,
        })
    }

    /// Creates the groups of the row's `place` that do not exist yet, outermost first,
    /// and returns the innermost one's id: the row's parent (the synthetic
    /// root's without groups). A group value that is empty, or whose id a row
    /// took first, is an error.
    fn add_groups(
        &self,
        tree: &mut TableTree,
        table: &Table,
        row: &Row,
        place: &Place,
        synthetic_root: bool,
    ) -> Result<Option<String>, FormatError> {
        let mut parent = synthetic_root.then(|| ROOT_ID.to_owned());
        let mut joined = String::new();
        for (value, column) in &place.groups {
            if value.is_empty() {
                return Err(FormatError::Field {
                    line: Some(row.line),
                    column: Some(column + 1),
                    node: Some(place.id.clone()),
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
                        self.id_column(),
                        &self.id_field,
                        &group_id,
                        value,
                        row.line,
                    ));
                }
                Some(_) => {}
            }
            parent = Some(group_id);
        }
        Ok(parent)
    }

    /// The row's node under `parent`: its carried fields, label, weight and
    /// colour, each checked.
    fn spec(
        &self,
        table: &Table,
        row: &Row,
        place: Place,
        parent: Option<String>,
    ) -> Result<NodeSpec, FormatError> {
        let Place { id, path_leaf, .. } = place;
        let field = |column: usize| cell(row, column);
        let mut spec = NodeSpec::new(id.clone());
        spec.parent = parent;
        spec.fields = self
            .carried
            .iter()
            .filter(|(_, column)| !field(*column).is_empty())
            .map(|(name, column)| (name.clone(), field(*column).to_owned()))
            .collect();
        spec.label = match (self.label, &path_leaf) {
            (Some(column), _) if !field(column).is_empty() => Some(field(column).to_owned()),
            (_, Some(leaf)) => Some(leaf.clone()),
            _ => None,
        };
        spec.weight = Some(match self.weight {
            Some(column) => {
                parse_weight(field(column), row.line, column, &table.header[column], &id)?
            }
            None => 1.0,
        });
        if let Some(column) = self.color {
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
        Ok(spec)
    }
}

/// The cell of `row` in `column`, read as empty where a hand-made [`Table`]
/// has a short row (`get`, not indexing).
fn cell(row: &Row, column: usize) -> &str {
    row.fields.get(column).map_or("", String::as_str)
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

/// The parse of a format that reads a node table plus one more input, `role`
/// (border list, embedding matrix, time series): `role` is required first,
/// then the table's tree is built, `add` puts on it what the input says, and
/// the tree becomes the dataset with `hint`. Errors name their input.
#[allow(clippy::result_large_err)] // InputError's shape is the Format API's
pub(crate) fn parse_with_input(
    inputs: &Inputs<'_>,
    options: &FormatOptions,
    role: &'static str,
    hint: SimilarityHint,
    add: impl FnOnce(&mut TableTree, &[u8]) -> Result<(), InputError>,
) -> Result<Dataset, InputError> {
    let bytes = inputs.require(role)?;
    let mut tree = node_tree(inputs, options)?;
    add(&mut tree, bytes)?;
    tree.build(Some(hint))
        .map_err(|error| InputError::new(NODES_ROLE.name, error))
}

/// Reads a node table within `options.limits` (one row per node, so at most
/// `max_nodes` rows are kept).
pub fn read_node_table(bytes: &[u8], options: &FormatOptions) -> Result<Table, FormatError> {
    let cap = Cap::new(options.limits, Limit::Nodes, 0, "rows");
    read_table_capped(bytes, options.delimiter, Some(cap))
}
