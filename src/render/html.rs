//! The interactive HTML page: one self-contained HTML5 file wrapping a finished
//! SVG with inline style, inline script and the node data as JSON, for the hover
//! behaviour of the paper's prototype (method reference §8.5) and exploring a
//! big map (issue 24: labels placed for the zoomed extent, search, touch, a
//! focus ring, title and legend as HTML text). Owns the page's structure, its
//! data block (real nodes only, numbers at the precision the picture shows)
//! and the escaping of both; the style and script live in `page/`. May not
//! build the SVG, do I/O, or reference anything over the network.
//! Output is deterministic: identical input gives identical bytes.

use std::collections::HashMap;
use std::sync::Arc;

use serde::Serialize;

use super::label_text::display_name;
use super::labels::{format_value, line_step_em};
use super::legend::LegendItem;
use super::overlay::Link;
use super::palette::TABLEAU10;
use super::parts::Parts;
use super::picture::{colors, compose_noted, fills, legend_items, Style};
use super::svg::{escape, leaf_labels, path_data};
use super::text::ascent_em;
use crate::layout::zero::HiddenUnder;
use crate::layout::{Computed, Layout};

mod patch;
mod view;

pub use patch::page_patch;

use view::RealView;

/// What the page knows about the map beyond its picture.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HtmlData {
    /// Page title, shown in the browser tab (escaped; any text is safe).
    pub title: String,
    /// A heading above the map (the picture's title); `None` shows none.
    #[serde(skip)]
    pub heading: Option<String>,
    /// The legend above the map, as HTML text; empty shows none.
    #[serde(skip)]
    pub legend: Vec<LegendItem>,
    /// Text after every weight (`" KiB"`), as the picture writes values.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub unit: String,
    /// Every real node, the root first, parents before their children.
    pub nodes: Vec<HtmlNode>,
    /// How the script labels cells when it zooms; `None` when the picture
    /// has no leaf labels (the page then adds none either).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub labels: Option<HtmlLabels>,
    /// Snapshots of the optimisation for the slider, in order; the page shows
    /// no slider when empty (layouts made without frames).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<HtmlFrame>,
    /// The session's past layouts, oldest first, for the page's ◀/▶ steps
    /// (`history:`, issue 25); the page as drawn is the latest. Empty: no
    /// step control and no history script (the page is as it was before).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub history: Vec<HtmlLayout>,
    /// The name of the field the links come from (`page.link`); `None`
    /// when the map has no links.
    #[serde(rename = "linkName", skip_serializing_if = "Option::is_none")]
    pub link_name: Option<String>,
    /// Links open in a new tab (`page.link_target: new-tab`).
    #[serde(rename = "newTab", skip_serializing_if = "std::ops::Not::not")]
    pub new_tab: bool,
}

/// One snapshot of the optimisation as the slider draws it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HtmlFrame {
    /// What the moment is (`level 2: tick 40`); shown beside the slider.
    pub label: String,
    /// The cells then: node id, SVG path data, fill colour.
    pub cells: Vec<(String, String, String)>,
}

/// One past layout as the page's steps draw it: every drawn cell (the
/// picture's `path[data-id]`s) with its path data and fill exactly as that
/// layout's own page drew them, so stepping back shows the earlier picture.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct HtmlLayout {
    /// Node id, SVG path data, fill colour (`none` for groups).
    pub cells: Vec<(String, String, String)>,
}

/// One node of the map as the page's script sees it. Relations are written
/// once, at the lower index of the two; the script makes them symmetric.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HtmlNode {
    /// Node id; equals the `data-id` of its cell `<path>` in the SVG.
    pub id: String,
    /// Display label; `None` when it is the id.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// The parent's index in [`HtmlData::nodes`]; `None` for the root.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parent: Option<usize>,
    /// The weight as the picture writes values (thousands separators, at
    /// most two decimals), without the unit.
    pub weight: String,
    /// The view box (`x y width height`) that zooms into this group, with the
    /// picture's aspect; `None` for leaves and for groups too large to zoom.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zoom: Option<[f64; 4]>,
    /// Leaves sharing an edge with this leaf that come after it in
    /// [`HtmlData::nodes`] (indices).
    #[serde(rename = "near", skip_serializing_if = "Vec::is_empty")]
    pub neighbors: Vec<usize>,
    /// Constraint partners after it (indices), each with whether the
    /// constraint is realised (the two cells share an edge).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub partners: Vec<(usize, bool)>,
    /// Further name–value pairs for the tooltip, in order (the user's own
    /// columns, `page.fields`); a field the node has no value for is left out.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fields: Vec<(String, String)>,
    /// The node's link (`page.link`), when it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link: Option<HtmlLink>,
    /// What of its children is not drawn for weighing 0 (issue 34), for
    /// the tooltips of its cells.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub empty: Option<HtmlEmpty>,
}

