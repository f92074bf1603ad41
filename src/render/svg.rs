//! The SVG picture of a finished layout: filled leaf cells coloured by top-level
//! group (colours assigned from which groups touch), white outlines thicker for
//! higher levels, and the SVG text of placed labels (`super::labels` decides
//! where). Owns the picture's structure and colours per node; may not compute or
//! alter geometry, fail, or do I/O. Output is deterministic: fixed two-decimal
//! coordinates, nodes in dataset order.

use crate::line_memo::{Line, LineMemo};
use nptreemap_formats::Dataset;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::chains::drawn_leaf;
use super::label_text::display_name;
use rayon::prelude::*;

use super::display::Shape;
use super::labels::{format_value, LabelStyle, Placed};
use super::palette::{self, PaletteKind, Rgb, WHITE};
use super::parts::{LabelKey, Parts};
use crate::geom::ConvexPolygon;
use crate::layout::Layout;

/// Halo stroke width around label glyphs, in font sizes (half of it shows).
pub(crate) const HALO_EM: f64 = 0.2;
/// Each hierarchy level down draws its outlines this much thinner.
const STROKE_DECAY: f64 = 0.5;
/// Thinnest outline, canvas units: thinner lines vanish in anti-aliasing.
const MIN_STROKE_WIDTH: f64 = 0.5;

/// How the picture looks. Geometry comes from the layout; this only styles it.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct SvgStyle {
    /// The `width` attribute (display size). The `viewBox` is always the layout's
    /// canvas, so a different size scales the whole picture.
    /// Default: `None`, the layout canvas width.
    pub width: Option<f64>,
    /// The `height` attribute. Default: `None`, the layout canvas height.
    pub height: Option<f64>,
    /// Background fill of the canvas; `None` leaves it transparent.
    /// Default: `Some(#ffffff)`.
    pub background: Option<Rgb>,
    /// Colour of cell outlines. Default: `#ffffff`.
    pub stroke: Rgb,
    /// Outline width, canvas units, between top-level groups; every level down
    /// halves it, never below 0.5 (or this value, if smaller). Default: `3.0`.
    pub stroke_width: f64,
    /// Leaf labels and group names: whether, how small, with values, names.
    pub labels: LabelStyle,
    /// The top-level groups' palette. Default: Tableau.
    pub palette: PaletteKind,
    /// Pinned colours of top-level groups, by id or label
    /// (`render.colors`); a node's own `color` still wins. Default: none.
    pub group_colors: BTreeMap<String, Rgb>,
    /// The colours kept from the last build (the state manifest's): a
    /// group keeps its colour while the palette still holds it, and a
    /// parent's colour stays on the same child; pins and a node's own
    /// colour win. Default: none.
    pub kept: Kept,
    /// CSS font-family list for labels (kept free of quotes). Default:
    /// `Helvetica, Arial, DejaVu Sans, sans-serif`, a generic stack; PNG output
    /// pins its own font.
    pub font_family: String,
    /// Label text colour; labels get a halo in the `stroke` colour.
    /// Default: `#1a1a1a`.
    pub text_color: Rgb,
}

impl Default for SvgStyle {
    fn default() -> Self {
        Self {
            width: None,
            height: None,
            background: Some(WHITE),
            stroke: WHITE,
            stroke_width: 3.0,
            labels: LabelStyle::default(),
            palette: PaletteKind::default(),
            group_colors: BTreeMap::new(),
            kept: Kept::default(),
            font_family: "Helvetica, Arial, DejaVu Sans, sans-serif".to_owned(),
            text_color: Rgb::new(0x1a, 0x1a, 0x1a),
        }
    }
}

/// What a build keeps of the last one's colours (issue 32), so that no
/// edit recolours the picture: each top-level group's colour, and per
/// parent the child that wears the parent's colour (its siblings' shades
/// are counted from it, so a new heaviest child would shift them all).
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq)]
pub struct Kept {
    /// Colour of each top-level group, by group id.
    pub groups: BTreeMap<String, Rgb>,
    /// The child (by id) that wears its parent's colour, by parent id.
    pub main: BTreeMap<String, String>,
}

/// How the label group opens (its attributes follow); its class lets tests
/// and pages find the cell labels among the picture's other text.
const LABELS_GROUP: &str = "<g class=\"np-labels\"";

/// Draws `layout` (cells indexed like `dataset`'s nodes) as an SVG document.
///
/// Every non-root cell is one `<path>`: leaves filled, internal nodes as
/// `fill="none"` outlines. Levels are drawn deepest first, so the thick outlines
/// between top-level groups lie on top. The root is drawn only when it is the
/// only cell. Identical input gives identical bytes.
pub fn svg(dataset: &Dataset, layout: &Layout, style: &SvgStyle) -> String {
    debug_assert_eq!(dataset.len(), layout.cells.len(), "one cell per node");
    let count = dataset.len().min(layout.cells.len());
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);

    let mut out = String::with_capacity(512 + 160 * count);
    out.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\">\n",
        num(style.width.unwrap_or(cw)),
        num(style.height.unwrap_or(ch)),
        num(cw),
        num(ch),
    ));
    if let Some(bg) = style.background {
        out.push_str(&format!(
            "<rect width=\"{}\" height=\"{}\" fill=\"{bg}\"/>\n",
            num(cw),
            num(ch)
        ));
    }

    let root = dataset.node(dataset.root());
    let adjacency = layout.level_adjacency(&root.children);
    let colors = cell_colors(
        dataset,
        adjacency.pairs(),
        style.palette,
        &style.group_colors,
        &style.kept,
    );
    push_cells(&mut out, dataset, layout, style, &colors, None);
    let labels = leaf_labels(dataset, layout, &style.labels, &Parts::new());
    push_labels(&mut out, &labels, style);
    out.push_str("</svg>\n");
    out
}

