//! The finished picture: the treemap ([`svg`](super::svg)) with its constraint
//! overlay, framed by an optional title band above and a legend band below, a
//! background and a border around the root outline. Owns the picture's frame
//! and the [`Style`] that configures it (issue 5: "title and legend from the
//! config; canvas size, background and outline configurable"); may not compute
//! geometry or do I/O. Map coordinates are never transformed: the bands extend
//! the `viewBox` above and below the canvas, so a cell's path is the same text
//! with or without a title.

use nptreemap_formats::Dataset;

use super::legend::{legend, LegendItem};
use super::overlay::{overlay, tab_edge, Link, OverlayStyle};
use super::palette::Rgb;
use super::svg::{cell_colors, escape, num, push_cells, push_labels, SvgStyle};
use crate::layout::{Computed, Layout};

/// How the picture looks, beyond the geometry of its layout.
#[derive(Clone, Debug, PartialEq)]
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
    /// A line around the root outline; `None` draws none. Default: `None`.
    pub border: Option<Border>,
}

/// The line drawn around the root outline.
#[derive(Clone, Copy, Debug, PartialEq)]
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
            border: None,
        }
    }
}

/// Title font size per unit of canvas scale (see [`unit`]): 28 px on a
/// 1,000 × 1,000 canvas, a heading next to 6–24 px labels.
const TITLE_EM: f64 = 28.0;
/// Space around the title and the legend, canvas units per unit of scale.
const PAD: f64 = 16.0;

/// Canvas scale: 1 on a 1,000 × 1,000 canvas, so text and padding grow with
/// the map instead of vanishing on large canvases; never below 0.75, so the
/// legend of a small picture stays readable (10.5 px text at 400 × 400).
fn unit(layout: &Layout) -> f64 {
    ((layout.canvas.width * layout.canvas.height).sqrt() / 1000.0).max(MIN_UNIT)
}

/// Smallest canvas scale for the frame's text (see [`unit`]).
const MIN_UNIT: f64 = 0.75;

/// The SVG picture of a finished computation: the treemap with, when there are
/// constraints, the interlocking tabs and unrealised-link markers of its
/// deepest level (where the paper draws them, method-reference §8.2–8.4),
/// framed as `style` says. Identical input gives identical bytes.
pub fn picture(computed: &Computed, style: &Style) -> String {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    let deepest = dataset.max_depth();
    let links: Vec<Link> = computed
        .constraints
        .iter()
        .zip(&computed.realized)
        .filter(|(c, _)| dataset.node(c.a).depth == deepest)
        .map(|(c, r)| Link {
            a: c.a,
            b: c.b,
            similarity: c.similarity,
            realized: *r,
        })
        .collect();
    compose(dataset, layout, &links, style)
}

/// Draws the picture of `layout` (cells indexed like `dataset`) with the
/// constraint `links` of its deepest level: the tabs under the labels, the
/// rest over them. Identical input gives identical bytes.
pub fn compose(dataset: &Dataset, layout: &Layout, links: &[Link], style: &Style) -> String {
    let (cw, ch) = (layout.canvas.width, layout.canvas.height);
    let u = unit(layout);
    let shown: Vec<Link> = links
        .iter()
        .filter(|l| style.tabs || !l.realized)
        .cloned()
        .collect();

    let title = style
        .title
        .as_deref()
        .filter(|t| !t.trim().is_empty())
        .map(|t| (t, TITLE_EM * u));
    let top = title.map_or(0.0, |(_, size)| size + 2.0 * PAD * u);
    let items = if style.legend {
        legend_items(dataset, layout, &shown, style)
    } else {
        Vec::new()
    };
    let (legend_text, legend_height) = legend(&items, cw, ch, u, &style.cells);
    let total = top + ch + legend_height;

    let width = style.cells.width.unwrap_or(cw);
    let height = style.cells.height.unwrap_or(width * total / cw);
    let mut out = String::with_capacity(1024 + 200 * dataset.len());
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
            "<rect y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{bg}\"/>\n",
            num(-top),
            num(cw),
            num(total)
        ));
    }
    if let Some((text, size)) = title {
        out.push_str(&format!(
            "<text class=\"np-title\" x=\"{}\" y=\"{}\" font-family=\"{}\" font-size=\"{}\" font-weight=\"bold\" fill=\"{}\">{}</text>\n",
            num(PAD * u),
            num(-PAD * u - 0.25 * size),
            escape(&style.cells.font_family),
            num(size),
            style.cells.text_color,
            escape(text)
        ));
    }
    push_cells(&mut out, dataset, layout, &style.cells);
    // Tabs under the labels (they sit on edges a fitted label may reach),
    // links and counts over them.
    let layers = (!shown.is_empty()).then(|| overlay(dataset, layout, &shown, &style.overlay));
    if let Some(layers) = &layers {
        out.push_str(&layers.tabs);
    }
    push_labels(&mut out, dataset, layout, &style.cells);
    if let Some(layers) = &layers {
        out.push_str(&layers.marks);
    }
    if let Some(border) = style
        .border
        .filter(|b| b.width > 0.0 && b.width.is_finite())
    {
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
    out.push_str(&legend_text);
    out.push_str("</svg>\n");
    out
}

