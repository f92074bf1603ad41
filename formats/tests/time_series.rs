//! Tests for the time-series format: 12 US stocks in four sectors (`data/stocks.csv`,
//! market capitalisation in $bn as weight) with 30 trading days of closing prices
//! (`data/stock_prices.csv`, 2024-06-03 to 2024-07-15 without the market holidays).
//! The prices are made up, not real quotes: a random walk with a market and a sector
//! factor from plausible starting prices, so that stocks of a sector correlate.
//! Plus malformed series with their positions.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use nptreemap_formats::registry;
use nptreemap_formats::{
    Dataset, Format, FormatError, FormatOptions, InputError, Inputs, OnUnknownId, SimilarityHint,
    TimeSeries,
};

const STOCKS: &[u8] = include_bytes!("data/stocks.csv");
const PRICES: &[u8] = include_bytes!("data/stock_prices.csv");

/// The fixtures' mapping; unknown ids are errors, so the tests of those
/// errors see them (the default skips them with a warning, tested apart).
fn options() -> FormatOptions {
    FormatOptions {
        on_unknown_id: OnUnknownId::Error,
        weight: Some("market_cap".into()),
        groups: vec!["sector".into()],
        ..FormatOptions::default()
    }
}

fn parse_with(nodes: &[u8], series: &[u8], options: &FormatOptions) -> Result<Dataset, InputError> {
    TimeSeries.parse(
        &Inputs::new().with("nodes", nodes).with("series", series),
        options,
    )
}

fn parse(series: &[u8]) -> Result<Dataset, InputError> {
    parse_with(STOCKS, series, &options())
}

fn filled(series: &[u8]) -> Result<Dataset, InputError> {
    let options = FormatOptions {
        fill_missing: true,
        ..options()
    };
    parse_with(STOCKS, series, &options)
}

fn prices_text() -> &'static str {
    std::str::from_utf8(PRICES).expect("utf8")
}

/// The prices with one line replaced (1-based line number).
fn with_line(line: usize, text: &str) -> Vec<u8> {
    let mut lines: Vec<&str> = prices_text().lines().collect();
    lines[line - 1] = text;
    (lines.join("\n") + "\n").into_bytes()
}

/// The prices with one cell (1-based line and column) replaced.
fn with_cell(line: usize, column: usize, text: &str) -> Vec<u8> {
    set_cell(PRICES, line, column, text)
}

/// `bytes` (comma-separated) with one cell (1-based line and column) replaced.
fn set_cell(bytes: &[u8], line: usize, column: usize, text: &str) -> Vec<u8> {
    let lines: Vec<String> = std::str::from_utf8(bytes)
        .expect("utf8")
        .lines()
        .enumerate()
        .map(|(n, l)| {
            let mut fields: Vec<&str> = l.split(',').collect();
            if n + 1 == line {
                fields[column - 1] = text;
            }
            fields.join(",")
        })
        .collect();
    (lines.join("\n") + "\n").into_bytes()
}

/// The first `count` lines of the prices (the header included).
fn first_lines(count: usize) -> Vec<u8> {
    let lines: Vec<&str> = prices_text().lines().take(count).collect();
    (lines.join("\n") + "\n").into_bytes()
}

/// The column of `id` in the prices file, read independently of the crate.
fn column_of(id: &str) -> Vec<f64> {
    let mut lines = prices_text().lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let column = header.iter().position(|&h| h == id).expect("id in header");
    lines
        .map(|l| {
            l.split(',')
                .nth(column)
                .expect("cell")
                .parse()
                .expect("number")
        })
        .collect()
}

fn failure(series: &[u8]) -> (InputError, String) {
    let error = parse(series).expect_err("must fail");
    let text = error.to_string();
    (error, text)
}

fn features(dataset: &Dataset, id: &str) -> Vec<f64> {
    let index = dataset.find(id).unwrap_or_else(|| panic!("no node {id}"));
    dataset
        .node(index)
        .features
        .as_ref()
        .and_then(|f| f.as_dense())
        .expect("a dense series")
        .to_vec()
}

