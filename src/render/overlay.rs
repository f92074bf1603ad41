//! What is drawn on top of the treemap for its similarity constraints: the
//! interlocking tab on every edge shared by two constrained neighbours
//! (method-reference §8.3) and, for constraints that are not neighbours,
//! dashed red links between the cells plus an "unlinked" count on the cell
//! (§8.4). Pure: a finished layout and its constraints in, SVG text out. The
//! tabs go under the picture's labels, the rest over them
//! ([`compose`](crate::render::picture::compose) places the two layers).

use super::svg::{cell_colors, escape, num};
use crate::geom::shared_edge::{shared_segments, PERPENDICULAR_TOL};
use crate::geom::Point;
use crate::layout::Layout;
use nptreemap_formats::Dataset;

/// One constraint to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// First node (index into the dataset).
    pub a: usize,
    /// Second node.
    pub b: usize,
    /// Raw similarity in [0, 1]; sizes the tab (§3.8).
    pub similarity: f64,
    /// Whether the two cells share an edge.
    pub realized: bool,
}

/// Overlay settings.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Draw the dashed links of unrealised constraints visibly (they are
    /// always present, hidden, for the HTML page's checkbox). Default: false.
    pub show_unrealized: bool,
    /// Draw the count of missing links on cells that have some. Default: true.
    pub unlinked_markers: bool,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        Self {
            show_unrealized: false,
            unlinked_markers: true,
        }
    }
}

/// Tab width along the edge and base depth across it, in the prototype's
/// pixels (8 and 6 px, §8.3), scaled like every prototype constant by the
/// canvas against its 32-gon of radius 192.
const TAB_WIDTH_PX: f64 = 8.0;
const TAB_DEPTH_PX: f64 = 6.0;

/// Size multiplier of a tab by raw similarity (the prototype's four levels, §3.8).
fn strength_multiplier(similarity: f64) -> f64 {
    if similarity >= 0.95 {
        2.0
    } else if similarity >= 0.75 {
        1.5
    } else if similarity >= 0.5 {
        1.25
    } else {
        1.0
    }
}

/// The canvas scale of the prototype's pixel constants.
fn scale(layout: &Layout) -> f64 {
    let proto = 0.5 * 32.0 * (std::f64::consts::TAU / 32.0).sin() * 192.0 * 192.0;
    (layout.canvas.width * layout.canvas.height / proto).sqrt()
}

/// Where a tab goes: the longest shared segment of the two cells, when it is at
/// least one tab wide. Returns its end points.
pub fn tab_edge(layout: &Layout, link: &Link) -> Option<[Point; 2]> {
    let tol = PERPENDICULAR_TOL * layout.diagonal();
    let width = TAB_WIDTH_PX * scale(layout);
    shared_segments(
        &layout.cells[link.a].polygon,
        &layout.cells[link.b].polygon,
        tol,
    )
    .into_iter()
    .filter(|s| s[0].distance(s[1]) >= width)
    .max_by(|s, t| s[0].distance(s[1]).total_cmp(&t[0].distance(t[1])))
}

/// The overlay's SVG elements in their two layers.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlay {
    /// The tabs, drawn over the cells but under the labels: they sit on cell
    /// edges, which a fitted label may reach, and at the paper's size (12 px
    /// scaled with the canvas) would otherwise hide whole words of small labels.
    pub tabs: String,
    /// The dashed links and the unlinked counts, drawn over everything: they
    /// point at cells and are small.
    pub marks: String,
}

