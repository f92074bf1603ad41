//! Tests for the border-list format: 31 real countries (`data/countries.csv`) and
//! their 48 real land borders among them (`data/borders.csv`), plus malformed pair
//! lists with their positions. Degrees below were counted by hand from the pair list.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use nptreemap_formats::registry;
use nptreemap_formats::{
    BorderList, Dataset, Format, FormatError, FormatOptions, InputError, Inputs, OnUnknownId,
    SimilarityHint,
};

const COUNTRIES: &[u8] = include_bytes!("data/countries.csv");
const BORDERS: &[u8] = include_bytes!("data/borders.csv");

/// The fixtures' mapping; unknown ids are errors, so the tests of those
/// errors see them (the default skips them with a warning, tested apart).
fn options() -> FormatOptions {
    FormatOptions {
        on_unknown_id: OnUnknownId::Error,
        weight: Some("population".into()),
        groups: vec!["continent".into()],
        ..FormatOptions::default()
    }
}

fn parse(nodes: &[u8], pairs: &[u8]) -> Result<Dataset, InputError> {
    BorderList.parse(
        &Inputs::new().with("nodes", nodes).with("pairs", pairs),
        &options(),
    )
}

/// For the small hand-written tables: default columns.
fn parse_plain(nodes: &[u8], pairs: &[u8]) -> Result<Dataset, InputError> {
    BorderList.parse(
        &Inputs::new().with("nodes", nodes).with("pairs", pairs),
        &FormatOptions::default(),
    )
}

fn neighbors(dataset: &Dataset, id: &str) -> Vec<String> {
    let node = dataset.node(dataset.find(id).expect("id"));
    let mut ids: Vec<String> = node
        .relations
        .iter()
        .map(|&i| dataset.node(i).id.clone())
        .collect();
    ids.sort();
    ids
}

#[test]
fn countries_and_borders() {
    let dataset = parse(COUNTRIES, BORDERS).expect("valid");
    assert_eq!(dataset.len(), 36);
    assert_eq!(dataset.leaves().count(), 31);
    assert_eq!(
        dataset.similarity_hint(),
        Some(SimilarityHint::NeighborList)
    );
    let total: usize = dataset.nodes().iter().map(|n| n.relations.len()).sum();
    assert_eq!(total, 2 * 48, "each border on both countries");
    assert_eq!(
        neighbors(&dataset, "DE"),
        ["AT", "BE", "CH", "CZ", "FR", "NL", "PL"]
    );
    assert_eq!(
        neighbors(&dataset, "CN"),
        ["IN", "KZ", "LA", "MM", "MN", "NP", "PK", "RU", "VN"]
    );
    assert_eq!(neighbors(&dataset, "PT"), ["ES"]);
    assert_eq!(neighbors(&dataset, "MX"), ["US"]);
    // Symmetric: every relation has its reverse.
    for (i, node) in dataset.nodes().iter().enumerate() {
        for &j in &node.relations {
            assert!(
                dataset.node(j).relations.contains(&i),
                "{} -> {}",
                node.id,
                dataset.node(j).id
            );
        }
    }
}

#[test]
fn registered_by_name() {
    let format = registry::find("border-list").expect("registered");
    let roles: Vec<&str> = format.roles().iter().map(|r| r.name).collect();
    assert_eq!(roles, ["nodes", "pairs"]);
    assert!(format.roles().iter().all(|r| r.required));
}

#[test]
fn bom_and_crlf_read_like_plain() {
    let plain = parse(COUNTRIES, BORDERS).expect("plain");
    let dos = |bytes: &[u8]| {
        let mut out = b"\xEF\xBB\xBF".to_vec();
        out.extend(String::from_utf8_lossy(bytes).replace('\n', "\r\n").bytes());
        out
    };
    assert_eq!(parse(&dos(COUNTRIES), &dos(BORDERS)).expect("dos"), plain);
}

