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

use rayon::prelude::*;

use std::sync::Arc;

use super::extras::JsonExtras;
use super::precision;
use super::spelled;
use super::DocumentMemo;
use super::FORMAT;
use crate::geom::Point;
use crate::layout::{Layout, ZeroItems};
use crate::line_memo::{Line, LineMemo};

/// Decimals of a constraint's `similarity`: the bins it fell into were
/// chosen from the exact value; a reader sees which pairs are alike and how
/// much, for which four places (0.8333) are plenty.
const SIMILARITY_DECIMALS: i32 = 4;

/// Writes the layout JSON document for `layout`, whose cells are indexed like
/// `dataset`'s nodes. Ends with a newline. Identical input gives identical bytes.
///
/// Coordinates (and power weights) are rounded to a grid chosen from the
/// canvas, finer for the cells that need it (the `precision` module), or written in
/// full precision when `extra.exact`. An only child's `power_weight` is left
/// out: its cell is its parent's whatever the weight (always 0).
pub fn layout_json(dataset: &Dataset, layout: &Layout, extra: &JsonExtras) -> String {
    layout_json_with(dataset, layout, extra, None)
}

/// [`layout_json`] with the memo of the documents written before
/// ([`DocumentMemo`]): the node lines it can take from there are taken, and
/// the precision choice takes over the checks of cells spelled as before;
/// the bytes are the same.
pub fn layout_json_with(
    dataset: &Dataset,
    layout: &Layout,
    extra: &JsonExtras,
    memo: Option<&DocumentMemo>,
) -> String {
    write_document(dataset, layout, extra, extra.exact, memo)
}

/// [`layout_json_with`], in full precision when `exact` whatever
/// `extra.exact` says (the stored layout shares the output's extras).
pub(super) fn write_document(
    dataset: &Dataset,
    layout: &Layout,
    extra: &JsonExtras,
    exact: bool,
    memo: Option<&DocumentMemo>,
) -> String {
    debug_assert_eq!(dataset.len(), layout.cells.len(), "one cell per node");
    let spelled = if exact {
        Arc::new(spelled::exact(layout))
    } else {
        let entries = extra.constraints.entries();
        let pairs: Vec<(usize, usize, bool)> = match extra.constraints.nodes() {
            Some(nodes) => nodes
                .iter()
                .zip(entries)
                .map(|(&(a, b), c)| (a, b, c.realized))
                .collect(),
            None => entries
                .iter()
                .filter_map(|c| Some((dataset.find(&c.a)?, dataset.find(&c.b)?, c.realized)))
                .collect(),
        };
        precision::choose(dataset, layout, &pairs, memo.map(|m| &m.checks))
    };
    let lines = memo.and_then(DocumentMemo::lines);
    // About what a node and a constraint take (a 6,000-leaf tree: 16 MB
    // for 38,629 nodes and 27,000 constraints), so the text grows rarely.
    let mut out =
        String::with_capacity(256 + 330 * layout.cells.len() + 110 * extra.constraints.len());
    out.push_str("{\n");
    out.push_str(&format!("  \"format\": {},\n", to_json(&FORMAT)));
    let canvas = CanvasOut {
        width: Num(layout.canvas.width),
        height: Num(layout.canvas.height),
    };
    out.push_str(&format!("  \"canvas\": {},\n", to_json(&canvas)));

    let nodes = dataset
        .nodes()
        .par_iter()
        .zip(&layout.cells)
        .zip(spelled.par_iter())
        .enumerate()
        .map(|(index, ((node, cell), spelled))| {
            let only_child = node
                .parent
                .is_some_and(|p| dataset.node(p).children.len() == 1);
            NodeOut {
                id: &node.id,
                label: &node.label,
                parent: node.parent.map(|p| dataset.node(p).id.as_str()),
                depth: node.depth,
                weight: Num(node.value),
                drawn_weight: extra
                    .drawn_weights
                    .as_ref()
                    .and_then(|d| d.get(index))
                    .filter(|w| **w != node.value)
                    .map(|w| Num(*w)),
                is_virtual: node.is_virtual,
                site: point(spelled.site),
                power_weight: (!only_child)
                    .then(|| Num(spelled::round(cell.power_weight, spelled.places))),
                polygon: Points(&spelled.polygon),
            }
        });
    match lines {
        Some(lines) => push_nodes(&mut out, nodes.collect(), exact, lines),
        None => {
            let nodes: Vec<NodeOut<'_>> = nodes.collect();
            push_array(&mut out, "nodes", nodes.iter());
        }
    }
    out.push(',');
    out.push('\n');

    // Spelled alike in both precisions: written once per list.
    out.push_str(extra.constraints.text(|| {
        let rows = extra.constraints.entries().iter().map(|c| ConstraintRow {
            a: &c.a,
            b: &c.b,
            similarity: Num(spelled::round(c.similarity, Some(SIMILARITY_DECIMALS))),
            strength: c.strength,
            realized: c.realized,
            also_above: (c.also_above > 0).then_some(c.also_above),
        });
        let mut text = String::with_capacity(110 * extra.constraints.len());
        push_array(&mut text, "constraints", rows);
        text
    }));

    push_zero_weights(&mut out, &extra.zero);
    push_metrics(&mut out, &extra.metrics);
    out.push_str("\n}\n");
    out
}

