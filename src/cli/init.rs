//! `nptreemap init [TABLE…]`: sniffs the given CSV/TSV tables and writes a
//! commented `nptreemap.yaml` that builds at once: the node table (the one the
//! others refer to; its id, label, numeric weight and grouping columns), and
//! what makes nodes similar: a pairs table (`a,b`), a vectors table (`id,v1..`),
//! a series table (a date column, then one column per id) or a genres column
//! (`Drama|Crime`). Reading goes through the formats' own table reader, so init
//! sees the table exactly as the build will.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;

use super::config_file::CONFIG_NAME;
use super::UsageError;
use nptreemap_formats::table::{read_table, Table};

/// Arguments of `nptreemap init`.
#[derive(Debug, Args)]
pub(crate) struct InitArgs {
    /// The tables (CSV or TSV with a header): the node table and, optionally,
    /// a pairs, vectors or series table referring to its ids.
    #[arg(required = true, value_name = "TABLE")]
    tables: Vec<PathBuf>,
    /// Where to write the config.
    #[arg(long, short, default_value = CONFIG_NAME, value_name = "FILE")]
    output: PathBuf,
    /// Replace an existing config.
    #[arg(long)]
    force: bool,
}

/// One table as read, with per-column facts.
struct Sniffed {
    /// As named on the command line.
    path: PathBuf,
    table: Table,
    columns: Vec<Column>,
}

struct Column {
    name: String,
    values: Vec<String>,
    numeric: bool,
    distinct: usize,
}

impl Sniffed {
    fn read(path: &Path) -> anyhow::Result<Sniffed> {
        let bytes = crate::workspace::read_bytes(path)?;
        let table =
            read_table(&bytes, None).map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
        let columns = table
            .header
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let values: Vec<String> = table.rows.iter().map(|r| r.fields[i].clone()).collect();
                let numeric = !values.is_empty()
                    && values
                        .iter()
                        .all(|v| v.parse::<f64>().is_ok_and(f64::is_finite));
                let distinct = values.iter().collect::<BTreeSet<_>>().len();
                Column {
                    name: name.clone(),
                    values,
                    numeric,
                    distinct,
                }
            })
            .collect();
        Ok(Sniffed {
            path: path.to_path_buf(),
            table,
            columns,
        })
    }

    fn rows(&self) -> usize {
        self.table.rows.len()
    }

    fn named(&self, names: &[&str]) -> Option<usize> {
        names.iter().find_map(|n| self.table.column(n))
    }

    /// The id column: `id`, else the first column whose values are all
    /// distinct and non-empty.
    fn id_column(&self) -> Option<usize> {
        self.named(&["id"]).or_else(|| {
            self.columns
                .iter()
                .position(|c| c.distinct == self.rows() && c.values.iter().all(|v| !v.is_empty()))
        })
    }
}

/// How another table relates to the node table.
enum Relation {
    /// `a,b[,strength]`: listed neighbours (border-list).
    Pairs { strength: Option<String> },
    /// `id,v1..vd`: feature vectors (embedding-matrix).
    Vectors,
    /// A date column, then one column per id (time-series).
    Series,
}

/// Share of values that must name node ids for a table to count as referring
/// to them (a few dangling ids are reported by the build, naming them).
const REFERS: f64 = 0.8;

fn share_in(values: &[String], ids: &BTreeSet<&str>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.iter().filter(|v| ids.contains(v.as_str())).count() as f64 / values.len() as f64
}

fn relation(other: &Sniffed, ids: &BTreeSet<&str>) -> Option<Relation> {
    let cols = &other.columns;
    let header_ids: Vec<String> = other.table.header.iter().skip(1).cloned().collect();
    if cols.len() >= 3 && share_in(&header_ids, ids) >= REFERS {
        return Some(Relation::Series);
    }
    let refers = |c: &Column| share_in(&c.values, ids) >= REFERS;
    if (2..=3).contains(&cols.len())
        && refers(&cols[0])
        && refers(&cols[1])
        && cols.get(2).is_none_or(|c| c.numeric)
    {
        return Some(Relation::Pairs {
            strength: cols.get(2).map(|c| c.name.clone()),
        });
    }
    if cols.len() >= 2 && refers(&cols[0]) && cols[1..].iter().all(|c| c.numeric) {
        return Some(Relation::Vectors);
    }
    None
}

/// The node table's field mapping.
struct Fields {
    id: String,
    label: Option<String>,
    weight: Option<String>,
    groups: Vec<String>,
    genres: Option<String>,
}

