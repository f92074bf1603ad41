//! Tests for the hierarchy JSON reader: every paper dataset, the peers' generator
//! output, and malformed inputs with their error positions.
//!
//! Reference numbers were counted independently of this crate, with Python over the
//! raw files (no virtual nodes, unlike MANIFEST.md's table):
//!
//! ```text
//! d = json.load(open(f)); walk the tree over "children";
//! nodes = all objects; leaves = those without children; max depth from the walk;
//! root value = len(nodes) if weightAttribute == "none" else sum(leaf[weightAttribute]);
//! relations = sum over nodes of len({x in neighbors if x is an id in the file and x != id})
//! ```
//!
//! The generator fixture `data/gen_n100_depth3_seed1.json` is the output of
//! `python3 tests/tools/gen.py --n 100 --depth 3 --seed 1 --out ...`, which reported
//! 100 leaves and 28 internal nodes, all leaves at depth 3; the leaf weights sum to
//! 138.458175 (Python `sum`).

use std::path::PathBuf;

use nptreemap_formats::{
    parse_hierarchy_json, Dataset, FormatError, HierarchyJsonOptions, ModelError, SimilarityHint,
};

const PAPER_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/paper");

fn paper_file(name: &str) -> Vec<u8> {
    let path = PathBuf::from(PAPER_DATA).join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
}

fn parse(bytes: &[u8]) -> Result<Dataset, FormatError> {
    parse_hierarchy_json(bytes, &HierarchyJsonOptions::default())
}