#[test]
fn stocks_by_sector() {
    let dataset = parse(PRICES).expect("valid");
    assert_eq!(dataset.len(), 1 + 4 + 12);
    assert_eq!(dataset.leaves().count(), 12);
    assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Pearson));
    let tech = dataset.node(dataset.find("group:Technology").expect("tech"));
    assert_eq!(tech.children.len(), 4);
    assert_eq!(tech.value, 3000.0 + 3100.0 + 2900.0 + 2100.0);
    assert_eq!(tech.features, None, "groups get no series");
    let energy = dataset.node(dataset.find("group:Energy").expect("energy"));
    let energy_ids: Vec<&str> = energy
        .children
        .iter()
        .map(|&c| dataset.node(c).id.as_str())
        .collect();
    assert_eq!(energy_ids, ["XOM", "CVX", "COP"]);
    for leaf in dataset.leaves() {
        let node = dataset.node(leaf);
        assert_eq!(
            node.features.as_ref().map(|f| f.len()),
            Some(30),
            "{}",
            node.id
        );
        assert_eq!(features(&dataset, &node.id), column_of(&node.id));
    }
    let apple = features(&dataset, "AAPL");
    assert_eq!((apple[0], apple[29]), (191.0, 192.84));
    assert_eq!(features(&dataset, "BAC")[0], 39.6);
    let jnj = dataset.node(dataset.find("JNJ").expect("jnj"));
    assert_eq!(jnj.label, "Johnson & Johnson");
    assert_eq!(jnj.weight, Some(380.0));
    assert_eq!(
        registry::find("time-series").map(|f| f.roles().len()),
        Some(2)
    );
}

#[test]
fn bom_crlf_and_tabs_read_like_plain() {
    let plain = parse(PRICES).expect("plain");
    let dos = |bytes: &[u8]| {
        let mut out = b"\xEF\xBB\xBF".to_vec();
        out.extend(String::from_utf8_lossy(bytes).replace('\n', "\r\n").bytes());
        out
    };
    assert_eq!(
        parse_with(&dos(STOCKS), &dos(PRICES), &options()).expect("dos"),
        plain
    );
    let tabs = prices_text().replace(',', "\t");
    assert_eq!(parse(tabs.as_bytes()).expect("tsv"), plain);
    // Positions still count lines after a BOM and CRLF.
    let (error, _) = failure(&dos(&with_cell(9, 4, "n/a")));
    assert_eq!(
        (error.error.line(), error.error.column()),
        (Some(9), Some(4))
    );
}

#[test]
fn unknown_id_in_the_header() {
    let header = prices_text()
        .lines()
        .next()
        .expect("header")
        .replace("GOOGL", "GOOG");
    let (error, text) = failure(&with_line(1, &header));
    assert_eq!(error.role, "series");
    assert!(
        matches!(&error.error, FormatError::Field { line: Some(1), column: Some(5), field, .. } if field == "GOOG"),
        "{error:?}"
    );
    assert!(
        text.starts_with("series: line 1, column 5: field \"GOOG\": unknown id \"GOOG\""),
        "{text}"
    );
}

#[test]
fn repeated_id_in_the_header() {
    let header = prices_text()
        .lines()
        .next()
        .expect("header")
        .replace("PFE", "JNJ");
    let (error, text) = failure(&with_line(1, &header));
    assert_eq!(
        (error.error.line(), error.error.column()),
        (Some(1), Some(10))
    );
    assert!(
        text.contains("id \"JNJ\" has a second column (the first is column 9)"),
        "{text}"
    );
}

#[test]
fn leaf_without_a_column() {
    // Drop the last column (BAC) from every line.
    let without: String = prices_text()
        .lines()
        .map(|l| l.rsplit_once(',').expect("comma").0.to_owned() + "\n")
        .collect();
    let (error, text) = failure(without.as_bytes());
    assert_eq!(error.role, "series");
    assert!(
        text.contains("node \"BAC\" (nodes line 13) has no column"),
        "{text}"
    );
}

#[test]
fn non_numeric_value() {
    let (error, text) = failure(&with_cell(7, 6, "12O.5"));
    assert_eq!(error.role, "series");
    assert!(
        matches!(&error.error, FormatError::Field { line: Some(7), column: Some(6), node: Some(n), .. } if n == "XOM"),
        "{error:?}"
    );
    assert!(
        text.starts_with("series: line 7, column 6: node \"XOM\""),
        "{text}"
    );
    assert!(
        text.contains("date \"2024-06-10\", found \"12O.5\""),
        "{text}"
    );
    let (_, text) = failure(&with_cell(3, 2, "inf"));
    assert!(text.contains("expected a finite number"), "{text}");
}

