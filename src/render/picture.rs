//! The finished picture: the treemap (`svg`) with its constraint
//! overlay, framed by an optional title band above and a legend band below, a
//! background and a border around the root outline. Owns the picture's frame
//! and the [`Style`] that configures it (issue 5: "title and legend from the
//! config; canvas size, background and outline configurable"); may not compute
//! geometry or do I/O. Map coordinates are never transformed: the bands extend
//! the `viewBox` above and below the canvas, so a cell's path is the same text
//! with or without a title.

use std::collections::HashMap;

use nptreemap_formats::Dataset;

use super::color_by::{self, Applied, ColorBy};
use super::display::{Cells, Picture};
use super::label_text::display_name;
use super::labels::{format_value, place_groups, Placed};
use super::legend::{legend, LegendItem};
use super::overlay::{marks_svg, place_markers, place_tabs, tabs_svg, Link, OverlayStyle};
use super::palette::{luminance, Rgb, WHITE};
use super::parts::Parts;
use super::svg::{
    cell_colors, cell_shapes, escape, leaf_labels, main_child, num, push_cells, push_labels,
    push_text, stroke_width, Kept, SvgStyle,
};
use super::text::width_em;
use crate::geom::Point;
use crate::layout::{Computed, Layout};

/// How the picture looks, beyond the geometry of its layout.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Style {
    /// Cells, outlines, labels, background and display size.
    pub cells: SvgStyle,
    /// Unrealised links and unlinked markers.
    pub overlay: OverlayStyle,
    /// Draw the interlocking tabs on realised constraints (method-reference
    /// §8.3). Default: `true`.
    pub tabs: bool,
    /// Text in a band above the map; `None` draws no band. Default: `None`.
    pub title: Option<String>,
    /// A band below the map naming the top-level groups with their colours and
    /// explaining the tab and unlinked glyphs when the picture has them.
    /// Default: `true` (drawn only when there is something to explain).
    pub legend: bool,
    /// The order of the legend's groups. Default: by weight.
    pub legend_order: LegendOrder,
    /// A line around the root outline; `None` draws none. Default: `None`.
    pub border: Option<Border>,
    /// Colour the leaves by a numeric field instead of by group; the legend
    /// then shows the scale. Default: `None`.
    pub color_by: Option<ColorBy>,
    /// What the HTML page shows of the data's own columns. Default: nothing.
    pub page: PageFields,
}

/// The data's own columns in the HTML page (issue 24 item 4).
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq, Eq)]
pub struct PageFields {
    /// Fields (carried columns) shown in the tooltip, in this order.
    pub fields: Vec<String>,
    /// The field holding each cell's link (`http:`, `https:` or a relative
    /// URL; any other value is shown as text, never followed).
    pub link: Option<String>,
    /// Open the link in a new tab (else in the page's own).
    pub new_tab: bool,
}

/// The order of the legend's groups.
#[derive(serde::Serialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum LegendOrder {
    /// Heaviest first.
    #[default]
    Weight,
    /// As in the data.
    Data,
    /// As in `render.labels.names`, the groups it does not name after them by weight.
    Names,
}

impl LegendOrder {
    /// The name used in configs.
    pub fn name(self) -> &'static str {
        match self {
            LegendOrder::Weight => "weight",
            LegendOrder::Data => "data",
            LegendOrder::Names => "names",
        }
    }

    /// Parses a config name.
    pub fn from_name(name: &str) -> Option<Self> {
        [LegendOrder::Weight, LegendOrder::Data, LegendOrder::Names]
            .into_iter()
            .find(|o| o.name() == name)
    }
}

/// The line drawn around the root outline.
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Border {
    /// Line colour.
    pub color: Rgb,
    /// Line width, canvas units.
    pub width: f64,
}

impl Default for Style {
    fn default() -> Self {
        Self {
            cells: SvgStyle::default(),
            overlay: OverlayStyle::default(),
            tabs: true,
            title: None,
            legend: true,
            legend_order: LegendOrder::default(),
            border: None,
            color_by: None,
            page: PageFields::default(),
        }
    }
}

/// Title font size per unit of canvas scale (see [`unit`]): 28 px on a
/// 1,000 × 1,000 canvas, a heading next to 9–24 px labels.
const TITLE_EM: f64 = 28.0;
/// Space around the title and the legend, canvas units per unit of scale.
const PAD: f64 = 16.0;
/// Baseline distance of a two-line title, in font sizes.
const TITLE_LEADING: f64 = 1.2;
/// Most lines of a title; the rest ends in an ellipsis.
const TITLE_LINES: usize = 2;
/// Bold text is this much wider than the regular font's metrics say
/// (DejaVu Sans Bold against Book, a little more than the widest).
const BOLD_WIDTH: f64 = 1.12;

