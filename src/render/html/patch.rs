//! The live preview's patch from one page of a map to the next (issue 32):
//! the cells whose outline or fill changed, the picture's other parts that
//! changed (each whole), the nodes of the page's data that changed and the
//! legend when it changed (whole: it lists the groups by weight), as
//! the page's script applies them in place (`page/patch.js`). `None` when
//! the two pages differ in anything else (a node added, removed or moved,
//! a legend that comes or goes, another title, script, history or
//! optimisation frames): the
//! page then loads whole, as before. It reads only the markup `html()` and
//! `svg.rs` write, so it lives beside them; a page it cannot read gets no
//! patch rather than a wrong one.
//!
//! Why by text and not from the layouts: the server holds the pages it
//! served, not the layouts they came from, and the page's bytes are what
//! the browser has. The test of the whole is that the patch applied to the
//! old page's text gives the new page's (`tests.rs`).

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::value::RawValue;

use crate::render::svg::unescape;

/// What changed from one page to the next, for the page to apply.
#[derive(Debug, Serialize)]
struct PagePatch<'a> {
    /// The build key of the new page (the server's, `serve/events.rs`).
    key: &'a str,
    /// Changed cells: position among the picture's `path[data-id]`s, the
    /// id (as `getAttribute` reads it, to check the position), new path
    /// data and fill.
    cells: Vec<(usize, String, &'a str, &'a str)>,
    /// How many `path[data-id]`s the picture has (the page checks it).
    count: usize,
    /// Changed parts of the picture other than the cells: the class of a
    /// top-level element and its new markup, whole.
    parts: Vec<(&'a str, String)>,
    /// Changed nodes of the page's data: index and the node, whole.
    nodes: Vec<(usize, &'a RawValue)>,
    /// The data's `labels` when it changed.
    #[serde(skip_serializing_if = "Option::is_none")]
    labels: Option<&'a RawValue>,
    /// The legend's new markup when it changed (a group outgrew another,
    /// and the legend lists groups by weight).
    #[serde(skip_serializing_if = "Option::is_none")]
    legend: Option<String>,
}

/// A page cut into the parts a patch compares.
struct Page<'a> {
    /// The container's id, which the page's other ids start with.
    key: &'a str,
    /// The map's picture.
    svg: &'a str,
    /// The data block's JSON.
    data: &'a str,
    /// Where the legend, `svg` and `data` start and end in the page (the
    /// legend empty when the page has none).
    cuts: [usize; 6],
}

const CONTAINER: &str = "<div class=\"nptreemap";
const LEGEND: &str = "<ul class=\"np-legend\" id=";
const CONTROLS: &str = "<div class=\"np-controls\">";
const MAP: &str = "<div class=\"np-map\"";
const DATA: &str = "class=\"np-data\"";

fn cut(html: &str) -> Option<Page<'_>> {
    let at = html.find(CONTAINER)?;
    let id = at + html[at..].find(" id=\"")? + 5;
    let key = &html[id..id + html[id..].find('"')?];
    let controls = html.find(CONTROLS)?;
    // The legend ends where the controls start (`html()` writes them so).
    let legend = html[..controls].find(LEGEND).unwrap_or(controls);
    let map = html.find(MAP)?;
    let svg_start = map + html[map..].find("<svg")?;
    let tooltip = svg_start + html[svg_start..].find("<div class=\"np-tooltip\"")?;
    let svg_end = html[..tooltip].rfind("</svg>")? + 6;
    let data_tag = tooltip + html[tooltip..].find(DATA)?;
    let data_start = data_tag + html[data_tag..].find(">\n")? + 2;
    let data_end = data_start + html[data_start..].find("\n</script>")?;
    (map > controls).then_some(Page {
        key,
        svg: &html[svg_start..svg_end],
        data: &html[data_start..data_end],
        cuts: [legend, controls, svg_start, svg_end, data_start, data_end],
    })
}

/// The page's text apart from its legend, picture and data.
fn frame<'a>(html: &'a str, page: &Page<'_>) -> [&'a str; 4] {
    let [l, m, a, b, c, d] = page.cuts;
    [&html[..l], &html[m..a], &html[b..c], &html[d..]]
}