fn parse_paper(name: &str) -> Dataset {
    parse(&paper_file(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Expected figures for one paper file, counted with Python (see the module docs).
struct Expected {
    file: &'static str,
    nodes: usize,
    leaves: usize,
    max_depth: usize,
    root_value: f64,
    /// True when `weightAttribute` is "none" (every node weighs 1).
    every_node_weighs_one: bool,
    hint: SimilarityHint,
    with_features: usize,
    feature_len: usize,
    relations: usize,
}

const PAPER: [Expected; 11] = [
    Expected {
        file: "country_pop_50M_AUS.json",
        nodes: 36,
        leaves: 29,
        max_depth: 2,
        root_value: 5_835_459_520.0,
        every_node_weighs_one: false,
        hint: SimilarityHint::NeighborList,
        with_features: 29,
        feature_len: 109,
        relations: 36,
    },
    Expected {
        file: "cifar10.json",
        nodes: 16,
        leaves: 10,
        max_depth: 3,
        root_value: 16.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 16,
        feature_len: 300,
        relations: 0,
    },
    Expected {
        file: "flare.json",
        nodes: 252,
        leaves: 220,
        max_depth: 4,
        root_value: 252.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Jaccard,
        with_features: 220,
        feature_len: 149,
        relations: 0,
    },
    Expected {
        file: "imdb_100_genre_sim_2child.json",
        nodes: 80,
        leaves: 59,
        max_depth: 2,
        root_value: 8407.0,
        every_node_weighs_one: false,
        hint: SimilarityHint::Binary,
        with_features: 59,
        feature_len: 18,
        relations: 0,
    },
    Expected {
        file: "syntheticPoints_10nodes_2components.json",
        nodes: 11,
        leaves: 10,
        max_depth: 1,
        root_value: 11.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 10,
        feature_len: 10,
        relations: 0,
    },
    Expected {
        file: "2_level_4_cousin_constraints.json",
        nodes: 23,
        leaves: 17,
        max_depth: 2,
        root_value: 23.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 17,
        feature_len: 17,
        relations: 0,
    },
    Expected {
        file: "syntheticPoints_4.json",
        nodes: 6,
        leaves: 5,
        max_depth: 1,
        root_value: 6.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 5,
        feature_len: 5,
        relations: 0,
    },
    Expected {
        file: "syntheticPoints_5nodes_fully_connected.json",
        nodes: 6,
        leaves: 5,
        max_depth: 1,
        root_value: 6.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 5,
        feature_len: 5,
        relations: 0,
    },
    Expected {
        file: "syntheticPoints_10nodes_all_attracted_to_1.json",
        nodes: 11,
        leaves: 10,
        max_depth: 1,
        root_value: 11.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 10,
        feature_len: 10,
        relations: 0,
    },
    // olympia sets both `useNeighborLeafs: true` and `similarityMeasure: "jaccard"`;
    // the neighbour list wins, as in the prototype.
    Expected {
        file: "olympia.json",
        nodes: 62,
        leaves: 50,
        max_depth: 3,
        root_value: 62.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::NeighborList,
        with_features: 50,
        feature_len: 15,
        relations: 140,
    },
    // language's leaves carry a `weight` field, but `weightAttribute: "none"` wins.
    Expected {
        file: "language.json",
        nodes: 42,
        leaves: 35,
        max_depth: 2,
        root_value: 42.0,
        every_node_weighs_one: true,
        hint: SimilarityHint::Cosine,
        with_features: 35,
        feature_len: 8,
        relations: 0,
    },
];

/// Structural invariants every dataset from a reader must meet.
fn check_invariants(name: &str, dataset: &Dataset) {
    let nodes = dataset.nodes();
    assert_eq!(dataset.root(), 0, "{name}");
    assert_eq!(nodes[0].parent, None, "{name}");
    assert_eq!(nodes[0].depth, 0, "{name}");
    for (i, node) in nodes.iter().enumerate() {
        // Breadth-first: depth never decreases along the node list.
        if i > 0 {
            assert!(nodes[i - 1].depth <= node.depth, "{name}: BFS order at {i}");
            let parent = node.parent.expect("non-root has a parent");
            assert!(parent < i, "{name}: parent after child at {i}");
            assert_eq!(nodes[parent].depth + 1, node.depth, "{name}");
            assert!(nodes[parent].children.contains(&i), "{name}");
        }
        assert!(!node.is_virtual, "{name}");
        assert_eq!(dataset.find(&node.id), Some(i), "{name}: find {}", node.id);
        // Own weight plus children, summed in any order: the values here are
        // integers or few enough that a tolerance covers summation order.
        let expected =
            node.weight.unwrap_or(0.0) + node.children.iter().map(|&c| nodes[c].value).sum::<f64>();
        assert!(
            (node.value - expected).abs() <= 1e-9 * expected.abs().max(1.0),
            "{name}: value of {}",
            node.id
        );
        for &r in &node.relations {
            assert!(r < nodes.len() && r != i, "{name}: relation of {}", node.id);
        }
        assert!(
            node.relations.windows(2).all(|w| w[0] < w[1]),
            "{name}: relations sorted and unique"
        );
    }
}

#[test]
fn every_paper_file_matches_independent_counts() {
    for expected in &PAPER {
        let name = expected.file;
        let dataset = parse_paper(name);
        check_invariants(name, &dataset);
        assert_eq!(dataset.len(), expected.nodes, "{name}: nodes");
        assert_eq!(dataset.leaves().count(), expected.leaves, "{name}: leaves");
        assert_eq!(dataset.max_depth(), expected.max_depth, "{name}: max depth");
        assert_eq!(
            dataset.similarity_hint(),
            Some(expected.hint),
            "{name}: hint"
        );

        let root_value = dataset.node(dataset.root()).value;
        assert_eq!(root_value, expected.root_value, "{name}: root value");
        if expected.every_node_weighs_one {
            assert!(
                dataset.nodes().iter().all(|n| n.weight == Some(1.0)),
                "{name}"
            );
            assert_eq!(root_value, dataset.len() as f64, "{name}");
        } else {
            let leaf_sum: f64 = dataset
                .leaves()
                .map(|i| dataset.node(i).weight.expect("leaf weight"))
                .sum();
            assert_eq!(root_value, leaf_sum, "{name}: root value = sum of leaves");
            assert!(
                dataset
                    .nodes()
                    .iter()
                    .filter(|n| !n.children.is_empty())
                    .all(|n| n.weight.is_none()),
                "{name}: internal nodes have no own weight"
            );
        }

        let with_features: Vec<&nptreemap_formats::Features> = dataset
            .nodes()
            .iter()
            .filter_map(|n| n.features.as_ref())
            .collect();
        assert_eq!(with_features.len(), expected.with_features, "{name}");
        assert!(
            with_features
                .iter()
                .all(|f| f.len() == expected.feature_len),
            "{name}: feature length (unwrapped)"
        );
        let relations: usize = dataset.nodes().iter().map(|n| n.relations.len()).sum();
        assert_eq!(relations, expected.relations, "{name}: resolved relations");
    }
}

#[test]
fn every_json_file_in_paper_data_is_covered_and_reads() {
    let mut names: Vec<String> = std::fs::read_dir(PAPER_DATA)
        .expect("tests/data/paper directory")
        .map(|entry| {
            entry
                .expect("entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|name| name.ends_with(".json"))
        .collect();
    names.sort();
    let mut covered: Vec<&str> = PAPER.iter().map(|e| e.file).collect();
    covered.sort_unstable();
    assert_eq!(names, covered);
}

#[test]
fn country_details() {
    let dataset = parse_paper("country_pop_50M_AUS.json");
    let cn = dataset.find("CN").expect("China");
    let china = dataset.node(cn);
    // Leaves use `Name` (capital N) for their label.
    assert_eq!(china.label, "China");
    assert_eq!(china.weight, Some(1_411_778_724.0));
    // Of CN's 16 listed neighbours only these 5 are in the file (Python check).
    let neighbors: Vec<&str> = china
        .relations
        .iter()
        .map(|&r| dataset.node(r).id.as_str())
        .collect();
    let mut sorted = neighbors.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, ["IN", "MM", "PK", "RU", "VN"]);

    let asia = dataset.node(dataset.find("Cont_AS").expect("Asia"));
    assert_eq!(asia.label, "AS");
    assert_eq!(asia.color.map(|c| c.to_hex()).as_deref(), Some("#4e79a7"));
    assert_eq!(asia.weight, None);
    assert_eq!(china.parent, dataset.find("Cont_AS"));
    // Continents come right after the root, in file order.
    let continents: Vec<&str> = dataset
        .node(0)
        .children
        .iter()
        .map(|&c| dataset.node(c).id.as_str())
        .collect();
    assert_eq!(
        continents,
        ["Cont_OC", "Cont_AS", "Cont_SA", "Cont_AF", "Cont_EU", "Cont_NA"]
    );
}

#[test]
fn cifar_internal_features_are_unwrapped() {
    let dataset = parse_paper("cifar10.json");
    let root = dataset.node(0);
    assert_eq!(root.id, "root");
    let features = root.features.as_ref().expect("root has its own vector");
    assert_eq!(features.len(), 300);
    assert_eq!(
        features.as_dense().expect("dense")[0],
        0.0010100001003593207
    );
    let top: Vec<&str> = root
        .children
        .iter()
        .map(|&c| dataset.node(c).id.as_str())
        .collect();
    assert_eq!(top, ["man-made", "nature"]);
}

#[test]
fn generator_output_reads_as_d3_hierarchy() {
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/gen_n100_depth3_seed1.json"
    ))
    .expect("fixture");
    let dataset = parse(&bytes).expect("generator output");
    check_invariants("gen.py", &dataset);
    assert_eq!(dataset.len(), 128);
    assert_eq!(dataset.leaves().count(), 100);
    assert!(dataset.leaves().all(|i| dataset.node(i).depth == 3));
    assert_eq!(dataset.max_depth(), 3);
    // Ids come from `name`; the weight field `weight` is found on the leaves.
    assert_eq!(dataset.node(0).id, "root");
    assert_eq!(dataset.node(1).id, "g1");
    let l3 = dataset.node(dataset.find("l3").expect("l3"));
    assert_eq!(l3.weight, Some(3.378669));
    assert_eq!(l3.label, "l3");
    assert!((dataset.node(0).value - 138.458175).abs() < 1e-9);
    // No vectors and no flags: nothing to say about similarity.
    assert_eq!(dataset.similarity_hint(), None);
}

#[test]
fn byte_order_mark_is_accepted() {
    let plain = paper_file("syntheticPoints_4.json");
    let mut with_bom = b"\xEF\xBB\xBF".to_vec();
    with_bom.extend_from_slice(&plain);
    assert_eq!(
        parse(&with_bom).expect("BOM"),
        parse(&plain).expect("plain")
    );
}

#[test]
fn truncated_file_is_a_syntax_error_on_its_last_line() {
    let bytes = paper_file("country_pop_50M_AUS.json");
    // Keep 300 whole lines plus 3 bytes of line 301: the parser hits EOF on line 301.
    let cut = bytes
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .nth(299)
        .map(|(i, _)| i + 4)
        .expect("file has 300 lines");
    let error = parse(&bytes[..cut]).expect_err("truncated");
    match &error {
        FormatError::Syntax { line, message, .. } => {
            assert_eq!(*line, 301);
            assert!(message.contains("EOF"), "{message}");
        }
        other => panic!("expected a syntax error, got {other:?}"),
    }
    assert!(
        error.to_string().starts_with("line 301, column "),
        "{error}"
    );
}

#[test]
fn syntax_error_points_at_the_bad_token() {
    let json = "{\n  \"id\": \"r\",\n  \"children\": [\n    {\"id\": \"a\" \"weight\": 1}\n  ]\n}";
    let error = parse(json.as_bytes()).expect_err("missing comma");
    assert_eq!(error.line(), Some(4));
    // The unexpected `"` of "weight" is character 16 on line 4.
    assert_eq!(error.column(), Some(16));
    assert!(
        error.to_string().starts_with("line 4, column 16: expected"),
        "{error}"
    );
}

#[test]
fn syntax_error_columns_count_characters() {
    // "é" is two bytes but one character; serde_json counts bytes.
    let json = "{\"name\": \"é\" x}";
    let error = parse(json.as_bytes()).expect_err("stray x");
    assert_eq!((error.line(), error.column()), (Some(1), Some(14)));
}

#[test]
fn string_weight_names_node_field_and_position() {
    let json = r#"{"id": "root", "weightAttribute": "Population", "children": [
  {"id": "IN", "Population": 5},
  {"id": "CN", "Population": "1411778724"}
]}"#;
    let error = parse(json.as_bytes()).expect_err("string weight");
    assert_eq!(
        error,
        FormatError::Field {
            line: Some(3),
            column: Some(30),
            node: Some("CN".into()),
            field: "Population".into(),
            message: "expected a number, found a string".into(),
        }
    );
    assert_eq!(
        error.to_string(),
        "line 3, column 30: node \"CN\": field \"Population\": expected a number, found a string"
    );
}

#[test]
fn negative_weight_is_an_error() {
    let json =
        "{\"children\": [{\"name\": \"a\", \"value\": 1}, {\"name\": \"b\", \"value\": -3}]}";
    let error = parse(json.as_bytes()).expect_err("negative");
    assert_eq!(
        error.to_string(),
        "line 1, column 65: node \"b\": field \"value\": weight -3 is negative"
    );
}

#[test]
fn missing_leaf_weight_is_an_error() {
    let json = "{\"weightAttribute\": \"duration\",\n \"children\": [{\"id\": \"m1\", \"duration\": 90},\n  {\"id\": \"m2\"}]}";
    let error = parse(json.as_bytes()).expect_err("missing weight");
    assert_eq!(
        error.to_string(),
        "line 3, column 3: node \"m2\": field \"duration\": missing; every leaf needs a weight"
    );
}

#[test]
fn duplicate_ids_point_at_the_second_node() {
    let json = "{\"id\": \"r\", \"children\": [\n  {\"id\": \"x\", \"weight\": 1},\n  {\"id\": \"x\", \"weight\": 2}\n]}";
    let error = parse(json.as_bytes()).expect_err("duplicate");
    assert_eq!(
        error,
        FormatError::Model {
            line: Some(3),
            column: Some(3),
            source: ModelError::DuplicateId { id: "x".into() },
        }
    );
    assert_eq!(
        error.to_string(),
        "line 3, column 3: node \"x\": the id is used by more than one node"
    );
}

#[test]
fn top_level_must_be_an_object() {
    let error = parse(b"\n  [1, 2]").expect_err("array");
    assert!(matches!(
        error,
        FormatError::Structure {
            line: Some(2),
            column: Some(3),
            ..
        }
    ));
    assert!(error.to_string().contains("found an array"), "{error}");
    let error = parse(b"{\"children\": [1]}").expect_err("number child");
    assert_eq!(
        error.to_string(),
        "line 1, column 15: expected a node object, found a number"
    );
}

#[test]
fn unknown_similarity_measure_names_the_field() {
    let json = r#"{"similarityMeasure": "euclid", "children": [{"id": "a", "weight": 1}]}"#;
    let error = parse(json.as_bytes()).expect_err("unknown measure");
    assert_eq!(
        error.to_string(),
        "line 1, column 23: field \"similarityMeasure\": unknown similarity measure \"euclid\"; expected \"cosine\", \"jaccard\" or \"binary\""
    );
}

#[test]
fn feature_entries_must_be_numbers() {
    let json = r#"{"children": [{"id": "a", "weight": 1, "embeddings": [[1, "x"]]}]}"#;
    let error = parse(json.as_bytes()).expect_err("bad feature");
    assert_eq!(
        error.to_string(),
        "line 1, column 59: node \"a\": field \"embeddings\": entry 1: expected a number, found a string"
    );
}

#[test]
fn features_follow_sim_attribute_and_unwrap_once() {
    let json = r#"{"simAttribute": "vec", "children": [
        {"id": "a", "weight": 1, "vec": [[1, 2]]},
        {"id": "b", "weight": 1, "vec": [3, 4], "embeddings": "ignored"},
        {"id": "c", "weight": 1, "vec": [[5], [6]]}
    ]}"#;
    let error = parse(json.as_bytes()).expect_err("c is a list of lists");
    assert!(
        error
            .to_string()
            .contains("node \"c\": field \"vec\": entry 0: expected a number, found an array"),
        "{error}"
    );
    let fixed = json.replace("[[5], [6]]", "[[5, 6]]");
    let dataset = parse(fixed.as_bytes()).expect("valid");
    let features: Vec<Option<Vec<f64>>> = dataset
        .nodes()
        .iter()
        .map(|n| {
            n.features
                .as_ref()
                .and_then(|f| f.as_dense())
                .map(<[f64]>::to_vec)
        })
        .collect();
    assert_eq!(
        features,
        [
            None,
            Some(vec![1.0, 2.0]),
            Some(vec![3.0, 4.0]),
            Some(vec![5.0, 6.0])
        ]
    );
    assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Cosine));
}