/// Items of weight 0 a node holds that have no cell.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HtmlEmpty {
    /// How many (leaves, through hidden groups too).
    pub items: usize,
    /// The labels of its first hidden children.
    pub names: Vec<String>,
    /// Its hidden children not named.
    pub more: usize,
}

/// A node's link: the value as given, and whether the page may follow it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HtmlLink {
    /// The URL text (shown as text when not followed).
    pub href: String,
    /// True for `http:`, `https:` and relative URLs ([`followable`]); any
    /// other scheme (`javascript:`, `data:`, `file:`, …) is never followed.
    pub ok: bool,
}

/// Whether the page may follow `url`: an `http:` or `https:` URL, or a
/// relative one (no scheme: no `:` before the first `/`, `?` or `#`). The
/// test is on the text as browsers read it, so control characters and
/// spaces (which browsers strip or drop) are refused.
pub fn followable(url: &str) -> bool {
    if url.is_empty()
        || url
            .chars()
            .any(|c| c.is_control() || c.is_whitespace() || c == '\\')
    {
        return false;
    }
    let lower = url.to_ascii_lowercase();
    if lower.starts_with("http://") || lower.starts_with("https://") {
        return true;
    }
    let end = url.find(['/', '?', '#']).unwrap_or(url.len());
    !url[..end].contains(':')
}

/// How the script fits labels into cells for a zoomed view, by the rules
/// of the picture's own labels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HtmlLabels {
    /// CSS font family of the labels.
    pub font: String,
    /// Text colour.
    pub fill: String,
    /// Halo colour (the outline colour).
    pub halo: String,
    /// Smallest label size, pixels on screen (the picture's `min_size`).
    pub min: f64,
    /// Largest label size on that scale.
    pub max: f64,
    /// Baseline to baseline of a label's lines, in ems, and the ascent: the
    /// picture's font's, so the page's fitter (`page/fit.js`) stacks lines
    /// as the picture does.
    pub line: f64,
    /// The ascent, in ems.
    pub ascent: f64,
    /// For each `<text>` of the picture's label group, in order, the index
    /// of the node it names; empty when that order could not be confirmed.
    pub placed: Vec<usize>,
}

/// Class of the JSON data block, which the script reads.
const DATA_CLASS: &str = "np-data";

/// The page's style, scoped to the map's container (see the file's header).
const STYLE: &str = include_str!("page/page.css");

/// The page's script: its ES modules (`page/*.js`, each file's header says
/// what it owns), bundled from `page/main.js` at build time into one
/// function scope (`page/bundle.rs`, run by `build.rs`). It finds
/// everything inside its own container, so several maps can share a
/// document; user text reaches the document only through `textContent` and
/// attribute values.
const SCRIPT: &str = include_str!(concat!(env!("OUT_DIR"), "/page.js"));

/// The script of a page with history: [`SCRIPT`]'s modules, then the
/// page's own steps through its past layouts (`page/past.js`, with the morph
/// the live preview shares, `page/history.js`). A page without history
/// keeps [`SCRIPT`], and so its bytes.
const SCRIPT_WITH_HISTORY: &str = include_str!(concat!(env!("OUT_DIR"), "/page-history.js"));

/// The step control's style, with [`SCRIPT_WITH_HISTORY`] only.
const HISTORY_STYLE: &str = include_str!("page/history.css");

/// Width over height of the SVG's `viewBox`.
fn view_aspect(svg: &str) -> Option<f64> {
    let start = svg.find("viewBox=\"")? + 9;
    let end = start + svg[start..].find('"')?;
    let v: Vec<f64> = svg[start..end]
        .split_whitespace()
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    (v.len() == 4 && v[2] > 0.0 && v[3] > 0.0).then(|| v[2] / v[3])
}

/// A short key for the page's ids, from its content: two maps' pages get
/// different ids, the same map always the same (FNV-1a, 32 bits).
fn page_key(svg: &str, data: &str) -> String {
    let mut h: u32 = 0x811c_9dc5;
    for b in svg.bytes().chain(data.bytes()) {
        h ^= u32::from(b);
        h = h.wrapping_mul(0x0100_0193);
    }
    format!("np-{h:08x}")
}

