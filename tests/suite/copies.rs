//! Issue 23 item 2: the virtual copies' constraints derived from their leaves'
//! similarities give exactly the lists of every row recomputed per level, on
//! the paper's files, the real datasets and a C-headers tree of this machine
//! (`benches/c_headers.py`: 10 levels of Jaccard sets, most leaves shallow, so
//! copies on every level). The unit tests of `neighborhood::copies` cover
//! random sets, duplicates and uneven dense trees.

use std::path::Path;

use nptreemap::neighborhood::constraints::{constraint_lists, constraint_lists_recomputed};
use nptreemap::neighborhood::{prepare, SimilarityKind};
use nptreemap_formats::{parse_hierarchy_json, Dataset, HierarchyJsonOptions};

use crate::support;

fn same_lists(dataset: &Dataset, kind: Option<SimilarityKind>, what: &str) {
    let p = prepare(dataset);
    let kind = kind.unwrap_or_else(|| SimilarityKind::for_dataset(&p));
    assert!(
        constraint_lists(&p, kind) == constraint_lists_recomputed(&p, kind),
        "{what}: derived lists differ from the recomputed ones ({kind:?})"
    );
}

#[test]
fn paper_files_derive_the_recomputed_lists() {
    let files = support::paper_files();
    assert!(files.len() >= 8, "paper files: {}", files.len());
    for file in files {
        let bytes = std::fs::read(&file).expect("readable");
        let dataset = parse_hierarchy_json(&bytes, &HierarchyJsonOptions::default())
            .expect("the paper's files parse");
        same_lists(&dataset, None, &file.display().to_string());
    }
}

#[test]
fn real_datasets_derive_the_recomputed_lists() {
    let real = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real");
    for name in ["debian-packages", "man-pages", "python-stdlib", "usr-bin"] {
        let config = nptreemap::config::Config::from_path(&real.join(name).join("nptreemap.yaml"))
            .expect("the real configs parse");
        for d in &config.datasets {
            let dataset = nptreemap::pipeline::load(d).expect("the real data loads");
            same_lists(&dataset, d.similarity, name);
        }
    }
}

#[test]
fn a_c_headers_tree_derives_the_recomputed_lists() {
    let root = Path::new("/usr/include");
    if !root.is_dir() {
        eprintln!("skipped: no /usr/include");
        return;
    }
    let dir = support::temp_dir("copies_c_headers");
    let out = dir.join("ch.json");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/c_headers.py");
    let status = std::process::Command::new("python3")
        .arg(&script)
        .arg(&out)
        .args(["--leaves", "1500"])
        .status()
        .expect("python3 runs");
    assert!(status.success(), "c_headers.py failed");
    let bytes = std::fs::read(&out).expect("written");
    let dataset =
        parse_hierarchy_json(&bytes, &HierarchyJsonOptions::default()).expect("the tree parses");
    assert!(dataset.max_depth() >= 3, "a deep tree");
    same_lists(&dataset, None, "C headers");
}