fn fields(t: &Sniffed, id: usize) -> Fields {
    let rows = t.rows();
    let text = |i: &usize| !t.columns[*i].numeric && *i != id;
    let label = t
        .named(&["label", "name", "title"])
        .filter(|i| *i != id)
        .or_else(|| {
            (0..t.columns.len())
                .filter(text)
                .find(|&i| t.columns[i].distinct == rows)
        });
    let weight = t
        .named(&["weight", "value", "size"])
        .filter(|&i| t.columns[i].numeric)
        .or_else(|| {
            (0..t.columns.len()).find(|&i| {
                i != id
                    && t.columns[i].numeric
                    && t.columns[i]
                        .values
                        .iter()
                        .all(|v| v.parse::<f64>().is_ok_and(|x| x >= 0.0))
            })
        });
    // A multi-valued column: at least a third of its cells list several values.
    let genres = (0..t.columns.len()).filter(text).find(|&i| {
        let c = &t.columns[i];
        3 * c.values.iter().filter(|v| v.contains('|')).count() >= c.values.len().max(1)
    });
    // Grouping columns: text that repeats (fewer distinct values than rows,
    // at least two), outermost (fewest values) first; at most two levels.
    let mut groups: Vec<usize> = (0..t.columns.len())
        .filter(text)
        .filter(|&i| Some(i) != label && Some(i) != genres)
        .filter(|&i| (2..rows).contains(&t.columns[i].distinct))
        .collect();
    groups.sort_by_key(|&i| (t.columns[i].distinct, i));
    groups.truncate(2);
    let name = |i: usize| t.columns[i].name.clone();
    Fields {
        id: name(id),
        label: label.map(name),
        weight: weight.map(name),
        groups: groups.into_iter().map(name).collect(),
        genres: genres.map(name),
    }
}

/// A path as the config at `config` should name it: relative to the config's
/// folder when inside it, else absolute.
fn relative_to_config(path: &Path, config: &Path) -> PathBuf {
    let dir = config.parent().filter(|d| !d.as_os_str().is_empty());
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let path_abs = absolute(path);
    let dir_abs = absolute(dir.unwrap_or(Path::new(".")));
    path_abs
        .strip_prefix(&dir_abs)
        .map(Path::to_path_buf)
        .unwrap_or(path_abs)
}

/// A YAML scalar: plain when safe, else double-quoted.
fn scalar(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.' | '/'))
        && !matches!(text, "null" | "true" | "false" | "yes" | "no" | "~");
    if plain {
        text.to_string()
    } else {
        serde_json::to_string(text).unwrap_or_else(|_| format!("{text:?}"))
    }
}

