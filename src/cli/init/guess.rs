//! `init`'s guesses about a node table, from a sample of its rows: the id,
//! label, weight, grouping and multi-valued (genres) columns, and how another
//! table relates to the node ids (pairs, vectors, a series). The flags
//! `--label`, `--weight`, `--groups` and `--genres` replace a guess; each names
//! a column of the node table, checked here with a "did you mean".

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::path::Path;

use nptreemap_formats::suggest::did_you_mean;
use nptreemap_formats::table::Table;

use super::super::UsageError;

/// Facts about one column of a sampled table.
pub(super) struct Column {
    pub(super) name: String,
    /// Every cell is a finite number (and there is at least one).
    pub(super) numeric: bool,
    /// Numeric and never negative.
    pub(super) nonnegative: bool,
    /// Distinct values.
    pub(super) distinct: usize,
    /// Cells that are not empty.
    pub(super) filled: usize,
    /// Mean length of the cells, in characters.
    pub(super) mean_chars: f64,
}

/// A sampled table with its columns' facts.
pub(super) struct Profile<'a> {
    pub(super) table: &'a Table,
    pub(super) columns: Vec<Column>,
}

impl<'a> Profile<'a> {
    pub(super) fn new(table: &'a Table) -> Self {
        let columns = table
            .header
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let cells = || table.rows.iter().map(move |r| cell(r, i));
                let number = |v: &str| v.parse::<f64>().ok().filter(|x| x.is_finite());
                let numeric = !table.rows.is_empty() && cells().all(|v| number(v).is_some());
                let chars: usize = cells().map(|v| v.chars().count()).sum();
                Column {
                    name: name.clone(),
                    numeric,
                    nonnegative: numeric && cells().all(|v| number(v).is_some_and(|x| x >= 0.0)),
                    distinct: cells().collect::<BTreeSet<_>>().len(),
                    filled: cells().filter(|v| !v.is_empty()).count(),
                    mean_chars: chars as f64 / table.rows.len().max(1) as f64,
                }
            })
            .collect();
        Profile { table, columns }
    }

    pub(super) fn rows(&self) -> usize {
        self.table.rows.len()
    }

    /// The cells of column `i`.
    pub(super) fn cells(&self, i: usize) -> impl Iterator<Item = &'a str> + 'a {
        self.table.rows.iter().map(move |r| cell(r, i))
    }

    /// The first column named one of `names` (ASCII case-insensitively).
    fn named(&self, names: &[&str]) -> Option<usize> {
        names.iter().find_map(|n| self.table.column(n))
    }

    /// The id column: `id`, else the first column whose values are all
    /// distinct and non-empty.
    pub(super) fn id_column(&self) -> Option<usize> {
        self.named(&["id"]).or_else(|| {
            self.columns
                .iter()
                .position(|c| c.distinct == self.rows() && c.filled == self.rows())
        })
    }

    fn is_text(&self, i: usize) -> bool {
        !self.columns[i].numeric
    }
}

fn cell(row: &nptreemap_formats::table::Row, i: usize) -> &str {
    row.fields.get(i).map_or("", String::as_str)
}

/// How another table relates to the node table.
pub(super) enum Relation {
    /// `a,b[,strength]`: listed neighbours (border-list).
    Pairs { strength: Option<String> },
    /// `id,v1..vd`: feature vectors (embedding-matrix) of `dims` values.
    Vectors { dims: usize },
    /// A date column, then one column per id (time-series).
    Series,
    /// A `.npy` matrix, one row per node (embedding-matrix).
    Npy { cols: usize },
}

/// Share of values that must name node ids for a table to count as referring
/// to them (a few dangling ids are reported by the build, naming them).
const REFERS: f64 = 0.8;

fn share_in<'v>(values: impl Iterator<Item = &'v str>, ids: &HashSet<String>) -> f64 {
    let (mut n, mut hits) = (0usize, 0usize);
    for v in values {
        n += 1;
        hits += usize::from(ids.contains(v));
    }
    if n == 0 {
        0.0
    } else {
        hits as f64 / n as f64
    }
}