/// A title in at most [`TITLE_LINES`] lines of at most `width` ems (bold):
/// broken at spaces, a word longer than a line cut, the last line ending in
/// an ellipsis when text is left over.
fn title_lines(text: &str, width: f64) -> Vec<String> {
    let fits = |t: &str| BOLD_WIDTH * width_em(t) <= width;
    // The longest prefix of `t` that fits followed by `tail` (whole chars).
    let cut = |t: &str, tail: &str| -> String {
        let chars: Vec<char> = t.chars().collect();
        let (mut lo, mut hi) = (0, chars.len());
        while lo < hi {
            let k = (lo + hi).div_ceil(2);
            let head: String = chars[..k].iter().collect();
            if fits(&format!("{}{tail}", head.trim_end())) {
                lo = k;
            } else {
                hi = k - 1;
            }
        }
        let head: String = chars[..lo].iter().collect();
        format!("{}{tail}", head.trim_end())
    };
    let mut lines = Vec::new();
    let mut rest = text.trim().to_owned();
    while !rest.is_empty() && lines.len() < TITLE_LINES {
        if fits(&rest) {
            lines.push(std::mem::take(&mut rest));
            break;
        }
        if lines.len() + 1 == TITLE_LINES {
            lines.push(cut(&rest, "…"));
            break;
        }
        // The most words that fit; a first word too long is cut.
        let mut end = 0;
        for (at, _) in rest.match_indices(' ') {
            if fits(&rest[..at]) {
                end = at;
            } else {
                break;
            }
        }
        let line = if end > 0 {
            rest[..end].to_owned()
        } else {
            cut(&rest, "")
        };
        if line.is_empty() {
            break;
        }
        rest = rest[line.len()..].trim_start().to_owned();
        lines.push(line);
    }
    lines
}

/// Canvas scale: 1 on a 1,000 × 1,000 canvas, so text and padding grow with
/// the map instead of vanishing on large canvases; never below 0.75, so the
/// legend of a small picture stays readable (10.5 px text at 400 × 400).
pub(crate) fn unit(layout: &Layout) -> f64 {
    ((layout.canvas.width * layout.canvas.height).sqrt() / 1000.0).max(MIN_UNIT)
}

/// Smallest canvas scale for the frame's text (see [`unit`]).
const MIN_UNIT: f64 = 0.75;

/// The constraint links the picture draws: those of the deepest level (where
/// the paper draws them, method-reference §8.2–8.4), each end named by
/// `real` (the page names a virtual copy by its original); a link with an
/// end `real` does not know is left out.
pub(crate) fn deepest_links(
    computed: &Computed,
    real: impl Fn(usize) -> Option<usize>,
) -> Vec<Link> {
    let dataset = &computed.dataset;
    let deepest = dataset.max_depth();
    computed
        .constraints
        .iter()
        .zip(&computed.realized)
        .filter(|(c, _)| dataset.node(c.a).depth == deepest)
        .filter_map(|(c, r)| {
            Some(Link {
                a: real(c.a)?,
                b: real(c.b)?,
                similarity: c.similarity,
                realized: *r,
            })
        })
        .collect()
}

/// The fill colour of every node of the picture (see [`fills`]).
pub(crate) fn colors(computed: &Computed, style: &Style) -> Vec<Option<Rgb>> {
    let pairs = computed.adjacency().get(1).map_or(&[][..], |a| a.pairs());
    fills(&computed.dataset, pairs, style).0
}

/// The fill colour of every node: by group ([`cell_colors`]), or the
/// leaves by `style.color_by` with the scale as applied.
pub(crate) fn fills(
    dataset: &Dataset,
    adjacent: &[(usize, usize)],
    style: &Style,
) -> (Vec<Option<Rgb>>, Option<Applied>) {
    let mut colors = cell_colors(
        dataset,
        adjacent,
        style.cells.palette,
        &style.cells.group_colors,
        &style.cells.kept,
    );
    let applied = style
        .color_by
        .as_ref()
        .and_then(|by| color_by::apply(dataset, &mut colors, by));
    (colors, applied)
}

