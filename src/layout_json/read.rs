//! The layout-JSON reader: a `nptreemap-layout/1` document back into a
//! [`Previous`] layout, so that a file alone can seed a warm start (issue 6).
//! Owns the reading of that text and its error messages, which name the
//! offending field (`nodes[3].site`); may not open files (the caller passes the
//! text) or decide whether the layout fits a run ([`Previous::fits`]).
//!
//! Hostile input is an error, never a panic: the text goes through
//! `serde_json` (which limits nesting). A document is read first into typed
//! records (`Doc`), about 2.5 times quicker than a `Value` tree on the
//! stored layout of a 6,000-header tree (20 MB: the tree of values was a
//! fifth of a warm build's samples, issue 32); anything that path does not
//! accept is read again as a `Value` walked with checked accessors, whose
//! errors name the field. Both paths end in the same checks.

use serde::Deserialize;
use serde_json::{Map, Value};

use super::FORMAT;
use crate::geom::{ConvexPolygon, Point};
use crate::layout::{Canvas, Previous, PreviousNode};

/// Why layout JSON could not be read as a previous layout.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// The text is not JSON.
    #[error("not JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A field is missing or has the wrong type or value.
    #[error("`{field}`: {reason}")]
    Field {
        /// Where: `format`, `canvas.width`, `nodes[3].polygon[1]`, ...
        field: String,
        /// What is wrong.
        reason: String,
    },
}

/// Reads layout JSON (`nptreemap-layout/1`) text, as written by
/// [`super::write`]. Each node needs `id`, `parent`, `weight`, `site` and
/// `polygon`; `power_weight` is used when present (files from before it
/// existed still warm-start, in more steps; an only child needs none).
/// `constraints` is optional; only its `a`, `b`, `realized` and
/// `also_above` are read: a realised constraint with `also_above: k` gives
/// its pair and the pairs of the two nodes' ancestors k levels up.
///
/// A layout made for another canvas or outline reads fine; it is then not
/// used, and the layout starts cold ([`Previous::fits`]). Values no layout of
/// the document's canvas can have (a power weight of 1e308, a site far
/// outside the canvas: [`PreviousNode::check`]) are an error naming the field.
pub fn previous(text: &str) -> Result<Previous, ReadError> {
    match serde_json::from_str::<Doc>(text) {
        Ok(doc) => typed(doc).or_else(|_| by_value(text)),
        Err(_) => by_value(text),
    }
}

/// A document as typed records: the fields [`previous`] reads, each of the
/// type it must have. `format` and `parent` stay values, so that a missing
/// field is an error here too (serde takes a missing `Option` for `None`).
#[derive(Deserialize)]
struct Doc {
    format: Value,
    canvas: DocCanvas,
    nodes: Vec<DocNode>,
    #[serde(default)]
    constraints: Option<Vec<DocConstraint>>,
}

#[derive(Deserialize)]
struct DocCanvas {
    width: f64,
    height: f64,
}

