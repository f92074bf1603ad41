//! The layout-JSON writer: a finished [`Layout`](crate::layout::Layout) and its
//! [`Dataset`](nptreemap_formats::Dataset) become one `nptreemap-layout/1`
//! document. Owns the document's shape and number formatting; may not compute
//! geometry, decide which constraints are realized, or do I/O.
//!
//! The outer structure is written by hand so that each node sits on its own line
//! (diffs of two layouts then show which nodes moved); each node, constraint and
//! number is serialised by `serde_json`, so quoting and escaping are never ours.

use nptreemap_formats::Dataset;
use serde::{Serialize, Serializer};

use super::extras::JsonExtras;
use super::FORMAT;
use crate::geom::Point;
use crate::layout::Layout;

/// Decimal places kept in coordinates. Rounding gives stable diffs (round-off
/// noise in the last bits does not show up as a change) and smaller files; 1e-6
/// canvas units is far below the checker's containment and shared-edge tolerances.
const COORD_DECIMALS: i32 = 6;

/// Writes the layout JSON document for `layout`, whose cells are indexed like
/// `dataset`'s nodes. Ends with a newline. Identical input gives identical bytes.
pub fn layout_json(dataset: &Dataset, layout: &Layout, extra: &JsonExtras) -> String {
    debug_assert_eq!(dataset.len(), layout.cells.len(), "one cell per node");
    let mut out = String::with_capacity(256 + 200 * layout.cells.len());
    out.push_str("{\n");
    out.push_str(&format!("  \"format\": {},\n", to_json(&FORMAT)));
    let exact = extra.exact;
    let canvas = CanvasOut {
        width: Coord(layout.canvas.width, exact),
        height: Coord(layout.canvas.height, exact),
    };
    out.push_str(&format!("  \"canvas\": {},\n", to_json(&canvas)));

    let nodes = dataset
        .nodes()
        .iter()
        .zip(&layout.cells)
        .map(|(node, cell)| NodeOut {
            id: &node.id,
            label: &node.label,
            parent: node.parent.map(|p| dataset.node(p).id.as_str()),
            depth: node.depth,
            weight: Num(node.value),
            is_virtual: node.is_virtual,
            site: point(cell.site, exact),
            power_weight: Num(cell.power_weight),
            polygon: cell
                .polygon
                .points()
                .iter()
                .map(|p| point(*p, exact))
                .collect(),
        });
    push_array(&mut out, "nodes", nodes);
    out.push(',');
    out.push('\n');

    let constraints = extra.constraints.iter().map(|c| ConstraintRow {
        a: &c.a,
        b: &c.b,
        similarity: Num(c.similarity),
        strength: c.strength,
        realized: c.realized,
    });
    push_array(&mut out, "constraints", constraints);

    if !extra.metrics.is_empty() {
        out.push_str(",\n  \"metrics\": {");
        for (i, (key, value)) in extra.metrics.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            out.push_str(&format!(
                "\n    {}: {}",
                to_json(key),
                to_json(&Num(*value))
            ));
        }
        out.push_str("\n  }");
    }
    out.push_str("\n}\n");
    out
}

/// Appends `  "name": [` + one element per line + `  ]` (or `[]` when empty).
fn push_array<T: Serialize>(out: &mut String, name: &str, items: impl Iterator<Item = T>) {
    out.push_str(&format!("  \"{name}\": ["));
    let mut any = false;
    for item in items {
        out.push_str(if any { ",\n    " } else { "\n    " });
        out.push_str(&to_json(&item));
        any = true;
    }
    out.push_str(if any { "\n  ]" } else { "]" });
}

/// Compact JSON for one value.
fn to_json<T: Serialize + ?Sized>(value: &T) -> String {
    // serde_json fails only on maps with non-string keys or on a Serialize impl
    // that reports an error; the types here have neither, and non-finite floats
    // are mapped to 0 by `Num`/`Coord` before serde_json sees them.
    serde_json::to_string(value).expect("plain structs of strings and numbers serialise")
}

fn point(p: Point, exact: bool) -> [Coord; 2] {
    [Coord(p.x, exact), Coord(p.y, exact)]
}

#[derive(Serialize)]
struct CanvasOut {
    width: Coord,
    height: Coord,
}