#[test]
fn invalid_color_names_node_and_field() {
    let json = r#"{"children": [{"id": "a", "weight": 1, "color": "teal"}]}"#;
    let error = parse(json.as_bytes()).expect_err("bad colour");
    assert_eq!(
        error.to_string(),
        "line 1, column 49: node \"a\": field \"color\": \"teal\" is not a hex color like #rgb or #rrggbb"
    );
}

#[test]
fn ids_labels_and_path_ids() {
    let json = r#"{"children": [
        {"id": 7, "name": "Seven", "weight": 1},
        {"Name": "Upper", "weight": 2},
        {"children": [{"weight": 3}, {"name": "named", "weight": 4}]}
    ]}"#;
    let dataset = parse(json.as_bytes()).expect("valid");
    let ids: Vec<&str> = dataset.nodes().iter().map(|n| n.id.as_str()).collect();
    assert_eq!(ids, ["root", "7", "Upper", "root/2", "root/2/0", "named"]);
    let labels: Vec<&str> = dataset.nodes().iter().map(|n| n.label.as_str()).collect();
    assert_eq!(
        labels,
        ["root", "Seven", "Upper", "root/2", "root/2/0", "named"]
    );
    assert_eq!(dataset.node(0).value, 10.0);
}

#[test]
fn weight_field_choice() {
    // `value` is preferred over `weight` when both appear on leaves.
    let json = r#"{"children": [{"id": "a", "weight": 5, "value": 1}, {"id": "b", "value": 2, "size": 9}]}"#;
    let dataset = parse(json.as_bytes()).expect("valid");
    assert_eq!(dataset.node(0).value, 3.0);

    // The option overrides the guess and the file's flag.
    let options = HierarchyJsonOptions {
        weight_field: Some("size".into()),
        ..HierarchyJsonOptions::default()
    };
    let error = parse_hierarchy_json(json.as_bytes(), &options).expect_err("a has no size");
    assert!(
        error
            .to_string()
            .contains("node \"a\": field \"size\": missing"),
        "{error}"
    );

    // "none" through the option counts every node, the root too.
    let options = HierarchyJsonOptions {
        weight_field: Some("none".into()),
        ..HierarchyJsonOptions::default()
    };
    let dataset = parse_hierarchy_json(json.as_bytes(), &options).expect("valid");
    assert_eq!(dataset.node(0).value, 3.0);
    assert_eq!(dataset.node(0).weight, Some(1.0));

    // No weight field anywhere: each leaf weighs 1, internal nodes nothing.
    let json =
        r#"{"children": [{"id": "a"}, {"id": "g", "children": [{"id": "b"}, {"id": "c"}]}]}"#;
    let dataset = parse(json.as_bytes()).expect("valid");
    assert_eq!(dataset.node(0).value, 3.0);
    assert_eq!(dataset.node(0).weight, None);
}