/// Appends every drawn cell, deepest level first, each level in its own group
/// with its outline width (see [`svg`]). With `memo`, a cell's element is
/// taken from the lines written before when its id, label, fill and outline
/// (bit for bit) are the same, and kept there when written.
pub(crate) fn push_cells(
    out: &mut String,
    dataset: &Dataset,
    layout: &Layout,
    style: &SvgStyle,
    colors: &[Option<Rgb>],
    memo: Option<&LineMemo>,
) {
    let by_depth = drawn_by_depth(dataset, layout);
    out.push_str(&format!(
        "<g class=\"np-cells\" stroke=\"{}\" stroke-linejoin=\"round\">\n",
        style.stroke
    ));
    for (depth, nodes) in by_depth.iter().enumerate().rev() {
        if nodes.is_empty() {
            continue;
        }
        out.push_str(&format!(
            "<g stroke-width=\"{}\">\n",
            num(stroke_width(style.stroke_width, depth))
        ));
        match memo {
            Some(memo) => push_remembered(out, dataset, layout, colors, nodes, memo),
            None => {
                for &i in nodes {
                    push_cell(out, dataset, layout, colors, i);
                }
            }
        }
        out.push_str("</g>\n");
    }
    out.push_str("</g>\n");
}

/// The drawn cells' node indices per depth, each list in dataset order:
/// the writer draws the lists deepest first.
fn drawn_by_depth(dataset: &Dataset, layout: &Layout) -> Vec<Vec<usize>> {
    let count = dataset.len().min(layout.cells.len());
    let mut by_depth: Vec<Vec<usize>> = vec![Vec::new(); dataset.max_depth() + 1];
    for i in (0..count).filter(|&i| is_drawn(dataset, i)) {
        let d = dataset.node(i).depth;
        if d >= by_depth.len() {
            by_depth.resize_with(d + 1, Vec::new);
        }
        by_depth[d].push(i);
    }
    by_depth
}

/// The cells [`push_cells`] draws, as shapes in its order with the numbers
/// its text spells (`display`); `None` when one has no such spelling.
pub(crate) fn cell_shapes(
    dataset: &Dataset,
    layout: &Layout,
    style: &SvgStyle,
    colors: &[Option<Rgb>],
) -> Option<Vec<Shape>> {
    use rayon::prelude::*;
    let by_depth = drawn_by_depth(dataset, layout);
    let order: Vec<(usize, f64)> = by_depth
        .iter()
        .enumerate()
        .rev()
        .flat_map(|(depth, nodes)| {
            let width = stroke_width(style.stroke_width, depth);
            nodes.iter().map(move |&i| (i, width))
        })
        .collect();
    order
        .par_iter()
        .map(|&(i, width)| {
            let points = layout.cells[i]
                .polygon
                .points()
                .iter()
                .map(|p| Some([spelled(p.x)?, spelled(p.y)?]))
                .collect::<Option<Vec<_>>>()?;
            Some(Shape {
                points,
                fill: cell_fill(dataset, colors, i),
                stroke: style.stroke,
                width: spelled(width)?,
            })
        })
        .collect()
}

/// The fill of cell `i`: its leaf's colour ([`drawn_leaf`]), none for a
/// group.
fn cell_fill(dataset: &Dataset, colors: &[Option<Rgb>], i: usize) -> Option<Rgb> {
    drawn_leaf(dataset, i).map(|leaf| colors[leaf].unwrap_or(palette::TABLEAU10[0]))
}

/// Appends cell `i`'s element: its path, fill and title.
fn push_cell(
    out: &mut String,
    dataset: &Dataset,
    layout: &Layout,
    colors: &[Option<Rgb>],
    i: usize,
) {
    let node = dataset.node(i);
    let fill = cell_fill(dataset, colors, i).map_or("none".to_owned(), |c| c.to_string());
    out.push_str("<path data-id=\"");
    out.push_str(&escape(&node.id));
    out.push_str("\" d=\"");
    path_data(out, &layout.cells[i].polygon);
    out.push_str(&format!("\" fill=\"{fill}\"><title>"));
    out.push_str(&escape(&node.label));
    if node.id != node.label {
        out.push_str(" (");
        out.push_str(&escape(&node.id));
        out.push(')');
    }
    out.push_str("</title></path>\n");
}

