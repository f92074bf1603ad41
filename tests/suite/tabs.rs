//! Issues 5 and 13: in a real picture, every interlocking tab belongs to a
//! realised leaf-level constraint and sits on the two cells' shared edge, its
//! head inside the receiving cell, taking a small share of either cell; most
//! realised constraints with room on their edge get one (a few give way to
//! labels). The shared edges are recomputed here from the layout JSON's
//! polygons alone (not with the renderer's code).

use std::collections::BTreeSet;

use resvg::usvg::roxmltree;
use serde_json::Value;

use crate::support;

type P = [f64; 2];

/// Shortest shared edge that can carry a tab: the renderer's smallest base
/// width at scale 1 (7 units on a 1,000-unit canvas) over its largest edge
/// share (a half), times its smallest scale (a half).
fn min_edge(width: f64, height: f64) -> f64 {
    let u = ((width * height).sqrt() / 1000.0).max(0.75);
    7.0 * u / 0.5 * 0.5
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
pub(crate) fn shared_segments(a: &[P], b: &[P], tol: f64) -> Vec<(P, P)> {
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

/// Every tab in the SVG: its ids and its outline (base end, head corners,
/// base end).
fn tabs_in(svg: &str) -> Vec<(String, String, Vec<P>)> {
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
            (
                g.attribute("data-a").expect("a").to_string(),
                g.attribute("data-b").expect("b").to_string(),
                pts,
            )
        })
        .collect()
}

fn inside(p: P, poly: &[P]) -> bool {
    // Convex and positively oriented (y down: clockwise on screen).
    let n = poly.len();
    let sign = |i: usize| cross(sub(poly[(i + 1) % n], poly[i]), sub(p, poly[i]));
    let s0 = (0..n)
        .map(sign)
        .fold(0.0, |acc: f64, v| if v.abs() > acc.abs() { v } else { acc });
    (0..n).all(|i| sign(i) * s0.signum() >= -1e-6)
}

fn area(poly: &[P]) -> f64 {
    let n = poly.len();
    0.5 * (0..n)
        .map(|i| cross(poly[i], poly[(i + 1) % n]))
        .sum::<f64>()
        .abs()
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
    let mut room = 0usize;
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
        if longest > 1.5 * min_edge(w, h) {
            room += 1;
        }
        segments.insert((a.to_string(), b.to_string()), shared);
    }
    let tabs = tabs_in(&svg);
    let drawn: BTreeSet<(String, String)> = tabs
        .iter()
        .map(|(a, b, _)| (a.clone(), b.clone()))
        .collect();
    assert_eq!(drawn.len(), tabs.len(), "{name}: one tab per pair");
    for (a, b, outline) in &tabs {
        let shared = segments
            .get(&(a.clone(), b.clone()))
            .unwrap_or_else(|| panic!("{name}: tab {a}-{b} without a realised constraint"));
        let on_edge = |p: P| {
            shared
                .iter()
                .map(|s| distance_to_segment(p, *s))
                .fold(f64::INFINITY, f64::min)
        };
        // The base ends on the shared edge (the SVG writes two decimals).
        for p in [outline[0], outline[outline.len() - 1]] {
            let off = on_edge(p);
            assert!(
                off < 0.02,
                "{name}: tab {a}-{b} is {off} off its shared edge"
            );
        }
        // The head in one of the two cells, the tab small against both.
        let (pa, pb) = (points(&node(a)["polygon"]), points(&node(b)["polygon"]));
        let head = &outline[1..outline.len() - 1];
        assert!(
            head.iter().all(|p| inside(*p, &pa)) || head.iter().all(|p| inside(*p, &pb)),
            "{name}: tab {a}-{b} pokes out of both cells"
        );
        let knob = area(outline);
        for poly in [&pa, &pb] {
            assert!(
                knob <= 0.05 * area(poly),
                "{name}: tab {a}-{b} too large for its cell"
            );
        }
    }
    assert!(
        2 * tabs.len() >= room,
        "{name}: {} tabs for {room} realised constraints with room",
        tabs.len()
    );
    tabs.len()
}

#[test]
fn tabs_are_the_realized_constraints_with_room_on_their_edges() {
    let countries = check("country_pop_50M_AUS");
    let movies = check("imdb_100_genre_sim_2child");
    assert!(countries > 5 && movies > 5, "{countries} and {movies} tabs");
}