#[derive(Deserialize)]
struct DocNode {
    id: String,
    parent: Value,
    weight: f64,
    site: [f64; 2],
    #[serde(default)]
    power_weight: Option<f64>,
    polygon: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
struct DocConstraint {
    a: String,
    b: String,
    realized: bool,
    #[serde(default)]
    also_above: Option<u64>,
}

/// The typed path's checks, the same as [`by_value`]'s: any failure sends
/// the text to [`by_value`] for the message that names the field.
fn typed(doc: Doc) -> Result<Previous, ReadError> {
    let wrong = || bad("the document", "read again field by field");
    if doc.format.as_str() != Some(FORMAT) || !(doc.canvas.width > 0.0 && doc.canvas.height > 0.0) {
        return Err(wrong());
    }
    let canvas = Canvas {
        width: doc.canvas.width,
        height: doc.canvas.height,
    };
    let nodes = doc
        .nodes
        .into_iter()
        .map(|n| {
            let parent = match n.parent {
                Value::Null => None,
                Value::String(p) => Some(p),
                _ => return Err(wrong()),
            };
            let points = n.polygon.iter().map(|&[x, y]| Point::new(x, y)).collect();
            Ok(PreviousNode {
                id: n.id,
                parent,
                weight: n.weight,
                site: Point::new(n.site[0], n.site[1]),
                power_weight: n.power_weight,
                polygon: ConvexPolygon::new(points).map_err(|_| wrong())?,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let realized = finish(canvas, &nodes)
        .and_then(|()| realized_from(doc.constraints.unwrap_or_default(), &nodes))?;
    Ok(Previous::new(canvas, nodes, realized))
}

/// The tree and canvas checks both paths end in.
fn finish(canvas: Canvas, nodes: &[PreviousNode]) -> Result<(), ReadError> {
    check_tree(nodes)?;
    for (i, n) in nodes.iter().enumerate() {
        n.check(canvas)
            .map_err(|(key, reason)| bad(format!("nodes[{i}].{key}"), reason))?;
    }
    Ok(())
}

/// The document walked as a `Value`, every field checked by name.
fn by_value(text: &str) -> Result<Previous, ReadError> {
    let doc: Value = serde_json::from_str(text)?;
    let top = object(&doc, "the document")?;
    match top.get("format").and_then(Value::as_str) {
        Some(FORMAT) => {}
        Some(other) => {
            return Err(bad(
                "format",
                format!("expected {FORMAT:?}, found {other:?}"),
            ));
        }
        None => return Err(bad("format", format!("missing; expected {FORMAT:?}"))),
    }
    let canvas = field(top, "canvas", "canvas")?;
    let canvas = object(canvas, "canvas")?;
    let canvas = Canvas {
        width: positive(field(canvas, "width", "canvas.width")?, "canvas.width")?,
        height: positive(field(canvas, "height", "canvas.height")?, "canvas.height")?,
    };
    let nodes = array(field(top, "nodes", "nodes")?, "nodes")?;
    let nodes = nodes
        .iter()
        .enumerate()
        .map(|(i, v)| node(v, &format!("nodes[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    finish(canvas, &nodes)?;
    let realized = match top.get("constraints") {
        None | Some(Value::Null) => Vec::new(),
        Some(v) => realized_from(constraints(v, nodes.len())?, &nodes)?,
    };
    Ok(Previous::new(canvas, nodes, realized))
}

fn bad(field: impl Into<String>, reason: impl Into<String>) -> ReadError {
    ReadError::Field {
        field: field.into(),
        reason: reason.into(),
    }
}

fn object<'a>(v: &'a Value, at: &str) -> Result<&'a Map<String, Value>, ReadError> {
    v.as_object().ok_or_else(|| bad(at, "expected an object"))
}

fn array<'a>(v: &'a Value, at: &str) -> Result<&'a Vec<Value>, ReadError> {
    v.as_array().ok_or_else(|| bad(at, "expected an array"))
}

fn field<'a>(obj: &'a Map<String, Value>, key: &str, at: &str) -> Result<&'a Value, ReadError> {
    obj.get(key).ok_or_else(|| bad(at, "missing"))
}

/// A finite number. serde_json never yields a non-finite one, but the check
/// keeps that assumption out of the geometry.
fn number(v: &Value, at: &str) -> Result<f64, ReadError> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| bad(at, "expected a number"))
}

fn positive(v: &Value, at: &str) -> Result<f64, ReadError> {
    let x = number(v, at)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(bad(at, "expected a positive number"))
    }
}

fn point(v: &Value, at: &str) -> Result<Point, ReadError> {
    match v.as_array().map(Vec::as_slice) {
        Some([x, y]) => Ok(Point::new(number(x, at)?, number(y, at)?)),
        _ => Err(bad(at, "expected [x, y]")),
    }
}

