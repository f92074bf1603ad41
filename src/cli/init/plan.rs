//! What `init`'s config says, decided from what was read of the inputs: which
//! table is the node table (the one the most others refer to), its fields,
//! which input makes nodes similar (and so the format), and the checks
//! against the limits `build` applies, so that init refuses, naming the
//! limit, rather than write a config that `build` would refuse.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};

use nptreemap_formats::{Limit, Limits};

use super::super::UsageError;
use super::guess::{self, Fields, Overrides, Profile, Relation};
use super::sample::{self, Content, Input, Sampled};
use super::yaml::Plan;

/// What init knows of one table: its sample's profile, and its whole row
/// count and id values (from the sample when it is the whole table, else
/// from one streaming pass).
struct Known<'a> {
    input: &'a Input,
    sampled: &'a Sampled,
    profile: Profile<'a>,
    id: Option<usize>,
    rows: usize,
    ids: HashSet<String>,
}

impl<'a> Known<'a> {
    fn new(input: &'a Input, sampled: &'a Sampled, limits: &Limits) -> anyhow::Result<Self> {
        let profile = Profile::new(&sampled.table);
        let id = profile.id_column();
        let (rows, ids) = if sampled.whole {
            let ids = id.map_or_else(HashSet::new, |i| {
                profile.cells(i).map(str::to_owned).collect()
            });
            (profile.rows(), ids)
        } else {
            let scan = sample::scan(&input.path, limits, sampled.delimiter, id)?;
            (scan.rows, scan.ids)
        };
        Ok(Known {
            input,
            sampled,
            profile,
            id,
            rows,
            ids,
        })
    }
}

/// The node table and how the other inputs relate to it.
struct NodeTable<'k, 'a> {
    known: &'k Known<'a>,
    /// Its index among the inputs.
    index: usize,
    /// Its id column.
    id: usize,
    /// (input index, relation) of every input that refers to its ids.
    relations: Vec<(usize, Relation)>,
}

/// The refusal of something `build` would refuse under `limits`.
fn over(path: &Path, limits: &Limits, limit: Limit, what: String) -> UsageError {
    UsageError(format!(
        "{}: {}; build would refuse it, so init wrote no config",
        path.display(),
        limits.exceeded(limit, what)
    ))
}

/// How input `other` (with what is known of it, for a table) relates to the
/// node table `nodes`.
fn relation_to(nodes: &Known<'_>, other: &Input, known: Option<&Known<'_>>) -> Option<Relation> {
    match (&other.content, known) {
        (Content::Npy { rows, cols }, _) => {
            (*rows == nodes.rows).then_some(Relation::Npy { cols: *cols })
        }
        (Content::Table(_), Some(k)) => guess::relation(&k.profile, &nodes.ids),
        (Content::Table(_), None) => None,
    }
}

/// The table the most other inputs refer to (ties: the first).
fn node_table<'k, 'a>(
    inputs: &[Input],
    known: &'k [Option<Known<'a>>],
) -> Result<NodeTable<'k, 'a>, UsageError> {
    let mut best: Option<NodeTable<'k, 'a>> = None;
    for (index, k) in known.iter().enumerate() {
        let Some((k, id)) = k.as_ref().and_then(|k| Some((k, k.id?))) else {
            continue;
        };
        let relations: Vec<(usize, Relation)> = inputs
            .iter()
            .enumerate()
            .filter(|(o, _)| *o != index)
            .filter_map(|(o, other)| relation_to(k, other, known[o].as_ref()).map(|r| (o, r)))
            .collect();
        if best
            .as_ref()
            .is_none_or(|b| relations.len() > b.relations.len())
        {
            best = Some(NodeTable {
                known: k,
                index,
                id,
                relations,
            });
        }
    }
    best.ok_or_else(|| {
        UsageError(
            "no table has an id column (`id`, or a column whose values are all distinct)".into(),
        )
    })
}

/// A path as the config at `config` should name it: relative to the config's
/// folder when inside it, else absolute; an error when it is not UTF-8 (YAML
/// text cannot name it).
fn relative_to_config(path: &Path, config: &Path) -> Result<String, UsageError> {
    let dir = config.parent().filter(|d| !d.as_os_str().is_empty());
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let path_abs = absolute(path);
    let dir_abs = absolute(dir.unwrap_or(Path::new(".")));
    let named = path_abs
        .strip_prefix(&dir_abs)
        .map(Path::to_path_buf)
        .unwrap_or(path_abs);
    named.to_str().map(str::to_owned).ok_or_else(|| {
        UsageError(format!(
            "{}: the name is not UTF-8 text, which a YAML config cannot hold; rename it",
            path.display()
        ))
    })
}

