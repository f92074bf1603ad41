//! Tests for CSV/TSV reading and node tables: hierarchy from grouping columns, a path
//! column and a parent column; BOM and CRLF; and every malformed table case with its
//! position.
//!
//! `data/countries.csv` holds 31 real countries (2023 populations, rounded) on four
//! continents; the expected counts below were counted by hand from the file.

use nptreemap_formats::node_table::tree_from_table;
use nptreemap_formats::table::{read_rows, read_table};
use nptreemap_formats::{Dataset, FormatError, FormatOptions};

const COUNTRIES: &[u8] = include_bytes!("data/countries.csv");
const REGIONS: &[u8] = include_bytes!("data/regions_path.csv");
const ORG: &[u8] = include_bytes!("data/org_parent.csv");

fn dataset(bytes: &[u8], options: &FormatOptions) -> Result<Dataset, FormatError> {
    let table = read_table(bytes, options.delimiter)?;
    tree_from_table(&table, options)?.build(None)
}

fn countries_options() -> FormatOptions {
    FormatOptions {
        weight: Some("population".into()),
        groups: vec!["continent".into()],
        ..FormatOptions::default()
    }
}

fn ids(dataset: &Dataset, indices: &[usize]) -> Vec<String> {
    indices
        .iter()
        .map(|&i| dataset.node(i).id.clone())
        .collect()
}

#[test]
fn grouping_column_gives_continents() {
    let dataset = dataset(COUNTRIES, &countries_options()).expect("valid");
    // root + 4 continents + 31 countries
    assert_eq!(dataset.len(), 36);
    assert_eq!(dataset.leaves().count(), 31);
    assert_eq!(dataset.max_depth(), 2);
    let root = dataset.node(0);
    assert_eq!(root.id, "root");
    assert_eq!(
        ids(&dataset, &root.children),
        [
            "group:Europe",
            "group:Asia",
            "group:Africa",
            "group:North America"
        ]
    );
    let europe = dataset.node(root.children[0]);
    assert_eq!(europe.label, "Europe");
    assert_eq!(europe.children.len(), 12);
    let asia = dataset.node(root.children[1]);
    assert_eq!(asia.children.len(), 11);
    let cn = dataset.node(dataset.find("CN").expect("CN"));
    assert_eq!(cn.label, "China");
    assert_eq!(cn.weight, Some(1_411_000_000.0));
    assert_eq!(cn.parent, Some(root.children[1]));
    let north_america = dataset.node(root.children[3]);
    assert_eq!(north_america.value, 335e6 + 40e6 + 128e6);
}

#[test]
fn nested_groups() {
    let csv = b"id,continent,region,weight\nFR,Europe,Western,1\nDE,Europe,Western,2\nIT,Europe,Southern,3\nCN,Asia,Eastern,4\n";
    let options = FormatOptions {
        groups: vec!["continent".into(), "region".into()],
        ..FormatOptions::default()
    };
    let dataset = dataset(csv, &options).expect("valid");
    assert_eq!(dataset.len(), 1 + 2 + 3 + 4);
    let western = dataset.find("group:Europe/Western").expect("nested group");
    assert_eq!(dataset.node(western).label, "Western");
    assert_eq!(ids(&dataset, &dataset.node(western).children), ["FR", "DE"]);
    assert_eq!(dataset.node(western).value, 3.0);
    assert_eq!(dataset.max_depth(), 3);
}

#[test]
fn path_column_creates_intermediate_nodes() {
    let options = FormatOptions {
        path: Some("path".into()),
        weight: Some("population".into()),
        root_label: Some("World".into()),
        ..FormatOptions::default()
    };
    let dataset = dataset(REGIONS, &options).expect("valid");
    // root; Europe, Asia, Africa; Western, Southern, Eastern, Southern(Asia); 6 rows
    assert_eq!(dataset.len(), 1 + 3 + 4 + 6);
    assert_eq!(dataset.leaves().count(), 6);
    assert_eq!(dataset.node(0).label, "World");
    let france = dataset
        .find("Europe/Western/France")
        .expect("row id = path");
    assert_eq!(dataset.node(france).label, "France");
    assert_eq!(dataset.node(france).depth, 3);
    let parent = dataset.node(france).parent.expect("parent");
    assert_eq!(dataset.node(parent).id, "group:Europe/Western");
    // Nigeria's path is shorter: its node sits at depth 2.
    let nigeria = dataset.find("Africa/Nigeria").expect("nigeria");
    assert_eq!(dataset.node(nigeria).depth, 2);
    assert!(dataset.find("group:Asia/Southern").is_some());
}

