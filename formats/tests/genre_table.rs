//! Tests for the genre-table format: 20 films by four directors (`data/films.csv`,
//! runtime in minutes as weight, IMDb genres as a `|`-separated column) and the same
//! data with one-hot genre columns in a shuffled order (`data/films_onehot.csv`),
//! plus malformed tables with their positions.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use nptreemap_formats::registry;
use nptreemap_formats::{
    Dataset, Format, FormatError, FormatOptions, GenreTable, InputError, Inputs, SimilarityHint,
};

const FILMS: &[u8] = include_bytes!("data/films.csv");
const FILMS_ONE_HOT: &[u8] = include_bytes!("data/films_onehot.csv");

/// The genres in the order of the feature vectors (sorted by name).
const GENRES: [&str; 12] = [
    "Action",
    "Adventure",
    "Biography",
    "Crime",
    "Drama",
    "Family",
    "History",
    "Mystery",
    "Sci-Fi",
    "Thriller",
    "War",
    "Western",
];

/// The one-hot columns of `films_onehot.csv`, as its header lists them.
const ONE_HOT_COLUMNS: [&str; 12] = [
    "Drama",
    "Crime",
    "Thriller",
    "Action",
    "Adventure",
    "Sci-Fi",
    "Mystery",
    "War",
    "Western",
    "Biography",
    "Family",
    "History",
];

fn options() -> FormatOptions {
    FormatOptions {
        label: Some("title".into()),
        weight: Some("runtime".into()),
        groups: vec!["director".into()],
        ..FormatOptions::default()
    }
}

fn one_hot_options() -> FormatOptions {
    FormatOptions {
        genre_columns: ONE_HOT_COLUMNS.iter().map(|&c| c.to_owned()).collect(),
        ..options()
    }
}

fn parse(nodes: &[u8], options: &FormatOptions) -> Result<Dataset, InputError> {
    GenreTable.parse(&Inputs::new().with("nodes", nodes), options)
}

/// `bytes` with one line replaced (1-based line number).
fn with_line(bytes: &[u8], line: usize, text: &str) -> Vec<u8> {
    let mut lines: Vec<&str> = std::str::from_utf8(bytes).expect("utf8").lines().collect();
    lines[line - 1] = text;
    (lines.join("\n") + "\n").into_bytes()
}

fn failure(nodes: &[u8], options: &FormatOptions) -> (InputError, String) {
    let error = parse(nodes, options).expect_err("must fail");
    let text = error.to_string();
    (error, text)
}

/// The 0/1 vector over [`GENRES`] for the named genres.
fn vector(genres: &[&str]) -> Vec<f64> {
    GENRES
        .iter()
        .map(|g| if genres.contains(g) { 1.0 } else { 0.0 })
        .collect()
}

fn features(dataset: &Dataset, id: &str) -> Option<Vec<f64>> {
    let index = dataset.find(id).unwrap_or_else(|| panic!("no node {id}"));
    dataset.node(index).features.as_ref().map(|f| {
        // Genres stay a set: member ids, never a one-hot row.
        assert!(f.as_sparse().is_some_and(|s| s.is_set()), "{id}: {f:?}");
        f.to_dense()
    })
}

#[test]
fn films_by_director() {
    let dataset = parse(FILMS, &options()).expect("valid");
    assert_eq!(dataset.len(), 1 + 4 + 20);
    assert_eq!(dataset.leaves().count(), 20);
    assert_eq!(dataset.max_depth(), 2);
    assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Jaccard));
    let nolan = dataset.node(dataset.find("group:Christopher Nolan").expect("Nolan"));
    assert_eq!(nolan.label, "Christopher Nolan");
    assert_eq!(nolan.children.len(), 5);
    assert_eq!(nolan.value, 152.0 + 148.0 + 169.0 + 113.0 + 130.0);
    assert_eq!(nolan.features, None, "groups get no genres");
    let root = dataset.node(dataset.root());
    assert_eq!(root.children.len(), 4);
    for leaf in dataset.leaves() {
        let node = dataset.node(leaf);
        let set = node.features.as_ref().expect("every film has a set");
        assert_eq!(set.len(), GENRES.len(), "{}", node.id);
        assert!(set.as_sparse().is_some_and(|s| s.is_set()), "{}", node.id);
    }
    let knight = dataset.node(dataset.find("dark-knight").expect("dark knight"));
    assert_eq!(knight.label, "The Dark Knight");
    assert_eq!(knight.weight, Some(152.0));
    assert_eq!(
        features(&dataset, "dark-knight"),
        Some(vector(&["Action", "Crime", "Drama", "Thriller"]))
    );
    assert_eq!(
        features(&dataset, "memento"),
        Some(vector(&["Mystery", "Thriller"]))
    );
    assert_eq!(
        features(&dataset, "schindlers-list"),
        Some(vector(&["Biography", "Drama", "History"]))
    );
    assert_eq!(
        features(&dataset, "django"),
        Some(vector(&["Drama", "Western"]))
    );
    assert_eq!(
        registry::find("genre-table").map(|f| f.roles().len()),
        Some(1)
    );
}

