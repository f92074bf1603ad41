//! The malformed-input catalogue (issue 4): each case is a small config plus
//! data written to a temp folder, built with `nptreemap build`. Every case must
//! exit with code 2, name the file and the line (and column or field) and the
//! problem, and leave an existing output byte-identical. A UTF-8 BOM and CRLF
//! line ends are not errors.

use std::path::Path;

use crate::support;

const NODES: &str = "iso,name,population,continent\nAU,Australia,25,Oceania\nCN,China,1400,Asia\nIN,India,1400,Asia\nFR,France,68,Europe\nDE,Germany,84,Europe\n";
const PAIRS: &str = "a,b\nCN,IN\nFR,DE\n";
const VECTORS: &str = "id,v1,v2\nAU,1,0\nCN,0,1\nIN,0.2,0.9\nFR,0.7,0.3\nDE,0.6,0.4\n";

fn border_config(extra: &str) -> String {
    format!(
        "datasets:\n  - name: c\n    format: border-list\n    files: {{nodes: nodes.csv, pairs: pairs.csv}}\n    fields: {{id: iso, label: name, weight: population, groups: [continent]}}\n    outputs: [{{path: out.svg}}]\n{extra}"
    )
}

fn embedding_config() -> String {
    "datasets:\n  - name: e\n    format: embedding-matrix\n    files: {nodes: nodes.csv, vectors: vectors.csv}\n    fields: {id: iso, label: name, weight: population, groups: [continent]}\n    outputs: [{path: out.svg}]\n".to_string()
}

/// Writes the files, puts a previous `out.svg` in place, builds, and checks the
/// exit code, the message and that `out.svg` is untouched.
fn case(name: &str, files: &[(&str, Vec<u8>)], expect: &[&str]) {
    let dir = support::temp_dir(&format!("bad_{name}"));
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).expect("write case file");
    }
    let previous = b"<svg>previous picture</svg>".to_vec();
    std::fs::write(dir.join("out.svg"), &previous).expect("write previous output");
    let out = support::bin()
        .arg("build")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run nptreemap");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{name}: expected exit 2, stderr: {stderr}"
    );
    for needle in expect {
        assert!(
            stderr.contains(needle),
            "{name}: expected {needle:?} in: {stderr}"
        );
    }
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    assert_eq!(
        std::fs::read(dir.join("out.svg")).expect("output still there"),
        previous,
        "{name}: the existing output changed"
    );
}

fn text(s: &str) -> Vec<u8> {
    s.as_bytes().to_vec()
}

fn border(name: &str, nodes: &str, pairs: &str, expect: &[&str]) {
    case(
        name,
        &[
            ("nptreemap.yaml", text(&border_config(""))),
            ("nodes.csv", text(nodes)),
            ("pairs.csv", text(pairs)),
        ],
        expect,
    );
}

#[test]
fn bad_csv_quoting() {
    let nodes = NODES.replace("AU,Australia", "AU,\"Austr\"alia");
    border("quoting", &nodes, PAIRS, &["nodes.csv", "line 2"]);
}

#[test]
fn wrong_column_count() {
    let nodes = NODES.replace("CN,China,1400,Asia", "CN,China,1400,Asia,extra");
    border("columns", &nodes, PAIRS, &["nodes.csv", "line 3"]);
}

#[test]
fn unknown_id_in_pair_list() {
    border(
        "unknown_pair",
        NODES,
        "a,b\nCN,IN\nFR,XX\n",
        &["pairs.csv", "line 3", "XX"],
    );
}

#[test]
fn non_numeric_weight() {
    let nodes = NODES.replace("FR,France,68", "FR,France,many");
    border(
        "non_numeric",
        &nodes,
        PAIRS,
        &["nodes.csv", "line 5", "many"],
    );
}

#[test]
fn negative_weight() {
    let nodes = NODES.replace("DE,Germany,84", "DE,Germany,-84");
    border("negative", &nodes, PAIRS, &["nodes.csv", "line 6", "-84"]);
}

