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

/// With `on_unknown_id: error` (the default skips such a pair with a
/// warning; `build.rs` tests both).
#[test]
fn unknown_id_in_pair_list() {
    let config = border_config("").replace(
        "groups: [continent]}",
        "groups: [continent], on_unknown_id: error}",
    );
    case(
        "unknown_pair",
        &[
            ("nptreemap.yaml", text(&config)),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text("a,b\nCN,IN\nFR,XX\n")),
        ],
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

/// A config that names nothing to build (an empty file, as a save in place
/// leaves it for a moment, or `datasets: []`) was a build of nothing that
/// exited 0; in `watch` it made every dataset leave and come back.
#[test]
fn a_config_without_datasets() {
    for (tag, config) in [
        ("empty", ""),
        ("none", "datasets: []\n"),
        ("layout", "layout: {seed: 3}\n"),
    ] {
        case(
            &format!("no_datasets_{tag}"),
            &[("nptreemap.yaml", text(config))],
            &["nptreemap.yaml", "no datasets"],
        );
    }
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

/// Like [`case`], with a time bound: for inputs that used to hang.
fn case_within(name: &str, files: &[(&str, Vec<u8>)], expect: &[&str], secs: u64) -> String {
    let dir = support::temp_dir(&format!("bad_{name}"));
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).expect("write case file");
    }
    let previous = b"<svg>previous picture</svg>".to_vec();
    std::fs::write(dir.join("out.svg"), &previous).expect("write previous output");
    let out = support::output_within(
        support::bin().arg("build").arg(dir.join("nptreemap.yaml")),
        secs,
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{name}: stderr: {stderr}");
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
    stderr
}

/// Issue 11 item 4: a FIFO as an input is refused at once, by `build` and by
/// `check` (it used to block forever in the read).
#[test]
fn a_fifo_as_input_is_refused_not_read() {
    let dir = support::temp_dir("bad_fifo_input");
    std::fs::write(dir.join("nptreemap.yaml"), border_config("")).expect("config");
    std::fs::write(dir.join("nodes.csv"), NODES).expect("nodes");
    support::mkfifo(&dir.join("pairs.csv"));
    for command in ["build", "check"] {
        let out = support::output_within(
            support::bin().arg(command).arg(dir.join("nptreemap.yaml")),
            30,
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {stderr}");
        assert!(
            stderr.contains("pairs.csv") && stderr.contains("not a regular file"),
            "{command}: {stderr}"
        );
    }
    // A FIFO as the config itself.
    support::mkfifo(&dir.join("fifo.yaml"));
    let out = support::output_within(support::bin().arg("check").arg(dir.join("fifo.yaml")), 30);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("fifo.yaml") && stderr.contains("not a regular file"),
        "{stderr}"
    );
}

fn hierarchy_config() -> String {
    "datasets:\n  - name: h\n    format: hierarchy-json\n    files: {hierarchy: tree.json}\n    outputs: [{path: out.svg}]\n".to_string()
}

/// Issue 11 item 6: weights whose sum overflows are refused naming the node;
/// a huge weight beside a small one is laid out, not squashed to 50/50.
#[test]
fn weight_sums_must_be_finite() {
    case(
        "weight_overflow",
        &[
            ("nptreemap.yaml", text(&hierarchy_config())),
            (
                "tree.json",
                text(
                    r#"{"id": "r", "children": [{"id": "a", "value": 1e308}, {"id": "b", "value": 1e308}]}"#,
                ),
            ),
        ],
        &["tree.json", "node \"r\"", "finite"],
    );
    let dir = support::temp_dir("weights_huge_and_small");
    let input = dir.join("tree.json");
    std::fs::write(
        &input,
        r#"{"id": "r", "children": [{"id": "a", "value": 1e308}, {"id": "b", "value": 2}]}"#,
    )
    .expect("tree");
    let json = dir.join("out.json");
    support::layout(&input, &[&json], &[]);
    let report = support::check_layout(&json);
    support::assert_area_error(&report, 0.01);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parses");
    let root = &doc["nodes"][0];
    assert_eq!(
        root["weight"].as_f64(),
        Some(1e308),
        "the root's weight is the sum: {root}"
    );
}

/// Issue 11 item 6: feature vectors whose squares overflow are refused
/// naming the node (they gave no constraints at all).
#[test]
fn feature_values_that_overflow_are_refused() {
    let vectors = VECTORS.replace("FR,0.7,0.3", "FR,1e300,3e300");
    case(
        "feature_overflow",
        &[
            ("nptreemap.yaml", text(&embedding_config())),
            ("nodes.csv", text(NODES)),
            ("vectors.csv", text(&vectors)),
        ],
        &["vectors.csv", "FR", "1e100"],
    );
}

/// Issue 11 item 9: the canvas range is checked with the key named (1e100
/// panicked in the layout; 1e-100 ran for minutes).
#[test]
fn extreme_canvas_sizes_are_refused() {
    for (tag, layout) in [
        ("huge", "layout: {width: 1e100}\n"),
        ("tiny", "layout: {height: 1e-100}\n"),
        ("zero", "layout: {width: 0}\n"),
    ] {
        let stderr = case_within(
            &format!("canvas_{tag}"),
            &[
                (
                    "nptreemap.yaml",
                    text(&format!("{layout}{}", border_config(""))),
                ),
                ("nodes.csv", text(NODES)),
                ("pairs.csv", text(PAIRS)),
            ],
            &["nptreemap.yaml", "1000000"],
            60,
        );
        assert!(
            stderr.contains("width") || stderr.contains("height"),
            "{stderr}"
        );
    }
    let dir = support::temp_dir("canvas_cli");
    let input = dir.join("tree.json");
    std::fs::write(
        &input,
        r#"{"id": "r", "children": [{"id": "a", "value": 1}, {"id": "b", "value": 2}]}"#,
    )
    .expect("tree");
    let out = support::output_within(
        support::bin()
            .arg("layout")
            .arg(&input)
            .args(["--width", "1e100", "--out"])
            .arg(dir.join("o.svg")),
        60,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("width") && !stderr.contains("panicked"),
        "{stderr}"
    );
}

/// Issue 11 item 5: a parent chain deeper than `limits.max_depth` is refused
/// by the reader with the key named, before the layout (5,000 levels took
/// 2.7 GB, 100,000 were killed at 24 GB).
#[test]
fn a_deep_parent_chain_is_refused_by_the_reader() {
    let config = "datasets:\n  - name: p\n    format: border-list\n    files: {nodes: nodes.csv, pairs: pairs.csv}\n    fields: {parent: parent}\n    outputs: [{path: out.svg}]\n";
    for depth in [5_000, 100_000] {
        let mut nodes = String::from("id,parent,weight\nn0,,1\n");
        for i in 1..depth {
            nodes.push_str(&format!("n{i},n{},1\n", i - 1));
        }
        case_within(
            &format!("chain_{depth}"),
            &[
                ("nptreemap.yaml", text(config)),
                ("nodes.csv", text(&nodes)),
                ("pairs.csv", text("a,b\nn1,n2\n")),
            ],
            &["nodes.csv", "depth", "limits.max_depth"],
            60,
        );
    }
    // Hierarchy JSON nested deeper than the limit: named the same way.
    let mut json = String::new();
    for i in 0..40 {
        json.push_str(&format!("{{\"id\": \"n{i}\", \"children\": ["));
    }
    json.push_str("{\"id\": \"leaf\", \"value\": 1}");
    json.push_str(&"]}".repeat(40));
    case_within(
        "json_depth",
        &[
            ("nptreemap.yaml", text(&hierarchy_config())),
            ("tree.json", text(&json)),
        ],
        &["tree.json", "limits.max_depth"],
        60,
    );
}

/// Issue 11 item 5: more nodes than `limits.max_nodes`, wider vectors than
/// `limits.max_dimensions`, a file larger than `limits.max_file_mb`: each is
/// refused with the key named; raising the key lets the input through.
#[test]
fn inputs_over_the_limits_are_refused_naming_the_key() {
    let limits = "limits: {max_nodes: 5}\n";
    case(
        "limit_nodes",
        &[
            (
                "nptreemap.yaml",
                text(&format!("{limits}{}", border_config(""))),
            ),
            ("nodes.csv", text(NODES)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nodes.csv", "limits.max_nodes", "5"],
    );
    case(
        "limit_dimensions",
        &[
            (
                "nptreemap.yaml",
                text(&format!(
                    "limits: {{max_dimensions: 1}}\n{}",
                    embedding_config()
                )),
            ),
            ("nodes.csv", text(NODES)),
            ("vectors.csv", text(VECTORS)),
        ],
        &["vectors.csv", "limits.max_dimensions"],
    );
    // Blank lines are skipped by the reader: only the size is wrong.
    let big = NODES.to_string() + &"\n".repeat((1 << 20) + 10);
    case(
        "limit_file",
        &[
            (
                "nptreemap.yaml",
                text(&format!(
                    "limits: {{max_file_mb: 1}}\n{}",
                    border_config("")
                )),
            ),
            ("nodes.csv", text(&big)),
            ("pairs.csv", text(PAIRS)),
        ],
        &["nodes.csv", "limits.max_file_mb"],
    );
    // Raised, the same data builds.
    let dir = support::temp_dir("limit_raised");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        format!("limits: {{max_nodes: 9}}\n{}", border_config("")),
    )
    .expect("config");
    std::fs::write(dir.join("nodes.csv"), NODES).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), PAIRS).expect("pairs");
    let out = support::bin()
        .arg("check")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A limit of 0 is a config error naming the key.
    std::fs::write(
        dir.join("nptreemap.yaml"),
        format!("limits: {{max_depth: 0}}\n{}", border_config("")),
    )
    .expect("config");
    let out = support::bin()
        .arg("check")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("max_depth"), "{stderr}");
}

