//! Degenerate input never panics and still yields a sound layout (issue 2 §5):
//! one child, zero-weight leaves, 10,000 children in one parent, weight ratios of
//! 1:10^6, coincident initial sites, a single leaf. Every test ends with
//! `sanity_check`.

use crate::support;
use nptreemap::geom::{ConvexPolygon, Point};
use nptreemap::layout::map::{MapSettings, MapSimulation};
use nptreemap::layout::{layout, Outline, Params, Report};
use nptreemap::measure;
use nptreemap::rng::Rng;
use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

fn flat(weights: &[f64]) -> Dataset {
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("root"));
    for (i, w) in weights.iter().enumerate() {
        b.add(NodeSpec::new(format!("n{i}")).parent("root").weight(*w));
    }
    b.build().expect("valid dataset")
}

fn share(ds: &Dataset, l: &nptreemap::Layout, id: &str) -> f64 {
    let i = ds.find(id).expect("node exists");
    l.cells[i].polygon.area() / l.cells[0].polygon.area()
}

#[test]
fn single_leaf_takes_the_whole_canvas() {
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("only").weight(3.0));
    let ds = b.build().expect("valid");
    let (l, report) = layout(&ds, &Params::default()).expect("layout");
    l.sanity_check(&ds).expect("sane");
    assert_eq!(report.diagrams, 0);
    assert!((l.cells[0].polygon.area() - 1_000_000.0).abs() < 1e-6);
}

#[test]
fn one_child_gets_its_parents_cell() {
    let mut b = DatasetBuilder::new();
    b.add(NodeSpec::new("root"));
    b.add(NodeSpec::new("a").parent("root"));
    b.add(NodeSpec::new("a1").parent("a").weight(1.0));
    b.add(NodeSpec::new("b").parent("root").weight(1.0));
    let ds = b.build().expect("valid");
    let (l, _) = layout(&ds, &Params::default()).expect("layout");
    l.sanity_check(&ds).expect("sane");
    let a = ds.find("a").expect("a");
    let a1 = ds.find("a1").expect("a1");
    assert_eq!(l.cells[a].polygon, l.cells[a1].polygon);
}

#[test]
fn zero_weight_leaves_get_small_cells() {
    let ds = flat(&[0.0, 5.0, 5.0, 0.0, 10.0]);
    let params = Params::default();
    let (l, _) = layout(&ds, &params).expect("layout");
    l.sanity_check(&ds).expect("sane");
    // Rule: max(value, min_weight_ratio × heaviest sibling) = 0.01 of 20.02.
    let expected = params.min_weight_ratio * 10.0 / (20.0 + 2.0 * params.min_weight_ratio * 10.0);
    for id in ["n0", "n3"] {
        let s = share(&ds, &l, id);
        assert!(
            s > 0.0 && (s - expected).abs() < 0.01,
            "{id}: share {s}, expected {expected}"
        );
    }
}

#[test]
fn all_zero_weights_share_equally() {
    let ds = flat(&[0.0; 4]);
    let (l, _) = layout(&ds, &Params::default()).expect("layout");
    l.sanity_check(&ds).expect("sane");
    for i in 0..4 {
        let s = share(&ds, &l, &format!("n{i}"));
        assert!((s - 0.25).abs() < 0.01, "share {s}");
    }
}

#[test]
fn ten_thousand_children_in_one_parent() {
    let weights: Vec<f64> = (0..10_000).map(|i| 1.0 + (i % 17) as f64).collect();
    let ds = flat(&weights);
    let (l, report) = layout(&ds, &Params::default()).expect("layout");
    l.sanity_check(&ds).expect("sane");
    let q = measure::quality(&ds, &l);
    assert!(q.area_error_diagram_mean <= 0.01, "{q:?} {report:?}");
}

#[test]
fn weight_ratio_of_a_million() {
    let ds = flat(&[1.0, 1e6, 3.0, 2e5, 7.0, 1e6]);
    let mut params = Params::default();
    params.min_weight_ratio = 0.0;
    let (l, _) = layout(&ds, &params).expect("layout");
    l.sanity_check(&ds).expect("sane");
    assert!(share(&ds, &l, "n0") > 0.0);
    let q = measure::quality(&ds, &l);
    assert!(q.area_error_diagram_mean <= 0.01, "{q:?}");
}

