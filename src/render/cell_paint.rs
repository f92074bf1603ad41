//! The map's cells painted straight onto the PNG's pixels (issue 32, item 1):
//! the cell group the SVG writer makes (`svg::push_cells`: `<g
//! class="np-cells" stroke stroke-linejoin>` holding one `<g stroke-width>`
//! per level, each of `<path data-id d fill>` with a `<title>`) read from
//! the parsed document into tiny-skia paths and painted as resvg paints them
//! (fill, then the outline: anti-aliased, butt caps, miter limit 4), so the
//! tens of thousands of cells of a large map skip usvg's tree, which took a
//! third of the PNG's time at 6,000 C headers (a single-threaded parse on
//! the render's critical path). Anything else in the group, or a path that
//! is not the writer's `M x,y L x,y … Z`, leaves the group to usvg.

use resvg::tiny_skia::{
    self, FillRule, LineCap, LineJoin, Paint, Path, PathBuilder, Stroke, Transform,
};
use resvg::usvg::roxmltree;

/// The class of the cell group (`svg::push_cells`).
const CELLS_CLASS: &str = "np-cells";

/// One cell ready to paint: its outline as a path in user units, its fill
/// (none for a group's outline) and its stroke.
pub(super) struct CellPaint {
    path: Path,
    fill: Option<tiny_skia::Color>,
    stroke: Option<(tiny_skia::Color, f32, LineJoin)>,
}

impl CellPaint {
    /// Paints the cell with `ts` (user units to pixels), as resvg would.
    pub(super) fn draw(&self, pixmap: &mut tiny_skia::Pixmap, ts: Transform) {
        let paint = |c: tiny_skia::Color| {
            let mut p = Paint::default();
            p.set_color(c);
            p.anti_alias = true;
            p
        };
        if let Some(c) = self.fill {
            pixmap.fill_path(&self.path, &paint(c), FillRule::Winding, ts, None);
        }
        if let Some((c, width, join)) = self.stroke {
            let stroke = Stroke {
                width,
                miter_limit: 4.0,
                line_cap: LineCap::Butt,
                line_join: join,
                dash: None,
            };
            pixmap.stroke_path(&self.path, &paint(c), &stroke, ts, None);
        }
    }
}

/// The paints of `el` when it is the writer's cell group, in paint order;
/// `None` otherwise (usvg then draws it). `color` reads a paint value as the
/// text layer does (`none` or `#rrggbb`).
pub(super) fn cell_group(
    el: roxmltree::Node,
    color: impl Fn(&str) -> Option<Option<tiny_skia::Color>>,
) -> Option<Vec<CellPaint>> {
    if el.tag_name().name() != "g" || el.attribute("class") != Some(CELLS_CLASS) {
        return None;
    }
    // SVG's defaults: no stroke, miter joins.
    let (mut stroke, mut join) = (None, LineJoin::Miter);
    for a in el.attributes() {
        match a.name() {
            "class" => {}
            "stroke" => stroke = color(a.value())?,
            "stroke-linejoin" => {
                join = match a.value() {
                    "miter" => LineJoin::Miter,
                    "round" => LineJoin::Round,
                    "bevel" => LineJoin::Bevel,
                    _ => return None,
                }
            }
            _ => return None,
        }
    }
    let mut out = Vec::new();
    for level in elements(el)? {
        if level.tag_name().name() != "g" {
            return None;
        }
        let mut width = 1.0f32;
        for a in level.attributes() {
            match a.name() {
                "stroke-width" => {
                    width = a.value().trim().parse().ok().filter(|w: &f32| *w >= 0.0)?
                }
                _ => return None,
            }
        }
        for cell in elements(level)? {
            out.push(cell_paint(cell, &color, stroke, width, join)?);
        }
    }
    Some(out)
}

/// One `<path data-id d fill>` of a level, its `<title>` aside.
fn cell_paint(
    cell: roxmltree::Node,
    color: &impl Fn(&str) -> Option<Option<tiny_skia::Color>>,
    stroke: Option<tiny_skia::Color>,
    width: f32,
    join: LineJoin,
) -> Option<CellPaint> {
    if cell.tag_name().name() != "path" {
        return None;
    }
    // SVG's default fill is black.
    let (mut d, mut fill) = (None, Some(tiny_skia::Color::BLACK));
    for a in cell.attributes() {
        match a.name() {
            "data-id" => {}
            "d" => d = Some(a.value()),
            "fill" => fill = color(a.value())?,
            _ => return None,
        }
    }
    if elements(cell)?
        .iter()
        .any(|c| c.tag_name().name() != "title")
    {
        return None;
    }
    Some(CellPaint {
        path: polygon_path(d?)?,
        fill,
        stroke: stroke.filter(|_| width > 0.0).map(|c| (c, width, join)),
    })
}

/// The element children of `node`; `None` when it holds text other than
/// white space between them.
fn elements<'a, 'i>(node: roxmltree::Node<'a, 'i>) -> Option<Vec<roxmltree::Node<'a, 'i>>> {
    let mut out = Vec::new();
    for child in node.children() {
        if child.is_element() {
            out.push(child);
        } else if child.is_text() && !child.text()?.trim().is_empty() {
            return None;
        }
    }
    Some(out)
}

/// The path of the writer's polygon data `M x,y L x,y … Z` (`svg::path_data`),
/// coordinates read as usvg reads them (f64, then f32 for the path).
fn polygon_path(d: &str) -> Option<Path> {
    let body = d.trim().strip_prefix('M')?.strip_suffix('Z')?;
    let mut builder = PathBuilder::new();
    for (k, point) in body.split('L').enumerate() {
        let (x, y) = point.split_once(',')?;
        let (x, y): (f64, f64) = (x.trim().parse().ok()?, y.trim().parse().ok()?);
        if k == 0 {
            builder.move_to(x as f32, y as f32);
        } else {
            builder.line_to(x as f32, y as f32);
        }
    }
    builder.close();
    builder.finish()
}