/// Groups shown in the legend before the rest fold away behind a button.
const LEGEND_SHOWN: usize = 12;

/// One legend entry as a list item; a group's swatch carries the group's
/// id, for the page's script to highlight and zoom to.
fn legend_entry(item: &LegendItem) -> String {
    let glyph = match item {
        LegendItem::Swatch { color, .. } => {
            format!("<span class=\"np-swatch\" style=\"background:{color}\"></span>")
        }
        LegendItem::Tab => "<svg class=\"np-glyph\" viewBox=\"0 0 20 20\" aria-hidden=\"true\">\
            <rect width=\"10\" height=\"20\" fill=\"#9c9c9c\"/><rect x=\"10\" width=\"10\" height=\"20\" fill=\"#cfcfcf\"/>\
            <polygon points=\"9.6,6.8 15.2,4.8 15.2,15.2 9.6,13.2\" fill=\"#9c9c9c\" stroke=\"#fff\" stroke-width=\"1.2\"/></svg>"
            .to_owned(),
        LegendItem::Unlinked => "<svg class=\"np-glyph\" viewBox=\"0 0 20 20\" aria-hidden=\"true\">\
            <circle cx=\"10\" cy=\"10\" r=\"8\" fill=\"#fff\" stroke=\"#d62728\" stroke-width=\"2.4\"/></svg>"
            .to_owned(),
        LegendItem::Scale {
            field,
            low,
            high,
            stops,
        } => {
            // The bar between its two ends, as CSS (no ids to collide
            // between two maps in one document).
            let css: Vec<String> = stops.iter().map(|c| c.to_string()).collect();
            return format!(
                "<li class=\"np-legend-item np-legend-scale\"><span class=\"np-legend-text\">{}: {}</span>\
                 <span class=\"np-scale-bar\" style=\"background:linear-gradient(to right,{})\"></span>\
                 <span class=\"np-legend-text\">{}</span></li>\n",
                escape(field),
                escape(low),
                css.join(","),
                escape(high)
            );
        }
        _ => String::new(),
    };
    let group = match item {
        LegendItem::Swatch {
            group: Some(id), ..
        } => format!(" data-id=\"{}\"", escape(id)),
        _ => String::new(),
    };
    format!(
        "<li class=\"np-legend-item\"{group}>{glyph}<span class=\"np-legend-text\">{}</span></li>\n",
        escape(&item.text())
    )
}

/// The legend as an HTML list: the glyph keys and the first
/// [`LEGEND_SHOWN`] group swatches; past them, a disclosure that opens the
/// full list of groups, with a box to filter it (issue 33).
fn legend_html(items: &[LegendItem], key: &str) -> String {
    if items.is_empty() {
        return String::new();
    }
    let groups = items
        .iter()
        .filter(|i| matches!(i, LegendItem::Swatch { .. }))
        .count();
    let fold = groups > LEGEND_SHOWN + 1;
    let mut out = format!("<ul class=\"np-legend\" id=\"{key}-legend\" aria-label=\"Legend\">\n");
    let mut shown_groups = 0;
    let mut all = String::new();
    for item in items {
        if matches!(item, LegendItem::Swatch { .. }) {
            shown_groups += 1;
            if fold {
                all.push_str(&legend_entry(item));
                if shown_groups > LEGEND_SHOWN {
                    continue;
                }
            }
        }
        out.push_str(&legend_entry(item));
    }
    if fold {
        let more = LegendItem::More(groups - LEGEND_SHOWN).text();
        out.push_str(&format!(
            "<li class=\"np-legend-more\"><details><summary>{}</summary>\n<div class=\"np-legend-all\">\
             <input type=\"search\" class=\"np-legend-filter\" id=\"{key}-legend-filter\" placeholder=\"Filter {groups} groups\" \
             aria-label=\"Filter the groups\" autocomplete=\"off\" spellcheck=\"false\">\n\
             <ul class=\"np-legend np-legend-list\" aria-label=\"All {groups} groups\">\n{all}</ul>\
             <p class=\"np-legend-none\" hidden>No group matches.</p></div></details></li>\n",
            escape(&more)
        ));
    }
    out.push_str("</ul>\n");
    out
}