/// How the sampled table `other` refers to the node ids `ids`, if it does.
pub(super) fn relation(other: &Profile<'_>, ids: &HashSet<String>) -> Option<Relation> {
    let cols = &other.columns;
    let header = other.table.header.iter().skip(1).map(String::as_str);
    if cols.len() >= 3 && share_in(header, ids) >= REFERS {
        return Some(Relation::Series);
    }
    let refers = |i: usize| share_in(other.cells(i), ids) >= REFERS;
    if (2..=3).contains(&cols.len())
        && refers(0)
        && refers(1)
        && cols.get(2).is_none_or(|c| c.numeric)
    {
        return Some(Relation::Pairs {
            strength: cols.get(2).map(|c| c.name.clone()),
        });
    }
    if cols.len() >= 2 && refers(0) && cols[1..].iter().all(|c| c.numeric) {
        return Some(Relation::Vectors {
            dims: cols.len() - 1,
        });
    }
    None
}

/// The node table's field mapping.
pub(super) struct Fields {
    pub(super) id: String,
    pub(super) label: Option<String>,
    pub(super) weight: Option<String>,
    pub(super) groups: Vec<String>,
    pub(super) genres: Option<String>,
    /// `render.labels.text` where the label column repeats: a template that
    /// makes it unique (`{name} {version}`).
    pub(super) label_text: Option<String>,
    /// Why a column was not taken where a reader might expect it (a
    /// repeating label, free text or links that are no grouping).
    pub(super) notes: Vec<String>,
}

/// Columns named on the command line, replacing init's guesses.
#[derive(Debug, Default)]
pub(super) struct Overrides {
    pub(super) label: Option<String>,
    pub(super) weight: Option<String>,
    /// `Some(vec![])` (from `--groups=`): no grouping.
    pub(super) groups: Option<Vec<String>>,
    pub(super) genres: Option<String>,
}

/// The separator of a multi-valued cell (the genre table's default).
const SEPARATOR: char = '|';

/// Share of a column's filled cells that must list several values for it to
/// count as multi-valued. A third missed a `requires` column with `|` in 25 of
/// 94 cells; a tenth still ignores free text with an occasional `|`, as does
/// the rule that values must recur across rows.
const MULTI_SHARE: f64 = 0.1;

/// How multi-valued text column `i` is: the share of its filled cells that
/// list several values, when at least [`MULTI_SHARE`] (and two cells) do and
/// some value recurs in two or more rows (else no two rows would be similar).
fn multi_valued(t: &Profile<'_>, i: usize) -> Option<f64> {
    let mut multi = 0usize;
    let mut rows_of: BTreeMap<&str, usize> = BTreeMap::new();
    for cell in t.cells(i) {
        let values: BTreeSet<&str> = cell
            .split(SEPARATOR)
            .map(str::trim)
            .filter(|v| !v.is_empty())
            .collect();
        multi += usize::from(values.len() >= 2);
        for v in values {
            *rows_of.entry(v).or_default() += 1;
        }
    }
    let filled = t.columns[i].filled.max(1);
    let share = multi as f64 / filled as f64;
    let recurs = rows_of.values().any(|&n| n >= 2);
    (multi >= 2 && share >= MULTI_SHARE && recurs).then_some(share)
}

/// Longest mean cell length (in characters) of a column taken for the label
/// by guess: names and titles, not sentences, which would be cut on the map.
const LABEL_CHARS: f64 = 32.0;

/// Longest value of a column that counts as an index of another column (its
/// first letter or two) rather than a grouping.
const INDEX_CHARS: usize = 3;

/// True when every value of column `g` is a short prefix (ignoring case) of the
/// same row's value in another text column: a first-letter index such as
/// `A` for `Alpha`, which would split the map into letters.
fn is_index(t: &Profile<'_>, g: usize, id: usize) -> bool {
    let short = t
        .cells(g)
        .all(|v| !v.is_empty() && v.chars().count() <= INDEX_CHARS);
    short
        && (0..t.columns.len())
            // Not the id: ids that start with their group (`EU-DE` in `EU`)
            // make a real grouping.
            .filter(|&c| c != g && c != id && t.is_text(c))
            .any(|c| {
                t.table.rows.iter().all(|r| {
                    let (prefix, whole) = (cell(r, g).to_lowercase(), cell(r, c).to_lowercase());
                    whole.len() > prefix.len() && whole.starts_with(&prefix)
                })
            })
}