/// The colours a picture is drawn with under `style`, as the next build
/// keeps them ([`Kept`]): each top-level group's colour, by id, and per
/// parent of two or more children the child that wears its colour. Drawing
/// again with these as `SvgStyle::kept` gives the same colours: every one
/// is fixed then.
pub fn group_colors(computed: &Computed, style: &Style) -> Kept {
    let dataset = &computed.dataset;
    let pairs = computed.adjacency().get(1).map_or(&[][..], |a| a.pairs());
    let (colors, _) = fills(dataset, pairs, style);
    let groups = dataset
        .node(dataset.root())
        .children
        .iter()
        .filter_map(|&g| {
            Some((
                dataset.node(g).id.clone(),
                colors.get(g).copied().flatten()?,
            ))
        })
        .collect();
    let main = (0..dataset.len())
        .filter(|&p| dataset.node(p).children.len() >= 2)
        .map(|p| {
            let node = dataset.node(p);
            let k = main_child(dataset, p, &style.cells.kept.main);
            (node.id.clone(), dataset.node(node.children[k]).id.clone())
        })
        .collect();
    Kept { groups, main }
}

/// The SVG picture of a finished computation: the treemap with, when there are
/// constraints, the interlocking tabs and unrealised-link markers of its
/// deepest level, framed as `style` says. Identical input gives identical bytes.
pub fn picture(computed: &Computed, style: &Style) -> String {
    picture_with(computed, style, &Parts::new()).text
}

/// Fits the leaf labels of `computed`'s picture into `parts` ahead of the
/// outputs that draw them (the picture and the page), so that outputs
/// rendered at once share one fitting instead of each making its own.
pub fn fit_labels(computed: &Computed, style: &Style, parts: &Parts) {
    leaf_labels(
        &computed.dataset,
        &computed.layout,
        &style.cells.labels,
        parts,
    );
}

/// [`picture`] with the labels `parts` has from this render's other outputs
/// and the render before (the same bytes, fewer labels fitted), and its
/// cells as shapes for the PNG.
pub fn picture_with(computed: &Computed, style: &Style, parts: &Parts) -> Picture {
    let pairs = computed.adjacency().get(1).map_or(&[][..], |a| a.pairs());
    compose_noted(
        &computed.dataset,
        &computed.layout,
        &deepest_links(computed, Some),
        pairs,
        style,
        computed.zero.summary().as_deref(),
        parts,
    )
    .with_shapes(&computed.dataset, &computed.layout, style)
}

/// Draws the picture of `layout` (cells indexed like `dataset`) with the
/// constraint `links` of its deepest level; `adjacent` are the top-level
/// groups that share an edge (node index pairs), for their colours. Labels are
/// placed first, tabs clear of them, markers clear of both. Identical input
/// gives identical bytes.
pub fn compose(
    dataset: &Dataset,
    layout: &Layout,
    links: &[Link],
    adjacent: &[(usize, usize)],
    style: &Style,
) -> String {
    compose_noted(dataset, layout, links, adjacent, style, None, &Parts::new()).text
}

/// A picture's text, with what its shapes need: the cells' group's bytes
/// and the fills.
pub(crate) struct Composed {
    pub text: String,
    cells: std::ops::Range<usize>,
    colors: Vec<Option<Rgb>>,
}

impl Composed {
    /// The picture, with its cells as shapes for the PNG (only a build with
    /// PNG output paints them).
    pub(crate) fn with_shapes(self, dataset: &Dataset, layout: &Layout, style: &Style) -> Picture {
        let shapes = cfg!(feature = "png")
            .then(|| cell_shapes(dataset, layout, &style.cells, &self.colors))
            .flatten();
        Picture {
            cells: shapes.map(|shapes| Cells {
                range: self.cells,
                shapes,
            }),
            text: self.text,
        }
    }
}

