//! Sets stay sets, end to end (issue 23 item 1): a genre table with 100,000
//! distinct genres over 200 films is laid out by the binary within a bounded
//! address space (a one-hot row per node would be 80 MB a row set, hundreds of
//! MB with the aggregated and projected copies), and hierarchy JSON written as
//! lists of names gives the constraints of the same data written as one-hot
//! vectors.

use crate::init::run_capped;
use crate::support;

#[cfg(unix)]
#[test]
fn a_genre_table_of_100000_distinct_genres_is_laid_out_in_bounded_memory() {
    let dir = support::temp_dir("sets_wide");
    // 100 pairs of films, each pair with a block of 1,000 genres of its own:
    // 100,000 distinct genres, and a perfect Jaccard match within each pair.
    let mut csv = String::from("id,group,value,genres\n");
    for film in 0..200 {
        let block: Vec<String> = (0..1000).map(|g| format!("p{}g{g}", film / 2)).collect();
        csv.push_str(&format!(
            "film{film},group{},{},{}\n",
            film % 4,
            1 + film % 7,
            block.join("|")
        ));
    }
    std::fs::write(dir.join("films.csv"), csv).expect("write");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        "datasets:\n  - name: films\n    format: genre-table\n    files:\n      nodes: films.csv\n    \
         fields:\n      weight: value\n      groups: [group]\n      genres: genres\n    \
         outputs:\n      - path: out/films.json\n",
    )
    .expect("write");
    let out = run_capped(&dir, 600, "build nptreemap.yaml");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/films.json")).expect("written"))
            .expect("json");
    let constraints = json["constraints"].as_array().expect("constraints");
    // Every pair of films with the same genres is linked.
    for pair in 0..100 {
        let (a, b) = (format!("film{}", 2 * pair), format!("film{}", 2 * pair + 1));
        assert!(
            constraints.iter().any(|c| {
                let ends = [c["a"].as_str(), c["b"].as_str()];
                ends.contains(&Some(a.as_str())) && ends.contains(&Some(b.as_str()))
            }),
            "{a}-{b} in {} constraints",
            constraints.len()
        );
    }
}

#[test]
fn lists_of_names_give_the_constraints_of_one_hot_vectors() {
    let dir = support::temp_dir("sets_forms");
    let names = ["a.h", "b.h", "c.h", "d.h", "e.h", "f.h"];
    let leaf = |i: usize, one_hot: bool| -> String {
        let members: Vec<usize> = (0..names.len())
            .filter(|k| (i * 7 + k * 3) % 5 < 2)
            .collect();
        let features = if one_hot {
            let v: Vec<String> = (0..names.len())
                .map(|k| u8::from(members.contains(&k)).to_string())
                .collect();
            format!("[{}]", v.join(","))
        } else {
            let v: Vec<String> = members.iter().map(|&k| format!("{:?}", names[k])).collect();
            format!("[{}]", v.join(","))
        };
        format!(
            r#"{{"id": "h{i}", "size": {}, "embeddings": {features}}}"#,
            1 + i % 4
        )
    };
    let tree = |one_hot: bool| -> String {
        let groups: Vec<String> = (0..4)
            .map(|g| {
                let leaves: Vec<String> = (0..8).map(|i| leaf(g * 8 + i, one_hot)).collect();
                format!(r#"{{"id": "g{g}", "children": [{}]}}"#, leaves.join(","))
            })
            .collect();
        // A leaf beside the groups gets virtual copies down to the leaf level.
        format!(
            r#"{{"id": "root", "similarityMeasure": "jaccard", "weightAttribute": "size",
                "children": [{}, {}]}}"#,
            groups.join(","),
            leaf(99, one_hot)
        )
    };
    let mut constraints = Vec::new();
    for (name, one_hot) in [("names.json", false), ("one-hot.json", true)] {
        std::fs::write(dir.join(name), tree(one_hot)).expect("write");
        let out_path = dir.join(format!("{name}.out.json"));
        let out = support::layout(&dir.join(name), &[&out_path], &[]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&out_path).expect("written")).expect("json");
        constraints.push(json["constraints"].clone());
    }
    assert!(constraints[0].as_array().is_some_and(|c| c.len() > 5));
    assert_eq!(constraints[0], constraints[1]);
}