#[test]
fn nan_weight() {
    let nodes = NODES.replace("IN,India,1400", "IN,India,NaN");
    border("nan", &nodes, PAIRS, &["nodes.csv", "line 4", "NaN"]);
}

#[test]
fn duplicate_id() {
    let nodes = NODES.replace("IN,India", "CN,India");
    border("duplicate", &nodes, PAIRS, &["nodes.csv", "line 4", "CN"]);
}

#[test]
fn cycle_in_parent_column() {
    let config = "datasets:\n  - name: p\n    format: border-list\n    files: {nodes: nodes.csv, pairs: pairs.csv}\n    fields: {parent: parent}\n    outputs: [{path: out.svg}]\n";
    let nodes = "id,parent,weight\nroot,,1\na,c,1\nb,a,1\nc,b,1\n";
    case(
        "cycle",
        &[
            ("nptreemap.yaml", text(config)),
            ("nodes.csv", text(nodes)),
            ("pairs.csv", text("a,b\n")),
        ],
        &["nodes.csv", "line ", "cycle"],
    );
}

#[test]
fn missing_file() {
    case(
        "missing",
        &[
            ("nptreemap.yaml", text(&border_config(""))),
            ("nodes.csv", text(NODES)),
        ],
        &["pairs.csv", "cannot read"],
    );
}

#[test]
fn empty_file() {
    border("empty", "", PAIRS, &["nodes.csv", "line 1"]);
}

#[test]
fn embedding_rows_of_different_lengths() {
    let vectors = VECTORS.replace("CN,0,1", "CN,0,1,5");
    case(
        "ragged",
        &[
            ("nptreemap.yaml", text(&embedding_config())),
            ("nodes.csv", text(NODES)),
            ("vectors.csv", text(&vectors)),
        ],
        &["vectors.csv", "line 3"],
    );
}

#[test]
fn all_zero_embedding() {
    let vectors = VECTORS.replace("FR,0.7,0.3", "FR,0,0");
    case(
        "zero",
        &[
            ("nptreemap.yaml", text(&embedding_config())),
            ("nodes.csv", text(NODES)),
            ("vectors.csv", text(&vectors)),
        ],
        &["vectors.csv", "line 5", "zero"],
    );
}