#[test]
fn unknown_neighbors_are_dropped_known_ones_kept() {
    let json = r#"{"useNeighborLeafs": true, "weightAttribute": "none", "children": [
        {"id": "a", "neighbors": ["b", "zz", "a", "b"]},
        {"id": "b", "neighbors": ["a"]}
    ]}"#;
    let dataset = parse(json.as_bytes()).expect("valid");
    assert_eq!(
        dataset.similarity_hint(),
        Some(SimilarityHint::NeighborList)
    );
    assert_eq!(dataset.node(1).relations, vec![2]);
    assert_eq!(dataset.node(2).relations, vec![1]);
}

#[test]
fn wrong_flag_types_are_errors() {
    let error = parse(br#"{"useNeighborLeafs": "yes", "children": []}"#).expect_err("flag type");
    assert_eq!(
        error.to_string(),
        "line 1, column 22: field \"useNeighborLeafs\": expected true or false, found a string"
    );
    let error = parse(br#"{"weightAttribute": 3}"#).expect_err("flag type");
    assert_eq!(
        error.to_string(),
        "line 1, column 21: field \"weightAttribute\": expected a string, found a number"
    );
}

#[test]
fn a_lone_root_is_a_dataset() {
    let dataset = parse(br#"{"id": "only", "weight": 2}"#).expect("valid");
    assert_eq!(dataset.len(), 1);
    assert_eq!(dataset.node(0).id, "only");
    assert_eq!(dataset.node(0).value, 2.0);
    assert!(dataset.is_leaf(0));
}

#[test]
fn empty_input_is_a_syntax_error() {
    let error = parse(b"").expect_err("empty");
    assert!(
        matches!(error, FormatError::Syntax { line: 1, .. }),
        "{error:?}"
    );
    let error = parse(b"\xEF\xBB\xBF").expect_err("only a BOM");
    assert!(
        matches!(error, FormatError::Syntax { line: 1, .. }),
        "{error:?}"
    );
}

#[test]
fn a_label_of_the_wrong_type_is_an_error() {
    let json = r#"{"children": [{"id": "a", "weight": 1, "name": {"en": "A"}}]}"#;
    let error = parse(json.as_bytes()).expect_err("object label");
    assert_eq!(
        error.to_string(),
        "line 1, column 48: node \"a\": field \"name\": expected a string or a number, found an object"
    );
}

#[test]
fn hierarchy_json_as_a_format() {
    use nptreemap_formats::{registry, FormatOptions, Inputs};
    let format = registry::find("hierarchy-json").expect("registered");
    assert_eq!(format.roles()[0].name, "hierarchy");
    let json = br#"{"name": "r", "children": [{"name": "a", "size": 2, "pop": 7}]}"#;
    let options = FormatOptions {
        weight: Some("pop".into()),
        ..FormatOptions::default()
    };
    let dataset = format
        .parse(&Inputs::new().with("hierarchy", json), &options)
        .expect("valid");
    assert_eq!(
        dataset.node(0).value,
        7.0,
        "options.weight is the weight field"
    );
    let error = format
        .parse(&Inputs::new().with("hierarchy", b"{"), &options)
        .expect_err("cut short");
    assert_eq!(error.role, "hierarchy");
    assert!(
        error.to_string().starts_with("hierarchy: line 1"),
        "{error}"
    );
}

/// Issue 21 papercut: neighbour lists (what an `exec` adapter prints) were
/// ignored without the paper's `"useNeighborLeafs": true`, and the build drew
/// a plain treemap without a word. Lists that name nodes now give the
/// neighbour-list similarity unless a flag chooses another, and a flag that
/// leaves them unused says so.
#[test]
fn neighbor_lists_are_used_without_the_paper_flag() {
    let tree = |flags: &str, a_features: &str| {
        format!(
            r#"{{{flags} "children": [
                {{"id": "a", "value": 1, "neighbors": ["b", "elsewhere"]{a_features}}},
                {{"id": "b", "value": 2{a_features}}},
                {{"id": "c", "value": 3{a_features}}}
            ]}}"#
        )
    };
    let hint_and_warnings = |text: String| {
        let dataset = parse(text.as_bytes()).expect("valid");
        let a = dataset.node(dataset.find("a").expect("a"));
        assert_eq!(
            a.relations,
            [dataset.find("b").expect("b")],
            "the lists are kept"
        );
        let warnings: Vec<String> = dataset.warnings().iter().map(|w| w.to_string()).collect();
        (dataset.similarity_hint(), warnings)
    };
    // No flags: the lists are the similarity, silently (nothing else is there).
    let (hint, warnings) = hint_and_warnings(tree("", ""));
    assert_eq!(hint, Some(SimilarityHint::NeighborList));
    assert!(warnings.is_empty(), "{warnings:?}");
    // Vectors too: the explicit lists win, and the warning says how to choose.
    let (hint, warnings) = hint_and_warnings(tree("", r#", "embeddings": [1, 2]"#));
    assert_eq!(hint, Some(SimilarityHint::NeighborList));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("\"useNeighborLeafs\": false"),
        "{warnings:?}"
    );
    // A flag that chooses another similarity keeps it, with a warning.
    for (flags, why) in [
        (
            r#""useNeighborLeafs": false,"#,
            "\"useNeighborLeafs\" is false",
        ),
        (
            r#""similarityMeasure": "cosine","#,
            "\"similarityMeasure\" is \"cosine\"",
        ),
    ] {
        let (hint, warnings) = hint_and_warnings(tree(flags, r#", "embeddings": [1, 2]"#));
        assert_eq!(hint, Some(SimilarityHint::Cosine), "{flags}");
        assert_eq!(warnings.len(), 1, "{flags}: {warnings:?}");
        assert!(
            warnings[0].contains("the neighbor lists of 1 node(s) are not used")
                && warnings[0].contains(why),
            "{flags}: {warnings:?}"
        );
    }
    // Lists that name no node of the file change nothing.
    let dataset =
        parse(br#"{"children": [{"id": "a", "neighbors": ["x"]}, {"id": "b"}]}"#).expect("valid");
    assert_eq!(dataset.similarity_hint(), None);
    assert!(dataset.warnings().is_empty());
}