/// The page's legend (empty when it has none).
fn legend<'a>(html: &'a str, page: &Page<'_>) -> &'a str {
    &html[page.cuts[0]..page.cuts[1]]
}

/// The patch that turns page `old` into page `new` (both as `html()`
/// writes them), stamped with `key`; `None` when only a whole page will do.
pub fn page_patch<'a>(old: &str, new: &'a str, key: &'a str) -> Option<String> {
    let (o, n) = (cut(old)?, cut(new)?);
    // The new page's ids carry its own key; the page patched keeps its own.
    let same_frame = if o.key == n.key {
        frame(old, &o) == frame(new, &n)
    } else {
        frame(old, &o)
            .iter()
            .zip(frame(new, &n))
            .all(|(a, b)| *a == b.replace(n.key, o.key))
    };
    if !same_frame {
        return None;
    }
    let (cells, count, parts) = picture_patch(o.svg, n.svg)?;
    let parts = parts
        .into_iter()
        .map(|(class, markup)| (class, markup.replace(n.key, o.key)))
        .collect();
    let (nodes, labels) = data_patch(o.data, n.data)?;
    let (lo, ln) = (legend(old, &o), legend(new, &n));
    // A legend that comes or goes changes what stands above the map: the
    // page's script lays out its controls once.
    if lo.is_empty() != ln.is_empty() {
        return None;
    }
    let legend = (lo != ln)
        .then(|| ln.replace(n.key, o.key))
        .filter(|l| *l != lo);
    let patch = PagePatch {
        key,
        cells,
        count,
        parts,
        nodes,
        labels,
        legend,
    };
    serde_json::to_string(&patch)
        .ok()
        .map(|json| json.replace('<', "\\u003c"))
}

/// One top-level element of the picture: its class and its lines.
struct Element<'a> {
    class: Option<&'a str>,
    text: &'a str,
}

/// The picture's top-level elements (inside `<svg>`), in order. Our SVG
/// writes each element on its own line and a group's children on lines
/// between its opening and closing tags; escaped text holds no `<`.
fn elements(svg: &str) -> Option<Vec<Element<'_>>> {
    let body_start = svg.find(">\n")? + 2;
    let body_end = svg.rfind("</svg>")?;
    let body = svg.get(body_start..body_end)?;
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i64, 0usize);
    let mut at = 0;
    for line in body.split_inclusive('\n') {
        if depth == 0 {
            start = at;
        }
        depth += (line.matches("<g ").count() + line.matches("<g>").count()) as i64;
        depth -= line.matches("</g>").count() as i64;
        at += line.len();
        if depth < 0 {
            return None;
        }
        if depth == 0 {
            let text = &body[start..at];
            out.push(Element {
                class: attr(first_tag(text), "class"),
                text,
            });
        }
    }
    (depth == 0).then_some(out)
}

fn first_tag(text: &str) -> &str {
    text.find('>').map_or(text, |e| &text[..e])
}

/// The value of attribute `name` in a tag's text (our own markup: one
/// space before every attribute, values in double quotes).
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    Some(&tag[start..start + tag[start..].find('"')?])
}

type CellChange<'a> = (usize, String, &'a str, &'a str);

/// The changed cells, the number of cells, and the other changed parts.
#[allow(clippy::type_complexity)]
fn picture_patch<'a>(
    old: &str,
    new: &'a str,
) -> Option<(Vec<CellChange<'a>>, usize, Vec<(&'a str, &'a str)>)> {
    if first_tag(old) != first_tag(new) {
        return None;
    }
    let (o, n) = (elements(old)?, elements(new)?);
    if o.len() != n.len() {
        return None;
    }
    let mut classes = BTreeMap::new();
    for e in &n {
        if let Some(class) = e.class {
            *classes.entry(class).or_insert(0) += 1;
        }
    }
    let (mut cells, mut count, mut parts) = (Vec::new(), 0, Vec::new());
    for (a, b) in o.iter().zip(&n) {
        if a.class != b.class {
            return None;
        }
        if b.class == Some("np-cells") {
            count += cell_patch(a.text, b.text, count, &mut cells)?;
        } else if a.text != b.text {
            // A changed part is found by its class: it must name one.
            let class = b.class.filter(|c| classes.get(c) == Some(&1))?;
            if b.text.contains("data-id=\"") || a.text.contains("data-id=\"") {
                return None;
            }
            parts.push((class, b.text));
        }
    }
    Some((cells, count, parts))
}