#[test]
fn yaml_type_error() {
    case(
        "yaml_type",
        &[
            (
                "nptreemap.yaml",
                text(&format!("layout:\n  seed: many\n{}", border_config(""))),
            ),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nptreemap.yaml", "line 2", "seed"],
    );
}

#[test]
fn unknown_yaml_key() {
    case(
        "yaml_key",
        &[
            (
                "nptreemap.yaml",
                text(&format!("layout:\n  colour: red\n{}", border_config(""))),
            ),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nptreemap.yaml", "line 2", "colour"],
    );
}

#[test]
fn invalid_yaml_syntax() {
    case(
        "yaml_syntax",
        &[("nptreemap.yaml", text("datasets:\n  - name: [unclosed\n"))],
        &["nptreemap.yaml", "line "],
    );
}

#[test]
fn large_binary_file_that_is_not_csv() {
    // 2 MB of SplitMix64 noise: the reader must refuse it, not panic or hang.
    let mut rng = nptreemap::rng::Rng::new(42);
    let blob: Vec<u8> = (0..2_000_000)
        .map(|_| (rng.next_u64() >> 56) as u8)
        .collect();
    case(
        "binary",
        &[
            ("nptreemap.yaml", text(&border_config(""))),
            ("nodes.csv", blob),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nodes.csv", "line "],
    );
}

#[test]
fn unknown_format_name() {
    let config = border_config("").replace("border-list", "border-lists");
    case(
        "format",
        &[
            ("nptreemap.yaml", text(&config)),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["unknown format", "border-lists", "border-list"],
    );
}

#[test]
fn missing_input_role() {
    let config = border_config("").replace(", pairs: pairs.csv", "");
    case(
        "role_missing",
        &[
            ("nptreemap.yaml", text(&config)),
            ("nodes.csv", text(NODES)),
        ],
        &["needs", "pairs"],
    );
}

#[test]
fn unknown_input_role() {
    let config = border_config("").replace("pairs: pairs.csv", "pairs: pairs.csv, edges: x.csv");
    case(
        "role_unknown",
        &[
            ("nptreemap.yaml", text(&config)),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["edges", "reads no file"],
    );
}

#[test]
fn output_with_unknown_extension() {
    let config = border_config("").replace("out.svg", "out.bmp");
    case(
        "extension",
        &[
            ("nptreemap.yaml", text(&config)),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nptreemap.yaml", "outputs[0].path", "out.bmp"],
    );
}

#[test]
fn genre_one_hot_value_that_is_not_a_flag() {
    let config = "datasets:\n  - name: g\n    format: genre-table\n    files: {nodes: films.csv}\n    fields: {genre_columns: [drama, crime]}\n    outputs: [{path: out.svg}]\n";
    let films = "id,weight,drama,crime\na,1,1,0\nb,2,maybe,1\nc,3,0,1\n";
    case(
        "one_hot",
        &[("nptreemap.yaml", text(config)), ("films.csv", text(films))],
        &["films.csv", "line 3", "maybe"],
    );
}

#[test]
fn time_series_value_that_is_not_a_number() {
    let config = "datasets:\n  - name: t\n    format: time-series\n    files: {nodes: ids.csv, series: prices.csv}\n    outputs: [{path: out.svg}]\n";
    let prices = "date,a,b\nd1,1,2\nd2,2,x3\nd3,3,4\n";
    case(
        "series",
        &[
            ("nptreemap.yaml", text(config)),
            ("ids.csv", text("id,weight\na,1\nb,2\n")),
            ("prices.csv", text(prices)),
        ],
        &["prices.csv", "line 3", "x3"],
    );
}

#[test]
fn truncated_hierarchy_json() {
    let config = "datasets:\n  - name: h\n    format: hierarchy-json\n    files: {hierarchy: tree.json}\n    outputs: [{path: out.svg}]\n";
    case(
        "json",
        &[
            ("nptreemap.yaml", text(config)),
            (
                "tree.json",
                text("{\"id\": \"r\", \"children\": [\n  {\"id\": \"a\", \"weight\": 1},\n"),
            ),
        ],
        &["tree.json", "line 3"],
    );
}

#[test]
fn dataset_name_used_twice() {
    let one = border_config("");
    let twice = format!("{one}{}", &one["datasets:\n".len()..]);
    case(
        "twice",
        &[
            ("nptreemap.yaml", text(&twice)),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nptreemap.yaml", "used twice"],
    );
}

/// Not errors: a UTF-8 BOM and CRLF line ends give the same picture as plain LF.
#[test]
fn bom_and_crlf_are_read_like_plain_files() {
    let build = |tag: &str, nodes: Vec<u8>, pairs: Vec<u8>| {
        let dir = support::temp_dir(&format!("encoding_{tag}"));
        std::fs::write(dir.join("nptreemap.yaml"), border_config("")).expect("write");
        std::fs::write(dir.join("nodes.csv"), nodes).expect("write");
        std::fs::write(dir.join("pairs.csv"), pairs).expect("write");
        let out = support::bin()
            .arg("build")
            .arg(dir.join("nptreemap.yaml"))
            .output()
            .expect("run");
        assert!(
            out.status.success(),
            "{tag}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(Path::new(&dir).join("out.svg")).expect("svg")
    };
    let crlf = |s: &str| s.replace('\n', "\r\n").into_bytes();
    let bom = |mut v: Vec<u8>| {
        v.splice(0..0, [0xEF, 0xBB, 0xBF]);
        v
    };
    let plain = build("plain", text(NODES), text(PAIRS));
    let odd = build("bom_crlf", bom(crlf(NODES)), bom(crlf(PAIRS)));
    assert!(plain == odd, "BOM + CRLF input drew a different picture");
}
