//! Tests for the embedding-matrix format: 20 foods (`data/foods.csv`, kcal per 100 g,
//! grouped fruit/vegetable/nut) with 4-d vectors of water, carbohydrate, protein and
//! fat in g per 100 g (`data/foods_vectors.tsv`, rounded USDA-style values), plus
//! malformed vector files with their positions.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use nptreemap_formats::registry;
use nptreemap_formats::{
    Dataset, EmbeddingMatrix, Format, FormatError, FormatOptions, InputError, Inputs, OnUnknownId,
    SimilarityHint,
};

const FOODS: &[u8] = include_bytes!("data/foods.csv");
const VECTORS: &[u8] = include_bytes!("data/foods_vectors.tsv");

/// The fixtures' mapping; unknown ids are errors, so the tests of those
/// errors see them (the default skips them with a warning, tested apart).
fn options() -> FormatOptions {
    FormatOptions {
        on_unknown_id: OnUnknownId::Error,
        weight: Some("kcal".into()),
        groups: vec!["group".into()],
        ..FormatOptions::default()
    }
}

fn parse(nodes: &[u8], vectors: &[u8]) -> Result<Dataset, InputError> {
    EmbeddingMatrix.parse(
        &Inputs::new().with("nodes", nodes).with("vectors", vectors),
        &options(),
    )
}

/// The foods vectors with one line replaced (1-based line number).
fn with_line(line: usize, text: &str) -> Vec<u8> {
    let mut lines: Vec<&str> = std::str::from_utf8(VECTORS)
        .expect("utf8")
        .lines()
        .collect();
    lines[line - 1] = text;
    (lines.join("\n") + "\n").into_bytes()
}

fn failure(vectors: &[u8]) -> (InputError, String) {
    let error = parse(FOODS, vectors).expect_err("must fail");
    let text = error.to_string();
    (error, text)
}

#[test]
fn foods_with_vectors() {
    let dataset = parse(FOODS, VECTORS).expect("valid");
    assert_eq!(dataset.len(), 1 + 3 + 20);
    assert_eq!(dataset.leaves().count(), 20);
    assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Cosine));
    for leaf in dataset.leaves() {
        assert_eq!(
            dataset.node(leaf).features.as_ref().map(|f| f.len()),
            Some(4)
        );
    }
    let walnut = dataset.node(dataset.find("walnut").expect("walnut"));
    assert_eq!(walnut.features, Some(vec![4.0, 14.0, 15.0, 65.0].into()));
    let nuts = dataset.node(dataset.find("group:nut").expect("nuts"));
    assert_eq!(nuts.children.len(), 5);
    assert_eq!(nuts.features, None, "groups get no vector");
    assert_eq!(
        registry::find("embedding-matrix").map(|f| f.roles().len()),
        Some(3),
        "nodes, vectors and the optional ids of a .npy matrix"
    );
}

#[test]
fn header_is_optional_and_csv_works() {
    let plain = parse(FOODS, VECTORS).expect("with header");
    let text = std::str::from_utf8(VECTORS).expect("utf8");
    let no_header: String = text
        .lines()
        .skip(1)
        .map(|l| l.replace('\t', ",") + "\n")
        .collect();
    assert_eq!(
        parse(FOODS, no_header.as_bytes()).expect("no header"),
        plain
    );
}

#[test]
fn bom_and_crlf_read_like_plain() {
    let plain = parse(FOODS, VECTORS).expect("plain");
    let dos = |bytes: &[u8]| {
        let mut out = b"\xEF\xBB\xBF".to_vec();
        out.extend(String::from_utf8_lossy(bytes).replace('\n', "\r\n").bytes());
        out
    };
    assert_eq!(parse(&dos(FOODS), &dos(VECTORS)).expect("dos"), plain);
}

#[test]
fn rows_of_different_lengths() {
    let (error, text) = failure(&with_line(5, "grape\t81\t18\t0.7"));
    assert_eq!(error.role, "vectors");
    assert_eq!(error.error.line(), Some(5));
    assert!(
        text.contains("the row has 3 values, the first row (line 2) has 4"),
        "{text}"
    );
}

#[test]
fn non_numeric_entry() {
    let (error, text) = failure(&with_line(7, "mango\t84\tlots\t0.8\t0.4"));
    assert!(
        matches!(&error.error, FormatError::Field { line: Some(7), column: Some(3), node: Some(n), field, .. } if n == "mango" && field == "carbs"),
        "{error:?}"
    );
    assert!(
        text.starts_with("vectors: line 7, column 3: node \"mango\""),
        "{text}"
    );
    assert!(text.contains("\"lots\""), "{text}");
    let (_, text) = failure(&with_line(7, "mango\t84\tNaN\t0.8\t0.4"));
    assert!(
        text.contains("expected a finite number, found \"NaN\""),
        "{text}"
    );
}

#[test]
fn typo_in_the_first_row_without_header_is_not_a_header() {
    let vectors = b"apple,86,x,0.3,0.2\n";
    let (error, text) = failure(vectors);
    assert_eq!(error.error.line(), Some(1));
    assert!(
        text.contains("column 3") && text.contains("\"x\""),
        "{text}"
    );
}

#[test]
fn all_zero_vector() {
    let (error, text) = failure(&with_line(4, "orange\t0\t0\t0.0\t0"));
    assert_eq!(error.error.line(), Some(4));
    assert!(
        text.contains("node \"orange\": the vector is all zeros"),
        "{text}"
    );
    assert!(text.contains("cosine similarity is undefined"), "{text}");
}

#[test]
fn unknown_and_repeated_ids() {
    let (error, text) = failure(&with_line(3, "kiwi\t83\t15\t1.1\t0.5"));
    assert!(
        matches!(
            error.error,
            FormatError::Field {
                line: Some(3),
                column: Some(1),
                ..
            }
        ),
        "{error:?}"
    );
    assert!(text.contains("unknown id \"kiwi\""), "{text}");
    let (error, text) = failure(&with_line(3, "apple\t86\t14\t0.3\t0.2"));
    assert_eq!(error.error.line(), Some(3));
    assert!(
        text.contains("\"apple\" has a second vector (the first is on line 2)"),
        "{text}"
    );
}

#[test]
fn node_without_vector() {
    let text = std::str::from_utf8(VECTORS).expect("utf8");
    let without_pea: String = text
        .lines()
        .filter(|l| !l.starts_with("pea\t"))
        .map(|l| l.to_owned() + "\n")
        .collect();
    let (error, text) = failure(without_pea.as_bytes());
    assert_eq!(error.role, "vectors");
    assert!(
        text.contains("node \"pea\" (nodes line 16) has no vector"),
        "{text}"
    );
}

#[test]
fn empty_and_header_only_and_binary() {
    let (error, text) = failure(b"");
    assert_eq!(error.role, "vectors");
    assert!(text.contains("line 1") && text.contains("empty"), "{text}");
    let (_, text) = failure(b"id,x,y\n");
    assert!(
        text.contains("line 1") && text.contains("only a header"),
        "{text}"
    );
    let mut state: u64 = 88172645463325252;
    let blob: Vec<u8> = (0..200 * 1024)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state as u8
        })
        .collect();
    let (error, _) = failure(&blob);
    assert!(error.error.line().is_some(), "{error}");
}