/// Appends the elements of `nodes` from `memo` where it has them (keyed by
/// everything [`push_cell`] writes: id, label, fill and the outline's
/// bits), writing the others (in parallel) and keeping them there.
fn push_remembered(
    out: &mut String,
    dataset: &Dataset,
    layout: &Layout,
    colors: &[Option<Rgb>],
    nodes: &[usize],
    memo: &LineMemo,
) {
    use rayon::prelude::*;
    let keys: Vec<u128> = nodes
        .par_iter()
        .map(|&i| {
            let node = dataset.node(i);
            let mut h = xxhash_rust::xxh3::Xxh3::new();
            for text in [&node.id, &node.label] {
                h.update(&text.len().to_le_bytes());
                h.update(text.as_bytes());
            }
            match cell_fill(dataset, colors, i) {
                Some(c) => h.update(&[1, c.r, c.g, c.b]),
                None => h.update(&[0]),
            }
            for p in layout.cells[i].polygon.points() {
                h.update(&p.x.to_bits().to_le_bytes());
                h.update(&p.y.to_bits().to_le_bytes());
            }
            h.digest128()
        })
        .collect();
    let mut found = memo.find(&keys);
    let missing: Vec<usize> = (0..nodes.len()).filter(|&k| found[k].is_none()).collect();
    let written: Vec<(usize, Line)> = missing
        .into_par_iter()
        .map(|k| {
            let mut line = String::with_capacity(256);
            push_cell(&mut line, dataset, layout, colors, nodes[k]);
            (k, Line::from(line))
        })
        .collect();
    memo.keep(
        written
            .iter()
            .map(|(k, l)| (keys[*k], Line::clone(l)))
            .collect(),
    );
    for (k, line) in written {
        found[k] = Some(line);
    }
    for line in found.iter().flatten() {
        out.push_str(line);
    }
}

/// Every non-root node of the data is drawn, the root only when it is the
/// whole dataset, and no virtual copy: a copy has the cell of the node it
/// continues (§2.2: a one-child diagram), so the chain a shallow leaf heads
/// is drawn once, as that leaf ([`drawn_leaf`]), not as a stack of equal
/// outlines under ids the data never had.
fn is_drawn(dataset: &Dataset, i: usize) -> bool {
    let node = dataset.node(i);
    !node.is_virtual && (node.parent.is_some() || dataset.is_leaf(i))
}

/// Outline width at `depth`: `top` for depth 0 and 1, then decaying per level.
pub(crate) fn stroke_width(top: f64, depth: usize) -> f64 {
    let steps = depth.saturating_sub(1).min(64) as i32;
    (top * STROKE_DECAY.powi(steps)).max(top.min(MIN_STROKE_WIDTH))
}

/// Fill colour of every node, indexed like the dataset. A node's own valid
/// `color` always wins, then a top-level group's pinned colour (`pins`, by
/// id, else by label), then its colour of the last build (`kept`, by id,
/// while `palette` can still give it); otherwise the top-level groups take `palette`'s
/// colours, assigned in the data's order (so a weight edit recolours
/// nothing) and so that groups sharing an edge
/// (`adjacent`, pairs of node indices) never look alike
/// ([`palette::assign`]), and deeper nodes a lightness variation of their
/// parent's colour, the heaviest child the parent's own
/// ([`palette::sibling_shade`]). The root has none unless it is
/// a leaf.
pub(crate) fn cell_colors(
    dataset: &Dataset,
    adjacent: &[(usize, usize)],
    palette: PaletteKind,
    pins: &BTreeMap<String, Rgb>,
    kept: &Kept,
) -> Vec<Option<Rgb>> {
    let own = |i: usize| dataset.node(i).color;
    let mut colors: Vec<Option<Rgb>> = vec![None; dataset.len()];
    let root = dataset.root();
    if root < dataset.len() && dataset.is_leaf(root) {
        colors[root] = Some(own(root).unwrap_or(palette::TABLEAU10[0]));
    }
    let groups = &dataset.node(root).children;
    // Group position per node index: a search through the groups per pair
    // cost a flat map of 20,000 groups 10⁹ steps.
    let mut group_of = vec![None; dataset.len()];
    for (k, &g) in groups.iter().enumerate() {
        if g < group_of.len() {
            group_of[g] = Some(k);
        }
    }
    let position = |i: usize| group_of.get(i).copied().flatten();
    // Groups take colours in the data's order, not by weight: an edit that
    // lets one group outgrow another must not recolour the picture (the
    // daemon redraws after every edit, and a picture that stays put is its
    // point). The order of first appearance is d3's ordinal scale's too.
    let order: Vec<usize> = (0..groups.len()).collect();
    let pairs: Vec<(usize, usize)> = adjacent
        .iter()
        .filter_map(|&(a, b)| Some((position(a)?, position(b)?)))
        .collect();
    let pinned = |g: usize| {
        let node = dataset.node(g);
        pins.get(node.id.as_str())
            .or_else(|| pins.get(node.label.as_str()))
            .copied()
    };
    // A kept colour stays even where a changed contact now puts it beside
    // a like one: a picture that stays put is the point of keeping it
    // (issue 32), and new groups still keep away from their neighbours.
    // One no longer in the palette (`render.palette` changed) is dropped.
    let family = if kept.groups.is_empty() {
        Default::default()
    } else {
        palette::family(palette, groups.len().max(kept.groups.len()))
    };
    let remembered = |g: usize| {
        kept.groups
            .get(dataset.node(g).id.as_str())
            .copied()
            .filter(|c| family.contains(c))
    };
    let fixed: Vec<Option<Rgb>> = groups
        .iter()
        .map(|&g| own(g).or_else(|| pinned(g)).or_else(|| remembered(g)))
        .collect();
    let top = palette::assign(
        &palette::group_palette(palette, groups.len()),
        &order,
        &pairs,
        &fixed,
    );
    // Breadth-first order puts every parent before its children, so one pass
    // sees each parent's colour settled before it is varied.
    for (p, parent) in dataset.nodes().iter().enumerate() {
        let n = parent.children.len();
        let base = colors[p].unwrap_or(palette::TABLEAU10[0]);
        let main = main_child(dataset, p, &kept.main);
        for (k, &c) in parent.children.iter().enumerate() {
            if c >= colors.len() {
                continue;
            }
            let derived = if p == root {
                // `top` holds the pins too; a node's own colour is applied below.
                top[k]
            } else {
                palette::sibling_shade(base, k, n, main)
            };
            colors[c] = Some(own(c).unwrap_or(derived));
        }
    }
    colors
}