fn node(v: &Value, at: &str) -> Result<PreviousNode, ReadError> {
    let obj = object(v, at)?;
    let sub = |key: &str| format!("{at}.{key}");
    let id = field(obj, "id", &sub("id"))?
        .as_str()
        .ok_or_else(|| bad(sub("id"), "expected a string"))?
        .to_string();
    let parent = match field(obj, "parent", &sub("parent"))? {
        Value::Null => None,
        Value::String(p) => Some(p.clone()),
        _ => return Err(bad(sub("parent"), "expected a string or null")),
    };
    let weight = number(field(obj, "weight", &sub("weight"))?, &sub("weight"))?;
    let site = point(field(obj, "site", &sub("site"))?, &sub("site"))?;
    let power_weight = match obj.get("power_weight") {
        None | Some(Value::Null) => None,
        Some(w) => Some(number(w, &sub("power_weight"))?),
    };
    let points = array(field(obj, "polygon", &sub("polygon"))?, &sub("polygon"))?
        .iter()
        .enumerate()
        .map(|(k, p)| point(p, &format!("{at}.polygon[{k}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let polygon = ConvexPolygon::new(points).map_err(|e| bad(sub("polygon"), e.to_string()))?;
    Ok(PreviousNode {
        id,
        parent,
        weight,
        site,
        power_weight,
        polygon,
    })
}

/// Unique ids, exactly one root, and every parent id naming a node.
fn check_tree(nodes: &[PreviousNode]) -> Result<(), ReadError> {
    let mut seen = std::collections::HashSet::new();
    for (i, n) in nodes.iter().enumerate() {
        if !seen.insert(n.id.as_str()) {
            return Err(bad(
                format!("nodes[{i}].id"),
                format!("duplicate id {:?}", n.id),
            ));
        }
    }
    let mut roots = nodes.iter().enumerate().filter(|(_, n)| n.parent.is_none());
    match (roots.next(), roots.next()) {
        (None, _) => return Err(bad("nodes", "no root (a node with parent null)")),
        (Some(_), Some((i, _))) => {
            return Err(bad(format!("nodes[{i}].parent"), "a second root"));
        }
        _ => {}
    }
    for (i, n) in nodes.iter().enumerate() {
        if let Some(p) = &n.parent {
            if !seen.contains(p.as_str()) {
                return Err(bad(
                    format!("nodes[{i}].parent"),
                    format!("no node has id {p:?}"),
                ));
            }
        }
    }
    Ok(())
}

/// The constraints' fields [`realized_from`] reads, each checked by name.
fn constraints(v: &Value, nodes: usize) -> Result<Vec<DocConstraint>, ReadError> {
    array(v, "constraints")?
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let at = format!("constraints[{i}]");
            let obj = object(c, &at)?;
            let text = |key: &str| {
                field(obj, key, &format!("{at}.{key}"))?
                    .as_str()
                    .map(str::to_string)
                    .ok_or_else(|| bad(format!("{at}.{key}"), "expected a string"))
            };
            let (a, b) = (text("a")?, text("b")?);
            let realized = field(obj, "realized", &format!("{at}.realized"))?
                .as_bool()
                .ok_or_else(|| bad(format!("{at}.realized"), "expected true or false"))?;
            let also_above = match obj.get("also_above") {
                None | Some(Value::Null) => None,
                Some(k) => Some(
                    k.as_u64()
                        .filter(|&k| usize::try_from(k).is_ok_and(|k| k < nodes))
                        .ok_or_else(|| above_error(i))?,
                ),
            };
            Ok(DocConstraint {
                a,
                b,
                realized,
                also_above,
            })
        })
        .collect()
}

fn above_error(i: usize) -> ReadError {
    bad(
        format!("constraints[{i}].also_above"),
        "expected a count of levels (0 or more, below the node count)",
    )
}

/// The `(a, b)` id pairs of the constraints marked realised, with those
/// their `also_above` repeats on the levels above.
fn realized_from(
    constraints: Vec<DocConstraint>,
    nodes: &[PreviousNode],
) -> Result<Vec<(String, String)>, ReadError> {
    let parent: std::collections::HashMap<&str, Option<&str>> = nodes
        .iter()
        .map(|n| (n.id.as_str(), n.parent.as_deref()))
        .collect();
    let mut out = Vec::new();
    for (i, c) in constraints.into_iter().enumerate() {
        let above = match c.also_above {
            None => 0,
            Some(k) => usize::try_from(k)
                .ok()
                .filter(|&k| k < nodes.len())
                .ok_or_else(|| above_error(i))?,
        };
        if !c.realized {
            continue;
        }
        // Bounded: each step climbs a level, at most `nodes.len()` of them.
        let (mut x, mut y) = (c.a.clone(), c.b.clone());
        out.push((c.a, c.b));
        for _ in 0..above {
            match (parent.get(x.as_str()), parent.get(y.as_str())) {
                (Some(Some(px)), Some(Some(py))) => {
                    (x, y) = (px.to_string(), py.to_string());
                    out.push((x.clone(), y.clone()));
                }
                _ => {
                    return Err(bad(
                        format!("constraints[{i}].also_above"),
                        format!("reaches above the root from {x:?} or {y:?}"),
                    ))
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{compute, Params, Request};
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec};

    fn dataset() -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for g in ["A", "B"] {
            b.add(NodeSpec::new(g).parent("root"));
            for k in 0..3 {
                b.add(
                    NodeSpec::new(format!("{g}{k}"))
                        .parent(g)
                        .weight(1.0 + k as f64),
                );
            }
        }
        b.build().expect("valid")
    }

    fn sample_text() -> (Dataset, String) {
        let ds = dataset();
        let c = compute(&ds, &Request::default()).expect("layout");
        let text = super::super::document(&c);
        (ds, text)
    }

    #[test]
    fn reads_what_the_writer_writes() {
        let (ds, text) = sample_text();
        let c = compute(&ds, &Request::default()).expect("layout");
        let prev = previous(&text).expect("reads");
        assert_eq!(prev.nodes().len(), ds.len());
        assert_eq!(prev.canvas(), Params::default().canvas);
        assert_eq!(prev.root().map(|r| r.id.as_str()), Some("root"));
        let a1 = prev.get("A1").expect("A1");
        assert_eq!(a1.parent.as_deref(), Some("A"));
        let i = ds.find("A1").expect("A1");
        // Power weights and sites on the canvas's grid (1e-4 on 1000 × 1000),
        // and bit for bit from the stored state.
        let exact = c.layout.cells[i].power_weight;
        assert!((a1.power_weight.expect("written") - exact).abs() <= 0.5e-4);
        assert!(a1.site.distance(c.layout.cells[i].site) <= 0.71e-4);
        let stored = previous(&super::super::state(&c)).expect("reads");
        assert_eq!(stored.get("A1").and_then(|n| n.power_weight), Some(exact));
        assert_eq!(
            stored.get("A1").map(|n| n.site),
            Some(c.layout.cells[i].site)
        );
        prev.fits(&ds, &Params::default())
            .expect("fits its own dataset");
    }

    #[test]
    fn the_typed_path_reads_what_the_field_by_field_path_reads() {
        // The stored state (full precision) and the layout JSON output
        // (`also_above_gives_back_the_pairs_of_the_levels_above` reads
        // constraints through the typed path).
        let (ds, text) = sample_text();
        let c = compute(&ds, &Request::default()).expect("layout");
        for text in [text, super::super::state(&c)] {
            let doc: Doc = serde_json::from_str(&text).expect("typed");
            let typed = typed(doc).expect("typed path reads it");
            assert_eq!(typed, by_value(&text).expect("reads"));
            assert_eq!(previous(&text).expect("reads"), typed);
        }
    }

    /// The error for `text`, which must name `field`.
    fn error_names(text: &str, field: &str) {
        match previous(text) {
            Err(ReadError::Field { field: f, .. }) => assert_eq!(f, field, "{text}"),
            other => panic!("expected an error at {field}, got {other:?}"),
        }
    }

    #[test]
    fn bad_files_are_errors_that_name_the_field() {
        let (_, text) = sample_text();
        let edit = |from: &str, to: &str| {
            assert!(text.contains(from), "{from}");
            text.replacen(from, to, 1)
        };
        error_names(&edit("nptreemap-layout/1", "other/2"), "format");
        error_names(&edit("\"format\": \"nptreemap-layout/1\",", ""), "format");
        error_names(&edit("\"width\":1000", "\"width\":-1"), "canvas.width");
        error_names(
            &edit("\"height\":1000", "\"height\":\"tall\""),
            "canvas.height",
        );
        error_names(&edit("\"id\":\"A\"", "\"id\":7"), "nodes[1].id");
        error_names(&edit("\"id\":\"B\"", "\"id\":\"A\""), "nodes[2].id");
        error_names(
            &edit("\"parent\":\"A\"", "\"parent\":\"Z\""),
            "nodes[3].parent",
        );
        error_names(
            &edit("\"parent\":\"root\"", "\"parent\":null"),
            "nodes[1].parent",
        );
        error_names(&edit("\"site\":[", "\"site\":[1,"), "nodes[0].site");
        error_names(
            &edit("\"power_weight\":0,", "\"power_weight\":\"x\","),
            "nodes[0].power_weight",
        );
        error_names(
            &edit("\"polygon\":[[0,0],", "\"polygon\":[[0],"),
            "nodes[0].polygon[0]",
        );
        error_names(
            &edit("\"polygon\":[[0,0],", "\"polygon\":[[0,0],[5,5],[2,2],"),
            "nodes[0].polygon",
        );
        error_names(&edit("\"nodes\": [", "\"nodes\": 3, \"x\": ["), "nodes");
    }

    #[test]
    fn hostile_text_is_an_error_not_a_panic() {
        for text in [
            "",
            "null",
            "[]",
            "{\"format\": \"nptreemap-layout/1\"}",
            &"[".repeat(100_000),
            "{\"format\": \"nptreemap-layout/1\", \"canvas\": {\"width\": 1e999, \"height\": 1}}",
            "{\"format\": \"nptreemap-layout/1\", \"canvas\": {\"width\": 1, \"height\": 1}, \"nodes\": []}",
            "{\"format\": \"nptreemap-layout/1\", \"canvas\": {\"width\": 1, \"height\": 1}, \"nodes\": [{}]}",
        ] {
            assert!(previous(text).is_err(), "{text:.60}");
        }
    }

    #[test]
    fn files_without_power_weights_still_read() {
        let (ds, text) = sample_text();
        let mut v: Value = serde_json::from_str(&text).expect("json");
        for n in v["nodes"].as_array_mut().expect("nodes") {
            n.as_object_mut().expect("object").remove("power_weight");
        }
        let prev = previous(&v.to_string()).expect("reads");
        assert!(prev.nodes().iter().all(|n| n.power_weight.is_none()));
        prev.fits(&ds, &Params::default()).expect("fits");
    }
    /// Issue 21, item 8: a stored layout whose power weights were 1e308 gave
    /// a degenerate picture (continents of zero area) with no word. Values no
    /// layout of the canvas can have are refused, naming the field, so the
    /// caller warns and starts cold.
    #[test]
    fn values_no_layout_can_have_are_refused_naming_the_field() {
        let (_, text) = sample_text();
        let doc: Value = serde_json::from_str(&text).expect("json");
        let with = |i: usize, key: &str, value: Value| {
            let mut d = doc.clone();
            d["nodes"][i][key] = value;
            d.to_string()
        };
        for w in [1e308, -1e308, 1e12] {
            error_names(
                &with(3, "power_weight", serde_json::json!(w)),
                "nodes[3].power_weight",
            );
        }
        for site in [[-50.0, 10.0], [10.0, 1e9], [1e300, 1e300]] {
            error_names(&with(2, "site", serde_json::json!(site)), "nodes[2].site");
        }
        error_names(
            &with(4, "weight", serde_json::json!(-1.0)),
            "nodes[4].weight",
        );
        error_names(
            &with(
                5,
                "polygon",
                serde_json::json!([[0.0, 0.0], [5e6, 0.0], [0.0, 5e6]]),
            ),
            "nodes[5].polygon",
        );
        // What layouts do have still reads: weights of a few squared canvas
        // diagonals (the prototype's reach 2.3), sites on the border.
        previous(&with(3, "power_weight", serde_json::json!(-5e6))).expect("reads");
        previous(&with(2, "site", serde_json::json!([0.0, 1000.0]))).expect("reads");
    }

    /// `also_above: k` stands for the same realised pair between the two
    /// nodes' ancestors on the k levels above; a count that climbs past the
    /// root is an error naming the field.
    #[test]
    fn also_above_gives_back_the_pairs_of_the_levels_above() {
        let doc = |above: u64| {
            let node = |id: &str, parent: Value, x: f64| {
                serde_json::json!({"id": id, "parent": parent, "weight": 1, "site": [x + 2.5, 5],
                    "polygon": [[x, 0], [x + 5.0, 0], [x + 5.0, 10], [x, 10]]})
            };
            serde_json::json!({
                "format": FORMAT,
                "canvas": {"width": 10, "height": 10},
                "nodes": [
                    {"id": "r", "parent": null, "weight": 2, "site": [5, 5],
                     "polygon": [[0, 0], [10, 0], [10, 10], [0, 10]]},
                    node("a", "r".into(), 0.0), node("b", "r".into(), 5.0),
                    node("a2", "a".into(), 0.0), node("b2", "b".into(), 5.0),
                ],
                "constraints": [{"a": "a2", "b": "b2", "similarity": 0.5, "strength": 2,
                                 "realized": true, "also_above": above}],
            })
            .to_string()
        };
        let pairs = |p: Previous| p.realized().to_vec();
        let pair = |a: &str, b: &str| (a.to_string(), b.to_string());
        assert_eq!(pairs(previous(&doc(0)).unwrap()), [pair("a2", "b2")]);
        assert_eq!(
            pairs(previous(&doc(1)).unwrap()),
            [pair("a2", "b2"), pair("a", "b")]
        );
        error_names(&doc(3), "constraints[0].also_above");
        error_names(
            &doc(1).replace("\"also_above\":1", "\"also_above\":-1"),
            "constraints[0].also_above",
        );
    }
}