/// One entry of `nodes`, fields in the spec's order.
#[derive(Serialize)]
struct NodeOut<'a> {
    id: &'a str,
    label: &'a str,
    parent: Option<&'a str>,
    depth: usize,
    weight: Num,
    #[serde(rename = "virtual")]
    is_virtual: bool,
    site: [Coord; 2],
    /// Not in the spec's list (it allows new fields): the site's power weight,
    /// written in full precision so that this file alone can seed a warm start
    /// (issue 6) that reproduces the cells.
    power_weight: Num,
    polygon: Vec<[Coord; 2]>,
}

/// One entry of `constraints`; a borrowed copy of [`ConstraintOut`] with the
/// similarity guarded against non-finite values.
#[derive(Serialize)]
struct ConstraintRow<'a> {
    a: &'a str,
    b: &'a str,
    similarity: Num,
    strength: u8,
    realized: bool,
}

/// A coordinate: rounded to [`COORD_DECIMALS`] places when written, unless
/// the second field asks for full precision.
#[derive(Clone, Copy)]
struct Coord(f64, bool);

/// Any other number: written as is, except that non-finite values become 0.
#[derive(Clone, Copy)]
struct Num(f64);

impl Serialize for Coord {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.1 {
            s.serialize_f64(finite(self.0) + 0.0)
        } else {
            s.serialize_f64(round_coord(self.0))
        }
    }
}

impl Serialize for Num {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(finite(self.0))
    }
}

/// `v` rounded to [`COORD_DECIMALS`] places, never `-0.0`, never non-finite.
///
/// Dividing the rounded integer by the power of ten gives the double nearest to
/// the decimal, so serde_json's shortest round-trip output prints exactly that
/// decimal (no `0.30000000000000004` tails).
fn round_coord(v: f64) -> f64 {
    let scale = 10f64.powi(COORD_DECIMALS);
    // `+ 0.0` turns -0.0 into 0.0 (IEEE: -0 + +0 = +0), so a coordinate that
    // rounds to zero from below is not written as "-0.0".
    finite((v * scale).round() / scale) + 0.0
}