/// Which child of node `p` (its position among the children) wears `p`'s
/// colour: the one `kept` names while it is still a child, else the
/// heaviest (the first on ties), so that the legend's swatch is the colour
/// of a cell.
pub(crate) fn main_child(dataset: &Dataset, p: usize, kept: &BTreeMap<String, String>) -> usize {
    let parent = dataset.node(p);
    let children = &parent.children;
    kept.get(parent.id.as_str())
        .and_then(|id| children.iter().position(|&c| dataset.node(c).id == *id))
        .unwrap_or_else(|| {
            (0..children.len())
                .max_by(|&a, &b| {
                    let value = |k: usize| dataset.node(children[k]).value;
                    value(a).total_cmp(&value(b)).then(b.cmp(&a))
                })
                .unwrap_or(0)
        })
}

/// Appends `M x,y L x,y … Z` with two-decimal coordinates.
pub(crate) fn path_data(out: &mut String, polygon: &ConvexPolygon) {
    for (k, p) in polygon.points().iter().enumerate() {
        out.push(if k == 0 { 'M' } else { 'L' });
        push_num(out, p.x);
        out.push(',');
        push_num(out, p.y);
    }
    out.push('Z');
}

/// Appends [`num`]`(v)`, the same text, without the formatter's exact
/// decimal expansion for all but a few values: the cells' outlines are most
/// of a picture's numbers (460,000 at 6,000 C headers), and the formatter
/// was a twentieth of a warm build. `v` × 100, rounded, is the formatter's
/// result unless the exact product lies near a half, which rounding to the
/// nearest double can cross: within 1e-6 of one (the product's own error is
/// below 1e-7 under 1e9) the formatter decides.
pub(crate) fn push_num(out: &mut String, v: f64) {
    let scaled = v.abs() * 100.0;
    let near_half = (scaled - scaled.floor() - 0.5).abs() <= 1e-6;
    if !v.is_finite() || scaled >= 1e9 || near_half {
        out.push_str(&num(v));
        return;
    }
    let n = scaled.round() as u64;
    if n > 0 && v < 0.0 {
        out.push('-');
    }
    let (whole, cents) = (n / 100, n % 100);
    // Writing into a String cannot fail.
    let _ = write!(out, "{whole}.");
    out.push(char::from(b'0' + (cents / 10) as u8));
    out.push(char::from(b'0' + (cents % 10) as u8));
}

/// The value a reader of [`num`]`(v)` gets back: `v` rounded to two
/// decimals as the text spells it (`svg::push_num`'s rule), as the nearest
/// double, the way an SVG reader parses it. `None` when `v` has no such
/// spelling (not finite).
pub(crate) fn spelled(v: f64) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    let scaled = v.abs() * 100.0;
    let near_half = (scaled - scaled.floor() - 0.5).abs() <= 1e-6;
    if scaled >= 1e9 || near_half {
        return num(v).parse().ok();
    }
    // The decimal `whole.cents` is n / 100 exactly, and both the division of
    // two exact integers and a reader's parse round it to the nearest double.
    let n = scaled.round();
    Some(if n > 0.0 && v < 0.0 {
        -n / 100.0
    } else {
        n / 100.0
    })
}

/// The leaf labels that fit, in dataset order (none when labels are off),
/// from `parts` where an earlier render fitted them to the same drawn cell.
pub(crate) fn leaf_labels(
    dataset: &Dataset,
    layout: &Layout,
    style: &LabelStyle,
    parts: &Parts,
) -> Vec<Placed> {
    if !style.show {
        return Vec::new();
    }
    let count = dataset.len().min(layout.cells.len());
    let keys: Vec<(usize, LabelKey)> = (0..count)
        .into_par_iter()
        // Every leaf, copies too: a chain's label sits in its last copy's
        // cell (the marker and tab placements look labels up by that node).
        .filter(|&i| dataset.is_leaf(i))
        .map(|i| {
            let text = display_name(dataset, i, &style.names, &style.text);
            let value = style
                .value
                .then(|| format_value(dataset.node(i).value, &style.unit));
            let cell = &layout.cells[i].polygon;
            (
                i,
                LabelKey::new(text, value, cell, style.min_size, style.max_size),
            )
        })
        .collect();
    parts.labels(keys).into_iter().flatten().collect()
}