#[test]
fn one_hot_columns_give_the_same_dataset() {
    let multi = parse(FILMS, &options()).expect("multi-valued");
    let one_hot = parse(FILMS_ONE_HOT, &one_hot_options()).expect("one-hot");
    assert_eq!(one_hot, multi);
}

#[test]
fn one_hot_cells_may_be_words_or_empty() {
    let plain = parse(FILMS_ONE_HOT, &one_hot_options()).expect("plain");
    let text = std::str::from_utf8(FILMS_ONE_HOT).expect("utf8");
    let words = ["true", "YES", "True", "yes"];
    let nos = ["", "false", "no", "NO", "0"];
    let mut out = String::new();
    for (n, line) in text.lines().enumerate() {
        if n == 0 {
            out.push_str(line);
        } else {
            let fields: Vec<String> = line
                .split(',')
                .enumerate()
                .map(|(i, f)| match (i >= 4, f) {
                    (true, "1") => words[(n + i) % words.len()].to_owned(),
                    (true, "0") => nos[(n + i) % nos.len()].to_owned(),
                    _ => f.to_owned(),
                })
                .collect();
            out.push_str(&fields.join(","));
        }
        out.push('\n');
    }
    assert_ne!(out.as_bytes(), FILMS_ONE_HOT);
    assert_eq!(
        parse(out.as_bytes(), &one_hot_options()).expect("words"),
        plain
    );
}

#[test]
fn bom_and_crlf_read_like_plain() {
    let dos = |bytes: &[u8]| {
        let mut out = b"\xEF\xBB\xBF".to_vec();
        out.extend(String::from_utf8_lossy(bytes).replace('\n', "\r\n").bytes());
        out
    };
    let plain = parse(FILMS, &options()).expect("plain");
    assert_eq!(parse(&dos(FILMS), &options()).expect("dos"), plain);
    assert_eq!(
        parse(&dos(FILMS_ONE_HOT), &one_hot_options()).expect("dos one-hot"),
        plain
    );
    // Positions still count lines after a BOM and CRLF.
    let bad = dos(&with_line(
        FILMS_ONE_HOT,
        6,
        "prestige,The Prestige,Christopher Nolan,130,1,0,1,0,0,1,maybe,0,0,0,0,0",
    ));
    let (_, text) = failure(&bad, &one_hot_options());
    assert!(text.starts_with("nodes: line 6, column 11:"), "{text}");
}

#[test]
fn genres_column_name_and_separator_are_options() {
    let plain = parse(FILMS, &options()).expect("plain");
    let text = std::str::from_utf8(FILMS)
        .expect("utf8")
        .replace(",genres", ",kinds")
        .replace('|', " ; ");
    let options = FormatOptions {
        genres: Some("kinds".into()),
        separator: Some(';'),
        ..options()
    };
    assert_eq!(parse(text.as_bytes(), &options).expect("kinds"), plain);
}

#[test]
fn empty_cell_means_no_genres_and_repeats_count_once() {
    let films = with_line(FILMS, 5, "memento,Memento,Christopher Nolan,113,");
    let films = with_line(
        &films,
        7,
        "pulp-fiction,Pulp Fiction,Quentin Tarantino,154,Crime| Drama |Crime||",
    );
    let dataset = parse(&films, &options()).expect("valid");
    assert_eq!(features(&dataset, "memento"), Some(vector(&[])));
    assert_eq!(
        features(&dataset, "pulp-fiction"),
        Some(vector(&["Crime", "Drama"]))
    );
}