/// The column `name` given with `flag`, or an error naming the table's
/// columns with a "did you mean".
fn named_column(t: &Profile<'_>, path: &Path, flag: &str, name: &str) -> Result<usize, UsageError> {
    t.table.column(name).ok_or_else(|| {
        UsageError(format!(
            "{flag} {name}: {} has no column {name:?}{}; its columns: {}",
            path.display(),
            did_you_mean(name, t.table.header.iter().map(String::as_str)),
            t.table.header.join(", ")
        ))
    })
}

/// The weight column: the one given (every value a number >= 0, else the
/// error names the line), else one named like a weight, else the first
/// column of numbers >= 0 but the id.
fn weight_column(
    t: &Profile<'_>,
    path: &Path,
    id: usize,
    given: &Overrides,
) -> Result<Option<usize>, UsageError> {
    Ok(match &given.weight {
        Some(name) => {
            let i = named_column(t, path, "--weight", name)?;
            if let Some(row) = t.table.rows.iter().find(|r| {
                !cell(r, i)
                    .parse::<f64>()
                    .is_ok_and(|x| x.is_finite() && x >= 0.0)
            }) {
                return Err(UsageError(format!(
                    "--weight {name}: column {name:?} of {} is not a number >= 0 (line {}: {:?}); \
                     a weight is a cell's area",
                    path.display(),
                    row.line,
                    cell(row, i)
                )));
            }
            Some(i)
        }
        None => t
            .named(&["weight", "value", "size"])
            .filter(|&i| t.columns[i].nonnegative)
            .or_else(|| (0..t.columns.len()).find(|&i| i != id && t.columns[i].nonnegative)),
    })
}

/// The field mapping of node table `t` (at `path`) with id column `id`: the
/// overrides where given, else init's guesses.
pub(super) fn fields(
    t: &Profile<'_>,
    path: &Path,
    id: usize,
    given: &Overrides,
) -> Result<Fields, UsageError> {
    let column = |flag: &str, name: &str| named_column(t, path, flag, name);
    let mut notes: Vec<String> = Vec::new();
    let genres = match &given.genres {
        Some(name) => Some(column("--genres", name)?),
        None => (0..t.columns.len())
            .filter(|&i| i != id && t.is_text(i))
            .filter_map(|i| multi_valued(t, i).map(|share| (i, share)))
            // The most multi-valued; the first of equals.
            .fold(None, |best: Option<(usize, f64)>, (i, s)| match best {
                Some((_, b)) if b >= s => best,
                _ => Some((i, s)),
            })
            .map(|(i, _)| i),
    };
    let free = |i: usize| i != id && Some(i) != genres && t.is_text(i);
    let label = match &given.label {
        Some(name) => Some(column("--label", name)?),
        None => t
            .named(&["label", "name", "title"])
            .filter(|&i| i != id && Some(i) != genres)
            .or_else(|| {
                // The first short text column that is (nearly) unique per row.
                // Not a version: it tells rows apart, it does not name them.
                let versions = |i: usize| {
                    let name = &t.columns[i].name;
                    VERSION_NAMES.iter().any(|v| name.eq_ignore_ascii_case(v))
                };
                (0..t.columns.len())
                    .filter(|&i| free(i) && !versions(i))
                    .find(|&i| {
                        let c = &t.columns[i];
                        c.filled == t.rows()
                            && c.distinct * 10 >= t.rows() * 9
                            && c.mean_chars <= LABEL_CHARS
                    })
            }),
    };
    let weight = weight_column(t, path, id, given)?;
    let groups = match &given.groups {
        Some(names) => names
            .iter()
            .map(|name| column("--groups", name))
            .collect::<Result<Vec<_>, _>>()?,
        None => {
            // Text that repeats (two values at least, fewer than the rows),
            // is not an index of another column; outermost (fewest values)
            // first; at most two levels.
            let mut groups: Vec<usize> = (0..t.columns.len())
                .filter(|&i| free(i) && Some(i) != label)
                .filter(|&i| match no_grouping(t, i) {
                    Some(why) => {
                        notes.push(format!("not a grouping: {} ({why})", t.columns[i].name));
                        false
                    }
                    None => true,
                })
                .filter(|&i| (2..t.rows()).contains(&t.columns[i].distinct))
                .filter(|&i| !is_index(t, i, id))
                .collect();
            groups.sort_by_key(|&i| (t.columns[i].distinct, i));
            groups.truncate(2);
            groups
        }
    };
    let (label, label_text) = match label {
        Some(l) if given.label.is_none() => unique_label(t, l, id, &mut notes),
        other => (other, None),
    };
    let name = |i: usize| t.columns[i].name.clone();
    Ok(Fields {
        id: name(id),
        label: label.map(name),
        weight: weight.map(name),
        groups: groups.into_iter().map(name).collect(),
        genres: genres.map(name),
        label_text,
        notes,
    })
}

