//! Sets stay sets (issue 23 item 1): genre tables and hierarchy JSON lists of
//! strings are read as member ids ([`SparseVector`]), never as one-hot rows;
//! their distinct members are capped by `limits.max_set_members`, not by
//! `max_dimensions`; 0/1 vectors of a Jaccard file are the same sets.

use nptreemap_formats::{
    parse_hierarchy_json, registry, Dataset, Features, FormatOptions, HierarchyJsonOptions, Inputs,
    Limits, SimilarityHint, SparseVector,
};

fn genre_table(csv: &str, limits: Limits) -> Result<Dataset, String> {
    let format = registry::find("genre-table").expect("registered");
    let inputs = Inputs::new().with("nodes", csv.as_bytes());
    let options = FormatOptions {
        groups: vec!["group".to_owned()],
        limits,
        ..FormatOptions::default()
    };
    format.parse(&inputs, &options).map_err(|e| e.to_string())
}

fn json(text: &str, limits: Limits) -> Result<Dataset, String> {
    let options = HierarchyJsonOptions {
        limits,
        ..HierarchyJsonOptions::default()
    };
    parse_hierarchy_json(text.as_bytes(), &options).map_err(|e| e.to_string())
}

fn set_of<'a>(dataset: &'a Dataset, id: &str) -> &'a SparseVector {
    let node = dataset.node(dataset.find(id).unwrap_or_else(|| panic!("no {id}")));
    match &node.features {
        Some(Features::Sparse(set)) if set.is_set() => set,
        other => panic!("{id}: expected a set, found {other:?}"),
    }
}

/// 200 films with 500 genres of their own each: 100,000 distinct genres.
fn wide_table() -> String {
    let mut csv = String::from("id,group,value,genres\n");
    for film in 0..200 {
        let genres: Vec<String> = (0..500).map(|g| format!("f{film}g{g}")).collect();
        // Every film also shares one genre with its neighbour in the list.
        csv.push_str(&format!(
            "film{film},group{},{},{}|shared{}\n",
            film % 4,
            1 + film % 7,
            genres.join("|"),
            film / 2
        ));
    }
    csv
}

#[test]
fn a_genre_table_with_100000_distinct_genres_is_read_as_sets() {
    let dataset = genre_table(&wide_table(), Limits::default()).expect("within the limits");
    assert_eq!(dataset.similarity_hint(), Some(SimilarityHint::Jaccard));
    // 100,000 own genres and 100 shared ones.
    let set = set_of(&dataset, "film7");
    assert_eq!(set.len(), 100_100);
    assert_eq!(set.indices().len(), 501);
    // The same shared genre, the same member id.
    let shared = |id: &str| -> std::collections::BTreeSet<u32> {
        set_of(&dataset, id).indices().iter().copied().collect()
    };
    assert_eq!(shared("film6").intersection(&shared("film7")).count(), 1);
    assert_eq!(shared("film7").intersection(&shared("film8")).count(), 0);
}

#[test]
fn distinct_genres_are_capped_by_max_set_members_not_max_dimensions() {
    let tight = Limits {
        max_dimensions: 4,
        ..Limits::default()
    };
    let csv = "id,group,value,genres\na,g,1,x|y|z\nb,g,1,v|w|x\n";
    let dataset = genre_table(csv, tight).expect("5 genres are no dense vector");
    assert_eq!(set_of(&dataset, "a").len(), 5);
    let capped = Limits {
        max_set_members: 4,
        ..Limits::default()
    };
    let error = genre_table(csv, capped).expect_err("5 genres over 4");
    assert!(
        error.contains("5 distinct genres") && error.contains("`limits.max_set_members`"),
        "{error}"
    );
}

#[test]
fn lists_of_strings_are_the_sets_of_one_hot_vectors_over_the_sorted_names() {
    let names = r#"{"id": "r", "children": [
        {"id": "g", "children": [
            {"id": "a", "size": 1, "embeddings": ["stdio.h", "string.h", "stdio.h"]},
            {"id": "b", "size": 2, "embeddings": ["zlib.h"]}
        ]},
        {"id": "c", "size": 3, "embeddings": []}
    ]}"#;
    // Sorted names: stdio.h, string.h, zlib.h.
    let one_hot = r#"{"id": "r", "similarityMeasure": "jaccard", "children": [
        {"id": "g", "children": [
            {"id": "a", "size": 1, "embeddings": [1, 1, 0]},
            {"id": "b", "size": 2, "embeddings": [0, 0, 1]}
        ]},
        {"id": "c", "size": 3, "embeddings": [0, 0, 0]}
    ]}"#;
    let from_names = json(names, Limits::default()).expect("valid");
    let from_vectors = json(one_hot, Limits::default()).expect("valid");
    // Without a flag, sets are compared by Jaccard.
    assert_eq!(from_names.similarity_hint(), Some(SimilarityHint::Jaccard));
    assert_eq!(from_names, from_vectors);
    assert_eq!(set_of(&from_names, "a").indices(), [0, 1]);
    assert_eq!(set_of(&from_names, "c").len(), 3);
    assert!(set_of(&from_names, "c").indices().is_empty());
}

#[test]
fn a_jaccard_file_of_wide_vectors_is_capped_by_max_set_members() {
    let ones = |n: usize, at: usize| -> String {
        let v: Vec<&str> = (0..n).map(|k| if k == at { "1" } else { "0" }).collect();
        v.join(",")
    };
    let text = |flag: &str| {
        format!(
            r#"{{"id": "r", {flag} "children": [
                {{"id": "a", "size": 1, "embeddings": [{}]}},
                {{"id": "b", "size": 1, "embeddings": [{}]}}]}}"#,
            ones(2000, 3),
            ones(2000, 1999)
        )
    };
    let dataset = json(
        &text(r#""similarityMeasure": "jaccard","#),
        Limits::default(),
    )
    .expect("2,000 members are within max_set_members");
    assert_eq!(set_of(&dataset, "b").indices(), [1999]);
    // A vector of other data is still dense, and capped by max_dimensions.
    let error = json(&text(""), Limits::default()).expect_err("2,000 values");
    assert!(error.contains("`limits.max_dimensions`"), "{error}");
    let capped = Limits {
        max_set_members: 1000,
        ..Limits::default()
    };
    let error = json(&text(r#""similarityMeasure": "jaccard","#), capped).expect_err("capped");
    assert!(error.contains("`limits.max_set_members`"), "{error}");
}

#[test]
fn distinct_strings_are_capped_and_kinds_are_not_mixed() {
    let text = r#"{"id": "r", "simAttribute": "includes", "children": [
        {"id": "a", "size": 1, "includes": ["x", "y"]},
        {"id": "b", "size": 1, "includes": ["y", "z"]}
    ]}"#;
    let capped = Limits {
        max_set_members: 2,
        ..Limits::default()
    };
    let error = json(text, capped).expect_err("3 names over 2");
    assert!(
        error.contains("3 distinct names")
            && error.contains("\"includes\"")
            && error.contains("`limits.max_set_members`"),
        "{error}"
    );
    let mixed = text.replace(r#"["y", "z"]"#, "[0, 1]");
    let error = json(&mixed, Limits::default()).expect_err("numbers and strings");
    assert!(
        error.contains("node \"b\"") && error.contains("\"includes\"") && error.contains("line 3"),
        "{error}"
    );
    let inside = text.replace(r#"["y", "z"]"#, r#"["y", 2]"#);
    let error = json(&inside, Limits::default()).expect_err("a number among strings");
    assert!(
        error.contains("node \"b\"") && error.contains("entry 1: expected a string"),
        "{error}"
    );
}