/// The similarity part of a plan: the format, the inputs by role beside the
/// node table, the pairs' strength column and why.
struct Similarity {
    format: &'static str,
    files: Vec<(&'static str, String)>,
    strength: Option<String>,
    why: String,
    /// The input it comes from, if not the node table.
    from: Option<usize>,
}

/// Everything `plan` needs besides the inputs.
pub(super) struct Request<'r> {
    /// Where the config goes.
    pub(super) output: &'r Path,
    /// The flags that replace guesses.
    pub(super) overrides: Overrides,
    /// The command as typed.
    pub(super) command_line: String,
    /// The limits the config will have.
    pub(super) limits: Limits,
}

/// Decides the config for `inputs`.
pub(super) fn plan(inputs: &[Input], request: &Request<'_>) -> anyhow::Result<Plan> {
    let limits = &request.limits;
    let known: Vec<Option<Known<'_>>> = inputs
        .iter()
        .map(|input| match &input.content {
            Content::Table(sampled) => Known::new(input, sampled, limits).map(Some),
            Content::Npy { .. } => Ok(None),
        })
        .collect::<anyhow::Result<_>>()?;
    let nodes = node_table(inputs, &known)?;
    let path = &nodes.known.input.path;
    let fields = guess::fields(&nodes.known.profile, path, nodes.id, &request.overrides)?;
    check_nodes(&nodes, &fields, inputs, limits)?;
    let similarity = similarity(&nodes, &fields, inputs, &known, request)?;
    let mut files = vec![("nodes", relative_to_config(path, request.output)?)];
    files.extend(similarity.files);
    let mut why = vec![similarity.why];
    for (o, input) in inputs.iter().enumerate() {
        if o == nodes.index || similarity.from == Some(o) {
            continue;
        }
        let related = nodes.relations.iter().any(|(r, _)| *r == o);
        why.push(format!(
            "{} is not used ({})",
            input.path.display(),
            if related {
                "one similarity per dataset"
            } else {
                "it refers to no ids of the node table"
            }
        ));
    }
    let name = dataset_name(path);
    let page = guess::page_offer(&nodes.known.profile, nodes.id, &fields);
    Ok(Plan {
        page,
        command_line: request.command_line.clone(),
        why,
        outputs: output_paths(&name),
        name,
        format: similarity.format,
        files,
        strength: similarity.strength,
        fields,
    })
}

/// Refuses a node table `build` would refuse (more rows than nodes, more
/// levels than the depth allows) and a `.npy` matrix that does not fit it.
fn check_nodes(
    nodes: &NodeTable<'_, '_>,
    fields: &Fields,
    inputs: &[Input],
    limits: &Limits,
) -> Result<(), UsageError> {
    let path = &nodes.known.input.path;
    let rows = nodes.known.rows;
    // Every row is a node, and so is the root.
    if rows.saturating_add(1) > limits.max_nodes {
        return Err(over(path, limits, Limit::Nodes, format!("{rows} rows")));
    }
    let levels = fields.groups.len();
    if levels + 1 > limits.max_depth {
        let what = format!(
            "{levels} grouping columns put the rows at depth {}",
            levels + 1
        );
        return Err(over(path, limits, Limit::Depth, what));
    }
    for (o, input) in inputs.iter().enumerate() {
        let related = nodes.relations.iter().any(|(r, _)| *r == o);
        if let (Content::Npy { rows: m, cols }, false) = (&input.content, related) {
            return Err(UsageError(format!(
                "{}: a matrix of {m} rows (shape ({m}, {cols})), but the node table {} has \
                 {rows} rows; row i of the matrix is the vector of the table's row i",
                input.path.display(),
                path.display(),
            )));
        }
    }
    Ok(())
}