/// [`compose`] with a `note` first in the legend: what the picture leaves
/// out or does not draw to scale (issue 34: "12 items of weight 0 not drawn"),
/// and the labels `parts` keeps.
pub(crate) fn compose_noted(
    dataset: &Dataset,
    layout: &Layout,
    links: &[Link],
    adjacent: &[(usize, usize)],
    style: &Style,
    note: Option<&str>,
    parts: &Parts,
) -> Composed {
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);
    let u = unit(layout);
    let (colors, applied) = fills(dataset, adjacent, style);
    let labels = leaf_labels(dataset, layout, &style.cells.labels, parts);
    let groups = if style.cells.labels.groups {
        place_groups(dataset, layout, &style.cells.labels, &labels, u)
    } else {
        Vec::new()
    };
    let edge_width = |a: usize, b: usize| outline_between(dataset, style.cells.stroke_width, a, b);
    let tabs = if style.tabs {
        place_tabs(layout, links, &labels, u, &edge_width)
    } else {
        Vec::new()
    };
    let markers = if style.overlay.unlinked_markers {
        place_markers(layout, links, &labels, &tabs, u, style.overlay.marker_share)
    } else {
        Vec::new()
    };

    let title_size = TITLE_EM * u;
    let title = style
        .title
        .as_deref()
        .map(super::label_text::clean)
        .filter(|t| !t.is_empty())
        .map(|t| title_lines(&t, (cw - 2.0 * PAD * u) / title_size))
        .filter(|lines| !lines.is_empty());
    let top = title.as_ref().map_or(0.0, |lines| {
        (1.0 + TITLE_LEADING * (lines.len() - 1) as f64) * title_size + 2.0 * PAD * u
    });
    let items = if style.legend {
        legend_items(
            dataset,
            &colors,
            applied.as_ref(),
            (!tabs.is_empty(), !markers.is_empty()),
            note,
            style,
        )
    } else {
        Vec::new()
    };
    let (legend_text, legend_height) = legend(&items, cw, ch, u, &style.cells);
    let total = top + ch + legend_height;

    let width = style.cells.width.unwrap_or(cw);
    let height = style.cells.height.unwrap_or(width * total / cw);
    let mut out = String::with_capacity(1024 + 300 * dataset.len());
    out.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 {} {} {}\">\n",
        num(width),
        num(height),
        num(-top),
        num(cw),
        num(total),
    ));
    if let Some(bg) = style.cells.background {
        out.push_str(&format!(
            "<rect class=\"np-background\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{bg}\"/>\n",
            num(-top),
            num(cw),
            num(total)
        ));
    }
    if let Some(lines) = &title {
        push_title(&mut out, lines, title_size, u, style);
    }
    let memo = parts.cell_lines();
    let start = out.len();
    push_cells(&mut out, dataset, layout, &style.cells, &colors, memo);
    let cells = start..out.len();
    // Tabs on the edges, group names across the groups, then the leaf labels
    // over both, the markers last (they never overlap a label).
    if !tabs.is_empty() {
        out.push_str(&tabs_svg(dataset, &tabs, &colors, style.cells.stroke));
    }
    push_group_labels(&mut out, &groups, &style.cells, |name| {
        name_fill(dataset, layout, &colors, name, style.cells.text_color)
    });
    push_labels(&mut out, &labels, &style.cells);
    if !links.is_empty() {
        out.push_str(&marks_svg(layout, links, &markers, &style.overlay, u));
    }
    push_border(&mut out, dataset, layout, style);
    out.push_str(&legend_text);
    out.push_str("</svg>\n");
    Composed {
        text: out,
        cells,
        colors,
    }
}

/// The outline width between cells `a` and `b`: that of their lowest common
/// ancestor's children.
fn outline_between(dataset: &Dataset, base: f64, a: usize, b: usize) -> f64 {
    let (mut x, mut y) = (a, b);
    while dataset.node(x).depth > dataset.node(y).depth {
        x = dataset.node(x).parent.unwrap_or(x);
    }
    while dataset.node(y).depth > dataset.node(x).depth {
        y = dataset.node(y).parent.unwrap_or(y);
    }
    while x != y {
        match (dataset.node(x).parent, dataset.node(y).parent) {
            (Some(px), Some(py)) => {
                x = px;
                y = py;
            }
            _ => break,
        }
    }
    stroke_width(base, dataset.node(x).depth + 1)
}

/// The title's lines, one `<text>` each, the last one's baseline where a
/// one-line title's is.
fn push_title(out: &mut String, lines: &[String], title_size: f64, u: f64, style: &Style) {
    let last = lines.len() - 1;
    for (k, line) in lines.iter().enumerate() {
        let y = -PAD * u - 0.25 * title_size - TITLE_LEADING * title_size * (last - k) as f64;
        out.push_str(&format!(
            "<text class=\"np-title\" x=\"{}\" y=\"{}\" font-family=\"{}\" font-size=\"{}\" font-weight=\"bold\" fill=\"{}\">{}</text>\n",
            num(PAD * u),
            num(y),
            escape(&style.cells.font_family),
            num(title_size),
            style.cells.text_color,
            escape(line)
        ));
    }
}

