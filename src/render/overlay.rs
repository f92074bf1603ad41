//! What is drawn on top of the treemap for its similarity constraints: the
//! interlocking tab on shared edges of constrained neighbours
//! (method-reference §8.3) and, for constraints that are not neighbours,
//! dashed red links between the cells plus a count marker on the cell
//! (§8.4). Placed against the labels (issue 13, item 1): a tab never covers a
//! label and never takes more than a small share of either cell; a marker
//! moves within its cell to free space or is left out, and all markers
//! together stay within a share of the map. Pure: a finished layout, its
//! constraints and the placed labels in, shapes and SVG text out.

use super::labels::{Placed, Rect};
use super::svg::{escape, num, push_num};
use crate::geom::shared_edge::{shared_segments, PERPENDICULAR_TOL};
use crate::geom::{ConvexPolygon, Point};
use crate::layout::Layout;
use nptreemap_formats::{Dataset, Rgb};

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
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Draw the dashed links of unrealised constraints visibly (they are
    /// always present, hidden, for the HTML page's checkbox). Default: false.
    pub show_unrealized: bool,
    /// Draw the count of missing links on cells that have some, where it
    /// fits. Default: true.
    pub unlinked_markers: bool,
    /// Largest share of the map all count markers together may cover; the
    /// cells with the most missing links come first. Default: 0.015.
    pub marker_share: f64,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        Self {
            show_unrealized: false,
            unlinked_markers: true,
            marker_share: 0.015,
        }
    }
}

/// Base width of a tab on its edge, canvas units at canvas scale 1: at least
/// [`TAB_WIDTH_MIN`], growing with the smaller cell's size
/// ([`TAB_WIDTH_SHARE`] of the side of a square of its area) up to
/// [`TAB_WIDTH_MAX`]. Its head is [`HEAD`] times as wide (a dovetail, so it
/// reads as interlocking rather than as a bar).
const TAB_WIDTH_MIN: f64 = 7.0;
/// See [`TAB_WIDTH_MIN`].
const TAB_WIDTH_MAX: f64 = 16.0;
/// See [`TAB_WIDTH_MIN`].
const TAB_WIDTH_SHARE: f64 = 0.07;
/// Head width over base width.
const HEAD: f64 = 1.5;
/// Depth over base width, by similarity strength: the paper's three sizes
/// (§3.8's levels, the lowest two merged, as real constraints rarely fall
/// below 0.5).
fn depth_ratio(similarity: f64) -> f64 {
    if similarity >= 0.95 {
        1.3
    } else if similarity >= 0.75 {
        0.95
    } else {
        0.65
    }
}
/// A tab takes at most this share of either cell's area.
const TAB_AREA_SHARE: f64 = 0.04;
/// A tab's base covers at most this share of the shared edge.
const TAB_EDGE_SHARE: f64 = 0.5;
/// A tab shrunk below this share of its full size is not drawn.
const TAB_MIN_SCALE: f64 = 0.5;
/// Where along the shared edge a tab may sit, tried in order.
const TAB_POSITIONS: [f64; 5] = [0.5, 0.35, 0.65, 0.22, 0.78];

/// A tab placed on a shared edge.
#[derive(Clone, Debug, PartialEq)]
pub struct Tab {
    /// The constraint's first node.
    pub a: usize,
    /// Its second node.
    pub b: usize,
    /// The cell whose colour protrudes (the smaller one).
    pub from: usize,
    /// The shape filled with `from`'s colour: the knob plus a sliver on
    /// `from`'s side that covers the edge's own line.
    pub fill: Vec<Point>,
    /// The knob's outline: base end, head corners, base end.
    pub outline: [Point; 4],
    /// Outline width.
    pub width: f64,
}

/// Where a tab may go: the longest shared segment of the two cells, with
/// `diagonal` the layout's ([`Layout::diagonal`], which walks every cell:
/// computed once per picture, not once per tab).
pub fn tab_edge(layout: &Layout, link: &Link, diagonal: f64) -> Option<[Point; 2]> {
    let tol = PERPENDICULAR_TOL * diagonal;
    shared_segments(
        &layout.cells[link.a].polygon,
        &layout.cells[link.b].polygon,
        tol,
    )
    .into_iter()
    .max_by(|s, t| s[0].distance(s[1]).total_cmp(&t[0].distance(t[1])))
}