/// Appends the items of weight 0 (issue 34), only when there are any: the
/// setting and their count, and with `hide` the nodes left out (no cell:
/// the checker's rules are about cells).
fn push_zero_weights(out: &mut String, zero: &ZeroItems) {
    if zero.items > 0 {
        let summary = ZeroOut {
            mode: zero.mode.name(),
            items: zero.items,
        };
        out.push_str(&format!(",\n  \"zero_weights\": {}", to_json(&summary)));
    }
    if !zero.hidden.is_empty() {
        out.push_str(",\n");
        let hidden = zero.hidden.iter().map(|h| HiddenOut {
            id: &h.id,
            label: &h.label,
            parent: &h.parent,
            depth: h.depth,
            weight: Num(0.0),
        });
        push_array(out, "hidden", hidden);
    }
}

/// Appends the `metrics` object, only when there are any.
fn push_metrics(out: &mut String, metrics: &[(String, f64)]) {
    if !metrics.is_empty() {
        out.push_str(",\n  \"metrics\": {");
        for (i, (key, value)) in metrics.iter().enumerate() {
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
}

/// Appends `  "name": [` + one element per line + `  ]` (or `[]` when empty).
/// Elements are not indented: one per line keeps diffs readable, and on a
/// deep tree four spaces a line were 2% of the file.
fn push_array<T: Serialize>(out: &mut String, name: &str, items: impl Iterator<Item = T>) {
    out.push_str(&format!("  \"{name}\": ["));
    let mut any = false;
    // One buffer for every element: a String allocated and freed per node
    // was a fifth of the writer's time on 38,000 nodes.
    let mut buf = Vec::with_capacity(512);
    for item in items {
        out.push_str(if any { ",\n" } else { "\n" });
        buf.clear();
        serde_json::to_writer(&mut buf, &item)
            .expect("plain structs of strings and numbers serialise");
        out.push_str(std::str::from_utf8(&buf).expect("serde_json writes UTF-8"));
        any = true;
    }
    out.push_str(if any { "\n  ]" } else { "]" });
}

/// Compact JSON for one value.
fn to_json<T: Serialize + ?Sized>(value: &T) -> String {
    // serde_json fails only on maps with non-string keys or on a Serialize impl
    // that reports an error; the types here have neither, and non-finite floats
    // are mapped to 0 by `Num` before serde_json sees them.
    serde_json::to_string(value).expect("plain structs of strings and numbers serialise")
}

fn point(p: Point) -> [Num; 2] {
    [Num(p.x), Num(p.y)]
}

/// The `nodes` array from `nodes`' lines: those in `lines` taken from it,
/// the others serialised (in parallel) and kept there.
fn push_nodes(out: &mut String, nodes: Vec<NodeOut<'_>>, exact: bool, lines: &LineMemo) {
    let keys: Vec<u128> = nodes.par_iter().map(|n| n.digest(exact)).collect();
    let mut found = lines.find(&keys);
    let written: Vec<(usize, Line)> = found
        .iter()
        .enumerate()
        .filter(|(_, f)| f.is_none())
        .map(|(k, _)| k)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|k| (k, Line::from(to_json(&nodes[k]))))
        .collect();
    let kept = written
        .iter()
        .map(|(k, line)| (keys[*k], line.clone()))
        .collect();
    for (k, line) in written {
        found[k] = Some(line);
    }
    out.push_str("  \"nodes\": [");
    for (k, line) in found.iter().enumerate() {
        out.push_str(if k == 0 { "\n" } else { ",\n" });
        out.push_str(line.as_deref().expect("every line found or written"));
    }
    out.push_str(if found.is_empty() { "]" } else { "\n  ]" });
    lines.keep(kept);
}

/// A polygon's vertices as `[[x, y], …]`, borrowed.
#[derive(Clone, Copy)]
struct Points<'a>(&'a [Point]);