pub(crate) fn run(args: &InitArgs) -> anyhow::Result<()> {
    if args.output.exists() && !args.force {
        return Err(UsageError(format!(
            "{}: exists; give --force to replace it",
            args.output.display()
        ))
        .into());
    }
    let tables = args
        .tables
        .iter()
        .map(|p| Sniffed::read(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let yaml = config_text(&tables, &args.output)?;
    // Checked as the build will read it, before anything is written.
    let base = args.output.parent().unwrap_or(Path::new(""));
    crate::config::Config::from_str(&yaml, base).map_err(|e| {
        anyhow::anyhow!(
            "init wrote a config that does not parse ({e}); please report this:\n{yaml}"
        )
    })?;
    std::fs::write(&args.output, &yaml)
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", args.output.display()))?;
    super::status(format_args!(
        "wrote {}; build it with `nptreemap build {}`",
        args.output.display(),
        args.output.display()
    ));
    Ok(())
}

/// A candidate node table: its index, its id column, and how each other
/// table relates to it.
type NodeTable = (usize, usize, Vec<(usize, Relation)>);

/// The commented config for `tables`, to be written at `output`.
fn config_text(tables: &[Sniffed], output: &Path) -> anyhow::Result<String> {
    // The node table is the one the most others refer to (ties: the first).
    let mut best: Option<NodeTable> = None;
    for (n, t) in tables.iter().enumerate() {
        let Some(id) = t.id_column() else { continue };
        let ids: BTreeSet<&str> = t.columns[id].values.iter().map(String::as_str).collect();
        let relations: Vec<(usize, Relation)> = tables
            .iter()
            .enumerate()
            .filter(|(o, _)| *o != n)
            .filter_map(|(o, other)| relation(other, &ids).map(|r| (o, r)))
            .collect();
        if best.as_ref().is_none_or(|b| relations.len() > b.2.len()) {
            best = Some((n, id, relations));
        }
    }
    let Some((n, id, relations)) = best else {
        return Err(UsageError(
            "no table has an id column (`id`, or a column whose values are all distinct)".into(),
        )
        .into());
    };
    let nodes = &tables[n];
    let f = fields(nodes, id);
    let file = |t: &Sniffed| scalar(&relative_to_config(&t.path, output).to_string_lossy());
    let mut files = vec![format!("nodes: {}", file(nodes))];
    let mut why = Vec::new();
    let mut strength = None;
    let format = match relations.first() {
        Some((o, Relation::Pairs { strength: s })) => {
            files.push(format!("pairs: {}", file(&tables[*o])));
            why.push(format!(
                "{} lists pairs of ids: neighbours",
                tables[*o].path.display()
            ));
            strength = s.clone();
            "border-list"
        }
        Some((o, Relation::Vectors)) => {
            files.push(format!("vectors: {}", file(&tables[*o])));
            why.push(format!(
                "{} holds a vector per id: cosine similarity",
                tables[*o].path.display()
            ));
            "embedding-matrix"
        }
        Some((o, Relation::Series)) => {
            files.push(format!("series: {}", file(&tables[*o])));
            why.push(format!(
                "{} holds a series per id: Pearson correlation",
                tables[*o].path.display()
            ));
            "time-series"
        }
        None if f.genres.is_some() => {
            why.push(format!(
                "column {:?} lists several values per row: Jaccard similarity of the sets",
                f.genres.as_deref().unwrap_or_default()
            ));
            "genre-table"
        }
        None => {
            return Err(UsageError(format!(
                "{}: found no similarity between its rows; also give a pairs table (a,b), a \
                 vectors table (id,v1,v2,..), a series table (a date column, then one column per \
                 id), or add a genres column (Drama|Crime)",
                nodes.path.display()
            ))
            .into())
        }
    };
    for (o, _) in relations.iter().skip(1) {
        why.push(format!(
            "{} is not used (one similarity per dataset)",
            tables[*o].path.display()
        ));
    }
    let name = nodes
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "data".to_string());
    let mut y = String::new();
    let args: Vec<String> = tables
        .iter()
        .map(|t| t.path.display().to_string())
        .collect();
    let _ = writeln!(y, "# Written by `nptreemap init {}`.", args.join(" "));
    let _ = writeln!(
        y,
        "# Build with `nptreemap build`, keep current with `nptreemap watch`."
    );
    let _ = writeln!(
        y,
        "# Every key, with its default, is listed in nptreemap's config/default.yaml."
    );
    for line in &why {
        let _ = writeln!(y, "# {line}");
    }
    let _ = writeln!(
        y,
        "layout:\n  seed: 1                # the same seed gives the same picture"
    );
    let _ = writeln!(y, "datasets:\n  - name: {}", scalar(&name));
    let _ = writeln!(y, "    format: {format}");
    let _ = writeln!(y, "    files: {{{}}}", files.join(", "));
    let _ = writeln!(y, "    fields:");
    let _ = writeln!(
        y,
        "      id: {}              # unique per row",
        scalar(&f.id)
    );
    if let Some(label) = &f.label {
        let _ = writeln!(y, "      label: {}", scalar(label));
    }
    match &f.weight {
        Some(w) => {
            let _ = writeln!(y, "      weight: {}          # cell areas", scalar(w));
        }
        None => {
            let _ = writeln!(
                y,
                "      # weight: COLUMN       # no numeric column found: every leaf weighs 1"
            );
        }
    }
    if f.groups.is_empty() {
        let _ = writeln!(
            y,
            "      # groups: [COLUMN]     # grouping columns, outermost first (none found)"
        );
    } else {
        let groups: Vec<String> = f.groups.iter().map(|g| scalar(g)).collect();
        let _ = writeln!(
            y,
            "      groups: [{}]   # outermost first",
            groups.join(", ")
        );
    }
    if format == "genre-table" {
        let _ = writeln!(
            y,
            "      genres: {}",
            scalar(f.genres.as_deref().unwrap_or("genres"))
        );
    }
    if let Some(s) = strength {
        let _ = writeln!(y, "      strength: {}", scalar(&s));
    }
    let _ = writeln!(y, "    outputs:");
    let mut kinds = vec!["svg"];
    if cfg!(feature = "png") {
        kinds.push("png");
    }
    kinds.push("html");
    for kind in kinds {
        let _ = writeln!(y, "      - path: out/{}.{kind}", name);
    }
    Ok(y)
}