#[test]
fn path_column_with_id_column_puts_rows_under_the_whole_path() {
    let csv = b"id,path\nFR,Europe/Western\nCN,Asia\n";
    let options = FormatOptions {
        path: Some("path".into()),
        ..FormatOptions::default()
    };
    let dataset = dataset(csv, &options).expect("valid");
    let fr = dataset.find("FR").expect("FR");
    assert_eq!(dataset.node(fr).depth, 3);
    assert_eq!(dataset.node(fr).weight, Some(1.0), "no weight column: 1");
}

#[test]
fn parent_column_with_a_single_root_row() {
    let options = FormatOptions {
        parent: Some("parent".into()),
        ..FormatOptions::default()
    };
    let dataset = dataset(ORG, &options).expect("valid");
    assert_eq!(dataset.len(), 6);
    assert_eq!(dataset.node(0).id, "ceo");
    assert_eq!(ids(&dataset, &dataset.node(0).children), ["cto", "cfo"]);
    assert_eq!(dataset.leaves().count(), 3);
    let cto = dataset.find("cto").expect("cto");
    assert_eq!(ids(&dataset, &dataset.node(cto).children), ["dev1", "dev2"]);
    // Own weights of internal rows count too (d3's hierarchy.sum).
    assert_eq!(dataset.node(0).value, 1.0 + 1.0 + 1.0 + 3.0 + 2.0 + 4.0);
}

#[test]
fn parent_column_with_several_top_rows_gets_a_synthetic_root() {
    let csv = b"id,parent\na,\nb,\nc,a\n";
    let options = FormatOptions {
        parent: Some("parent".into()),
        ..FormatOptions::default()
    };
    let dataset = dataset(csv, &options).expect("valid");
    assert_eq!(dataset.node(0).id, "root");
    assert_eq!(ids(&dataset, &dataset.node(0).children), ["a", "b"]);
}

#[test]
fn flat_table_and_missing_weight_column() {
    let csv = b"id,name\nx,Ex\ny,Why\n";
    let dataset = dataset(csv, &FormatOptions::default()).expect("valid");
    assert_eq!(dataset.len(), 3);
    assert_eq!(dataset.node(1).label, "Ex", "name column is the label");
    assert_eq!(dataset.node(0).value, 2.0, "every row weighs 1");
}

#[test]
fn bom_and_crlf_read_like_plain() {
    let plain = dataset(COUNTRIES, &countries_options()).expect("plain");
    let crlf: Vec<u8> = String::from_utf8_lossy(COUNTRIES)
        .replace('\n', "\r\n")
        .into_bytes();
    let mut bom_crlf = b"\xEF\xBB\xBF".to_vec();
    bom_crlf.extend_from_slice(&crlf);
    assert_eq!(dataset(&crlf, &countries_options()).expect("crlf"), plain);
    assert_eq!(
        dataset(&bom_crlf, &countries_options()).expect("bom crlf"),
        plain
    );
}

#[test]
fn tsv_is_detected() {
    let tsv = b"id\tweight\na\t2\nb\t3\n";
    let dataset = dataset(tsv, &FormatOptions::default()).expect("tsv");
    assert_eq!(dataset.node(0).value, 5.0);
}

#[test]
fn quoted_fields_are_read() {
    let csv = b"id,label\nUS,\"United States, the\"\nX,\"say \"\"hi\"\"\"\n";
    let dataset = dataset(csv, &FormatOptions::default()).expect("valid");
    assert_eq!(dataset.node(1).label, "United States, the");
    assert_eq!(dataset.node(2).label, "say \"hi\"");
}

fn error_text(bytes: &[u8], options: &FormatOptions) -> (FormatError, String) {
    let error = dataset(bytes, options).expect_err("must fail");
    let text = error.to_string();
    (error, text)
}