/// Why text column `i` is no grouping, if it is not: its values are mostly
/// distinct (a grouping of one or two rows a group says nothing), long free
/// text, or links.
fn no_grouping(t: &Profile<'_>, i: usize) -> Option<String> {
    let c = &t.columns[i];
    if is_links(t, i) {
        return Some("links; offered as the page's link".to_string());
    }
    if c.mean_chars > LABEL_CHARS {
        return Some(format!(
            "free text, {:.0} characters a row on average",
            c.mean_chars
        ));
    }
    (c.distinct * 2 > c.filled).then(|| {
        format!(
            "{} distinct values in {} rows: mostly one row a group",
            c.distinct, c.filled
        )
    })
}

/// Share of a column's filled cells that must be `http(s)://` URLs for it
/// to count as links whatever its name.
const LINK_SHARE: f64 = 0.8;

/// Column `i` holds links: named so (`url`, `homepage`, ...), or mostly
/// `http://` and `https://` URLs.
fn is_links(t: &Profile<'_>, i: usize) -> bool {
    let c = &t.columns[i];
    if c.filled == 0 {
        return false;
    }
    let named = LINK_NAMES.iter().any(|n| c.name.eq_ignore_ascii_case(n));
    let urls = t
        .cells(i)
        .filter(|v| v.starts_with("http://") || v.starts_with("https://"))
        .count();
    named || urls as f64 >= LINK_SHARE * c.filled as f64
}

/// Names of a column that tells rows of one name apart, first choices.
const VERSION_NAMES: [&str; 4] = ["version", "vers", "release", "tag"];

/// The label column `l` if its values are unique; else a template that is
/// (`{name} {version}`: with a column that tells the rows of one name apart,
/// a version first), or no label (the ids, unique, are shown), with a note
/// saying which and why.
fn unique_label(
    t: &Profile<'_>,
    l: usize,
    id: usize,
    notes: &mut Vec<String>,
) -> (Option<usize>, Option<String>) {
    let c = &t.columns[l];
    if c.distinct >= t.rows() {
        return (Some(l), None);
    }
    let repeats = format!(
        "label {} is not unique ({} distinct values in {} rows)",
        c.name,
        c.distinct,
        t.rows()
    );
    let tells_apart = |v: usize| {
        v != l
            && v != id
            && t.columns[v].filled == t.rows()
            && t.columns[v].mean_chars <= LABEL_CHARS
            && t.table
                .rows
                .iter()
                .map(|r| (cell(r, l), cell(r, v)))
                .collect::<BTreeSet<_>>()
                .len()
                == t.rows()
    };
    let by_name = VERSION_NAMES.iter().filter_map(|n| t.table.column(n));
    let by_shape = (0..t.columns.len()).filter(|&v| !is_links(t, v));
    match by_name.chain(by_shape).find(|&v| tells_apart(v)) {
        Some(v) => {
            let text = format!("{{{}}} {{{}}}", c.name, t.columns[v].name);
            notes.push(format!("{repeats}: labels read {text}"));
            (Some(l), Some(text))
        }
        None => {
            notes.push(format!("{repeats}: labels show the id"));
            (None, None)
        }
    }
}