#[test]
fn missing_value_is_an_error_unless_filled() {
    let gap = with_cell(5, 13, "");
    let (error, text) = failure(&gap);
    assert_eq!(
        (error.error.line(), error.error.column()),
        (Some(5), Some(13))
    );
    assert!(
        text.contains("node \"BAC\"") && text.contains("missing value for date \"2024-06-06\""),
        "{text}"
    );
    assert!(text.contains("fill_missing"), "{text}");

    let dataset = filled(&gap).expect("filled");
    let bac = features(&dataset, "BAC");
    let original = column_of("BAC");
    // Line 5 is the 4th date: it takes the 3rd date's value.
    assert_eq!(bac[3], original[2]);
    assert_eq!(bac[4..], original[4..]);

    // Leading gaps take the first value given: dates 1 and 2 of AAPL are missing.
    let leading = set_cell(&with_cell(2, 2, ""), 3, 2, "");
    let dataset = filled(&leading).expect("filled");
    let apple = features(&dataset, "AAPL");
    let original = column_of("AAPL");
    assert_eq!(apple[..3], [original[2], original[2], original[2]]);
    assert_eq!(apple[2..], original[2..]);
}

#[test]
fn a_column_without_values_is_an_error_even_when_filled() {
    let empty: String = prices_text()
        .lines()
        .enumerate()
        .map(|(n, l)| {
            let mut fields: Vec<&str> = l.split(',').collect();
            if n > 0 {
                fields[8] = "";
            }
            fields.join(",") + "\n"
        })
        .collect();
    let error = filled(empty.as_bytes()).expect_err("no values");
    assert_eq!(
        (error.error.line(), error.error.column()),
        (Some(1), Some(9))
    );
    assert!(
        error
            .to_string()
            .contains("id \"JNJ\" has no value on any date"),
        "{error}"
    );
}

#[test]
fn fewer_than_three_dates() {
    let (error, text) = failure(&first_lines(3));
    assert_eq!(error.role, "series");
    assert_eq!(error.error.line(), Some(3));
    assert!(
        text.contains("2 date(s); a correlation needs at least 3"),
        "{text}"
    );
    let (_, text) = failure(&first_lines(1));
    assert!(text.contains("0 date(s)"), "{text}");
    let dataset = parse(&first_lines(4)).expect("3 dates are enough");
    assert_eq!(features(&dataset, "MSFT").len(), 3);
}

#[test]
fn constant_series_is_allowed() {
    let constant: String = prices_text()
        .lines()
        .enumerate()
        .map(|(n, l)| {
            let mut fields: Vec<&str> = l.split(',').collect();
            if n > 0 {
                fields[9] = "28.50";
            }
            fields.join(",") + "\n"
        })
        .collect();
    let dataset = parse(constant.as_bytes()).expect("constant is fine");
    assert!(features(&dataset, "PFE").iter().all(|&v| v == 28.5));
}

#[test]
fn malformed_tables() {
    let (error, text) = failure(&with_line(12, "2024-06-17,181.2,410.0"));
    assert_eq!(error.error.line(), Some(12));
    assert!(text.contains("wrong number of fields"), "{text}");
    let (error, text) = failure(b"date\n2024-06-03\n2024-06-04\n2024-06-05\n");
    assert_eq!(error.error.line(), Some(1));
    assert!(text.contains("at least one id column"), "{text}");
    let (error, text) = failure(b"");
    assert_eq!(error.role, "series");
    assert!(text.contains("empty"), "{text}");
    // Without the options the table is flat: still valid, 12 leaves under the root.
    let flat = parse_with(STOCKS, PRICES, &FormatOptions::default()).map(|d| d.len());
    assert_eq!(flat, Ok(13));
}

#[test]
fn hierarchy_from_a_path_column_and_node_errors() {
    let nodes = b"id,path\nAAPL,US/Technology\nXOM,US/Energy\nSAP,Europe/Technology\n";
    let series = b"day,SAP,AAPL,XOM\n1,120,190,110\n2,121,188,111\n3,119.5,189,109\n";
    let options = FormatOptions {
        path: Some("path".into()),
        ..FormatOptions::default()
    };
    let dataset = parse_with(nodes, series, &options).expect("valid");
    let ids: Vec<&str> = dataset.nodes().iter().map(|n| n.id.as_str()).collect();
    assert_eq!(
        ids,
        [
            "root",
            "group:US",
            "group:Europe",
            "group:US/Technology",
            "group:US/Energy",
            "group:Europe/Technology",
            "AAPL",
            "XOM",
            "SAP"
        ]
    );
    assert_eq!(features(&dataset, "SAP"), [120.0, 121.0, 119.5]);
    let bad_nodes = b"id,path\nAAPL,US/Technology\n,US/Energy\n";
    let error = parse_with(bad_nodes, series, &options).expect_err("empty id");
    assert_eq!(error.role, "nodes");
    assert_eq!(error.error.line(), Some(3));
}