/// Issue 23 item 6: `/usr/bin` (one 127 MB binary beside hundreds of
/// scripts of a few kB) ended at a diagram area error of 0.1355 against its
/// weights while the report said `unconverged: 0`: the 1:1000 floor of
/// `min_weight_ratio` alone moved 13% of the area. Every diagram's error
/// against the real weights stays within the convergence ratio, or the
/// report counts it as unconverged.
#[test]
fn many_leaves_below_the_weight_floor_keep_the_areas_of_their_weights() {
    // One heavy leaf, 600 sizes spread log-uniformly over 10 to 10⁸ (as
    // `/usr/bin`'s), a few zeros. The 1:1000 floor alone moved 2.2% here.
    let mut weights = vec![1.3e8];
    weights.extend((0..600).map(|i| 10f64.powf(1.0 + 7.0 * ((i * 7919) % 600) as f64 / 600.0)));
    weights.extend([0.0; 5]);
    let ds = flat(&weights);
    let params = Params::default();
    let (l, report) = layout(&ds, &params).expect("layout");
    l.sanity_check(&ds).expect("sane");
    let q = measure::quality(&ds, &l);
    assert_converged_or_says_so(&q, &report, &params);
    assert!(q.area_error_diagram_max <= 0.01, "{q:?} {report:?}");
    // The zero-weight leaves still have a cell.
    for i in 601..606 {
        assert!(share(&ds, &l, &format!("n{i}")) > 0.0);
    }
}

/// Issue 34: a folder of source files has empty files as its median leaf
/// and a heavy tail (`__init__.py` beside 91 KB modules). One diagram of
/// 2,000 such children, half of them zero (floored to 1:1000 of the
/// heaviest), the rest Pareto-distributed over 20 bytes to 91 KB, ran its
/// Lloyd ticks to the cap at an area error of 0.58. It must converge, well
/// inside the cap.
#[test]
fn two_thousand_children_half_of_them_empty_converge_well_inside_the_cap() {
    let mut rng = Rng::new(3);
    let weights: Vec<f64> = (0..2000)
        .map(|_| {
            let empty = rng.next_f64() < 0.5;
            let tail = (20.0 * (1.0 - rng.next_f64()).powf(-1.0 / 0.6)).min(91_000.0);
            if empty {
                0.0
            } else {
                tail.floor()
            }
        })
        .collect();
    assert!(weights.iter().filter(|w| **w == 0.0).count() > 900);
    let ds = flat(&weights);
    let params = Params::default();
    let (l, report) = layout(&ds, &params).expect("layout");
    l.sanity_check(&ds).expect("sane");
    let q = measure::quality(&ds, &l);
    assert_eq!(report.unconverged, 0, "{q:?} {report:?}");
    assert!(
        q.area_error_diagram_max <= params.convergence_ratio,
        "{q:?}"
    );
    assert!(
        report.iterations <= params.max_iterations / 4,
        "{} ticks of a cap of {}",
        report.iterations,
        params.max_iterations
    );
    // Converged cells keep a compact shape: a centroidal power diagram of
    // these areas averages about 1.3 (the mean aspect of the Lloyd ticks when
    // they do converge, on a Pareto diagram of 1,826 such children); sites
    // frozen where the stalled Lloyd ticks left them gave long slivers, 2.66.
    assert!(
        q.aspect_ratio_mean <= 1.45,
        "mean leaf aspect {}",
        q.aspect_ratio_mean
    );
}

/// A diagram above the convergence ratio against its real weights is counted
/// in `unconverged`.
fn assert_converged_or_says_so(q: &measure::Quality, report: &Report, params: &Params) {
    assert!(
        q.area_error_diagram_max <= params.convergence_ratio || report.unconverged > 0,
        "area error {} above {} while unconverged is 0: {report:?}",
        q.area_error_diagram_max,
        params.convergence_ratio
    );
}