/// Writes one self-contained HTML5 page showing `svg` (inserted verbatim, so it
/// must be our own SVG text, whose cell `<path>`s carry `data-id`) with `data`.
///
/// The page has no network references: style, script and data are inline. The
/// data is JSON in `<script type="application/json" class="np-data">`, with
/// every `<` written as `\u003c` so no label can close the block. Above the
/// map: the heading, the legend, a search box, a checkbox "Show unrealized
/// links" (off by default, for SVG elements of class `np-unrealized`), the
/// optimisation slider when there are frames, and the zoom's breadcrumb.
/// Identical input gives identical bytes.
pub fn html(svg: &str, data: &HtmlData) -> String {
    let json = data_json(data);
    let key = page_key(svg, &json);
    let script = if data.history.is_empty() {
        SCRIPT
    } else {
        SCRIPT_WITH_HISTORY
    };
    let mut out = String::with_capacity(svg.len() + json.len() + STYLE.len() + script.len() + 4096);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str(
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>",
    );
    out.push_str(&escape(&data.title));
    out.push_str("</title>\n<style>\nbody { margin: 1em; }\n@media (prefers-color-scheme: dark) { body { background: #161616; } }\n</style>\n</head>\n<body>\n");
    // Everything of the map lives in one container with ids under one key:
    // it can be copied into another document as it is.
    out.push_str(&format!(
        "<div class=\"nptreemap np-hide-unrealized\" id=\"{key}\">\n<style>\n"
    ));
    out.push_str(STYLE);
    if !data.history.is_empty() {
        out.push_str(HISTORY_STYLE);
    }
    out.push_str("</style>\n");
    if let Some(heading) = data.heading.as_deref().filter(|h| !h.is_empty()) {
        out.push_str(&format!(
            "<h1 class=\"np-title\" id=\"{key}-title\">{}</h1>\n",
            escape(heading)
        ));
    }
    out.push_str(&legend_html(&data.legend, &key));
    out.push_str("<div class=\"np-controls\">\n");
    out.push_str(&format!(
        "<div class=\"np-search\" role=\"search\"><input type=\"search\" class=\"np-search-box\" id=\"{key}-search\" \
         placeholder=\"Find (press /)\" aria-label=\"Find a cell by name or path\" autocomplete=\"off\" spellcheck=\"false\" \
         role=\"combobox\" aria-autocomplete=\"list\" aria-expanded=\"false\" aria-controls=\"{key}-matches\">\
         <ul class=\"np-matches\" id=\"{key}-matches\" role=\"listbox\" aria-label=\"Matches\" hidden></ul></div>\n"
    ));
    out.push_str(&format!(
        "<label><input type=\"checkbox\" class=\"np-unrealized-toggle\" id=\"{key}-unrealized\"> \
         Show unrealized links</label>\n"
    ));
    if !data.frames.is_empty() {
        // The last position is the finished picture; the others are frames.
        out.push_str(&format!(
            "<div class=\"np-frames\"><label>Optimisation <input type=\"range\" class=\"np-frame\" id=\"{key}-frame\" \
             min=\"0\" max=\"{n}\" value=\"{n}\" step=\"1\"></label> \
             <span class=\"np-frame-label\" id=\"{key}-frame-label\">final layout</span></div>\n",
            n = data.frames.len()
        ));
    }
    if !data.history.is_empty() {
        // The page as drawn is the latest of them; the script moves the
        // picture back and forth through the past ones.
        let n = data.history.len() + 1;
        out.push_str(&format!(
            "<div class=\"np-history\" role=\"group\" aria-label=\"Layouts of the session\">\
             <button type=\"button\" class=\"np-history-back\" id=\"{key}-history-back\" aria-label=\"Previous layout\">\u{25c0}</button>\
             <span class=\"np-history-label\" id=\"{key}-history-label\" aria-live=\"polite\"> layout {n} of {n} (latest) </span>\
             <button type=\"button\" class=\"np-history-ahead\" id=\"{key}-history-ahead\" aria-label=\"Next layout\" disabled>\u{25b6}</button></div>\n"
        ));
    }
    out.push_str(&format!(
        "<nav class=\"np-crumbs\" id=\"{key}-crumbs\" aria-label=\"Zoom\"></nav>\n"
    ));
    if let Some(name) = &data.link_name {
        // The clicked cell's link, filled by the script.
        out.push_str(&format!(
            "<div class=\"np-link\" id=\"{key}-link\" aria-live=\"polite\" data-name=\"{}\" hidden></div>\n",
            escape(name)
        ));
    }
    out.push_str("</div>\n");
    // As wide as the container, and no wider than keeps the whole picture
    // within the window's height below the header (the script refines the
    // estimate with the header's real height).
    let aspect = view_aspect(svg).unwrap_or(1.0);
    out.push_str(&format!(
        "<div class=\"np-map\" id=\"{key}-map\" data-aspect=\"{aspect:.4}\" style=\"max-width: calc((100vh - 9em) * {aspect:.4})\">\n"
    ));
    out.push_str(svg);
    if !svg.ends_with('\n') {
        out.push('\n');
    }
    out.push_str(&format!(
        "</div>\n<div class=\"np-tooltip\" id=\"{key}-tooltip\" role=\"tooltip\" hidden></div>\n"
    ));
    out.push_str(&format!(
        "<script type=\"application/json\" class=\"{DATA_CLASS}\" id=\"{key}-data\">\n"
    ));
    out.push_str(&json);
    out.push_str("\n</script>\n<script>\n");
    out.push_str(script);
    out.push_str("</script>\n</div>\n</body>\n</html>\n");
    out
}

