//! Every file of the paper's data lays out, passes the independent checker and
//! meets d3-voronoi-treemap's default area-error target (issue 2 acceptance).

use crate::support;

#[test]
fn every_paper_file_passes_check_layout() {
    let dir = support::temp_dir("paper_data");
    let files = support::paper_files();
    assert!(
        files.len() >= 11,
        "expected the paper's 11 files, found {}",
        files.len()
    );
    for file in files {
        let stem = file
            .file_stem()
            .expect("file name")
            .to_string_lossy()
            .into_owned();
        let json = dir.join(format!("{stem}.json"));
        let svg = dir.join(format!("{stem}.svg"));
        support::layout(&file, &[&json, &svg], &[]);
        let report = support::check_layout(&json);
        support::assert_area_error(&report, 0.01);
        let svg_text = std::fs::read_to_string(&svg).expect("svg written");
        assert!(svg_text.starts_with("<svg") && svg_text.trim_end().ends_with("</svg>"));
    }
}

#[test]
fn readme_example_lays_out() {
    let dir = support::temp_dir("readme_example");
    let input = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/data/world-population.json");
    let json = dir.join("world.json");
    let svg = dir.join("world.svg");
    support::layout(&input, &[&json, &svg], &[]);
    let report = support::check_layout(&json);
    assert_eq!(report["leaves"].as_u64(), Some(65));
    support::assert_area_error(&report, 0.01);
    let svg_text = std::fs::read_to_string(&svg).expect("svg written");
    assert!(
        svg_text.contains(">China<"),
        "the largest countries are labelled"
    );
}