/// One leaf of 10⁸ beside 600 of 100 to 50,000: 13% of the area for 600
/// cells beside one of 87%. The Lloyd ticks did not reach 1% here in 200 (or
/// 1,000) ticks (error 0.17 at the cap), and the report must say so (it once
/// said `unconverged: 0` at an error of 0.49, the floor's); since issue 34
/// the weight-only steps after the stalled Lloyd ticks reach it.
#[test]
fn a_diagram_that_missed_its_areas_now_converges_or_says_so() {
    let mut weights = vec![1.0e8];
    weights.extend((0..600).map(|i| 100.0 + (i * 7919 % 50_000) as f64));
    weights.extend([0.0; 5]);
    let ds = flat(&weights);
    let params = Params::default();
    let (l, report) = layout(&ds, &params).expect("layout");
    l.sanity_check(&ds).expect("sane");
    let q = measure::quality(&ds, &l);
    assert_converged_or_says_so(&q, &report, &params);
    assert_eq!(report.unconverged, 0, "{q:?} {report:?}");
    assert!(
        q.area_error_diagram_max <= params.convergence_ratio,
        "{q:?}"
    );
}

#[test]
fn coincident_initial_sites_separate() {
    let clip = ConvexPolygon::rectangle(0.0, 0.0, 100.0, 100.0).expect("rect");
    let n = 12;
    let targets = vec![10_000.0 / n as f64; n];
    let positions = vec![Point::new(50.0, 50.0); n];
    let settings = MapSettings {
        convergence_ratio: 0.01,
        max_iterations: 200,
        min_iterations: 5,
    };
    let mut sim = MapSimulation::new(
        clip.clone(),
        targets,
        positions,
        None,
        settings,
        Rng::new(1),
    );
    sim.run();
    let state = sim.state();
    assert!(
        state.convergence_ratio <= 0.01,
        "error {}",
        state.convergence_ratio
    );
    assert!(state.diagram.cells.iter().all(|c| c.polygon.is_some()));
    state
        .diagram
        .sanity_check(state.sites, &clip)
        .expect("diagram sane");
}

#[test]
fn outlines_hold_their_children() {
    let ds = flat(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    for outline in [Outline::Circle, Outline::Regular(5), Outline::Regular(32)] {
        let mut params = Params::default();
        params.outline = outline.clone();
        let (l, _) = layout(&ds, &params).expect("layout");
        l.sanity_check(&ds).expect("sane");
        assert!(measure::quality(&ds, &l).area_error_diagram_mean <= 0.01);
    }
}

#[test]
fn bad_parameters_are_errors_not_panics() {
    let ds = flat(&[1.0, 2.0]);
    let with = |change: fn(&mut Params)| {
        let mut p = Params::default();
        change(&mut p);
        p
    };
    for params in [
        with(|p| {
            p.canvas = nptreemap::Canvas {
                width: 0.0,
                height: 10.0,
            }
        }),
        with(|p| p.convergence_ratio = f64::NAN),
        with(|p| p.max_iterations = 0),
    ] {
        assert!(layout(&ds, &params).is_err());
    }
}

/// Issue 21, item 8: a stored layout whose power weights were 1e308 gave a
/// degenerate picture (continents of zero area, area error 0.65) for two
/// builds, with no warning (a debug build stopped on its sanity check). The
/// stored layout is refused with a warning naming the file and the field,
/// the layout starts cold, and its areas are right.
#[test]
fn a_stored_layout_with_absurd_power_weights_is_refused_with_a_warning() {
    let config = support::example("countries", "absurd_state");
    let dir = config.parent().expect("folder").to_path_buf();
    support::build(&config);
    let state = dir.join("out/.nptreemap/countries.layout.json");
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&state).expect("stored layout")).expect("json");
    for node in doc["nodes"].as_array_mut().expect("nodes") {
        node["power_weight"] = serde_json::json!(1e308);
    }
    std::fs::write(&state, doc.to_string()).expect("write state");
    // A data edit, so the layout is not simply taken over.
    let nodes = dir.join("countries.csv");
    let text = std::fs::read_to_string(&nodes).expect("countries.csv");
    let edited = text.replacen("AU,Australia,24992369", "AU,Australia,34992369", 1);
    assert_ne!(edited, text, "the edit applies");
    std::fs::write(&nodes, edited).expect("write countries.csv");
    let out = support::build(&config);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("countries.layout.json") && stderr.contains("power_weight"),
        "the warning names the file and the field: {stderr}"
    );
    let report = support::check_layout(&dir.join("out/countries.json"));
    support::assert_area_error(&report, 0.01);
}