/// What the legend lists: the top-level groups (when they have children of
/// their own; otherwise every cell is labelled already), then a key for each
/// glyph the overlay actually draws.
fn legend_items(
    dataset: &Dataset,
    layout: &Layout,
    links: &[Link],
    style: &Style,
) -> Vec<LegendItem> {
    let mut items = Vec::new();
    let root = dataset.node(dataset.root());
    let groups_have_children = root
        .children
        .iter()
        .any(|&c| !dataset.node(c).children.is_empty());
    if root.children.len() >= 2 && groups_have_children {
        let colors = cell_colors(dataset);
        for &c in &root.children {
            let label = &dataset.node(c).label;
            // Virtual nodes (issue 3's depth padding) repeat their child's label
            // and colour; the legend names only groups people gave.
            if dataset.node(c).is_virtual {
                continue;
            }
            items.push(LegendItem::Swatch {
                color: colors[c].unwrap_or(super::palette::TABLEAU10[0]),
                label: label.clone(),
            });
        }
    }
    if links
        .iter()
        .any(|l| l.realized && tab_edge(layout, l).is_some())
    {
        items.push(LegendItem::Tab);
    }
    if style.overlay.unlinked_markers && links.iter().any(|l| !l.realized) {
        items.push(LegendItem::Unlinked);
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
        let s = compose(&ds, &layout, &[], &style);
        assert!(s.contains("class=\"np-border\""));
        assert!(s.contains("stroke=\"#333333\" stroke-width=\"2.00\""));
        assert!(!s.contains("<rect y="), "no background rectangle");
        let s = compose(&ds, &layout, &[], &Style::default());
        assert!(!s.contains("np-border"));
        assert!(s.contains("<rect y=\"0.00\" width=\"400.00\""));
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
        let with = compose(&ds, &layout, std::slice::from_ref(&link), &Style::default());
        assert_eq!(with.matches("class=\"np-tab\"").count(), 1);
        assert!(with.contains("class=\"np-legend-tab\""));
        let without = compose(
            &ds,
            &layout,
            &[link],
            &Style {
                tabs: false,
                ..Style::default()
            },
        );
        assert_eq!(without.matches("class=\"np-tab\"").count(), 0);
        assert!(!without.contains("np-legend-tab"));
    }

    #[test]
    fn svg_parses_and_is_deterministic() {
        let (ds, layout) = sample();
        let style = Style {
            title: Some("T & <t>".to_string()),
            ..Style::default()
        };
        let a = compose(&ds, &layout, &[], &style);
        assert_eq!(a, compose(&ds, &layout, &[], &style));
        #[cfg(feature = "png")]
        resvg::usvg::Tree::from_str(&a, &resvg::usvg::Options::default()).expect("valid SVG");
    }
}