/// The overlay's SVG elements in their two layers (see [`Overlay`]).
pub fn overlay(
    dataset: &Dataset,
    layout: &Layout,
    links: &[Link],
    style: &OverlayStyle,
) -> Overlay {
    let s = scale(layout);
    let colors = cell_colors(dataset);
    let fill = |i: usize| colors[i].map_or("#cccccc".to_string(), |c| c.to_string());
    let mut out = String::new();
    out.push_str("<g class=\"np-tabs\" stroke-linejoin=\"round\">\n");
    for link in links.iter().filter(|l| l.realized) {
        let Some([p0, p1]) = tab_edge(layout, link) else {
            continue;
        };
        let (big, small) = if layout.cells[link.a].power_weight >= layout.cells[link.b].power_weight
        {
            (link.a, link.b)
        } else {
            (link.b, link.a)
        };
        let m = (p0 + p1) * 0.5;
        let p = (p1 - p0).normalize_or_zero();
        let half = 0.5 * TAB_WIDTH_PX * s;
        let mut n =
            Point::new(-p.y, p.x) * (TAB_DEPTH_PX * s * strength_multiplier(link.similarity));
        // n points into the larger cell ("max" cell, §8.3).
        let into_big = layout.cells[big].polygon.centroid() - m;
        if n.dot(into_big) < 0.0 {
            n = -n;
        }
        let pts = |v: &[Point]| {
            v.iter()
                .map(|q| format!("{},{}", num(q.x), num(q.y)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        out.push_str(&format!(
            "<g class=\"np-tab\" data-a=\"{}\" data-b=\"{}\">",
            escape(&dataset.node(link.a).id),
            escape(&dataset.node(link.b).id)
        ));
        // The larger cell's tongue pokes into the smaller one and vice versa.
        out.push_str(&format!(
            "<polygon points=\"{}\" fill=\"{}\"/>",
            pts(&[m + n * 0.5, m + p * half, m + p * half - n, m - n]),
            fill(big)
        ));
        out.push_str(&format!(
            "<polygon points=\"{}\" fill=\"{}\"/>",
            pts(&[m - n * 0.5, m - p * half, m - p * half + n, m + n]),
            fill(small)
        ));
        out.push_str(&format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"#ffffff\" stroke-width=\"{}\"/></g>\n",
            pts(&[
                m - p * half,
                m - p * half + n,
                m + n,
                m - n,
                m + p * half - n,
                m + p * half
            ]),
            num(s.max(1.0))
        ));
    }
    out.push_str("</g>\n");
    let tabs = std::mem::take(&mut out);
    let display = if style.show_unrealized {
        ""
    } else {
        " display=\"none\""
    };
    out.push_str(&format!(
        "<g class=\"np-unrealized\" stroke=\"#d62728\" stroke-width=\"{}\" stroke-dasharray=\"{}\"{display}>\n",
        num(2.0 * s.max(0.5)),
        num(4.0 * s.max(0.5))
    ));
    let mut missing = vec![0usize; dataset.len()];
    for link in links.iter().filter(|l| !l.realized) {
        let (a, b) = (
            layout.cells[link.a].polygon.centroid(),
            layout.cells[link.b].polygon.centroid(),
        );
        out.push_str(&format!(
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>\n",
            num(a.x),
            num(a.y),
            num(b.x),
            num(b.y)
        ));
        missing[link.a] += 1;
        missing[link.b] += 1;
    }
    out.push_str("</g>\n");
    if style.unlinked_markers {
        // Radius 4.5 prototype px: a marker as big as the glyph's box in the
        // prototype (scale 0.5 of a ~18 px icon), readable at 1,000 px.
        let r = 4.5 * s;
        out.push_str(&format!(
            "<g class=\"np-unlinked\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"{}\" text-anchor=\"middle\">\n",
            num(r * 1.2)
        ));
        for (i, &count) in missing.iter().enumerate().filter(|(_, c)| **c > 0) {
            // Below the centred label rather than on it (the prototype's
            // (-10, +10) offset sits on the label at our label sizes); back to
            // the centroid when the cell is too small to hold it there.
            let polygon = &layout.cells[i].polygon;
            let below = polygon.centroid() + Point::new(0.0, 2.8 * r);
            let c = if polygon.contains(below + Point::new(0.0, r)) {
                below
            } else {
                polygon.centroid()
            };
            out.push_str(&format!(
                "<g><title>{} unrealized link(s)</title><circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#ffffff\" stroke=\"#d62728\" stroke-width=\"{}\"/><text x=\"{}\" y=\"{}\" fill=\"#d62728\">{count}</text></g>\n",
                count,
                num(c.x),
                num(c.y),
                num(r),
                num(0.25 * r),
                num(c.x),
                num(c.y + 0.4 * r)
            ));
        }
        out.push_str("</g>\n");
    }
    Overlay { tabs, marks: out }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::ConvexPolygon;
    use crate::layout::{Canvas, LayoutCell};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// root split into three columns a | b | c of a 900 × 300 canvas, and a
    /// fourth node d as a thin strip under c whose edge with b is too short.
    fn sample() -> (Dataset, Layout) {
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("root"));
        for id in ["a", "b", "c", "d"] {
            builder.add(NodeSpec::new(id).parent("root").weight(1.0));
        }
        let ds = builder.build().expect("valid");
        let rect = |x: f64, y: f64, w: f64, h: f64, weight: f64| {
            let polygon = ConvexPolygon::rectangle(x, y, w, h).expect("rectangle");
            LayoutCell {
                site: polygon.centroid(),
                power_weight: weight,
                polygon,
            }
        };
        let layout = Layout {
            canvas: Canvas {
                width: 900.0,
                height: 300.0,
            },
            cells: vec![
                rect(0.0, 0.0, 900.0, 300.0, 0.0),
                rect(0.0, 0.0, 300.0, 300.0, 5.0),
                rect(300.0, 0.0, 300.0, 300.0, 1.0),
                rect(600.0, 0.0, 300.0, 299.0, 2.0),
                rect(600.0, 299.0, 300.0, 1.0, 0.0),
            ],
        };
        (ds, layout)
    }

    #[test]
    fn one_tab_per_realized_link_with_room_centered_on_its_edge() {
        let (ds, layout) = sample();
        let (a, b, c, d) = (1, 2, 3, 4);
        let links = vec![
            Link {
                a,
                b,
                similarity: 0.9,
                realized: true,
            },
            Link {
                a: b,
                b: c,
                similarity: 0.3,
                realized: true,
            },
            // b and d share a 1-unit edge: too short for a tab.
            Link {
                a: b,
                b: d,
                similarity: 0.99,
                realized: true,
            },
            Link {
                a,
                b: c,
                similarity: 0.6,
                realized: false,
            },
        ];
        let Overlay { tabs, marks } = overlay(&ds, &layout, &links, &OverlayStyle::default());
        assert_eq!(tabs.matches("class=\"np-tab\"").count(), 2);
        assert!(!marks.contains("np-tab"));
        // Each tab's edge is the shared side of its two cells: x = 300 and x = 600.
        for (link, x) in [(&links[0], 300.0), (&links[1], 600.0)] {
            let [p0, p1] = tab_edge(&layout, link).expect("room for a tab");
            assert!((p0.x - x).abs() < 1e-9 && (p1.x - x).abs() < 1e-9);
        }
        assert!(tab_edge(&layout, &links[2]).is_none());
        // The unrealised link is a hidden dashed line, and a and c carry a marker each.
        assert_eq!(marks.matches("<line ").count(), 1);
        assert!(marks.contains("class=\"np-unrealized\"") && marks.contains("display=\"none\""));
        assert_eq!(marks.matches("unrealized link(s)").count(), 2);
    }
}