#[test]
fn unterminated_quote() {
    let (error, text) = error_text(b"id,label\na,A\nb,\"B\nc,C\n", &FormatOptions::default());
    assert!(
        matches!(
            error,
            FormatError::Syntax {
                line: 3,
                column: 2,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(text.contains("never closed"), "{text}");
}

#[test]
fn stray_quotes() {
    let (error, text) = error_text(b"id,label\na,A\"x\n", &FormatOptions::default());
    assert!(
        matches!(
            error,
            FormatError::Syntax {
                line: 2,
                column: 2,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(text.contains("bad quoting"), "{text}");
    let (error, text) = error_text(b"id,label\na,\"A\"x\n", &FormatOptions::default());
    assert!(
        matches!(
            error,
            FormatError::Syntax {
                line: 2,
                column: 2,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(text.contains("after the closing quote"), "{text}");
}

#[test]
fn wrong_column_count() {
    let (error, text) = error_text(b"id,weight\na,1\nb,2,3\n", &FormatOptions::default());
    assert_eq!(error.line(), Some(3));
    assert!(
        text.contains("found 3, the header (line 1) has 2"),
        "{text}"
    );
}

#[test]
fn bad_weights() {
    for (value, needle) in [
        ("lots", "expected a number, found \"lots\""),
        ("-5", "finite number >= 0, found \"-5\""),
        ("NaN", "finite number >= 0, found \"NaN\""),
        ("inf", "finite number >= 0, found \"inf\""),
    ] {
        let csv = format!("id,weight\na,1\nb,{value}\n");
        let (error, text) = error_text(csv.as_bytes(), &FormatOptions::default());
        assert!(
            matches!(&error, FormatError::Field { line: Some(3), column: Some(2), node: Some(n), field, .. } if n == "b" && field == "weight"),
            "{error:?}"
        );
        assert!(text.contains(needle), "{text}");
        assert!(
            text.starts_with("line 3, column 2: node \"b\": field \"weight\""),
            "{text}"
        );
    }
}

#[test]
fn duplicate_id_names_the_second_line() {
    let (error, text) = error_text(b"id\na\nb\na\n", &FormatOptions::default());
    assert_eq!(error.line(), Some(4));
    assert!(
        text.contains("duplicate id \"a\": already used by line 2"),
        "{text}"
    );
}

#[test]
fn cycle_in_parent_column() {
    let csv = b"id,parent\nr,\na,r\nb,c\nc,b\n";
    let options = FormatOptions {
        parent: Some("parent".into()),
        ..FormatOptions::default()
    };
    let (error, text) = error_text(csv, &options);
    assert_eq!(error.line(), Some(4), "{text}");
    assert!(
        text.contains("node \"b\": the parent column forms a cycle: b -> c -> b"),
        "{text}"
    );
}

#[test]
fn unknown_parent() {
    let csv = b"id,parent\nr,\na,zz\n";
    let options = FormatOptions {
        parent: Some("parent".into()),
        ..FormatOptions::default()
    };
    let (error, text) = error_text(csv, &options);
    assert_eq!(error.line(), Some(3));
    assert!(text.contains("parent \"zz\" does not exist"), "{text}");
}

#[test]
fn empty_inputs() {
    for bytes in [&b""[..], b"\xEF\xBB\xBF", b"\r\n\n  \n"] {
        let (error, text) = error_text(bytes, &FormatOptions::default());
        assert_eq!(error.line(), Some(1));
        assert!(text.contains("the input is empty"), "{text}");
    }
}

#[test]
fn missing_columns_are_named() {
    let (error, text) = error_text(
        COUNTRIES,
        &FormatOptions {
            weight: Some("pop".into()),
            ..FormatOptions::default()
        },
    );
    assert_eq!(error.line(), Some(1));
    assert!(
        text.contains("no column \"pop\" (the weight column)"),
        "{text}"
    );
    let (_, text) = error_text(b"name\nx\n", &FormatOptions::default());
    assert!(text.contains("no column \"id\""), "{text}");
}

#[test]
fn invalid_utf8_is_a_syntax_error() {
    let (error, text) = error_text(b"id,label\na,\xff\xfe\n", &FormatOptions::default());
    assert!(
        matches!(
            error,
            FormatError::Syntax {
                line: 2,
                column: 2,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(text.contains("not valid UTF-8"), "{text}");
}

/// A 200 KB xorshift blob: an error, never a panic.
#[test]
fn binary_blob_is_an_error() {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let blob: Vec<u8> = (0..200 * 1024)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 24) as u8
        })
        .collect();
    let (error, text) = error_text(&blob, &FormatOptions::default());
    assert!(matches!(error, FormatError::Syntax { .. }), "{error:?}");
    assert!(error.line().is_some());
    assert!(
        text.contains("binary data") || text.contains("UTF-8") || text.contains("quot"),
        "{text}"
    );
    // Rows alone, too.
    assert!(read_rows(&blob, None).is_err());
}

#[test]
fn positions_survive_bom_crlf_and_quoted_newlines() {
    for csv in [
        &b"id,label,weight\na,\"two\nlines\",1\nb,B,x\n"[..],
        b"\xEF\xBB\xBFid,label,weight\r\na,\"two\r\nlines\",1\r\n\r\nb,B,x\r\n",
    ] {
        let (error, text) = error_text(csv, &FormatOptions::default());
        let expected = if csv.starts_with(b"\xEF") { 5 } else { 4 };
        assert_eq!(
            (error.line(), error.column()),
            (Some(expected), Some(3)),
            "{text}"
        );
        assert!(text.contains("node \"b\""), "{text}");
    }
    let tsv = b"id\tlabel\r\na\t\"A\r\nb\tB\r\n";
    let (error, _) = error_text(tsv, &FormatOptions::default());
    assert_eq!((error.line(), error.column()), (Some(2), Some(2)));
}

/// With no delimiter given, the header decides: a comma wins (a `|` inside
/// cells is a genre list), else tab, `;` (spreadsheets in many locales) or `|`.
#[test]
fn the_delimiter_is_sniffed_from_the_header() {
    use nptreemap_formats::table::detect_delimiter;
    for (text, d) in [
        ("id,name\na,b\n", b','),
        ("id\tname\na\tb\n", b'\t'),
        ("id;name;weight\na;A;1,5\n", b';'),
        ("id|name\na|b\n", b'|'),
        ("id\n", b','),
        ("id,genres\na,Drama|Crime\n", b','),
    ] {
        assert_eq!(detect_delimiter(text.as_bytes(), None), d, "{text:?}");
    }
    assert_eq!(detect_delimiter(b"id;name", Some(b',')), b',');
    let t = read_table(b"id;name;population\nfr;France;68\n", None).expect("semicolons");
    assert_eq!(t.header, ["id", "name", "population"]);
    assert_eq!(t.rows[0].fields, ["fr", "France", "68"]);
}

/// Issue 21, item 8: a row whose id is the id a grouping value generates
/// (`group:Asia`) took the group's place when listed first (China and India
/// were drawn inside Europe, no error) and, listed after, was reported as a
/// duplicate of China's line. Both orders are an error at the row with the id,
/// naming the line of the group's first row.
#[test]
fn a_row_id_that_is_a_generated_group_id_is_an_error_in_either_order() {
    let options = FormatOptions {
        weight: Some("weight".into()),
        groups: vec!["continent".into()],
        ..FormatOptions::default()
    };
    let before = b"id,continent,weight\nFrance,Europe,67\ngroup:Asia,Europe,10\n\
                   China,Asia,1400\nIndia,Asia,1380\n";
    let after = b"id,continent,weight\nFrance,Europe,67\nChina,Asia,1400\n\
                  India,Asia,1380\ngroup:Asia,Europe,10\n";
    for (bytes, row_line, group_line) in [(&before[..], 3, 4), (&after[..], 5, 3)] {
        let (error, text) = error_text(bytes, &options);
        assert_eq!(error.line(), Some(row_line), "{text}");
        assert!(
            text.contains(&format!(
                "node \"group:Asia\": field \"id\": the id of the group \"Asia\" generated \
                 from line {group_line}"
            )),
            "{text}"
        );
    }
    // The same through a path column: the row `group:Asia` (a path of one
    // segment) and the group of `Asia/China`.
    let path = FormatOptions {
        path: Some("path".into()),
        ..FormatOptions::default()
    };
    let (error, text) = error_text(b"path\ngroup:Asia\nAsia/China\n", &path);
    assert_eq!(error.line(), Some(2), "{text}");
    assert!(text.contains("from line 3"), "{text}");
    // Ids that only look alike are fine: `group:asia` is not `group:Asia`.
    let fine = b"id,continent,weight\ngroup:asia,Europe,10\nChina,Asia,1400\n";
    assert_eq!(dataset(fine, &options).expect("distinct ids").len(), 5);
}