/// The border round the map (the root's cell), when the style has one.
fn push_border(out: &mut String, dataset: &Dataset, layout: &Layout, style: &Style) {
    let Some(border) = style
        .border
        .filter(|b| b.width > 0.0 && b.width.is_finite())
    else {
        return;
    };
    let root = dataset.root();
    if root < layout.cells.len() {
        let pts: Vec<String> = layout.cells[root]
            .polygon
            .points()
            .iter()
            .map(|p| format!("{},{}", num(p.x), num(p.y)))
            .collect();
        out.push_str(&format!(
            "<polygon class=\"np-border\" points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\"/>\n",
            pts.join(" "),
            border.color,
            num(border.width)
        ));
    }
}

/// Opacity of the group names: large and light, under the leaf labels.
const GROUP_OPACITY: f64 = 0.3;

/// Appends the group names in their own group, drawn without a halo, each
/// in the colour `fill` picks for it.
fn push_group_labels(
    out: &mut String,
    groups: &[Placed],
    style: &SvgStyle,
    fill: impl Fn(&Placed) -> Rgb,
) {
    if groups.is_empty() {
        return;
    }
    out.push_str(&format!(
        "<g class=\"np-group-labels\" font-family=\"{}\" text-anchor=\"middle\" fill=\"{}\" fill-opacity=\"{}\" pointer-events=\"none\">\n",
        escape(&style.font_family),
        style.text_color,
        num(GROUP_OPACITY)
    ));
    for g in groups {
        push_text(out, g, false, Some(fill(g)));
    }
    out.push_str("</g>\n");
}

/// Points sampled across a group name's box per side (across, down) to find
/// the cells under it.
const NAME_SAMPLES: (usize, usize) = (7, 3);

/// The colour of a group name: `text` (the labels' colour) or white,
/// whichever contrasts more (WCAG ratio) with the cells under the name, the
/// mean luminance of its group's leaf cells at points across its box. Cells
/// keep their colours in the page's dark mode, so the choice holds in every
/// output; a fixed colour (white in dark mode, dark otherwise) was unreadable
/// on light or dark cells (issue 21).
fn name_fill(
    dataset: &Dataset,
    layout: &Layout,
    colors: &[Option<Rgb>],
    name: &Placed,
    text: Rgb,
) -> Rgb {
    let color_of = |i: usize| colors.get(i).copied().flatten();
    let mut leaves = Vec::new();
    let mut stack = vec![name.node];
    while let Some(i) = stack.pop() {
        if i >= dataset.len() {
            continue;
        }
        let children = &dataset.node(i).children;
        if children.is_empty() {
            leaves.push(i);
        }
        stack.extend(children.iter().copied());
    }
    let r = &name.rect;
    let center = Point::new(0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1));
    let (sin, cos) = name.angle.to_radians().sin_cos();
    let (nx, ny) = NAME_SAMPLES;
    let mut sum = 0.0;
    let mut found = 0usize;
    for ix in 0..nx {
        for iy in 0..ny {
            let f = |k: usize, n: usize| (k as f64 + 0.5) / n as f64;
            let d = Point::new(
                r.x0 + f(ix, nx) * (r.x1 - r.x0),
                r.y0 + f(iy, ny) * (r.y1 - r.y0),
            ) - center;
            let p = center + Point::new(d.x * cos - d.y * sin, d.x * sin + d.y * cos);
            let under = leaves
                .iter()
                .find(|&&l| l < layout.cells.len() && layout.cells[l].polygon.contains(p));
            if let Some(c) = under.and_then(|&l| color_of(l)) {
                sum += luminance(c);
                found += 1;
            }
        }
    }
    let under = if found > 0 {
        sum / found as f64
    } else {
        luminance(color_of(name.node).unwrap_or(super::palette::TABLEAU10[0]))
    };
    let contrast = |c: Rgb| {
        let l = luminance(c);
        (l.max(under) + 0.05) / (l.min(under) + 0.05)
    };
    if contrast(WHITE) > contrast(text) {
        WHITE
    } else {
        text
    }
}

/// The legend of a picture coloured by a field: its scale (named log or
/// clipped when it is), and a swatch for the cells without a value.
fn scale_items(a: &Applied) -> Vec<LegendItem> {
    // A clipped scale's ends hold every value beyond them.
    let (below, above) = if a.clipped {
        ("≤ ", "≥ ")
    } else {
        ("", "")
    };
    let mut items = vec![LegendItem::Scale {
        field: if a.log {
            format!("{} (log scale)", a.field)
        } else if a.clipped {
            format!("{} (scale clipped at outliers)", a.field)
        } else {
            a.field.clone()
        },
        low: format!("{below}{}", format_value(a.lo, "")),
        high: format!("{above}{}", format_value(a.hi, "")),
        stops: a.stops.clone(),
    }];
    if a.missing {
        items.push(LegendItem::Swatch {
            color: color_by::MISSING,
            label: format!("no {} value", a.field),
            group: None,
        });
    }
    items
}

