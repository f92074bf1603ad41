//! Issue 5 acceptance: in a real picture, the interlocking tabs are exactly the
//! realised leaf-level constraints whose shared edge is long enough to carry
//! one, and each tab sits on that edge. The shared edges are recomputed here
//! from the layout JSON's polygons alone (not with the renderer's code).

use std::collections::BTreeSet;

use resvg::usvg::roxmltree;
use serde_json::Value;

use crate::support;

type P = [f64; 2];

/// The tab's width along the edge: the prototype's 8 px (method-reference
/// §8.3), scaled like its other pixel constants by the canvas against the
/// prototype's 32-gon of radius 192.
fn tab_width(width: f64, height: f64) -> f64 {
    let proto = 0.5 * 32.0 * (std::f64::consts::TAU / 32.0).sin() * 192.0 * 192.0;
    8.0 * (width * height / proto).sqrt()
}

fn points(v: &Value) -> Vec<P> {
    v.as_array()
        .expect("polygon")
        .iter()
        .map(|p| [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")])
        .collect()
}

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn len(a: P) -> f64 {
    dot(a, a).sqrt()
}

/// Segments along which the boundaries of two polygons overlap (collinear
/// edges within `tol`), as (start, end).
fn shared_segments(a: &[P], b: &[P], tol: f64) -> Vec<(P, P)> {
    let mut out = Vec::new();
    for i in 0..a.len() {
        let (p, q) = (a[i], a[(i + 1) % a.len()]);
        let d = sub(q, p);
        let l = len(d);
        if l == 0.0 {
            continue;
        }
        let u = [d[0] / l, d[1] / l];
        for j in 0..b.len() {
            let (r, s) = (b[j], b[(j + 1) % b.len()]);
            if cross(u, sub(r, p)).abs() > tol || cross(u, sub(s, p)).abs() > tol {
                continue;
            }
            let (t0, t1) = (dot(sub(r, p), u), dot(sub(s, p), u));
            let lo = t0.min(t1).max(0.0);
            let hi = t0.max(t1).min(l);
            if hi > lo {
                out.push((
                    [p[0] + u[0] * lo, p[1] + u[1] * lo],
                    [p[0] + u[0] * hi, p[1] + u[1] * hi],
                ));
            }
        }
    }
    out
}

fn distance_to_segment(x: P, (a, b): (P, P)) -> f64 {
    let d = sub(b, a);
    let t = (dot(sub(x, a), d) / dot(d, d)).clamp(0.0, 1.0);
    len(sub(x, [a[0] + d[0] * t, a[1] + d[1] * t]))
}

/// `(a, b, midpoint)` of every tab in the SVG: the ids from its group and the
/// middle of its Z outline (points 3 and 4 are M + n and M − n, §8.3).
fn tabs_in(svg: &str) -> Vec<(String, String, P)> {
    let doc = roxmltree::Document::parse(svg).expect("SVG is XML");
    doc.descendants()
        .filter(|n| n.attribute("class") == Some("np-tab"))
        .map(|g| {
            let line = g
                .children()
                .find(|c| c.has_tag_name("polyline"))
                .expect("tab outline");
            let pts: Vec<P> = line
                .attribute("points")
                .expect("points")
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').expect("x,y");
                    [x.parse().expect("x"), y.parse().expect("y")]
                })
                .collect();
            let m = [(pts[2][0] + pts[3][0]) / 2.0, (pts[2][1] + pts[3][1]) / 2.0];
            (
                g.attribute("data-a").expect("a").to_string(),
                g.attribute("data-b").expect("b").to_string(),
                m,
            )
        })
        .collect()
}

fn check(name: &str) -> usize {
    let dir = support::temp_dir(&format!("tabs_{name}"));
    let input = support::paper_data().join(format!("{name}.json"));
    let (svg_path, json_path) = (dir.join("map.svg"), dir.join("map.json"));
    support::layout(&input, &[&svg_path, &json_path], &[]);
    let layout: Value =
        serde_json::from_slice(&std::fs::read(&json_path).expect("json")).expect("JSON");
    let svg = std::fs::read_to_string(&svg_path).expect("svg");
    let (w, h) = (
        layout["canvas"]["width"].as_f64().expect("w"),
        layout["canvas"]["height"].as_f64().expect("h"),
    );
    let width = tab_width(w, h);
    let nodes = layout["nodes"].as_array().expect("nodes");
    let deepest = nodes
        .iter()
        .filter_map(|n| n["depth"].as_u64())
        .max()
        .expect("depth");
    let node = |id: &str| {
        nodes
            .iter()
            .find(|n| n["id"] == id)
            .unwrap_or_else(|| panic!("node {id}"))
    };
    // Coordinates are written to 1e-6; collinearity within a thousandth of a unit.
    let tol = 1e-3;
    let mut want = BTreeSet::new();
    let mut either = BTreeSet::new();
    let mut segments = std::collections::BTreeMap::new();
    for c in layout["constraints"].as_array().expect("constraints") {
        let (a, b) = (c["a"].as_str().expect("a"), c["b"].as_str().expect("b"));
        if c["realized"] != true || node(a)["depth"].as_u64() != Some(deepest) {
            continue;
        }
        let shared = shared_segments(
            &points(&node(a)["polygon"]),
            &points(&node(b)["polygon"]),
            tol,
        );
        let longest = shared
            .iter()
            .map(|(p, q)| len(sub(*q, *p)))
            .fold(0.0, f64::max);
        let key = (a.to_string(), b.to_string());
        // An edge within 1% of the tab width may go either way (rounding).
        if (longest - width).abs() <= 0.01 * width {
            either.insert(key.clone());
        } else if longest > width {
            want.insert(key.clone());
        }
        segments.insert(key, shared);
    }
    let tabs = tabs_in(&svg);
    let drawn: BTreeSet<(String, String)> = tabs
        .iter()
        .map(|(a, b, _)| (a.clone(), b.clone()))
        .collect();
    assert_eq!(drawn.len(), tabs.len(), "{name}: one tab per pair");
    let missing: Vec<_> = want.difference(&drawn).collect();
    let extra: Vec<_> = drawn
        .difference(&want)
        .filter(|k| !either.contains(*k))
        .collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "{name}: tabs missing {missing:?}, tabs without a long enough realised edge {extra:?}"
    );
    for (a, b, m) in &tabs {
        let shared = &segments[&(a.clone(), b.clone())];
        let off = shared
            .iter()
            .map(|s| distance_to_segment(*m, *s))
            .fold(f64::INFINITY, f64::min);
        // The SVG writes two decimals.
        assert!(
            off < 0.02,
            "{name}: tab {a}-{b} is {off} off its shared edge"
        );
    }
    tabs.len()
}

#[test]
fn tabs_are_the_realized_constraints_with_room_on_their_edges() {
    let countries = check("country_pop_50M_AUS");
    let movies = check("imdb_100_genre_sim_2child");
    assert!(countries > 5 && movies > 5, "{countries} and {movies} tabs");
}