/// Signed distance from `p` to the inside of a convex polygon's boundary:
/// positive inside, the smallest over its edges.
fn inset(polygon: &ConvexPolygon, p: Point) -> f64 {
    let pts = polygon.points();
    (0..pts.len())
        .map(|k| {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            let e = b - a;
            let len = e.length();
            if len > 0.0 {
                crate::geom::cross(e, p - a) / len
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Whether a polygon and a box overlap.
fn hits_rect(poly: &[Point], r: &Rect) -> bool {
    let quad = r.corners();
    convex_overlap(poly, &quad)
}

/// Whether two convex polygons overlap with positive area (separating axes).
fn convex_overlap(a: &[Point], b: &[Point]) -> bool {
    for poly in [a, b] {
        for k in 0..poly.len() {
            let e = poly[(k + 1) % poly.len()] - poly[k];
            let n = Point::new(-e.y, e.x);
            let span = |q: &[Point]| {
                q.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                        let v = n.dot(*p);
                        (lo.min(v), hi.max(v))
                    })
            };
            let ((a0, a1), (b0, b1)) = (span(a), span(b));
            if a1 <= b0 + 1e-9 || b1 <= a0 + 1e-9 {
                return false;
            }
        }
    }
    true
}

/// The tabs of the realised `links`, each on its shared edge, sized to the
/// edge and the smaller cell, clear of every label box and of each other;
/// a link with no such place gets none. `u` is the canvas scale; `width(a, b)`
/// the outline width of the edge between two cells.
pub fn place_tabs(
    layout: &Layout,
    links: &[Link],
    labels: &[Placed],
    u: f64,
    width: &dyn Fn(usize, usize) -> f64,
) -> Vec<Tab> {
    let mut by_cell: std::collections::HashMap<usize, Vec<Rect>> = Default::default();
    for l in labels {
        by_cell
            .entry(l.node)
            .or_default()
            .push(l.rect.grown(0.5 * u));
    }
    let mut tabs: Vec<Tab> = Vec::new();
    let mut grid = TabGrid::new(TAB_GRID_EM * u);
    let diagonal = layout.diagonal();
    for link in links.iter().filter(|l| l.realized) {
        let line = width(link.a, link.b);
        if let Some(tab) = place_tab(layout, link, diagonal, &by_cell, &grid, u, line) {
            grid.insert([tab.fill[0], tab.outline[1], tab.outline[2], tab.fill[5]]);
            tabs.push(tab);
        }
    }
    tabs
}

/// Side of a [`TabGrid`] square in canvas units per unit of scale: about
/// the largest tab (`TAB_WIDTH_MAX` wide, as deep), so a tab's box spans
/// few squares.
const TAB_GRID_EM: f64 = 2.0 * TAB_WIDTH_MAX;

/// The hulls of the tabs placed so far, bucketed by their bounding boxes
/// on a square grid, so that a new tab is tested against the tabs near it
/// rather than every tab of the picture (which made placing the tabs
/// quadratic in their number). Exact: convex hulls whose bounding boxes are
/// disjoint are disjoint, and the separating-axis test finds them so.
struct TabGrid {
    side: f64,
    hulls: Vec<[Point; 4]>,
    squares: std::collections::HashMap<(i64, i64), Vec<usize>>,
}

impl TabGrid {
    fn new(side: f64) -> Self {
        TabGrid {
            side: if side > 0.0 && side.is_finite() {
                side
            } else {
                1.0
            },
            hulls: Vec::new(),
            squares: Default::default(),
        }
    }

    /// The grid squares `hull`'s bounding box touches (bounded: a hull is
    /// a tab's, at most a few squares across; a degenerate one is clamped).
    fn squares_of(&self, hull: &[Point]) -> impl Iterator<Item = (i64, i64)> {
        let (mut lo, mut hi) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in hull {
            lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        let square = |v: f64| (v / self.side).floor().clamp(-1e9, 1e9) as i64;
        let (x0, y0) = (square(lo.x), square(lo.y));
        let (x1, y1) = (square(hi.x).min(x0 + 64), square(hi.y).min(y0 + 64));
        (x0..=x1).flat_map(move |x| (y0..=y1).map(move |y| (x, y)))
    }

    fn insert(&mut self, hull: [Point; 4]) {
        let k = self.hulls.len();
        let squares: Vec<(i64, i64)> = self.squares_of(&hull).collect();
        for square in squares {
            self.squares.entry(square).or_default().push(k);
        }
        self.hulls.push(hull);
    }

    /// The placed hulls whose squares `hull` touches, each once.
    fn near<'g>(&'g self, hull: &[Point]) -> impl Iterator<Item = &'g [Point; 4]> + 'g {
        let mut seen: Vec<usize> = self
            .squares_of(hull)
            .filter_map(|square| self.squares.get(&square))
            .flatten()
            .copied()
            .collect();
        seen.sort_unstable();
        seen.dedup();
        seen.into_iter().map(move |k| &self.hulls[k])
    }
}

fn place_tab(
    layout: &Layout,
    link: &Link,
    diagonal: f64,
    labels: &std::collections::HashMap<usize, Vec<Rect>>,
    placed: &TabGrid,
    u: f64,
    line: f64,
) -> Option<Tab> {
    let [p0, p1] = tab_edge(layout, link, diagonal)?;
    let (pa, pb) = (&layout.cells[link.a].polygon, &layout.cells[link.b].polygon);
    let (from, into) = if pa.area() <= pb.area() {
        (link.a, link.b)
    } else {
        (link.b, link.a)
    };
    let (small, large) = (&layout.cells[from].polygon, &layout.cells[into].polygon);
    let edge = p1 - p0;
    let len = edge.length();
    if len <= 0.0 {
        return None;
    }
    let p = edge * (1.0 / len);
    let mut n = Point::new(-p.y, p.x);
    // n points into the receiving cell.
    if n.dot(large.centroid() - (p0 + p1) * 0.5) < 0.0 {
        n = -n;
    }
    let ratio = depth_ratio(link.similarity);
    let full = (TAB_WIDTH_SHARE * small.area().sqrt()).clamp(TAB_WIDTH_MIN * u, TAB_WIDTH_MAX * u);
    // Largest scale the edge and both cells allow.
    let area_at_1 = 0.5 * (1.0 + HEAD) * full * ratio * full;
    let limit = [
        TAB_EDGE_SHARE * len / full,
        (TAB_AREA_SHARE * small.area() / area_at_1).sqrt(),
        (TAB_AREA_SHARE * large.area() / area_at_1).sqrt(),
        1.0,
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min);
    let cover = 0.5 * line + 0.3 * u.min(1.0);
    for scale in [limit, 0.8 * limit, 0.64 * limit] {
        if scale < TAB_MIN_SCALE {
            break;
        }
        let w = full * scale;
        let (hb, hh, d) = (0.5 * w, 0.5 * HEAD * w, ratio * w);
        for t in TAB_POSITIONS {
            let along = t * len;
            if along < hh + line || len - along < hh + line {
                continue;
            }
            let m = p0 + p * along;
            let outline = [
                m - p * hb,
                m - p * hh + n * d,
                m + p * hh + n * d,
                m + p * hb,
            ];
            // The head stays inside the receiving cell, clear of its other edges.
            if outline[1..3]
                .iter()
                .any(|q| inset(large, *q) < line + 0.5 * u.min(1.0))
            {
                continue;
            }
            let fill = vec![
                m - p * hb - n * cover,
                outline[0],
                outline[1],
                outline[2],
                outline[3],
                m + p * hb - n * cover,
            ];
            let hull = [fill[0], outline[1], outline[2], fill[5]];
            let clear_of_labels = [from, into].iter().all(|c| {
                labels
                    .get(c)
                    .is_none_or(|rs| rs.iter().all(|r| !hits_rect(&hull, r)))
            });
            let clear_of_tabs = placed
                .near(&hull)
                .all(|other| !convex_overlap(&hull, other));
            if clear_of_labels && clear_of_tabs {
                return Some(Tab {
                    a: link.a,
                    b: link.b,
                    from,
                    fill,
                    outline,
                    width: line,
                });
            }
        }
    }
    let _ = small;
    None
}

/// A count marker placed in its cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// The cell.
    pub node: usize,
    /// Its centre.
    pub at: Point,
    /// Its radius.
    pub r: f64,
    /// Missing links.
    pub count: usize,
}

/// Marker radius at canvas scale 1, canvas units: its count stays readable
/// (8.75 px digits) while 60 markers take about 1 % of a 1,000 px map.
const MARKER_R: f64 = 7.0;
/// A marker covers at most this share of its cell.
const MARKER_CELL_SHARE: f64 = 0.06;

/// The count markers: one per cell with missing links, where a circle fits
/// inside the cell clear of its label and tabs, nearest the label's
/// upper-right corner (or the cell's centre); the cells with the most missing
/// links (then the largest) first, until the markers would cover more than
/// `share` of the map.
pub fn place_markers(
    layout: &Layout,
    links: &[Link],
    labels: &[Placed],
    tabs: &[Tab],
    u: f64,
    share: f64,
) -> Vec<Marker> {
    let cells = layout.cells.len();
    let mut missing = vec![0usize; cells];
    for link in links.iter().filter(|l| !l.realized) {
        missing[link.a] += 1;
        missing[link.b] += 1;
    }
    let r = MARKER_R * u;
    let marker_area = std::f64::consts::PI * r * r;
    let budget = share * layout.canvas.width * layout.canvas.height;
    let mut order: Vec<usize> = (0..cells).filter(|&i| missing[i] > 0).collect();
    order.sort_by(|&a, &b| {
        missing[b]
            .cmp(&missing[a])
            .then(
                layout.cells[b]
                    .polygon
                    .area()
                    .total_cmp(&layout.cells[a].polygon.area()),
            )
            .then(a.cmp(&b))
    });
    let mut label_of: Vec<Option<&Rect>> = vec![None; cells];
    for l in labels {
        if l.node < cells {
            label_of[l.node] = Some(&l.rect);
        }
    }
    let mut tabs_in: Vec<Vec<[Point; 4]>> = vec![Vec::new(); cells];
    for t in tabs {
        let hull = [t.fill[0], t.outline[1], t.outline[2], t.fill[5]];
        tabs_in[t.a].push(hull);
        tabs_in[t.b].push(hull);
    }
    let mut out = Vec::new();
    let mut used = 0.0;
    for i in order {
        if used + marker_area > budget {
            break;
        }
        let polygon = &layout.cells[i].polygon;
        if marker_area > MARKER_CELL_SHARE * polygon.area() {
            continue;
        }
        let margin = r + 1.5 * u;
        let label = label_of[i].map(|l| l.grown(1.5 * u));
        let wanted = match &label {
            Some(l) => Point::new(l.x1 + r, l.y0),
            None => polygon.centroid(),
        };
        let best = marker_spot(polygon, label.as_ref(), &tabs_in[i], r, margin, wanted);
        if let Some(at) = best {
            used += marker_area;
            out.push(Marker {
                node: i,
                at,
                r,
                count: missing[i],
            });
        }
    }
    out.sort_by_key(|m| m.node);
    out
}

/// The centre of a marker of radius `r` in `polygon` at least `margin`
/// inside it, clear of its label box and its tabs, nearest `wanted`: the best
/// of a 13 × 13 grid over the cell's box, if any point of it fits.
fn marker_spot(
    polygon: &ConvexPolygon,
    label: Option<&Rect>,
    tabs: &[[Point; 4]],
    r: f64,
    margin: f64,
    wanted: Point,
) -> Option<Point> {
    let (lo, hi) = polygon.bbox();
    const STEPS: usize = 12;
    let mut best: Option<(f64, Point)> = None;
    for iy in 0..=STEPS {
        for ix in 0..=STEPS {
            let c = Point::new(
                lo.x + (hi.x - lo.x) * ix as f64 / STEPS as f64,
                lo.y + (hi.y - lo.y) * iy as f64 / STEPS as f64,
            );
            if inset(polygon, c) < margin {
                continue;
            }
            let hits_label = label.is_some_and(|l| {
                let dx = c.x - c.x.clamp(l.x0, l.x1);
                let dy = c.y - c.y.clamp(l.y0, l.y1);
                dx * dx + dy * dy < r * r
            });
            let square = [
                c + Point::new(-r, -r),
                c + Point::new(r, -r),
                c + Point::new(r, r),
                c + Point::new(-r, r),
            ];
            let hits_tab = tabs.iter().any(|t| convex_overlap(t, &square));
            if hits_label || hits_tab {
                continue;
            }
            let d = c.distance(wanted);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, c));
            }
        }
    }
    best.map(|(_, at)| at)
}