/// Non-finite numbers are a bug upstream (a finished layout is finite); JSON
/// cannot hold them, so release builds write 0 rather than produce a file the
/// checker rejects as unparseable.
fn finite(v: f64) -> f64 {
    debug_assert!(
        v.is_finite(),
        "non-finite number reached the layout JSON: {v}"
    );
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::extras::ConstraintOut;
    use super::*;
    use crate::render::test_support::sample;
    use serde_json::Value;

    #[test]
    fn document_has_the_spec_fields_and_types() {
        let (dataset, layout) = sample();
        let text = layout_json(&dataset, &layout, &JsonExtras::default());
        assert!(text.ends_with("}\n"));
        let v: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["format"], "nptreemap-layout/1");
        assert_eq!(v["canvas"]["width"].as_f64(), Some(400.0));
        assert_eq!(v["canvas"]["height"].as_f64(), Some(200.0));
        assert!(v.get("metrics").is_none(), "metrics left out when empty");
        assert_eq!(v["constraints"].as_array().map(Vec::len), Some(0));

        let nodes = v["nodes"].as_array().unwrap();
        assert_eq!(nodes.len(), dataset.len());
        for (n, node) in nodes.iter().zip(dataset.nodes()) {
            let keys: Vec<&str> = n.as_object().unwrap().keys().map(String::as_str).collect();
            for k in [
                "id",
                "label",
                "parent",
                "depth",
                "weight",
                "virtual",
                "site",
                "power_weight",
                "polygon",
            ] {
                assert!(keys.contains(&k), "missing {k}");
            }
            assert_eq!(n["id"], node.id.as_str());
            assert_eq!(n["label"], node.label.as_str());
            assert_eq!(n["depth"].as_u64(), Some(node.depth as u64));
            assert_eq!(n["weight"].as_f64(), Some(node.value));
            assert_eq!(n["virtual"], false);
            assert_eq!(n["site"].as_array().unwrap().len(), 2);
            let poly = n["polygon"].as_array().unwrap();
            assert!(poly.len() >= 3);
            assert!(poly
                .iter()
                .all(|p| p.as_array().unwrap().iter().all(Value::is_f64)));
            match node.parent {
                None => assert!(n["parent"].is_null()),
                Some(p) => assert_eq!(n["parent"], dataset.node(p).id.as_str()),
            }
        }
        // The hand-written layout: one node per line.
        let node_lines = text
            .lines()
            .filter(|l| l.starts_with("    {\"id\":"))
            .count();
        assert_eq!(node_lines, dataset.len());
    }

    #[test]
    fn parents_name_their_ids() {
        let (dataset, layout) = sample();
        let v: Value =
            serde_json::from_str(&layout_json(&dataset, &layout, &JsonExtras::default())).unwrap();
        let parent_of = |id: &str| {
            v["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|n| n["id"] == id)
                .unwrap()["parent"]
                .clone()
        };
        assert!(parent_of("root").is_null());
        assert_eq!(parent_of("A"), "root");
        assert_eq!(parent_of("A1"), "A");
        assert_eq!(parent_of("A3"), "A");
    }

    #[test]
    fn constraints_and_metrics_in_order() {
        let (dataset, layout) = sample();
        let extra = JsonExtras {
            constraints: vec![ConstraintOut {
                a: "A".into(),
                b: "B".into(),
                similarity: 0.83,
                strength: 3,
                realized: true,
            }],
            metrics: vec![("zeta".into(), 1.5), ("alpha".into(), f64::from(2u8))],
            exact: false,
        };
        let text = layout_json(&dataset, &layout, &extra);
        let v: Value = serde_json::from_str(&text).unwrap();
        let c = &v["constraints"][0];
        assert_eq!((c["a"].as_str(), c["b"].as_str()), (Some("A"), Some("B")));
        assert_eq!(c["similarity"].as_f64(), Some(0.83));
        assert_eq!(c["strength"].as_u64(), Some(3));
        assert_eq!(c["realized"], true);
        assert_eq!(v["metrics"]["zeta"].as_f64(), Some(1.5));
        let zeta = text.find("\"zeta\"").unwrap();
        let alpha = text.find("\"alpha\"").unwrap();
        assert!(zeta < alpha, "metrics keep the caller's order");
    }

    #[test]
    fn exact_coordinates_round_trip_bit_for_bit() {
        let v = 1.0 / 3.0 + 123.456;
        let text = to_json(&Coord(v, true));
        assert_eq!(text.parse::<f64>().ok(), Some(v));
        assert_eq!(to_json(&Coord(-0.0, true)), "0.0");
    }

    #[test]
    fn coordinates_are_rounded_to_six_places() {
        assert_eq!(round_coord(1.0 / 3.0), 0.333333);
        assert_eq!(to_json(&Coord(1.0 / 3.0, false)), "0.333333");
        assert_eq!(to_json(&Coord(0.1 + 0.2, false)), "0.3");
        assert_eq!(to_json(&Coord(-1e-9, false)), "0.0");
        assert_eq!(to_json(&Coord(-0.0, false)), "0.0");
        assert_eq!(to_json(&Coord(-2.5000004, false)), "-2.5");
        assert_eq!(to_json(&Num(1411778724.0)), "1411778724.0");

        let (dataset, layout) = sample();
        let text = layout_json(&dataset, &layout, &JsonExtras::default());
        let v: Value = serde_json::from_str(&text).unwrap();
        for n in v["nodes"].as_array().unwrap() {
            for p in n["polygon"].as_array().unwrap().iter().chain([&n["site"]]) {
                for x in p.as_array().unwrap() {
                    let s = x.to_string();
                    let decimals = s.split_once('.').map_or(0, |(_, f)| f.len());
                    assert!(decimals <= 6, "{s}");
                }
            }
        }
    }

    #[test]
    fn output_is_deterministic() {
        let (dataset, layout) = sample();
        let a = layout_json(&dataset, &layout, &JsonExtras::default());
        let b = layout_json(&dataset, &layout, &JsonExtras::default());
        assert_eq!(a, b);
    }

    #[test]
    fn user_text_is_escaped_by_serde() {
        let (dataset, layout) = sample();
        let text = layout_json(&dataset, &layout, &JsonExtras::default());
        let v: Value = serde_json::from_str(&text).unwrap();
        assert!(v["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n["label"] == "<script>alert(1)</script> \"q\""));
    }
}