/// Issue 11 item 10: a group value holding `/` is its own group, not the
/// path of two (rows in groups `Asia/East` and `Asia` + `East` collided).
#[test]
fn group_values_with_slashes_do_not_collide() {
    let dir = support::temp_dir("groups_with_slashes");
    let config = "datasets:\n  - name: g\n    format: border-list\n    files: {nodes: nodes.csv, pairs: pairs.csv}\n    fields: {groups: [region, part]}\n    outputs: [{path: out.json}]\n";
    std::fs::write(dir.join("nptreemap.yaml"), config).expect("config");
    std::fs::write(
        dir.join("nodes.csv"),
        "id,weight,region,part\na,1,Asia/East,North\nb,2,Asia,East\nc,3,Asia,West\n",
    )
    .expect("nodes");
    std::fs::write(dir.join("pairs.csv"), "a,b\na,c\n").expect("pairs");
    let out = support::bin()
        .arg("build")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out.json")).expect("json"))
            .expect("parses");
    let nodes = doc["nodes"].as_array().expect("nodes");
    let by_id = |id: &str| {
        nodes
            .iter()
            .find(|n| n["id"] == id)
            .unwrap_or_else(|| panic!("node {id}"))
    };
    // The chain of labels from each leaf up to the root's child.
    let labels_up = |id: &str| {
        let mut labels = Vec::new();
        let mut node = by_id(id);
        while let Some(parent) = node["parent"].as_str() {
            node = by_id(parent);
            if node["parent"].is_null() {
                break;
            }
            labels.push(node["label"].as_str().unwrap_or("").to_string());
        }
        labels
    };
    // Leaves may sit under virtual copies; drop the repeats they make.
    let mut a = labels_up("a");
    a.dedup();
    let mut b = labels_up("b");
    b.dedup();
    assert_eq!(a, ["North", "Asia/East"], "a's groups");
    assert_eq!(b, ["East", "Asia"], "b's groups");
}