/// The interactive page of a finished computation: the picture of its real
/// nodes (the unrealised links drawn, for the page's checkbox to show or
/// hide; title and legend as HTML instead of in the picture), and per node
/// its parent, weight, neighbours and constraint partners.
pub fn html_page(computed: &Computed, style: &Style) -> String {
    html_page_with_history(computed, style, &[])
}

/// [`html_page`] carrying `past` layouts (oldest first) for the page's
/// steps; with none it is [`html_page`], byte for byte.
pub fn html_page_with_history(
    computed: &Computed,
    style: &Style,
    past: &[Arc<Computed>],
) -> String {
    html_page_with_parts(computed, style, past, &Parts::new())
}

/// [`html_page_with_history`] with the labels `parts` has from this
/// render's other outputs and the render before: the same bytes.
pub fn html_page_with_parts(
    computed: &Computed,
    style: &Style,
    past: &[Arc<Computed>],
    parts: &Parts,
) -> String {
    let view = RealView::new(computed);
    let dataset = view.dataset.as_ref();
    let layout = view.layout.as_ref();
    let mut page_style = style.clone();
    page_style.overlay.show_unrealized = true;
    page_style.title = None;
    page_style.legend = false;
    let links = view.links(computed);
    let adjacent = view.top_pairs(computed);
    let svg_text = compose_noted(dataset, layout, &links, &adjacent, &page_style, None, parts).text;
    let svg_text = lighten(&svg_text);

    let nodes = page_nodes(computed, &view, &links, style);

    let labels = page_style.cells.labels.show.then(|| {
        let placed = leaf_labels(dataset, layout, &page_style.cells.labels, parts);
        let texts = label_texts(&svg_text);
        HtmlLabels {
            font: page_style.cells.font_family.clone(),
            fill: page_style.cells.text_color.to_string(),
            halo: page_style.cells.stroke.to_string(),
            min: page_style.cells.labels.min_size,
            max: page_style.cells.labels.max_size,
            line: line_step_em(),
            ascent: ascent_em(),
            // The script pairs the picture's label texts with nodes in
            // this order; it must be the picture's own.
            placed: if texts == placed.len() {
                placed.iter().map(|p| p.node).collect()
            } else {
                Vec::new()
            },
        }
    });
    let legend = if style.legend {
        let (colors, applied) = fills(dataset, &adjacent, style);
        let tabs = svg_text.contains("class=\"np-tab\"");
        let markers = svg_text.contains("class=\"np-unlinked\"");
        let note = computed.zero.summary();
        legend_items(
            dataset,
            &colors,
            applied.as_ref(),
            (tabs, markers),
            note.as_deref(),
            style,
        )
    } else {
        Vec::new()
    };
    let heading = style
        .title
        .as_deref()
        .map(super::label_text::clean)
        .filter(|t| !t.is_empty());
    let title = heading
        .clone()
        .unwrap_or_else(|| computed.dataset.node(computed.dataset.root()).label.clone());
    html(
        &svg_text,
        &HtmlData {
            title,
            heading,
            legend,
            unit: style.cells.labels.unit.clone(),
            nodes,
            labels,
            frames: frames(computed, style, &view),
            history: past.iter().map(|p| past_layout(p, style)).collect(),
            link_name: style.page.link.clone(),
            new_tab: style.page.new_tab,
        },
    )
}