/// What makes nodes similar: `--genres`, else the first input that refers
/// to the node ids, else a multi-valued column; within the limits.
fn similarity(
    nodes: &NodeTable<'_, '_>,
    fields: &Fields,
    inputs: &[Input],
    known: &[Option<Known<'_>>],
    request: &Request<'_>,
) -> Result<Similarity, UsageError> {
    let limits = &request.limits;
    let dims = |count: usize, what: &str, path: &Path| -> Result<(), UsageError> {
        if count > limits.max_dimensions {
            return Err(over(
                path,
                limits,
                Limit::Dimensions,
                format!("{count} {what}"),
            ));
        }
        Ok(())
    };
    let nodes_path = &nodes.known.input.path;
    let chosen = nodes
        .relations
        .first()
        .filter(|_| request.overrides.genres.is_none());
    let Some((o, relation)) = chosen else {
        let Some(genres) = &fields.genres else {
            return Err(UsageError(format!(
                "{}: found no similarity between its rows; also give a pairs table (a,b), a \
                 vectors table (id,v1,v2,..) or .npy matrix, a series table (a date column, \
                 then one column per id), or add a genres column (Drama|Crime)",
                nodes_path.display()
            )));
        };
        let values = genre_values(nodes.known, genres);
        // Genres are sets, capped by max_set_members (issue 23), not dense dimensions.
        if values > limits.max_set_members {
            return Err(over(
                nodes_path,
                limits,
                Limit::SetMembers,
                format!("{values} distinct values of the genres column"),
            ));
        }
        return Ok(Similarity {
            format: "genre-table",
            files: Vec::new(),
            strength: None,
            why: format!(
                "column {genres:?} lists several values per row: Jaccard similarity of the sets"
            ),
            from: None,
        });
    };
    let other: &PathBuf = &inputs[*o].path;
    let shown = other.display();
    let rows = known[*o].as_ref().map_or(0, |k| k.rows);
    let file = |role| Ok::<_, UsageError>(vec![(role, relative_to_config(other, request.output)?)]);
    let (format, files, strength, why) = match relation {
        Relation::Pairs { strength } => (
            "border-list",
            file("pairs")?,
            strength.clone(),
            format!("{shown} lists pairs of ids: neighbours"),
        ),
        Relation::Vectors { dims: d } => {
            dims(*d, "values per vector", other)?;
            if rows.saturating_add(1) > limits.max_nodes {
                let what = format!("{rows} vector rows");
                return Err(over(other, limits, Limit::Nodes, what));
            }
            let why = format!("{shown} holds a vector per id: cosine similarity");
            ("embedding-matrix", file("vectors")?, None, why)
        }
        Relation::Npy { cols } => {
            dims(*cols, "values per vector", other)?;
            let why = format!(
                "{shown} is a matrix with a vector per row of {}: cosine similarity",
                nodes_path.display()
            );
            ("embedding-matrix", file("vectors")?, None, why)
        }
        Relation::Series => {
            dims(rows, "dates", other)?;
            let why = format!("{shown} holds a series per id: Pearson correlation");
            ("time-series", file("series")?, None, why)
        }
    };
    Ok(Similarity {
        format,
        files,
        strength,
        why,
        from: Some(*o),
    })
}

/// Distinct values of the genres column `column` in the node table's sample
/// (a lower bound for the whole table).
fn genre_values(nodes: &Known<'_>, column: &str) -> usize {
    let Some(i) = nodes.sampled.table.column(column) else {
        return 0;
    };
    nodes
        .profile
        .cells(i)
        .flat_map(|cell| cell.split('|').map(str::trim))
        .filter(|v| !v.is_empty())
        .collect::<BTreeSet<_>>()
        .len()
}

/// The dataset's name: the node table's file stem, control characters
/// replaced (it names the outputs and appears in status lines); `data` for a
/// stem without a letter or digit.
fn dataset_name(nodes: &Path) -> String {
    let stem = nodes
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name: String = stem
        .chars()
        .map(|c| if c.is_control() { '_' } else { c })
        .collect();
    if !name.chars().any(char::is_alphanumeric) {
        "data".to_owned()
    } else {
        name
    }
}

/// The outputs of dataset `name`: SVG, PNG (with the feature) and HTML.
fn output_paths(name: &str) -> Vec<String> {
    let mut kinds = vec!["svg"];
    if cfg!(feature = "png") {
        kinds.push("png");
    }
    kinds.push("html");
    kinds
        .into_iter()
        .map(|kind| format!("out/{name}.{kind}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_names_have_no_control_characters() {
        assert_eq!(dataset_name(Path::new("dir/a\nb.csv")), "a_b");
        assert_eq!(dataset_name(Path::new("na: me #1.csv")), "na: me #1");
        assert_eq!(dataset_name(Path::new("\n.csv")), "data");
    }
}