/// Issue 11 item 15: what is read but probably not meant is a warning in
/// `check` (and `build`), naming the file and line; the exit code stays 0.
#[test]
fn check_warns_about_silent_acceptance() {
    let run = |tag: &str, nodes: &str, pairs: &str, state: Option<&str>| -> String {
        let dir = support::temp_dir(&format!("warn_{tag}"));
        std::fs::write(dir.join("nptreemap.yaml"), border_config("")).expect("config");
        std::fs::write(dir.join("nodes.csv"), nodes).expect("nodes");
        std::fs::write(dir.join("pairs.csv"), pairs).expect("pairs");
        if let Some(state) = state {
            std::fs::create_dir_all(dir.join(".nptreemap")).expect("state dir");
            std::fs::write(dir.join(".nptreemap/c.layout.json"), state).expect("state");
        }
        let out = support::output_within(
            support::bin().arg("check").arg(dir.join("nptreemap.yaml")),
            60,
        );
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{tag}: {stderr}");
        stderr
    };
    let header_only = run(
        "header_only",
        "iso,name,population,continent\n",
        "a,b\n",
        None,
    );
    assert!(
        header_only.contains("warning: ")
            && header_only.contains("nodes.csv: line 1")
            && header_only.contains("no rows"),
        "{header_only}"
    );
    let twice = run(
        "column_twice",
        &NODES
            .lines()
            .enumerate()
            .map(|(i, l)| {
                let extra = if i == 0 { "name" } else { "x" };
                format!("{l},{extra}\n")
            })
            .collect::<String>(),
        PAIRS,
        None,
    );
    assert!(
        twice.contains("nodes.csv: line 1") && twice.contains("\"name\""),
        "{twice}"
    );
    let self_pair = run("self_pair", NODES, "a,b\nCN,IN\nFR,FR\n", None);
    assert!(
        self_pair.contains("pairs.csv: line 3") && self_pair.contains("itself"),
        "{self_pair}"
    );
    let contradicting = run(
        "strengths",
        NODES,
        "a,b,strength\nCN,IN,1\nFR,DE,2\nIN,CN,5\n",
        None,
    );
    assert!(
        contradicting.contains("pairs.csv: line 4") && contradicting.contains("line 2"),
        "{contradicting}"
    );
    // The same strength twice is only a repeat: no warning.
    let repeat = run("repeat", NODES, "a,b,strength\nCN,IN,1\nIN,CN,1\n", None);
    assert!(!repeat.contains("warning"), "{repeat}");
    let truncated = run(
        "state",
        NODES,
        PAIRS,
        Some("{\"format\": \"nptreemap-layout/1\", \"canv"),
    );
    assert!(
        truncated.contains("c.layout.json") && truncated.contains("cold"),
        "{truncated}"
    );
}