/// The tab layer's SVG: each tab as its cell-coloured shape and its outline.
pub fn tabs_svg(dataset: &Dataset, tabs: &[Tab], colors: &[Option<Rgb>], stroke: Rgb) -> String {
    let pts = |v: &[Point]| {
        v.iter()
            .map(|q| format!("{},{}", num(q.x), num(q.y)))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut out = format!(
        "<g class=\"np-tabs\" stroke-linejoin=\"round\" stroke-linecap=\"round\" stroke=\"{stroke}\">\n"
    );
    for t in tabs {
        let fill = colors
            .get(t.from)
            .copied()
            .flatten()
            .map_or("#cccccc".to_string(), |c| c.to_string());
        out.push_str(&format!(
            "<g class=\"np-tab\" data-a=\"{}\" data-b=\"{}\"><polygon points=\"{}\" fill=\"{fill}\" stroke=\"none\"/><polyline points=\"{}\" fill=\"none\" stroke-width=\"{}\"/></g>\n",
            escape(&dataset.node(t.a).id),
            escape(&dataset.node(t.b).id),
            pts(&t.fill),
            pts(&t.outline),
            num(t.width)
        ));
    }
    out.push_str("</g>\n");
    out
}

/// The dashed links of unrealised constraints (hidden unless `style` shows
/// them) and the count markers: circles, then their counts, in two groups
/// (circles never overlap, so the order within is free, and text in a group
/// of its own renders fast).
pub fn marks_svg(
    layout: &Layout,
    links: &[Link],
    markers: &[Marker],
    style: &OverlayStyle,
    u: f64,
) -> String {
    let display = if style.show_unrealized {
        ""
    } else {
        " display=\"none\""
    };
    let mut out = format!(
        "<g class=\"np-unrealized\" stroke=\"#d62728\" stroke-width=\"{}\" stroke-dasharray=\"{}\"{display}>\n",
        num(1.5 * u.max(0.5)),
        num(4.0 * u.max(0.5))
    );
    for link in links.iter().filter(|l| !l.realized) {
        let (a, b) = (
            layout.cells[link.a].polygon.centroid(),
            layout.cells[link.b].polygon.centroid(),
        );
        // One line per unrealised constraint (16,000 on 6,000 C headers):
        // spelled in place, as `num` would.
        out.push_str("<line x1=\"");
        push_num(&mut out, a.x);
        out.push_str("\" y1=\"");
        push_num(&mut out, a.y);
        out.push_str("\" x2=\"");
        push_num(&mut out, b.x);
        out.push_str("\" y2=\"");
        push_num(&mut out, b.y);
        out.push_str("\"/>\n");
    }
    out.push_str("</g>\n");
    if markers.is_empty() {
        return out;
    }
    let r = markers[0].r;
    out.push_str(&format!(
        "<g class=\"np-unlinked\" fill=\"#ffffff\" stroke=\"#d62728\" stroke-width=\"{}\">\n",
        num(0.2 * r)
    ));
    for m in markers {
        out.push_str(&format!(
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\"><title>{} unrealized link(s)</title></circle>\n",
            num(m.at.x),
            num(m.at.y),
            num(m.r),
            m.count
        ));
    }
    out.push_str("</g>\n");
    out.push_str(&format!(
        "<g class=\"np-unlinked-count\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"{}\" text-anchor=\"middle\" fill=\"#d62728\" pointer-events=\"none\">\n",
        num(1.25 * r)
    ));
    for m in markers {
        out.push_str(&format!(
            "<text x=\"{}\" y=\"{}\">{}</text>\n",
            num(m.at.x),
            num(m.at.y + 0.45 * r),
            m.count
        ));
    }
    out.push_str("</g>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{Canvas, LayoutCell};
    use crate::render::labels::Line;

    /// Three columns a | b | c of a 900 × 300 canvas, and d, a thin strip
    /// under c whose edge with b is 1 unit long.
    fn sample() -> Layout {
        let rect = LayoutCell::rectangle;
        Layout {
            canvas: Canvas {
                width: 900.0,
                height: 300.0,
            },
            cells: vec![
                rect(0.0, 0.0, 900.0, 300.0),
                rect(0.0, 0.0, 300.0, 300.0),
                rect(300.0, 0.0, 300.0, 300.0),
                rect(600.0, 0.0, 300.0, 299.0),
                rect(600.0, 299.0, 300.0, 1.0),
            ],
        }
    }

    fn link(a: usize, b: usize, similarity: f64, realized: bool) -> Link {
        Link {
            a,
            b,
            similarity,
            realized,
        }
    }

    #[test]
    fn tabs_sit_on_their_edge_inside_the_larger_cell_and_never_on_a_label() {
        let layout = sample();
        let links = [
            link(1, 2, 0.99, true),
            link(2, 3, 0.3, true),
            link(2, 4, 0.99, true),
        ];
        let tabs = place_tabs(&layout, &links, &[], 1.0, &|_, _| 1.0);
        // b–d shares one unit: no room.
        assert_eq!(tabs.len(), 2, "{tabs:?}");
        for (t, x) in tabs.iter().zip([300.0, 600.0]) {
            assert!((t.outline[0].x - x).abs() < 1e-9 && (t.outline[3].x - x).abs() < 1e-9);
            let into = if t.from == t.a { t.b } else { t.a };
            for q in &t.outline[1..3] {
                assert!(layout.cells[into].polygon.contains(*q), "head inside");
            }
        }
        // The stronger similarity draws the deeper tab.
        let depth = |t: &Tab| (t.outline[1].x - t.outline[0].x).abs();
        assert!(depth(&tabs[0]) > depth(&tabs[1]));
        // A label across the middle of the edge moves the tab along it.
        let label = Placed {
            node: 2,
            lines: vec![Line {
                text: "b".into(),
                x: 450.0,
                baseline: 155.0,
                size: 10.0,
            }],
            rect: Rect {
                x0: 295.0,
                y0: 140.0,
                x1: 605.0,
                y1: 160.0,
            },
            angle: 0.0,
        };
        let moved = place_tabs(
            &layout,
            &links[..1],
            std::slice::from_ref(&label),
            1.0,
            &|_, _| 1.0,
        );
        assert_eq!(moved.len(), 1);
        assert!(!hits_rect(&moved[0].fill, &label.rect));
        assert!((moved[0].outline[0].y - 150.0).abs() > 10.0);
    }

    #[test]
    fn markers_fit_their_cell_avoid_the_label_and_respect_the_budget() {
        let layout = sample();
        let links = [link(1, 3, 0.9, false), link(1, 2, 0.9, false)];
        let label = Placed {
            node: 1,
            lines: Vec::new(),
            rect: Rect {
                x0: 100.0,
                y0: 140.0,
                x1: 200.0,
                y1: 160.0,
            },
            angle: 0.0,
        };
        let markers = place_markers(
            &layout,
            &links,
            std::slice::from_ref(&label),
            &[],
            1.0,
            0.02,
        );
        assert_eq!(markers.len(), 3, "a, b and c; d is too thin");
        for m in &markers {
            assert!(inset(&layout.cells[m.node].polygon, m.at) >= m.r);
        }
        let a = markers.iter().find(|m| m.node == 1).expect("a has one");
        assert_eq!(a.count, 2);
        let dx = a.at.x - a.at.x.clamp(100.0, 200.0);
        let dy = a.at.y - a.at.y.clamp(140.0, 160.0);
        assert!(dx.hypot(dy) >= a.r, "clear of the label");
        // A budget of one marker keeps the cell with the most missing links.
        let one = std::f64::consts::PI * 49.0 / (900.0 * 300.0) * 1.5;
        let markers = place_markers(&layout, &links, &[], &[], 1.0, one);
        assert_eq!(markers.iter().map(|m| m.node).collect::<Vec<_>>(), vec![1]);
    }
}