impl Serialize for Points<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter().map(|p| point(*p)))
    }
}

#[derive(Serialize)]
struct CanvasOut {
    width: Num,
    height: Num,
}

/// One entry of `nodes`, fields in the spec's order.
#[derive(Serialize)]
struct NodeOut<'a> {
    id: &'a str,
    label: &'a str,
    parent: Option<&'a str>,
    depth: usize,
    weight: Num,
    /// Not in the spec's list: with `zero_weights: floor`, the weight an
    /// item of weight 0 is drawn at (the floor), against which the
    /// document's own area errors are measured (issue 34).
    #[serde(skip_serializing_if = "Option::is_none")]
    drawn_weight: Option<Num>,
    #[serde(rename = "virtual")]
    is_virtual: bool,
    site: [Num; 2],
    /// Not in the spec's list (it allows new fields): the site's power weight,
    /// so that this file alone can seed a warm start (issue 6) that reproduces
    /// the cells; left out for an only child, whose cell needs none.
    #[serde(skip_serializing_if = "Option::is_none")]
    power_weight: Option<Num>,
    polygon: Points<'a>,
}

impl NodeOut<'_> {
    /// A digest of everything the line spells, and of the document's
    /// precision: two nodes with one digest have one line. Every field
    /// above is fed here, in order.
    fn digest(&self, exact: bool) -> u128 {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        let text = |h: &mut xxhash_rust::xxh3::Xxh3, t: &str| {
            h.update(&t.len().to_le_bytes());
            h.update(t.as_bytes());
        };
        let num = |h: &mut xxhash_rust::xxh3::Xxh3, n: Option<Num>| match n {
            Some(Num(v)) => h.update(&v.to_bits().to_le_bytes()),
            None => h.update(b"-"),
        };
        h.update(&[u8::from(exact)]);
        text(&mut h, self.id);
        text(&mut h, self.label);
        match self.parent {
            Some(p) => text(&mut h, p),
            None => h.update(b"-"),
        }
        h.update(&self.depth.to_le_bytes());
        num(&mut h, Some(self.weight));
        num(&mut h, self.drawn_weight);
        h.update(&[u8::from(self.is_virtual)]);
        num(&mut h, Some(self.site[0]));
        num(&mut h, Some(self.site[1]));
        num(&mut h, self.power_weight);
        h.update(&self.polygon.0.len().to_le_bytes());
        for p in self.polygon.0 {
            h.update(&p.x.to_bits().to_le_bytes());
            h.update(&p.y.to_bits().to_le_bytes());
        }
        h.digest128()
    }
}

/// The `zero_weights` object: the setting and how many items it applied to.
#[derive(Serialize)]
struct ZeroOut {
    mode: &'static str,
    items: usize,
}

/// One entry of `hidden`: a node left out for its weight of 0, as the
/// nodes are written but without geometry.
#[derive(Serialize)]
struct HiddenOut<'a> {
    id: &'a str,
    label: &'a str,
    parent: &'a str,
    depth: usize,
    weight: Num,
}

/// One entry of `constraints`; a borrowed copy of [`super::ConstraintOut`]
/// with the similarity guarded against non-finite values.
#[derive(Serialize)]
struct ConstraintRow<'a> {
    a: &'a str,
    b: &'a str,
    similarity: Num,
    strength: u8,
    realized: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    also_above: Option<usize>,
}

/// A number, written in the shortest form that reads back as the same
/// double: a whole number without `.0` (`1000`, not `1000.0`), and
/// non-finite values as 0.
#[derive(Clone, Copy)]
struct Num(f64);

/// Largest magnitude written as an integer: every whole double up to it is
/// exact as an i64 and reads back as the same double.
const WHOLE_LIMIT: f64 = 9_007_199_254_740_992.0; // 2^53