#[test]
fn hierarchy_from_a_parent_column() {
    let table = b"id,parent,label,genres\n\
                  films,,Films,\n\
                  nolan,films,Christopher Nolan,\n\
                  memento,nolan,Memento,Mystery|Thriller\n\
                  jaws,films,Jaws,Adventure|Thriller\n";
    let options = FormatOptions {
        parent: Some("parent".into()),
        ..FormatOptions::default()
    };
    let dataset = parse(table, &options).expect("valid");
    let ids: Vec<&str> = dataset.nodes().iter().map(|n| n.id.as_str()).collect();
    assert_eq!(ids, ["films", "nolan", "jaws", "memento"]);
    // Over Adventure, Mystery, Thriller; inner rows are rows too, with no genres.
    assert_eq!(features(&dataset, "memento"), Some(vec![0.0, 1.0, 1.0]));
    assert_eq!(features(&dataset, "jaws"), Some(vec![1.0, 0.0, 1.0]));
    assert_eq!(features(&dataset, "nolan"), Some(vec![0.0, 0.0, 0.0]));
}

#[test]
fn bad_one_hot_cell() {
    let bad = with_line(
        FILMS_ONE_HOT,
        6,
        "prestige,The Prestige,Christopher Nolan,130,1,0,1,0,0,1,maybe,0,0,0,0,0",
    );
    let (error, text) = failure(&bad, &one_hot_options());
    assert_eq!(error.role, "nodes");
    assert!(
        matches!(&error.error, FormatError::Field { line: Some(6), column: Some(11), field, .. } if field == "Mystery"),
        "{error:?}"
    );
    assert!(
        text.contains("node \"prestige\": field \"Mystery\""),
        "{text}"
    );
    assert!(text.contains("found \"maybe\""), "{text}");
    let bad = with_line(
        FILMS_ONE_HOT,
        3,
        "inception,Inception,Christopher Nolan,148,0,0,1,2,1,1,0,0,0,0,0,0",
    );
    let (error, text) = failure(&bad, &one_hot_options());
    assert_eq!(
        (error.error.line(), error.error.column()),
        (Some(3), Some(8))
    );
    assert!(
        text.contains("field \"Action\"") && text.contains("\"2\""),
        "{text}"
    );
}

#[test]
fn both_kinds_of_genres_named() {
    let options = FormatOptions {
        genres: Some("genres".into()),
        ..one_hot_options()
    };
    let (error, text) = failure(FILMS_ONE_HOT, &options);
    assert_eq!(error.role, "nodes");
    assert_eq!(error.error.line(), Some(1));
    assert!(
        text.contains("either a genres column or one-hot genre columns, not both"),
        "{text}"
    );
}

#[test]
fn missing_genre_columns() {
    // No `genres` column and no one-hot columns given.
    let (error, text) = failure(FILMS_ONE_HOT, &options());
    assert_eq!(error.role, "nodes");
    assert!(
        text.starts_with("nodes: line 1: no genres:") && text.contains("Drama, Crime"),
        "{text}"
    );
    let named = FormatOptions {
        genres: Some("kinds".into()),
        ..options()
    };
    let (_, text) = failure(FILMS, &named);
    assert!(
        text.contains("line 1: no column \"kinds\" (the genres column)"),
        "{text}"
    );
    let mut columns = one_hot_options();
    columns.genre_columns.push("Musical".into());
    let (_, text) = failure(FILMS_ONE_HOT, &columns);
    assert!(
        text.contains("line 1: no column \"Musical\" (a one-hot genre column)"),
        "{text}"
    );
    let mut twice = one_hot_options();
    twice.genre_columns.push("drama".into());
    let (error, text) = failure(FILMS_ONE_HOT, &twice);
    assert_eq!(error.error.column(), Some(5));
    assert!(
        text.contains("the one-hot genre column \"Drama\" is named twice"),
        "{text}"
    );
}

#[test]
fn no_row_has_a_genre() {
    let table = b"id,director,genres\na,X,\nb,Y,\n";
    let options = FormatOptions {
        groups: vec!["director".into()],
        ..FormatOptions::default()
    };
    let (error, text) = failure(table, &options);
    assert_eq!(error.role, "nodes");
    assert!(text.contains("no row has a genre"), "{text}");
}

#[test]
fn table_errors_name_the_line_and_value() {
    let bad = with_line(
        FILMS,
        9,
        "kill-bill-1,Kill Bill: Vol. 1,Quentin Tarantino,long,Action|Crime|Thriller",
    );
    let (error, text) = failure(&bad, &options());
    assert_eq!(error.role, "nodes");
    assert!(
        text.starts_with("nodes: line 9, column 4: node \"kill-bill-1\": field \"runtime\""),
        "{text}"
    );
    assert!(text.contains("\"long\""), "{text}");
    let (error, text) = failure(
        &with_line(FILMS, 4, "interstellar,Interstellar"),
        &options(),
    );
    assert_eq!(error.error.line(), Some(4));
    assert!(text.contains("wrong number of fields"), "{text}");
}