/// Adds to `out` the cells of group `new` that differ from `old` (line by
/// line: the same cells in the same order, only path data and fills
/// changed), positions from `base`; the number of cells, or `None` when
/// anything else differs.
fn cell_patch<'a>(
    old: &str,
    new: &'a str,
    base: usize,
    out: &mut Vec<CellChange<'a>>,
) -> Option<usize> {
    let mut count = 0;
    let mut lines = old.lines();
    for b in new.lines() {
        let a = lines.next()?;
        let cell = b.starts_with("<path data-id=\"");
        if cell != a.starts_with("<path data-id=\"") {
            return None;
        }
        if cell {
            count += 1;
        }
        if a == b {
            continue;
        }
        if !cell || shape(a)? != shape(b)? {
            return None;
        }
        let (d, fill) = (attr(b, "d")?, attr(b, "fill")?);
        out.push((base + count - 1, unescape(attr(b, "data-id")?), d, fill));
    }
    lines.next().is_none().then_some(count)
}

/// A cell's line without its path data and fill: two lines with the same
/// shape differ only in those.
fn shape(line: &str) -> Option<String> {
    let mut out = line.to_owned();
    for name in ["d", "fill"] {
        let value = attr(&out, name)?;
        let start = out.find(&format!(" {name}=\""))? + name.len() + 3;
        out.replace_range(start..start + value.len(), "");
    }
    (out.ends_with("\"></path>") && out.matches('<').count() == 2).then_some(out)
}