/// Appends the label group: one `<text>` per placed label (a `<tspan>` per
/// line when it has several), with a halo in the stroke colour.
pub(crate) fn push_labels(out: &mut String, labels: &[Placed], style: &SvgStyle) {
    if labels.is_empty() {
        return;
    }
    // pointer-events="none" lets hovering reach the cells' <title>s.
    out.push_str(LABELS_GROUP);
    out.push_str(&format!(
        " font-family=\"{}\" text-anchor=\"middle\" fill=\"{}\" stroke=\"{}\" \
         stroke-linejoin=\"round\" paint-order=\"stroke\" pointer-events=\"none\">\n",
        escape(&style.font_family),
        style.text_color,
        style.stroke,
    ));
    for p in labels {
        push_text(out, p, true, None);
    }
    out.push_str("</g>\n");
}

/// One placed label as a `<text>`: a single line inline, several as
/// `<tspan>`s with their own position and size; `halo` adds the halo's
/// stroke width, `fill` its own colour (else its group's); a turned label
/// rotates about its box's centre.
pub(crate) fn push_text(out: &mut String, p: &Placed, halo: bool, fill: Option<Rgb>) {
    let Some(first) = p.lines.first() else {
        return;
    };
    let fill = fill.map_or_else(String::new, |c| format!(" fill=\"{c}\""));
    let halo_width = |size: f64| {
        if halo {
            format!(" stroke-width=\"{}\"", num(HALO_EM * size))
        } else {
            String::new()
        }
    };
    let turn = if p.angle != 0.0 {
        format!(
            " transform=\"rotate({} {} {})\"",
            num(p.angle),
            num(0.5 * (p.rect.x0 + p.rect.x1)),
            num(0.5 * (p.rect.y0 + p.rect.y1))
        )
    } else {
        String::new()
    };
    if p.lines.len() == 1 {
        out.push_str(&format!(
            "<text x=\"{}\" y=\"{}\" font-size=\"{}\"{fill}{}{turn}>{}</text>\n",
            num(first.x),
            num(first.baseline),
            num(first.size),
            halo_width(first.size),
            escape(&first.text),
        ));
        return;
    }
    out.push_str(&format!(
        "<text font-size=\"{}\"{fill}{}{turn}>",
        num(first.size),
        halo_width(first.size)
    ));
    for line in &p.lines {
        let own = if (line.size - first.size).abs() > 1e-9 {
            format!(" font-size=\"{}\"{}", num(line.size), halo_width(line.size))
        } else {
            String::new()
        };
        out.push_str(&format!(
            "<tspan x=\"{}\" y=\"{}\"{own}>{}</tspan>",
            num(line.x),
            num(line.baseline),
            escape(&line.text)
        ));
    }
    out.push_str("</text>\n");
}

/// A number with exactly two decimals; never `-0.00`, never non-finite.
pub(crate) fn num(v: f64) -> String {
    debug_assert!(v.is_finite(), "non-finite number reached the SVG: {v}");
    let v = if v.is_finite() { v } else { 0.0 };
    let s = format!("{v:.2}");
    if s == "-0.00" {
        "0.00".to_owned()
    } else {
        s
    }
}

/// XML-escapes user text for both element content and quoted attributes, and
/// drops characters XML 1.0 forbids (C0 controls other than tab, LF and CR;
/// U+FFFE, U+FFFF), which would otherwise make the whole document unparseable.
/// Also valid for HTML text and attributes (used by [`super::html`]).
pub(crate) fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => {}
            c => out.push(c),
        }
    }
    out
}