/// Columns a reader may want in the HTML page (issue 24 item 4), offered
/// commented out: a link column by its name, and up to [`OFFERED`] text
/// columns that the mapping leaves unused and that say something of their
/// own row (a summary, a version: mostly distinct values; a column of few
/// repeated values is a grouping the reader left out).
#[derive(Debug, Default, PartialEq)]
pub(super) struct PageOffer {
    pub(super) fields: Vec<String>,
    pub(super) link: Option<String>,
}

/// Most tooltip fields offered.
const OFFERED: usize = 4;

/// Longest mean cell length of a column offered for the tooltip: a line of
/// it (a one-line summary, not a description).
const FIELD_CHARS: f64 = 80.0;

/// Names of a column of links.
const LINK_NAMES: [&str; 6] = ["url", "link", "href", "homepage", "website", "homepage_url"];

/// The page offer for node table `t` with id column `id` mapped as `f`.
pub(super) fn page_offer(t: &Profile<'_>, id: usize, f: &Fields) -> PageOffer {
    let used = |name: &str| {
        name == t.columns[id].name
            || f.label.as_deref() == Some(name)
            || f.weight.as_deref() == Some(name)
            || f.groups.iter().any(|g| g == name)
            || f.genres.as_deref() == Some(name)
    };
    let link = (0..t.columns.len())
        .find(|&i| is_links(t, i))
        .map(|i| t.columns[i].name.clone())
        .filter(|name| !used(name));
    // Short text the mapping leaves unused that says something of its own
    // row (a version, a summary line): not numbers, not links, nothing
    // longer than a line of a tooltip.
    let fields = (0..t.columns.len())
        .filter(|&i| {
            let c = &t.columns[i];
            c.filled > 0
                && !used(&c.name)
                && !c.numeric
                && !is_links(t, i)
                && c.mean_chars <= FIELD_CHARS
                // Mostly distinct: a column of few repeated values is a
                // grouping the reader left out.
                && 5 * c.distinct >= 4 * c.filled
        })
        .take(OFFERED)
        .map(|i| t.columns[i].name.clone())
        .collect();
    PageOffer { fields, link }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::table::read_table;

    fn guess(csv: &str) -> Fields {
        let table = read_table(csv.as_bytes(), None).expect("table");
        let t = Profile::new(&table);
        let id = t.id_column().expect("id");
        fields(&t, Path::new("t.csv"), id, &Overrides::default()).expect("fields")
    }

    #[test]
    fn a_first_letter_column_is_no_grouping_but_a_real_one_is() {
        let f = guess(
            "id,title,initial,team\na,Alpha,A,x\nb,Beta,B,y\nc,Bravo,B,x\nd,Delta,D,y\ne,Echo,E,x\n",
        );
        assert_eq!(f.label.as_deref(), Some("title"));
        assert_eq!(f.groups, ["team"]);
    }

    #[test]
    fn sentences_are_no_label() {
        let f = guess(
            "id,summary,size\n\
             a,A long sentence that describes the first item in detail,1\n\
             b,Another long sentence about the second item of the list,2\n",
        );
        assert_eq!(f.label, None);
        assert_eq!(f.weight.as_deref(), Some("size"));
    }

    #[test]
    fn multi_valued_columns_need_recurring_values() {
        // Two of four cells list several values, and `x` recurs.
        let f = guess("id,tags\na,x|y\nb,x\nc,z|w\nd,\n");
        assert_eq!(f.genres.as_deref(), Some("tags"));
        // Free text with pipes that never share a value is no genre set.
        let f = guess("id,note\na,p|q\nb,r|s\nc,t\nd,u\n");
        assert_eq!(f.genres, None);
    }
}
