//! One element of the picture as the PNG paints it (issue 32, items 1-2):
//! its outline as a tiny-skia path in user units with its fill and stroke,
//! painted as resvg paints an SVG shape (anti-aliased, non-zero fill, the
//! stroke's miter limit 4), plus what a repaint needs to know of it: the
//! pixel rows it can touch and a digest of everything that decides its
//! pixels. Cells, shapes and glyph runs are all items; `png_plan` makes
//! them from the SVG writer's elements.

use resvg::tiny_skia::{
    self, FillRule, LineCap, LineJoin, Paint, Path, PathSegment, Stroke, StrokeDash, Transform,
};
use xxhash_rust::xxh3::Xxh3;

/// How an item's outline is stroked.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Line {
    pub color: tiny_skia::Color,
    pub width: f32,
    pub join: LineJoin,
    pub cap: LineCap,
    /// Dash lengths (an even count), `None` for a solid line.
    pub dash: Option<Vec<f32>>,
}

/// One painted element (see the module docs).
pub(super) struct Item {
    pub path: Path,
    pub fill: Option<tiny_skia::Color>,
    pub stroke: Option<Line>,
    /// `paint-order: stroke`: the stroke under the fill (the labels' halo).
    pub stroke_first: bool,
}

/// The stroke's miter limit: SVG's default, which the writer never changes.
const MITER_LIMIT: f32 = 4.0;

/// Rows of anti-aliasing around an item's bounds that a repaint also
/// counts as touched: coverage reaches at most one pixel past an edge, and
/// the second row absorbs the rounding of the bounds to whole pixels.
const AA_ROWS: f32 = 2.0;

impl Item {
    /// Paints the item with `ts` (user units to pixels), as resvg would.
    pub(super) fn draw(&self, pixmap: &mut tiny_skia::PixmapMut<'_>, ts: Transform) {
        let paint = |c: tiny_skia::Color| {
            let mut p = Paint::default();
            p.set_color(c);
            p.anti_alias = true;
            p
        };
        let fill = |pixmap: &mut tiny_skia::PixmapMut<'_>| {
            if let Some(c) = self.fill {
                pixmap.fill_path(&self.path, &paint(c), FillRule::Winding, ts, None);
            }
        };
        let stroke = |pixmap: &mut tiny_skia::PixmapMut<'_>| {
            if let Some(line) = &self.stroke {
                let st = Stroke {
                    width: line.width,
                    miter_limit: MITER_LIMIT,
                    line_cap: line.cap,
                    line_join: line.join,
                    dash: line.dash.clone().and_then(|d| StrokeDash::new(d, 0.0)),
                };
                pixmap.stroke_path(&self.path, &paint(line.color), &st, ts, None);
            }
        };
        if self.stroke_first {
            stroke(pixmap);
            fill(pixmap);
        } else {
            fill(pixmap);
            stroke(pixmap);
        }
    }

    /// The pixel rows `[first, end)` the item can touch under `ts`, which
    /// only scales and moves (the picture's view transform): its bounds, the
    /// stroke's reach (half its width, times the miter limit at a spike) and
    /// the anti-aliasing around them. `None` when it touches no row.
    pub(super) fn rows(&self, ts: Transform) -> Option<(i64, i64)> {
        let b = self.path.bounds();
        let reach = self
            .stroke
            .as_ref()
            .map_or(0.0, |l| 0.5 * l.width * MITER_LIMIT.max(1.0));
        let (top, bottom) = (
            (b.top() - reach) * ts.sy + ts.ty,
            (b.bottom() + reach) * ts.sy + ts.ty,
        );
        let (top, bottom) = (top.min(bottom) - AA_ROWS, top.max(bottom) + AA_ROWS);
        if !(top.is_finite() && bottom.is_finite()) {
            return None;
        }
        Some((top.floor() as i64, bottom.ceil() as i64 + 1))
    }

    /// Feeds everything that decides the item's pixels to `h`: every
    /// segment's points (their bits), the fill, the stroke and the order.
    pub(super) fn digest(&self, h: &mut Xxh3) {
        let point = |h: &mut Xxh3, p: tiny_skia::Point| {
            h.update(&p.x.to_bits().to_le_bytes());
            h.update(&p.y.to_bits().to_le_bytes());
        };
        for segment in self.path.segments() {
            match segment {
                PathSegment::MoveTo(p) => {
                    h.update(b"M");
                    point(h, p);
                }
                PathSegment::LineTo(p) => {
                    h.update(b"L");
                    point(h, p);
                }
                PathSegment::QuadTo(a, b) => {
                    h.update(b"Q");
                    point(h, a);
                    point(h, b);
                }
                PathSegment::CubicTo(a, b, c) => {
                    h.update(b"C");
                    point(h, a);
                    point(h, b);
                    point(h, c);
                }
                PathSegment::Close => h.update(b"Z"),
            }
        }
        let color = |h: &mut Xxh3, c: Option<tiny_skia::Color>| match c {
            None => h.update(b"-"),
            Some(c) => {
                for v in [c.red(), c.green(), c.blue(), c.alpha()] {
                    h.update(&v.to_bits().to_le_bytes());
                }
            }
        };
        color(h, self.fill);
        match &self.stroke {
            None => h.update(b"-"),
            Some(l) => {
                color(h, Some(l.color));
                h.update(&l.width.to_bits().to_le_bytes());
                h.update(&[l.join as u8, l.cap as u8]);
                for d in l.dash.iter().flatten() {
                    h.update(&d.to_bits().to_le_bytes());
                }
            }
        }
        h.update(&[u8::from(self.stroke_first)]);
    }
}