/// What the legend lists: the `note` (first, so that no cut drops it), a
/// key for each glyph the picture draws (`tabs`, `markers`), then the
/// top-level groups (when they have children of their own; otherwise every
/// cell is labelled already) in the style's order. Two groups with the same
/// name are told apart by their ids.
pub(crate) fn legend_items(
    dataset: &Dataset,
    colors: &[Option<Rgb>],
    applied: Option<&Applied>,
    (tabs, markers): (bool, bool),
    note: Option<&str>,
    style: &Style,
) -> Vec<LegendItem> {
    let mut items = Vec::new();
    if let Some(note) = note {
        items.push(LegendItem::Note(note.to_string()));
    }
    if tabs {
        items.push(LegendItem::Tab);
    }
    if markers {
        items.push(LegendItem::Unlinked);
    }
    // Coloured by a field, the colours mean its values, not the groups
    // (whose names are on the map).
    if let Some(a) = applied {
        items.extend(scale_items(a));
        return items;
    }
    let root = dataset.node(dataset.root());
    let groups_have_children = root
        .children
        .iter()
        .any(|&c| !dataset.node(c).children.is_empty());
    if root.children.len() < 2 || !groups_have_children {
        return items;
    }
    let names = &style.cells.labels.names;
    // Virtual nodes (issue 3's depth padding) repeat their child's label
    // and colour; the legend names only groups people gave.
    let mut groups: Vec<usize> = root
        .children
        .iter()
        .copied()
        .filter(|&c| !dataset.node(c).is_virtual)
        .collect();
    let by_weight = |a: &usize, b: &usize| {
        dataset
            .node(*b)
            .value
            .total_cmp(&dataset.node(*a).value)
            .then(a.cmp(b))
    };
    match style.legend_order {
        LegendOrder::Data => {}
        LegendOrder::Weight => groups.sort_by(by_weight),
        LegendOrder::Names => {
            let rank = |i: usize| {
                let n = dataset.node(i);
                let names = &style.cells.labels.names;
                let ranks = [names.rank(&n.id), names.rank(&n.label)];
                ranks.into_iter().flatten().min().unwrap_or(usize::MAX)
            };
            groups.sort_by(|a, b| rank(*a).cmp(&rank(*b)).then(by_weight(a, b)));
        }
    }
    let labels: Vec<String> = groups
        .iter()
        .map(|&g| display_name(dataset, g, names, &style.cells.labels.text))
        .collect();
    // How often each name is given: a name two groups share is told apart
    // by their ids. Counted once, not per group (a count per group was
    // quadratic: 26 s of string comparisons in the SVG and HTML renders
    // of 50,000 top-level files).
    let mut given: HashMap<&str, usize> = HashMap::with_capacity(labels.len());
    for label in &labels {
        *given.entry(label.as_str()).or_default() += 1;
    }
    for (k, &g) in groups.iter().enumerate() {
        let twice = given.get(labels[k].as_str()).is_some_and(|&n| n > 1);
        let id = &dataset.node(g).id;
        let label = if twice && *id != labels[k] {
            format!("{} ({})", labels[k], super::label_text::clean(id))
        } else {
            labels[k].clone()
        };
        items.push(LegendItem::Swatch {
            color: colors[g].unwrap_or(super::palette::TABLEAU10[0]),
            label,
            group: Some(id.clone()),
        });
    }
    items
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::test_support::sample;

    fn view_box(svg: &str) -> Vec<f64> {
        let start = svg.find("viewBox=\"").expect("viewBox") + 9;
        let end = start + svg[start..].find('"').expect("closing quote");
        svg[start..end]
            .split(' ')
            .map(|v| v.parse().expect("number"))
            .collect()
    }

    #[test]
    fn title_and_legend_extend_the_view_without_moving_cells() {
        let (ds, layout) = sample();
        let plain = compose(
            &ds,
            &layout,
            &[],
            &[],
            &Style {
                legend: false,
                ..Style::default()
            },
        );
        assert_eq!(view_box(&plain), vec![0.0, 0.0, 400.0, 200.0]);
        let framed = compose(
            &ds,
            &layout,
            &[],
            &[],
            &Style {
                title: Some("World <b>".to_string()),
                ..Style::default()
            },
        );
        let vb = view_box(&framed);
        assert!(vb[1] < 0.0, "title band above the canvas: {vb:?}");
        assert!(vb[1] + vb[3] > 200.0, "legend band below: {vb:?}");
        assert!(framed.contains("World &lt;b&gt;"));
        // The cells are the same text either way.
        let cells = |s: &str| {
            s.lines()
                .filter(|l| l.starts_with("<path "))
                .map(str::to_owned)
                .collect::<Vec<_>>()
        };
        assert_eq!(cells(&plain), cells(&framed));
        // The legend names the two top-level groups (A has children).
        assert_eq!(framed.matches("class=\"np-legend-item\"").count(), 2);
    }

    #[test]
    fn a_long_title_wraps_to_two_lines_within_the_canvas_then_ends_in_an_ellipsis() {
        let (ds, layout) = sample();
        let titles = |t: &str| -> (Vec<String>, Vec<f64>) {
            let svg = compose(
                &ds,
                &layout,
                &[],
                &[],
                &Style {
                    title: Some(t.to_string()),
                    ..Style::default()
                },
            );
            let lines: Vec<&str> = svg
                .lines()
                .filter(|l| l.contains("class=\"np-title\""))
                .collect();
            let text = |l: &str| {
                l.split('>')
                    .nth(1)
                    .and_then(|t| t.split('<').next())
                    .unwrap_or("")
                    .to_string()
            };
            let attr = |l: &str, a: &str| -> f64 {
                l.split(&format!(" {a}=\""))
                    .nth(1)
                    .and_then(|t| t.split('"').next())
                    .and_then(|t| t.parse().ok())
                    .expect("number")
            };
            (
                lines.iter().map(|l| text(l)).collect(),
                lines
                    .iter()
                    .map(|l| attr(l, "x") + attr(l, "font-size") * width_em(&text(l)))
                    .collect(),
            )
        };
        let (short, _) = titles("Packages");
        assert_eq!(short, vec!["Packages".to_string()]);
        let long = "Every package of the Debian archive by section and size, with its neighbours \
                    by the packages it depends on, drawn as a Voronoi treemap";
        let (lines, right) = titles(long);
        assert_eq!(lines.len(), 2, "{lines:?}");
        // Inside the 400-unit canvas (right edges, the regular font's metrics).
        assert!(right.iter().all(|&r| r <= 400.0), "{right:?} {lines:?}");
        // The words in order, the second line cut with an ellipsis.
        assert!(long.starts_with(&lines[0]), "{lines:?}");
        let second = lines[1].strip_suffix('…').expect("ellipsis");
        assert!(
            long[lines[0].len()..].trim_start().starts_with(second),
            "{lines:?}"
        );
        // One word longer than a line is cut, not left running off the canvas.
        let (word, right) = titles(&"W".repeat(80));
        assert!(
            !word.is_empty() && right.iter().all(|&r| r <= 400.0),
            "{word:?}"
        );
    }

    #[test]
    fn border_and_background_follow_the_style() {
        let (ds, layout) = sample();
        let style = Style {
            border: Some(Border {
                color: Rgb::new(0x33, 0x33, 0x33),
                width: 2.0,
            }),
            cells: SvgStyle {
                background: None,
                ..SvgStyle::default()
            },
            ..Style::default()
        };
        let s = compose(&ds, &layout, &[], &[], &style);
        assert!(s.contains("class=\"np-border\""));
        assert!(s.contains("stroke=\"#333333\" stroke-width=\"2.00\""));
        assert!(!s.contains("np-background"), "no background rectangle");
        let s = compose(&ds, &layout, &[], &[], &Style::default());
        assert!(!s.contains("np-border"));
        assert!(s.contains("<rect class=\"np-background\" y=\"0.00\" width=\"400.00\""));
    }

    #[test]
    fn tabs_can_be_switched_off() {
        let (ds, layout) = sample();
        // A1 and A2 share a 240-unit edge: room for a tab.
        let link = Link {
            a: ds.find("A1").expect("A1"),
            b: ds.find("A2").expect("A2"),
            similarity: 0.9,
            realized: true,
        };
        let with = compose(
            &ds,
            &layout,
            std::slice::from_ref(&link),
            &[],
            &Style::default(),
        );
        assert_eq!(with.matches("class=\"np-tab\"").count(), 1);
        assert!(with.contains("class=\"np-legend-tab\""));
        let without = compose(
            &ds,
            &layout,
            &[link],
            &[],
            &Style {
                tabs: false,
                ..Style::default()
            },
        );
        assert_eq!(without.matches("class=\"np-tab\"").count(), 0);
        assert!(!without.contains("np-legend-tab"));
    }

    /// Issue 21: a group's legend swatch (`#8cd17d`) differed from its
    /// largest cell's colour (`#65c151`). Every swatch's colour fills a cell
    /// of its group: the heaviest one.
    #[test]
    fn every_legend_swatch_is_the_colour_of_its_groups_largest_cell() {
        let (ds, layout) = sample();
        let svg = compose(&ds, &layout, &[], &[], &Style::default());
        let legend = &svg[svg.find("np-legend").expect("a legend")..];
        let swatches: Vec<&str> = legend
            .split("<rect ")
            .skip(1)
            .filter_map(|r| r.split("fill=\"").nth(1)?.split('"').next())
            .collect();
        assert_eq!(swatches.len(), 2, "{legend}");
        let fill_of = |id: &str| {
            let at = svg.find(&format!("data-id=\"{id}\"")).expect("cell");
            svg[at..]
                .split("fill=\"")
                .nth(1)
                .and_then(|f| f.split('"').next())
                .expect("fill")
                .to_owned()
        };
        // A's heaviest child is A1; B is a leaf with its own colour.
        assert!(swatches.contains(&fill_of("A1").as_str()), "{swatches:?}");
        assert!(swatches.contains(&fill_of("B").as_str()), "{swatches:?}");
    }

    /// Issue 21: in dark mode the group names were white whatever the cells
    /// under them, unreadable on light cells (and the light mode's dark
    /// names on dark cells). Each name takes the colour, dark or white, that
    /// contrasts more with the cells under it, in every output.
    #[test]
    fn group_names_contrast_with_the_cells_under_them() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for (g, color) in [("Light", "#f2efe6"), ("Dark", "#1d2b5c")] {
            b.add(
                NodeSpec::new(g)
                    .parent("root")
                    .color(Rgb::from_hex(color).expect("colour")),
            );
            for k in 0..3 {
                b.add(
                    NodeSpec::new(format!("{g}{k}"))
                        .parent(g)
                        .weight(10.0 + k as f64),
                );
            }
        }
        let ds = b.build().expect("valid");
        let c = crate::layout::compute(&ds, &crate::layout::Request::default()).expect("layout");
        let svg = picture(&c, &Style::default());
        let names = &svg[svg.find("np-group-labels").expect("group names")..];
        let names = &names[..names.find("</g>").expect("end")];
        let fill_of = |name: &str| {
            let at = names.find(&format!(">{name}<")).expect(name);
            let start = names[..at].rfind("<text").expect("text");
            names[start..at]
                .split("fill=\"")
                .nth(1)
                .and_then(|f| f.split('"').next())
                .map(str::to_owned)
        };
        let text = SvgStyle::default().text_color.to_string();
        assert_eq!(fill_of("Light"), Some(text), "{names}");
        assert_eq!(fill_of("Dark"), Some("#ffffff".to_owned()), "{names}");
    }

    /// Two top-level groups labelled alike are told apart in the legend by
    /// their ids; a name given once keeps its own text. (The names are
    /// counted once for all groups: counting them per group was quadratic,
    /// 26 s of renders for 50,000 top-level files.)
    #[test]
    fn legend_names_two_groups_of_one_label_by_their_ids() {
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for (g, label) in [("north", "Same"), ("south", "Same"), ("east", "Other")] {
            b.add(NodeSpec::new(g).parent("root").label(label));
            for k in 0..2 {
                b.add(
                    NodeSpec::new(format!("{g}{k}"))
                        .parent(g)
                        .weight(10.0 + k as f64),
                );
            }
        }
        let ds = b.build().expect("valid");
        let colors = vec![None; ds.len()];
        let labels: Vec<String> =
            legend_items(&ds, &colors, None, (false, false), None, &Style::default())
                .into_iter()
                .filter_map(|item| match item {
                    LegendItem::Swatch { label, .. } => Some(label),
                    _ => None,
                })
                .collect();
        let mut sorted = labels.clone();
        sorted.sort();
        assert_eq!(
            sorted,
            ["Other", "Same (north)", "Same (south)"],
            "{labels:?}"
        );
    }

    #[test]
    fn svg_parses_and_is_deterministic() {
        let (ds, layout) = sample();
        let style = Style {
            title: Some("T & <t>".to_string()),
            ..Style::default()
        };
        let a = compose(&ds, &layout, &[], &[], &style);
        assert_eq!(a, compose(&ds, &layout, &[], &[], &style));
        #[cfg(feature = "png")]
        resvg::usvg::Tree::from_str(&a, &resvg::usvg::Options::default()).expect("valid SVG");
    }
}