/// The text [`escape`] was given back, as a browser's `getAttribute` reads
/// it: the five entities `escape` writes (the characters it drops stay
/// dropped). `&amp;` last, so that `&amp;lt;` gives `&lt;`.
pub(crate) fn unescape(text: &str) -> String {
    text.replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unescape_gives_back_what_escape_was_given() {
        for text in [
            "plain",
            "a & b",
            "<script>\"x\" 'y'</script>",
            "&amp;lt; stays text",
            "&",
        ] {
            assert_eq!(unescape(&escape(text)), text);
        }
    }

    /// What a reader of the text gets is what `spelled` gives, bit for bit,
    /// over values near halves, negatives that round to zero and large ones.
    #[test]
    fn spelled_is_the_text_read_back() {
        let mut values = vec![
            0.0, -0.0, -0.004, 0.005, 0.015, 1.005, -2.675, 1e9, 123456.785,
        ];
        let mut x = 0.123_456_789_f64;
        for _ in 0..20_000 {
            x = (x * 7919.123 + 0.377).fract();
            values.push((x - 0.5) * 4000.0);
            values.push((x * 1e4).round() / 1e4);
        }
        for v in values {
            let read: f64 = num(v).parse().expect("a number");
            assert_eq!(spelled(v).map(f64::to_bits), Some(read.to_bits()), "{v}");
        }
        assert_eq!(spelled(f64::NAN), None);
    }

    #[test]
    fn push_num_spells_as_num() {
        let mut values = vec![
            0.0,
            -0.0,
            0.004,
            -0.004,
            0.005,
            -0.005,
            0.015,
            0.125,
            0.375,
            2.675,
            1.005,
            999.995,
            1000.0,
            -1000.0,
            0.1 + 0.2,
            1e-300,
            5e8,
            9.99999e8,
            1e9,
            1e12,
            -7.125,
            12.345,
        ];
        // Every k/800 near the canvas (halves of cents, exact and not), and
        // a spread of others, both signs.
        values.extend((0..200_000).map(|k| k as f64 / 800.0));
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            values.push((x >> 11) as f64 / (1u64 << 53) as f64 * 4000.0 - 2000.0);
        }
        for v in values {
            let mut out = String::new();
            push_num(&mut out, v);
            assert_eq!(out, num(v), "{v:e}");
        }
    }
    use crate::render::test_support::sample;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn count(hay: &str, needle: &str) -> usize {
        hay.matches(needle).count()
    }

    /// Issue 32, item 2: the cell elements written with the memo of the
    /// render before are the bytes written without it, and only the moved
    /// cell's element is written again.
    #[test]
    fn cell_elements_from_the_memo_are_the_bytes_written_without_it() {
        use crate::geom::Point;
        use crate::line_memo::{LineCounts, LineMemo};
        let (dataset, mut layout) = sample();
        let style = SvgStyle::default();
        let colors = vec![Some(Rgb::new(0x4e, 0x79, 0xa7)); dataset.len()];
        let cells = |layout: &Layout, memo: Option<&LineMemo>| {
            let mut out = String::new();
            push_cells(&mut out, &dataset, layout, &style, &colors, memo);
            out
        };
        let memo = LineMemo::new();
        assert_eq!(cells(&layout, Some(&memo)), cells(&layout, None));
        let drawn = memo.next_build().written;
        assert_eq!(drawn, dataset.len() - 1, "every cell but the root's");
        let leaf = dataset.find("A3").expect("A3");
        let moved: Vec<Point> = layout.cells[leaf]
            .polygon
            .points()
            .iter()
            .map(|p| Point::new(p.x + 0.5, p.y))
            .collect();
        layout.cells[leaf].polygon = ConvexPolygon::new(moved).expect("convex");
        assert_eq!(cells(&layout, Some(&memo)), cells(&layout, None));
        assert_eq!(
            memo.counts(),
            LineCounts {
                reused: drawn - 1,
                written: 1
            }
        );
    }

    /// A tree of uneven depth (a leaf beside groups of three levels, as a
    /// folder of files beside subfolders): `prepare` continues each shallow
    /// leaf with a chain of virtual copies, each with the leaf's cell. The
    /// picture draws one cell per node of the data: no copy's id, a chain
    /// drawn once, filled with its leaf's colour, and no leaf named as a
    /// group (a regression: the chains were drawn as stacks of equal
    /// outlines, 3,606 paths for 953 nodes at 500 C headers, and their heads
    /// got group names).
    #[test]
    fn a_chain_of_virtual_copies_is_drawn_once_as_its_leaf() {
        use crate::layout::{layout, Params};
        use crate::neighborhood::prepare;
        use crate::render::picture::{compose, Style};
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        b.add(NodeSpec::new("readme.md").parent("root").weight(400.0));
        for g in ["src", "docs"] {
            b.add(NodeSpec::new(g).parent("root"));
            for s in 0..3 {
                let sub = format!("{g}/sub{s}");
                b.add(NodeSpec::new(sub.as_str()).parent(g));
                for k in 0..4 {
                    b.add(
                        NodeSpec::new(format!("{sub}/file{k}.rs"))
                            .parent(sub.as_str())
                            .weight(5.0 + (s * 4 + k) as f64),
                    );
                }
            }
            b.add(NodeSpec::new(format!("{g}/top.rs")).parent(g).weight(30.0));
        }
        let data = b.build().expect("valid");
        let ds = prepare(&data);
        let copies = ds.nodes().iter().filter(|n| n.is_virtual).count();
        assert!(
            copies >= 4,
            "readme.md and the two top.rs continue: {copies}"
        );
        let (laid, _) = layout(&ds, &Params::default()).expect("laid out");
        let text = compose(&ds, &laid, &[], &[], &Style::default());
        let start = text.find("class=\"np-cells\"").expect("cells");
        let cells = &text[start..start + text[start..].find("\n<g class=").expect("next")];
        assert_eq!(
            count(cells, "<path"),
            data.len() - 1,
            "one per node of the data"
        );
        for node in ds.nodes().iter().filter(|n| n.is_virtual) {
            let id = format!("data-id=\"{}\"", escape(&node.id));
            assert!(!text.contains(&id), "no element of the copy {}", node.id);
        }
        let style = Style::default();
        let (colors, _) = crate::render::picture::fills(&ds, &[], &style);
        for head in ["readme.md", "src/top.rs", "docs/top.rs"] {
            let i = ds.find(head).expect(head);
            let leaf = drawn_leaf(&ds, i).expect("a chain ends in a leaf");
            assert_ne!(leaf, i, "{head} heads a chain");
            let fill = colors[leaf].expect("a leaf has a colour").to_string();
            let element = format!("data-id=\"{head}\" d=\"");
            let at = cells.find(&element).expect(head);
            let line = &cells[at..at + cells[at..].find('\n').expect("line")];
            assert!(line.contains(&format!("fill=\"{fill}\"")), "{line}");
            let named = text
                .find("class=\"np-group-labels\"")
                .map(|g| &text[g..g + text[g..].find("</g>").expect("end")]);
            assert!(
                !named.unwrap_or("").contains(&format!(">{head}<")),
                "{head} is a leaf, not a group"
            );
        }
    }

    #[test]
    fn one_path_per_drawn_cell() {
        let (dataset, layout) = sample();
        let text = svg(&dataset, &layout, &SvgStyle::default());
        let drawn = (0..dataset.len())
            .filter(|&i| is_drawn(&dataset, i))
            .count();
        assert_eq!(drawn, dataset.len() - 1, "every node but the root");
        assert_eq!(count(&text, "<path") + count(&text, "<polygon"), drawn);
        let leaves = (0..dataset.len()).filter(|&i| dataset.is_leaf(i)).count();
        let internal_drawn = drawn - leaves;
        assert_eq!(count(&text, "fill=\"none\""), internal_drawn);
        assert!(text.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400.00\""));
        assert!(text.contains("viewBox=\"0 0 400.00 200.00\""));
        assert!(text.contains("<rect width=\"400.00\" height=\"200.00\" fill=\"#ffffff\"/>"));
        assert!(text.ends_with("</svg>\n"));
    }

    #[test]
    fn deeper_levels_first_and_thinner() {
        let (dataset, layout) = sample();
        let text = svg(&dataset, &layout, &SvgStyle::default());
        let depth2 = text.find("<g stroke-width=\"1.50\">").unwrap();
        let depth1 = text.find("<g stroke-width=\"3.00\">").unwrap();
        assert!(depth2 < depth1, "top-level outlines drawn last, on top");
        assert_eq!(stroke_width(3.0, 1), 3.0);
        assert_eq!(stroke_width(3.0, 3), 0.75);
        assert_eq!(stroke_width(3.0, 9), MIN_STROKE_WIDTH);
        assert_eq!(stroke_width(0.2, 5), 0.2);
    }

    #[test]
    fn labels_are_escaped_never_raw() {
        let (dataset, layout) = sample();
        let text = svg(&dataset, &layout, &SvgStyle::default());
        assert!(!text.contains("<script>"));
        assert!(!text.contains("\"q\""));
        let escaped = "&lt;script&gt;alert(1)&lt;/script&gt; &quot;q&quot;";
        assert!(text.contains(&format!("<title>{escaped} (B)</title>")));
        // Too long for one line at 9 px: wrapped at its space.
        let labels = &text[text.find("np-labels").unwrap_or(0)..];
        assert!(
            labels.contains("&lt;script&gt;alert(1)&lt;/</tspan>")
                && labels.contains(">script&gt; &quot;q&quot;</tspan>"),
            "B's label is drawn: {labels}"
        );
        assert_eq!(escape("a&b<'>\u{1}\t"), "a&amp;b&lt;&apos;&gt;\t");
    }

    #[test]
    fn byte_identical_across_calls() {
        let (dataset, layout) = sample();
        let style = SvgStyle::default();
        assert_eq!(
            svg(&dataset, &layout, &style),
            svg(&dataset, &layout, &style)
        );
    }

    #[test]
    fn tiny_cells_lose_their_labels() {
        let (dataset, layout) = sample();
        let text = svg(&dataset, &layout, &SvgStyle::default());
        assert!(text.contains(">A1</text>"));
        assert!(text.contains(">A2</text>"));
        assert!(!text.contains(">A3</text>"), "A3 is 2 units tall");
        assert!(text.contains("<title>A3</title>"), "but its cell is drawn");
        let off = SvgStyle {
            labels: LabelStyle {
                show: false,
                ..LabelStyle::default()
            },
            ..SvgStyle::default()
        };
        assert_eq!(count(&svg(&dataset, &layout, &off), "<text"), 0);
    }

    /// Every node's colour in Tableau, nothing pinned or kept, no contacts.
    fn fresh_tableau(dataset: &Dataset) -> Vec<Option<Rgb>> {
        cell_colors(
            dataset,
            &[],
            PaletteKind::Tableau,
            &BTreeMap::new(),
            &Kept::default(),
        )
    }

    #[test]
    fn colors_follow_the_hierarchy() {
        let (dataset, layout) = sample();
        let colors = fresh_tableau(&dataset);
        let idx = |id: &str| dataset.nodes().iter().position(|n| n.id == id).unwrap();
        assert_eq!(colors[idx("root")], None);
        assert_eq!(colors[idx("A")], Some(palette::TABLEAU10[0]));
        // B has its own colour in the sample.
        assert_eq!(colors[idx("B")], Rgb::from_hex("#ff0000"));
        let a = palette::TABLEAU10[0];
        // A1 is A's heaviest child: A's own colour.
        assert_eq!(colors[idx("A1")], Some(a));
        assert_eq!(colors[idx("A2")], Some(palette::sibling_shade(a, 1, 3, 0)));
        assert_ne!(colors[idx("A2")], Some(a));
        // A kept main child wears the parent's colour though it is lighter.
        let kept = Kept {
            groups: BTreeMap::new(),
            main: BTreeMap::from([("A".to_string(), "A2".to_string())]),
        };
        let shaded = cell_colors(&dataset, &[], PaletteKind::Tableau, &BTreeMap::new(), &kept);
        assert_eq!(shaded[idx("A2")], Some(a));
        assert_ne!(shaded[idx("A1")], Some(a));
        let text = svg(&dataset, &layout, &SvgStyle::default());
        assert!(text.contains("fill=\"#ff0000\""));
    }

    #[test]
    fn a_pinned_group_colour_holds_and_a_node_colour_still_wins() {
        // `render.colors` pins a top-level group by id or by label; a node's
        // own `color` is not overridden by a pin.
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("root"));
        builder.add(NodeSpec::new("group:eu").parent("root").label("Europe"));
        builder.add(NodeSpec::new("fr").parent("group:eu").weight(3.0));
        builder.add(NodeSpec::new("de").parent("group:eu").weight(2.0));
        let red = Rgb::new(0xff, 0, 0);
        builder.add(NodeSpec::new("B").parent("root").weight(1.0).color(red));
        let dataset = builder.build().expect("valid");
        let idx = |id: &str| dataset.nodes().iter().position(|n| n.id == id).unwrap();
        let pin = Rgb::new(0x12, 0x34, 0x56);
        let unpinned = fresh_tableau(&dataset);
        assert_ne!(unpinned[idx("group:eu")], Some(pin));
        for key in ["group:eu", "Europe"] {
            let pins = BTreeMap::from([(key.to_string(), pin), ("B".to_string(), pin)]);
            let colors = cell_colors(&dataset, &[], PaletteKind::Tableau, &pins, &Kept::default());
            assert_eq!(colors[idx("group:eu")], Some(pin), "pinned by {key}");
            // The heaviest child keeps the group's colour, its sibling a shade.
            assert_eq!(colors[idx("fr")], Some(pin));
            assert_eq!(
                colors[idx("de")],
                Some(palette::sibling_shade(pin, 1, 2, 0))
            );
            assert_eq!(colors[idx("B")], Some(red));
        }
    }

    #[test]
    fn kept_colours_hold_while_the_palette_has_them_and_pins_win() {
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("root"));
        for g in ["g0", "g1", "g2"] {
            builder.add(NodeSpec::new(g).parent("root"));
            builder.add(NodeSpec::new(format!("{g}-leaf")).parent(g).weight(1.0));
        }
        let dataset = builder.build().expect("valid");
        let idx = |id: &str| dataset.nodes().iter().position(|n| n.id == id).unwrap();
        let none = BTreeMap::new();
        let fresh = cell_colors(&dataset, &[], PaletteKind::Tableau, &none, &Kept::default());
        // g0 kept the colour fresh colouring gives g2, and the reverse.
        let t = |id: &str| fresh[idx(id)].expect("coloured");
        let kept = Kept {
            groups: BTreeMap::from([("g0".to_string(), t("g2")), ("g2".to_string(), t("g0"))]),
            main: BTreeMap::new(),
        };
        let colors = cell_colors(&dataset, &[], PaletteKind::Tableau, &none, &kept);
        assert_eq!(colors[idx("g0")], Some(t("g2")));
        assert_eq!(colors[idx("g2")], Some(t("g0")));
        // The group not kept takes a colour not in use.
        let g1 = colors[idx("g1")].expect("coloured");
        assert!(g1 != t("g0") && g1 != t("g2"), "{g1}");
        // A pin wins over a kept colour.
        let pin = Rgb::new(1, 2, 3);
        let pins = BTreeMap::from([("g0".to_string(), pin)]);
        let pinned = cell_colors(&dataset, &[], PaletteKind::Tableau, &pins, &kept);
        assert_eq!(pinned[idx("g0")], Some(pin));
        // Another palette: the Tableau colours kept are dropped.
        let blind = cell_colors(&dataset, &[], PaletteKind::Colorblind, &none, &kept);
        for g in ["g0", "g1", "g2"] {
            let c = blind[idx(g)].expect("coloured");
            assert!(palette::OKABE_ITO.contains(&c), "{g}: {c}");
        }
    }

    #[test]
    fn group_colours_survive_a_weight_edit_that_reorders_the_groups() {
        // `nptreemap watch` re-renders after every edit: a group that grows
        // past another must keep its colour, or the whole picture changes
        // colour for one edited value (seen on tests/data/real/man-pages:
        // 1,320 of 1,434 cells after man8 outgrew man5).
        let groups = |weights: [f64; 4]| {
            let mut builder = DatasetBuilder::new();
            builder.add(NodeSpec::new("root"));
            for (k, w) in weights.iter().enumerate() {
                let g = format!("g{k}");
                builder.add(NodeSpec::new(&g).parent("root"));
                builder.add(NodeSpec::new(format!("{g}-leaf")).parent(&g).weight(*w));
            }
            let dataset = builder.build().expect("valid");
            let colors = fresh_tableau(&dataset);
            (0..4)
                .map(|k| {
                    let i = dataset.nodes().iter().position(|n| n.id == format!("g{k}"));
                    colors[i.expect("group")]
                })
                .collect::<Vec<_>>()
        };
        let before = groups([40.0, 30.0, 20.0, 10.0]);
        let after = groups([40.0, 30.0, 20.0, 90.0]);
        assert_eq!(before, after);
        // Still four different colours.
        let distinct: std::collections::HashSet<_> = after.iter().collect();
        assert_eq!(distinct.len(), 4, "{after:?}");
    }

    #[test]
    fn every_path_carries_its_escaped_id() {
        let (dataset, layout) = sample();
        let text = svg(&dataset, &layout, &SvgStyle::default());
        assert_eq!(count(&text, "<path data-id=\""), count(&text, "<path"));
        assert!(text.contains("<path data-id=\"A3\" d=\""));
        assert!(!text.contains("data-id=\"root\""));
    }

    #[test]
    fn numbers_have_two_decimals() {
        assert_eq!(num(1.0 / 3.0), "0.33");
        assert_eq!(num(-0.001), "0.00");
        assert_eq!(num(-1.005), "-1.00");
        assert_eq!(num(12.0), "12.00");
    }
}