impl Serialize for Num {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let v = finite(self.0) + 0.0;
        if v.fract() == 0.0 && v.abs() <= WHOLE_LIMIT {
            s.serialize_i64(v as i64)
        } else {
            s.serialize_f64(v)
        }
    }
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
    use super::super::extras::{ConstraintList, ConstraintOut};
    use super::*;
    use crate::line_memo::LineCounts;
    use crate::render::test_support::sample;
    use serde_json::Value;

    /// Issue 32, item 2: a document written with the node lines of the one
    /// before is byte for byte the document written from scratch, and
    /// formats only the lines of the nodes that changed.
    #[test]
    fn node_lines_from_the_last_document_give_the_same_bytes() {
        let (dataset, layout) = sample();
        let memo = DocumentMemo::with_lines();
        let lines = &memo.lines;
        for exact in [false, true] {
            let extra = JsonExtras {
                exact,
                ..JsonExtras::default()
            };
            let plain = layout_json(&dataset, &layout, &extra);
            assert_eq!(
                layout_json_with(&dataset, &layout, &extra, Some(&memo)),
                plain
            );
        }
        let counts = lines.next_build();
        assert_eq!((counts.reused, counts.written), (0, 2 * dataset.len()));
        // One cell moved: only its line is written again.
        let mut moved = layout.clone();
        let leaf = dataset.find("A3").expect("A3");
        moved.cells[leaf].site = Point::new(moved.cells[leaf].site.x + 1.0, 199.0);
        let extra = JsonExtras::default();
        assert_eq!(
            layout_json_with(&dataset, &moved, &extra, Some(&memo)),
            layout_json(&dataset, &moved, &extra)
        );
        assert_eq!(
            lines.counts(),
            LineCounts {
                reused: dataset.len() - 1,
                written: 1
            }
        );
    }

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
                "id", "label", "parent", "depth", "weight", "virtual", "site", "polygon",
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
                .all(|p| p.as_array().unwrap().iter().all(Value::is_number)));
            match node.parent {
                None => assert!(n["parent"].is_null()),
                Some(p) => assert_eq!(n["parent"], dataset.node(p).id.as_str()),
            }
        }
        // The hand-written layout: one node per line.
        let node_lines = text.lines().filter(|l| l.starts_with("{\"id\":")).count();
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
            constraints: Arc::new(ConstraintList::from(vec![ConstraintOut {
                a: "A".into(),
                b: "B".into(),
                similarity: 0.83,
                strength: 3,
                realized: true,
                also_above: 0,
            }])),
            metrics: vec![("zeta".into(), 1.5), ("alpha".into(), f64::from(2u8))],
            ..JsonExtras::default()
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
    fn numbers_are_written_short_and_read_back_the_same() {
        let v = 1.0 / 3.0 + 123.456;
        assert_eq!(to_json(&Num(v)).parse::<f64>().ok(), Some(v));
        assert_eq!(to_json(&Num(-0.0)), "0");
        assert_eq!(to_json(&Num(1000.0)), "1000");
        assert_eq!(to_json(&Num(1411778724.0)), "1411778724");
        assert_eq!(to_json(&Num(-2.5)), "-2.5");
        assert_eq!(to_json(&Num(1e300)).parse::<f64>().ok(), Some(1e300));
    }

    #[test]
    fn coordinates_are_rounded_to_the_canvas_grid() {
        // 1000 × 1000: a tenth of 1e-6 of the diagonal (1414) is 1.4e-4: four places.
        let mut b = nptreemap_formats::DatasetBuilder::new();
        b.add(nptreemap_formats::NodeSpec::new("root"));
        for k in 0..7 {
            b.add(
                nptreemap_formats::NodeSpec::new(format!("n{k}"))
                    .parent("root")
                    .weight(1.0 + k as f64),
            );
        }
        let dataset = b.build().unwrap();
        let computed =
            crate::layout::compute(&dataset, &crate::layout::Request::default()).unwrap();
        let layout = computed.layout;
        let text = layout_json(&dataset, &layout, &JsonExtras::default());
        let v: Value = serde_json::from_str(&text).unwrap();
        let mut most = 0;
        for n in v["nodes"].as_array().unwrap() {
            for p in n["polygon"].as_array().unwrap().iter().chain([&n["site"]]) {
                for x in p.as_array().unwrap() {
                    let s = x.to_string();
                    let decimals = s.split_once('.').map_or(0, |(_, f)| f.len());
                    most = most.max(decimals);
                    assert!(decimals <= 4, "{s}");
                }
            }
        }
        assert_eq!(most, 4, "some coordinate uses the whole grid");
        let exact = JsonExtras {
            exact: true,
            ..JsonExtras::default()
        };
        let text = layout_json(&dataset, &layout, &exact);
        let v: Value = serde_json::from_str(&text).unwrap();
        for (n, cell) in v["nodes"].as_array().unwrap().iter().zip(&layout.cells) {
            assert_eq!(n["site"][0].as_f64(), Some(cell.site.x), "full precision");
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