/// Per node of the real view, what the page's script reads: id, label,
/// parent, weight, zoom box, neighbours and constraint partners, the
/// `page:` fields and link, and the items of weight 0 under it.
fn page_nodes(
    computed: &Computed,
    view: &RealView<'_>,
    links: &[Link],
    style: &Style,
) -> Vec<HtmlNode> {
    let dataset = view.dataset.as_ref();
    let layout = view.layout.as_ref();
    let names = &style.cells.labels.names;
    let mut partners: Vec<Vec<(usize, bool)>> = vec![Vec::new(); dataset.len()];
    for link in links {
        let (a, b) = (link.a.min(link.b), link.a.max(link.b));
        if a != b && a < partners.len() && !partners[a].iter().any(|p| p.0 == b) {
            partners[a].push((b, link.realized));
        }
    }
    let hidden: HashMap<&str, &HiddenUnder> = computed
        .zero
        .under
        .iter()
        .map(|u| (u.parent.as_str(), u))
        .collect();
    let count = dataset.len().min(layout.cells.len());
    (0..count)
        .map(|i| {
            let node = dataset.node(i);
            let label = display_name(dataset, i, names, &style.cells.labels.text);
            let leaf = node.children.is_empty();
            HtmlNode {
                id: node.id.clone(),
                label: (label != node.id).then_some(label),
                parent: node.parent,
                weight: format_value(node.value, ""),
                zoom: zoom_box(dataset, layout, i),
                neighbors: if leaf {
                    view.leaf_neighbors(computed, i)
                        .into_iter()
                        .filter(|&j| j > i)
                        .collect()
                } else {
                    Vec::new()
                },
                partners: std::mem::take(&mut partners[i]),
                fields: shown_fields(&node.fields, &style.page.fields),
                link: style.page.link.as_deref().and_then(|name| {
                    let href = &node.fields.iter().find(|(n, _)| n == name)?.1;
                    Some(HtmlLink {
                        href: href.clone(),
                        ok: followable(href),
                    })
                }),
                empty: hidden.get(node.id.as_str()).map(|u| HtmlEmpty {
                    items: u.items,
                    names: u.names.clone(),
                    more: u.more,
                }),
            }
        })
        .collect()
}

/// The node's values of the `wanted` fields, in that order.
fn shown_fields(fields: &[(String, String)], wanted: &[String]) -> Vec<(String, String)> {
    wanted
        .iter()
        .filter_map(|w| fields.iter().find(|(name, _)| name == w).cloned())
        .collect()
}

/// The optimisation's snapshots, their cells named by the real nodes.
fn frames(computed: &Computed, style: &Style, view: &RealView<'_>) -> Vec<HtmlFrame> {
    if computed.report.frames.is_empty() {
        return Vec::new();
    }
    let colors = colors(computed, style);
    computed
        .report
        .frames
        .iter()
        .map(|f| HtmlFrame {
            label: format!("level {}: {}", f.depth, f.label),
            cells: f
                .cells
                .iter()
                .map(|(i, polygon)| {
                    let mut d = String::new();
                    path_data(&mut d, polygon);
                    let fill = colors[*i].map_or("#cccccc".to_string(), |c| c.to_string());
                    (view.dataset.node(view.real_of(*i)).id.clone(), d, fill)
                })
                .collect(),
        })
        .collect()
}

/// A past layout's drawn cells as its own page's picture has them: the
/// same nodes (real ones, every node but a root over groups), path data
/// and fills as `svg::cells` writes them.
fn past_layout(computed: &Computed, style: &Style) -> HtmlLayout {
    let view = RealView::new(computed);
    let dataset = view.dataset.as_ref();
    let layout = view.layout.as_ref();
    let (colors, _) = fills(dataset, &view.top_pairs(computed), style);
    let count = dataset.len().min(layout.cells.len());
    let cells = (0..count)
        .filter(|&i| dataset.node(i).parent.is_some() || dataset.is_leaf(i))
        .map(|i| {
            let mut d = String::new();
            path_data(&mut d, &layout.cells[i].polygon);
            let fill = if dataset.is_leaf(i) {
                colors[i].unwrap_or(TABLEAU10[0]).to_string()
            } else {
                "none".to_owned()
            };
            (dataset.node(i).id.clone(), d, fill)
        })
        .collect();
    HtmlLayout { cells }
}