/// The data's changed nodes (same ids and parents, in the same order) and
/// its labels when they changed; `None` when anything else changed.
#[allow(clippy::type_complexity)]
fn data_patch<'a>(
    old: &str,
    new: &'a str,
) -> Option<(Vec<(usize, &'a RawValue)>, Option<&'a RawValue>)> {
    let o: BTreeMap<&str, &RawValue> = serde_json::from_str(old).ok()?;
    let n: BTreeMap<&str, &RawValue> = serde_json::from_str(new).ok()?;
    if o.keys().ne(n.keys()) {
        return None;
    }
    let mut labels = None;
    let mut nodes = Vec::new();
    for (name, b) in &n {
        let a = o.get(name)?;
        if a.get() == b.get() {
            continue;
        }
        match *name {
            "labels" => labels = Some(*b),
            "nodes" => nodes = node_patch(a.get(), b.get())?,
            _ => return None,
        }
    }
    Some((nodes, labels))
}

/// What a node must keep for a patch: its place in the tree.
#[derive(serde::Deserialize, PartialEq)]
struct Place {
    id: String,
    parent: Option<usize>,
}

fn node_patch<'a>(old: &str, new: &'a str) -> Option<Vec<(usize, &'a RawValue)>> {
    let o: Vec<&RawValue> = serde_json::from_str(old).ok()?;
    let n: Vec<&'a RawValue> = serde_json::from_str(new).ok()?;
    if o.len() != n.len() {
        return None;
    }
    let mut out = Vec::new();
    for (i, (a, b)) in o.iter().zip(&n).enumerate() {
        if a.get() == b.get() {
            continue;
        }
        let pa: Place = serde_json::from_str(a.get()).ok()?;
        let pb: Place = serde_json::from_str(b.get()).ok()?;
        if pa != pb {
            return None;
        }
        out.push((i, *b));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{compute, Computed, Request};
    use crate::render::html::tests::{drawn_cells, hostile_uneven};
    use crate::render::{html_page, Style};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// Four groups of six leaves with vectors, leaf `a0`'s weight `w`,
    /// warm from `previous` when given (as `watch` lays out an edit).
    fn map(w: f64, previous: Option<&Computed>) -> Computed {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for (g, group) in ["a", "b", "c", "d"].iter().enumerate() {
            b.add(NodeSpec::new(*group).parent("root"));
            for k in 0..6 {
                let weight = if g == 0 && k == 0 {
                    w
                } else {
                    5.0 + ((g * 7 + k * 3) % 11) as f64
                };
                let f = vec![g as f64, k as f64 * 0.3, ((g + k) % 3) as f64];
                b.add(
                    NodeSpec::new(format!("{group}{k}"))
                        .parent(*group)
                        .weight(weight)
                        .features(f),
                );
            }
        }
        let dataset = b.build().expect("valid");
        let request = Request {
            previous: previous.map(Computed::previous),
            ..Request::default()
        };
        compute(&dataset, &request).expect("layout")
    }

    /// The pages of `map` before and after leaf `a0` grows by a tenth.
    fn edit() -> (String, String) {
        let style = Style::default();
        let before = map(10.0, None);
        (
            html_page(&before, &style),
            html_page(&map(11.0, Some(&before)), &style),
        )
    }

    /// `old` with `patch` applied to its text, as the page applies it to
    /// its document: cells by position, parts by class, nodes by index.
    fn apply(old: &str, patch: &serde_json::Value) -> (String, serde_json::Value) {
        let page = cut(old).expect("page");
        let mut svg = String::new();
        let changed: BTreeMap<usize, (&str, &str)> = patch["cells"]
            .as_array()
            .expect("cells")
            .iter()
            .map(|c| {
                let at = c[0].as_u64().expect("position") as usize;
                (
                    at,
                    (c[2].as_str().expect("d"), c[3].as_str().expect("fill")),
                )
            })
            .collect();
        let parts: BTreeMap<&str, &str> = patch["parts"]
            .as_array()
            .expect("parts")
            .iter()
            .map(|p| {
                (
                    p[0].as_str().expect("class"),
                    p[1].as_str().expect("markup"),
                )
            })
            .collect();
        let head_end = page.svg.find(">\n").expect("head") + 2;
        svg.push_str(&page.svg[..head_end]);
        let mut position = 0;
        for e in elements(page.svg).expect("elements") {
            if let Some(markup) = e.class.and_then(|c| parts.get(c)) {
                svg.push_str(markup);
                continue;
            }
            for line in e.text.split_inclusive('\n') {
                if !line.starts_with("<path data-id=\"") {
                    svg.push_str(line);
                    continue;
                }
                let mut line = line.to_owned();
                if let Some((d, fill)) = changed.get(&position) {
                    for (name, value) in [("d", d), ("fill", fill)] {
                        let start =
                            line.find(&format!(" {name}=\"")).expect("attr") + name.len() + 3;
                        let len = line[start..].find('"').expect("quote");
                        line.replace_range(start..start + len, value);
                    }
                }
                position += 1;
                svg.push_str(&line);
            }
        }
        svg.push_str("</svg>");
        let mut data: serde_json::Value = serde_json::from_str(page.data).expect("data");
        for n in patch["nodes"].as_array().expect("nodes") {
            data["nodes"][n[0].as_u64().expect("index") as usize] = n[1].clone();
        }
        if let Some(labels) = patch.get("labels") {
            data["labels"] = labels.clone();
        }
        (svg, data)
    }

    fn parse(patch: &str) -> serde_json::Value {
        serde_json::from_str(patch).expect("the patch is JSON")
    }

    #[test]
    fn a_patch_applied_to_the_old_page_gives_the_new_one() {
        let (old, new) = edit();
        let patch = parse(&page_patch(&old, &new, "k.2").expect("a weight edit patches"));
        assert_eq!(patch["key"], "k.2");
        let (svg, data) = apply(&old, &patch);
        let (o, n) = (cut(&old).expect("old"), cut(&new).expect("new"));
        assert_ne!(o.key, n.key, "the pages' own keys differ");
        assert_eq!(svg, n.svg.replace(n.key, o.key), "the picture");
        let want: serde_json::Value = serde_json::from_str(n.data).expect("new data");
        assert_eq!(data, want, "the data");
        // Only cells whose outline or fill changed are sent, by the
        // page's own reading of the cells.
        let (before, after) = (drawn_cells(&old), drawn_cells(&new));
        let moved: Vec<&str> = before
            .iter()
            .zip(&after)
            .filter(|(a, b)| a != b)
            .map(|(_, b)| b.0.as_str())
            .collect();
        let sent: Vec<&str> = patch["cells"]
            .as_array()
            .expect("cells")
            .iter()
            .map(|c| c[1].as_str().expect("id"))
            .collect();
        assert!(!sent.is_empty());
        assert_eq!(sent, moved);
        assert_eq!(patch["count"], before.len());
    }

    #[test]
    fn ids_are_sent_as_the_page_reads_them() {
        let style = Style::default();
        let old = html_page(&hostile_uneven(10.0), &style);
        let new = old.replacen(" d=\"M", " d=\"M1", 1);
        let patch = parse(&page_patch(&old, &new, "k").expect("patch"));
        assert_eq!(patch["cells"][0][1], "</script><b>g1");
        assert_eq!(patch["cells"][0][0], 0);
    }

    #[test]
    fn a_legend_reordered_by_an_edit_is_sent_whole() {
        let style = Style::default();
        let before = map(10.0, None);
        let old = html_page(&before, &style);
        // Leaf a0 grows until its group is the heaviest: the legend, by
        // weight, lists it first.
        let new = html_page(&map(400.0, Some(&before)), &style);
        let (o, n) = (cut(&old).expect("old"), cut(&new).expect("new"));
        assert_ne!(legend(&old, &o), legend(&new, &n).replace(n.key, o.key));
        let patch = parse(&page_patch(&old, &new, "k").expect("a reorder patches"));
        let sent = patch["legend"].as_str().expect("the legend is sent");
        assert_eq!(sent, legend(&new, &n).replace(n.key, o.key));
        assert!(sent.starts_with(LEGEND) && sent.ends_with("</ul>\n"));
        let first = sent.find("data-id=\"").expect("an entry") + 9;
        assert_eq!(&sent[first..first + 2], "a\"", "the heaviest group first");
        // Everything else as before: the picture and the data apply.
        let (svg, data) = apply(&old, &patch);
        assert_eq!(svg, n.svg.replace(n.key, o.key));
        assert_eq!(
            data,
            serde_json::from_str::<serde_json::Value>(n.data).expect("data")
        );
    }

    #[test]
    fn the_same_page_patches_to_nothing() {
        let page = html_page(&hostile_uneven(10.0), &Style::default());
        let patch = parse(&page_patch(&page, &page, "k").expect("patch"));
        for list in ["cells", "parts", "nodes"] {
            assert_eq!(patch[list].as_array().map(Vec::len), Some(0), "{list}");
        }
        assert!(patch.get("labels").is_none());
        assert!(patch.get("legend").is_none());
    }

    #[test]
    fn anything_but_outlines_weights_and_labels_loads_the_whole_page() {
        let (old, new) = edit();
        assert!(page_patch(&old, &new, "k").is_some());
        // Another title, another legend entry, a node renamed, a cell
        // group's stroke, a page that is not ours.
        let titled = new.replacen("<title>", "<title>x", 1);
        assert!(page_patch(&old, &titled, "k").is_none(), "title");
        let renamed = new.replace("\"id\":\"b1\"", "\"id\":\"b9\"");
        assert!(page_patch(&old, &renamed, "k").is_none(), "a node's id");
        let stroke = new.replacen("<g stroke-width=\"", "<g stroke-width=\"9", 1);
        assert!(page_patch(&old, &stroke, "k").is_none(), "a cell group");
        assert!(
            page_patch(&old, "<html></html>", "k").is_none(),
            "not a page"
        );
        let mut bigger = Style::default();
        bigger.legend = !bigger.legend;
        let other = html_page(&map(11.0, None), &bigger);
        if other != new {
            assert!(page_patch(&old, &other, "k").is_none(), "the legend");
        }
    }
}