#[test]
fn strength_self_pairs_and_repeats() {
    let nodes = b"id\nx\ny\nz\n";
    let pairs = b"from,to,strength\nx,y,2.5\ny,x,1\nx,x,1\ny,z,0\n";
    let dataset = parse_plain(nodes, pairs).expect("valid");
    assert_eq!(neighbors(&dataset, "x"), ["y"]);
    assert_eq!(neighbors(&dataset, "y"), ["x"], "strength 0 drops y,z");
    assert!(neighbors(&dataset, "z").is_empty());
}

#[test]
fn unknown_id_in_pairs() {
    let pairs = b"a,b\nDE,FR\nCN,AF\n";
    let error = parse(COUNTRIES, pairs).expect_err("unknown id");
    assert_eq!(error.role, "pairs");
    assert!(
        matches!(
            error.error,
            FormatError::Field {
                line: Some(3),
                column: Some(2),
                ..
            }
        ),
        "{error:?}"
    );
    let text = error.to_string();
    assert!(
        text.starts_with("pairs: line 3, column 2: field \"b\""),
        "{text}"
    );
    assert!(text.contains("unknown id \"AF\""), "{text}");
}

#[test]
fn bad_strength() {
    let error = parse_plain(b"id\nx\ny\n", b"a,b,strength\nx,y,-1\n").expect_err("negative");
    let text = error.to_string();
    assert!(
        text.starts_with("pairs: line 2, column 3: field \"strength\""),
        "{text}"
    );
    assert!(text.contains("found \"-1\""), "{text}");
}

#[test]
fn wrong_column_count_in_pairs() {
    let error = parse(COUNTRIES, b"a,b\nDE,FR\nDE\n").expect_err("short row");
    assert_eq!(error.role, "pairs");
    assert_eq!(error.error.line(), Some(3));
    assert!(error
        .to_string()
        .contains("found 1, the header (line 1) has 2"));
}

#[test]
fn errors_in_the_node_table_name_the_nodes_role() {
    let nodes =
        b"id,label,population,continent\nDE,Germany,84000000,Europe\nFR,France,lots,Europe\n";
    let error = parse(nodes, b"a,b\nDE,FR\n").expect_err("bad weight");
    assert_eq!(error.role, "nodes");
    let text = error.to_string();
    assert!(
        text.starts_with("nodes: line 3, column 3: node \"FR\": field \"population\""),
        "{text}"
    );
    assert!(text.contains("\"lots\""), "{text}");
    let error = parse(b"", b"a,b\n").expect_err("empty nodes");
    assert_eq!(error.role, "nodes");
    assert!(error.to_string().contains("line 1"));
    let error = parse(COUNTRIES, b"").expect_err("empty pairs");
    assert_eq!(error.role, "pairs");
    assert!(error.to_string().contains("the input is empty"));
}

#[test]
fn missing_input() {
    let error = BorderList
        .parse(&Inputs::new().with("nodes", COUNTRIES), &options())
        .expect_err("no pairs");
    assert_eq!(error.role, "pairs");
    assert!(error.to_string().contains("required"));
}

#[test]
fn binary_pairs_are_an_error() {
    let mut state: u32 = 12345;
    let blob: Vec<u8> = (0..200 * 1024)
        .map(|_| {
            state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
            (state >> 16) as u8
        })
        .collect();
    let error = parse(COUNTRIES, &blob).expect_err("binary");
    assert_eq!(error.role, "pairs");
    assert!(error.error.line().is_some(), "{error}");
}

/// By default a pair naming no node is skipped with a warning naming the
/// line and id (a node removed while `watch` runs), and the rest is read.
#[test]
fn unknown_ids_are_skipped_with_a_warning_by_default() {
    let nodes = b"id\nx\ny\nz\n";
    let pairs = b"a,b\nx,y\ny,gone\n";
    let dataset = parse_plain(nodes, pairs).expect("the known pairs are read");
    assert_eq!(neighbors(&dataset, "x"), ["y"]);
    assert_eq!(neighbors(&dataset, "y"), ["x"]);
    let warned: Vec<String> = dataset.warnings().iter().map(|w| w.to_string()).collect();
    assert!(
        warned
            .iter()
            .any(|w| w.starts_with("line 3: unknown id \"gone\"") && w.contains("skipped")),
        "{warned:?}"
    );
}