/// The picture as the page needs it, without what the page's script does
/// better and what would only slow a big map's loading: the cells' `<title>`
/// elements (the page has its own tooltip and names the focused cell; the
/// browser's would show beside it) and the unrealised links' lines (one per
/// unrealised constraint; the script draws them from the data when the
/// checkbox asks, into the group left empty). Our own SVG text, so plain
/// text surgery is exact; anything unexpected is left as it is.
fn lighten(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len());
    let mut rest = svg;
    // A cell is `<path data-id=".." d=".." fill=".."><title>..</title></path>`;
    // escaped text holds no `<`, so a title ends at the first `</title>`.
    while let Some(at) = rest.find("<title>") {
        let Some(len) = rest[at..].find("</title></path>") else {
            break;
        };
        let opening = rest[..at].rfind('<').map_or("", |o| &rest[o..at]);
        out.push_str(&rest[..at]);
        if !opening.starts_with("<path ") || rest[at + 7..at + len].contains('<') {
            out.push_str(&rest[at..at + len + 8]);
        }
        rest = &rest[at + len + 8..];
    }
    out.push_str(rest);
    const LINKS: &str = "<g class=\"np-unrealized\"";
    if let Some(at) = out.find(LINKS) {
        let body = out[at..].find(">\n").map(|e| at + e + 2);
        let end = body.and_then(|b| out[b..].find("</g>\n").map(|e| b + e));
        if let (Some(body), Some(end)) = (body, end) {
            if out[body..end].lines().all(|l| l.starts_with("<line ")) {
                out.replace_range(body..end, "");
            }
        }
    }
    out
}

/// How many `<text>` elements the picture's leaf label group holds.
fn label_texts(svg: &str) -> usize {
    let Some(start) = svg.find("<g class=\"np-labels\"") else {
        return 0;
    };
    let end = svg[start..].find("</g>").map_or(svg.len(), |e| start + e);
    svg[start..end].matches("<text").count()
}

/// Groups whose cell spans more than this share of the canvas in both
/// directions are not worth zooming into.
const ZOOM_MIN_GAIN: f64 = 0.97;

/// The view box that shows group `i` as large as the picture allows: its
/// cell's bounding box with a margin, widened to the canvas's aspect.
fn zoom_box(dataset: &nptreemap_formats::Dataset, layout: &Layout, i: usize) -> Option<[f64; 4]> {
    let node = dataset.node(i);
    if node.children.is_empty() || node.parent.is_none() || node.is_virtual {
        return None;
    }
    let (lo, hi) = layout.cells.get(i)?.polygon.bbox();
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);
    let margin = 0.03 * (hi.x - lo.x).max(hi.y - lo.y);
    let (mut w, mut h) = (hi.x - lo.x + 2.0 * margin, hi.y - lo.y + 2.0 * margin);
    if w / h < cw / ch {
        w = h * cw / ch;
    } else {
        h = w * ch / cw;
    }
    if w > ZOOM_MIN_GAIN * cw && h > ZOOM_MIN_GAIN * ch {
        return None;
    }
    let (cx, cy) = (0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y));
    // Centred on the group, then moved back inside the canvas where the box
    // fits in it: a group at the map's edge fills the view instead of
    // sharing it with blank page (the Python email package, at the bottom
    // of its map, took the top half of its zoomed view).
    let inside = |c: f64, size: f64, canvas: f64| {
        let start = c - 0.5 * size;
        if size <= canvas {
            start.clamp(0.0, canvas - size)
        } else {
            start
        }
    };
    let (x, y) = (inside(cx, w, cw), inside(cy, h, ch));
    let r = |v: f64| (v * 100.0).round() / 100.0;
    Some([r(x), r(y), r(w), r(h)])
}

/// `data` as JSON safe inside a `<script>` element: every `<` becomes the JSON
/// escape `\u003c`, so neither `</script` nor `<!--` can appear, and the text
/// still parses to the same value.
fn data_json(data: &HtmlData) -> String {
    // Serialising strings, numbers and bools cannot fail (non-finite numbers
    // become `null`); the fallback only keeps the page well-formed.
    let json = serde_json::to_string(data).unwrap_or_else(|_| "{\"nodes\":[]}".to_owned());
    json.replace('<', "\\u003c")
}

// The path first: the architecture test reads `#[cfg(test)]` as applying
// to the `mod` line right after it.
#[cfg(test)]
mod tests;
