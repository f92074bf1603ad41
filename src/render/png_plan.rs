//! The SVG text the picture writer makes, read back into what the PNG
//! paints (issue 32, item 1): each top-level element made only of what
//! [`Item`]s draw (groups, the writer's shapes and cells, plain text) becomes
//! an item layer, the rest runs of documents for usvg. Reads the parsed
//! document's structure, never text lines (a title may hold a line break,
//! issue 11 item 7). Text is shaped as usvg shapes it, from the built-in
//! font's caches (`super::text`; usvg's set-up per text element was most of
//! a labelled picture's time, issue 13 item 7), and the cells, tens of
//! thousands on a large map, skip usvg's tree, which took a third of the
//! PNG's time at 6,000 C headers. Anything else an element holds (a
//! transform on a group, an opacity, another path syntax) leaves it to usvg.

use resvg::tiny_skia::{self, LineCap, LineJoin, Path, PathBuilder, Rect, Transform};
use resvg::usvg::roxmltree;

use rayon::prelude::*;

use super::display::{Cells, Shape};
use super::paint::{Item, Line};
use super::text;

/// Most usvg documents a plan leaves: runs of elements the items cannot
/// draw, between item layers, are merged until there are at most this many.
const LAYERS: usize = 3;

/// What the PNG draws, in paint order.
pub(super) struct Plan {
    pub layers: Vec<Layer>,
    /// The root element's size and view box (for the item layers).
    pub view: Option<View>,
}

pub(super) enum Layer {
    /// A document usvg parses: the root element with a run of its children
    /// that the items do not draw.
    Svg(String),
    /// A top-level element painted item by item.
    Items(Vec<Item>),
}

/// The root element's `width`, `height` and `viewBox`.
pub(super) struct View {
    pub width: f64,
    pub height: f64,
    view_box: [f64; 4],
}

impl View {
    /// User units to the image's units (`preserveAspectRatio` xMidYMid meet,
    /// the default).
    pub(super) fn transform(&self) -> Transform {
        let [x, y, w, h] = self.view_box;
        let s = (self.width / w).min(self.height / h);
        let tx = 0.5 * (self.width - w * s) - x * s;
        let ty = 0.5 * (self.height - h * s) - y * s;
        Transform::from_row(s as f32, 0.0, 0.0, s as f32, tx as f32, ty as f32)
    }
}

/// Splits SVG text into layers by its XML structure (the parsed document's
/// element ranges), never by text lines: a title or label may hold a line
/// break (issue 11, item 7). A top-level element made only of what the items
/// draw becomes an item layer; runs of the others become documents with the
/// same root element, merged to at most [`LAYERS`]. `None` when the text
/// does not parse; it is then parsed whole, and usvg reports the error.
pub(super) fn plan(svg: &str) -> Option<Plan> {
    let doc = roxmltree::Document::parse(svg).ok()?;
    layered(svg, doc.root_element(), None)
}

/// [`plan`] of a picture writer's text whose cells' group the writer also
/// gave as shapes (`super::display`): the group is cut out of the text
/// before it is parsed (nine tenths of a map's text), and its items are
/// made from the shapes, the layer the group's text would have made.
/// `None` as for [`plan`], or when the rest has no view to place them in.
pub(super) fn plan_drawn(svg: &str, cells: &Cells) -> Option<Plan> {
    let at = cells.range.start;
    let rest = format!("{}{}", svg.get(..at)?, svg.get(cells.range.end..)?);
    let doc = roxmltree::Document::parse(&rest).ok()?;
    view_of(doc.root_element())?;
    let items = cells.shapes.par_iter().filter_map(shape_item).collect();
    layered(&rest, doc.root_element(), Some((at, items)))
}

/// A cell's shape as the item its `<path>` in the cells' group reads back
/// to (`shape` under the group's `stroke` and `stroke-linejoin="round"` and
/// its level's `stroke-width`); `None` for a shape of no corners, which
/// draws nothing.
fn shape_item(shape: &Shape) -> Option<Item> {
    let mut builder = PathBuilder::new();
    for (k, [x, y]) in shape.points.iter().enumerate() {
        if k == 0 {
            builder.move_to(*x as f32, *y as f32);
        } else {
            builder.line_to(*x as f32, *y as f32);
        }
    }
    builder.close();
    let color = |c: super::palette::Rgb| tiny_skia::Color::from_rgba8(c.r, c.g, c.b, 255);
    let style = Inherited {
        fill: shape.fill.map(|c| (color(c), 1.0)),
        stroke: Some(color(shape.stroke)),
        stroke_width: shape.width,
        join: LineJoin::Round,
        ..Inherited::default()
    };
    Some(painted(builder.finish()?, &style))
}

/// The layers of the document `src` whose root element is `root`, with
/// `inserted` items (at a byte offset of `src`) as a layer of their own
/// before the first element at or after that offset.
fn layered(src: &str, root: roxmltree::Node, inserted: Option<(usize, Vec<Item>)>) -> Option<Plan> {
    let elements: Vec<roxmltree::Node> = root.children().filter(|n| n.is_element()).collect();
    let first = elements.first()?.range().start;
    let last = elements.last()?.range().end;
    let header = &src[..first];
    let footer = &src[last..];
    let view = view_of(root);
    let mut inserted = inserted;
    // Runs of elements: Err(a layer we paint) or Ok(source range).
    let mut runs: Vec<Result<std::ops::Range<usize>, Layer>> = Vec::new();
    for (k, el) in elements.iter().enumerate() {
        if inserted
            .as_ref()
            .is_some_and(|(at, _)| el.range().start >= *at)
        {
            runs.extend(inserted.take().map(|(_, items)| Err(Layer::Items(items))));
        }
        let end = elements.get(k + 1).map_or(last, |n| n.range().start);
        let painted = view.as_ref().and_then(|_| items(*el).map(Layer::Items));
        match (painted, runs.last_mut()) {
            (Some(layer), _) => runs.push(Err(layer)),
            (None, Some(Ok(r))) => r.end = end,
            (None, _) => runs.push(Ok(el.range().start..end)),
        }
    }
    runs.extend(inserted.map(|(_, items)| Err(Layer::Items(items))));
    // Merge the shortest gaps between shape runs while there are too many:
    // a text layer between two merged runs moves into the document instead.
    let svg_runs =
        |runs: &[Result<std::ops::Range<usize>, Layer>]| runs.iter().filter(|r| r.is_ok()).count();
    while svg_runs(&runs) > LAYERS {
        // Fold the smallest item layer that separates two usvg runs back
        // into them (as SVG, which usvg then draws itself).
        let candidate = (1..runs.len().saturating_sub(1))
            .filter(|&i| {
                matches!(runs[i], Err(Layer::Items(_)))
                    && runs[i - 1].is_ok()
                    && runs[i + 1].is_ok()
            })
            .min_by_key(|&i| match &runs[i] {
                Err(Layer::Items(t)) => t.len(),
                _ => usize::MAX,
            });
        let Some(i) = candidate else { break };
        let end = match &runs[i + 1] {
            Ok(r) => r.end,
            Err(_) => break,
        };
        if let Ok(r) = &mut runs[i - 1] {
            r.end = end;
        }
        runs.drain(i..=i + 1);
    }
    let layers = runs
        .into_iter()
        .map(|r| match r {
            Ok(range) => Layer::Svg(format!("{header}{}{footer}", &src[range])),
            Err(layer) => layer,
        })
        .collect();
    Some(Plan { layers, view })
}

fn view_of(root: roxmltree::Node) -> Option<View> {
    let number = |name: &str| -> Option<f64> { root.attribute(name)?.trim().parse().ok() };
    let view_box: Vec<f64> = root
        .attribute("viewBox")?
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|v| !v.is_empty())
        .map(|v| v.parse().ok())
        .collect::<Option<_>>()?;
    let [x, y, w, h] = view_box[..] else {
        return None;
    };
    let (width, height) = (number("width")?, number("height")?);
    (w > 0.0 && h > 0.0 && width > 0.0 && height > 0.0).then_some(View {
        width,
        height,
        view_box: [x, y, w, h],
    })
}

/// The paint an element inherits (the SVG defaults to start with).
#[derive(Clone)]
struct Inherited {
    size: f64,
    anchor: f64,
    fill: Option<(tiny_skia::Color, f32)>,
    stroke: Option<tiny_skia::Color>,
    stroke_width: f64,
    join: LineJoin,
    cap: LineCap,
    dash: Option<Vec<f32>>,
    stroke_first: bool,
}

impl Default for Inherited {
    fn default() -> Self {
        Self {
            size: 12.0,
            anchor: 0.0,
            fill: Some((tiny_skia::Color::BLACK, 1.0)),
            stroke: None,
            stroke_width: 1.0,
            join: LineJoin::Miter,
            cap: LineCap::Butt,
            dash: None,
            stroke_first: false,
        }
    }
}

/// Attributes any element the items draw may carry: presentation the
/// drawing below reproduces, and attributes without effect on pixels.
const PLAIN: [&str; 20] = [
    "class",
    "x",
    "y",
    "font-family",
    "font-size",
    "font-weight",
    "text-anchor",
    "fill",
    "fill-opacity",
    "stroke",
    "stroke-width",
    "stroke-linejoin",
    "paint-order",
    "pointer-events",
    "transform",
    "data-a",
    "data-b",
    "data-id",
    "stroke-linecap",
    "stroke-dasharray",
];

fn color(value: &str) -> Option<Option<tiny_skia::Color>> {
    if value == "none" {
        return Some(None);
    }
    let rgb: super::palette::Rgb = value.parse().ok()?;
    Some(Some(tiny_skia::Color::from_rgba8(rgb.r, rgb.g, rgb.b, 255)))
}

/// Applies `node`'s own presentation attributes to `base`; `None` when one is
/// outside what the items draw. `geometry` names the element's own
/// geometry attributes, which its reader takes.
fn inherit(node: roxmltree::Node, base: &Inherited, geometry: &[&str]) -> Option<Inherited> {
    let mut out = base.clone();
    for a in node.attributes() {
        let (name, v) = (a.name(), a.value());
        if a.namespace().is_some() || !(PLAIN.contains(&name) || geometry.contains(&name)) {
            return None;
        }
        match name {
            "font-size" => out.size = v.parse().ok().filter(|s: &f64| *s > 0.0)?,
            "text-anchor" => {
                out.anchor = match v {
                    "start" => 0.0,
                    "middle" => 0.5,
                    "end" => 1.0,
                    _ => return None,
                }
            }
            "fill" => {
                let opacity = out.fill.map_or(1.0, |(_, o)| o);
                out.fill = color(v)?.map(|c| (c, opacity));
            }
            "fill-opacity" => {
                let o: f32 = v.parse().ok()?;
                out.fill = out.fill.map(|(c, _)| (c, o.clamp(0.0, 1.0)));
            }
            "stroke" => out.stroke = color(v)?,
            "stroke-width" => out.stroke_width = v.parse().ok().filter(|w: &f64| *w >= 0.0)?,
            "stroke-linejoin" => {
                out.join = match v {
                    "miter" => LineJoin::Miter,
                    "round" => LineJoin::Round,
                    "bevel" => LineJoin::Bevel,
                    _ => return None,
                }
            }
            "stroke-linecap" => {
                out.cap = match v {
                    "butt" => LineCap::Butt,
                    "round" => LineCap::Round,
                    "square" => LineCap::Square,
                    _ => return None,
                }
            }
            "stroke-dasharray" => out.dash = dashes(v)?,
            "paint-order" => {
                out.stroke_first = match v {
                    "stroke" | "stroke fill" | "stroke fill markers" => true,
                    "normal" | "fill" | "fill stroke" => false,
                    _ => return None,
                }
            }
            "font-family" => {
                // Every family resolves to the one built-in face.
            }
            "font-weight" => {
                // The built-in face has one weight; usvg draws it for any.
            }
            _ => {}
        }
    }
    Some(out)
}

/// A `rotate(a cx cy)` or `rotate(a)` transform.
fn rotation(value: &str) -> Option<Transform> {
    let inner = value.trim().strip_prefix("rotate(")?.strip_suffix(')')?;
    let v: Vec<f32> = inner
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().ok())
        .collect::<Option<_>>()?;
    match v[..] {
        [a] => Some(Transform::from_rotate(a)),
        [a, x, y] => Some(Transform::from_rotate_at(a, x, y)),
        _ => None,
    }
}

/// Whether usvg would draw `text` as it stands: no white space it would
/// collapse or trim, no right-to-left or bidi control characters (usvg
/// reorders those), every character in the built-in font.
fn plain_content(text: &str) -> bool {
    let rtl = |c: char| {
        matches!(c as u32,
            0x0590..=0x08FF | 0xFB1D..=0xFDFF | 0xFE70..=0xFEFF | 0x10800..=0x10FFF
            | 0x1E800..=0x1EFFF | 0x200E | 0x200F | 0x202A..=0x202E | 0x2066..=0x2069)
    };
    !text.is_empty()
        && !text.starts_with(' ')
        && !text.ends_with(' ')
        && !text.contains("  ")
        && !text.chars().any(|c| c.is_control() || rtl(c))
        && text::covers(text)
}

/// The items of `el` when it holds nothing but what they draw: groups
/// (without transforms), shapes (`rect`, `circle`, `polygon`, `polyline`,
/// `line`, the writer's `path`), plain `<text>` (content, or `<tspan x y>`
/// lines) and titles, all with attributes the items draw; `None` otherwise.
fn items(el: roxmltree::Node) -> Option<Vec<Item>> {
    let mut out = Vec::new();
    collect(el, &Inherited::default(), &mut out)?;
    Some(out)
}

fn collect(node: roxmltree::Node, base: &Inherited, out: &mut Vec<Item>) -> Option<()> {
    if node.attribute("display") == Some("none") {
        // Draws nothing, children included (the hidden unrealised links).
        return Some(());
    }
    match node.tag_name().name() {
        "g" => {
            if node.attribute("transform").is_some() {
                return None;
            }
            let style = inherit(node, base, &["display"])?;
            for child in elements(node)? {
                collect(child, &style, out)?;
            }
            Some(())
        }
        "title" => Some(()),
        "text" => text(node, base, out),
        _ => {
            out.extend(shape(node, base)?);
            Some(())
        }
    }
}

/// A `<text>` element's glyphs as one item.
fn text(node: roxmltree::Node, base: &Inherited, out: &mut Vec<Item>) -> Option<()> {
    let style = inherit(node, base, &[])?;
    let turn = match node.attribute("transform") {
        Some(t) => rotation(t)?,
        None => Transform::identity(),
    };
    let mut builder = PathBuilder::new();
    let spans: Vec<roxmltree::Node> = node.children().filter(|c| c.is_element()).collect();
    if spans.is_empty() {
        let (x, y) = (number(node, "x")?, number(node, "y")?);
        push_line(&mut builder, node.text()?, x, y, &style)?;
    } else {
        if node
            .children()
            .any(|c| c.is_text() && !c.text().unwrap_or("").is_empty())
        {
            return None;
        }
        for span in spans {
            if span.tag_name().name() != "tspan" || span.children().any(|c| !c.is_text()) {
                return None;
            }
            let own = inherit(span, &style, &[])?;
            let (x, y) = (number(span, "x")?, number(span, "y")?);
            push_line(&mut builder, span.text()?, x, y, &own)?;
        }
    }
    let Some(path) = builder.finish() else {
        return Some(());
    };
    out.push(painted(path.transform(turn)?, &style));
    Some(())
}

/// The geometry attributes of each shape the items draw.
const SHAPES: [(&str, &[&str]); 6] = [
    ("rect", &["x", "y", "width", "height"]),
    ("circle", &["cx", "cy", "r"]),
    ("polygon", &["points"]),
    ("polyline", &["points"]),
    ("line", &["x1", "y1", "x2", "y2"]),
    ("path", &["d"]),
];

/// A shape element as an item, `Some(None)` when SVG renders nothing of it
/// (a rectangle or circle of no size, a polyline of fewer than two points);
/// `None` when it is not a shape the items draw.
fn shape(node: roxmltree::Node, base: &Inherited) -> Option<Option<Item>> {
    let name = node.tag_name().name();
    let (_, geometry) = SHAPES.iter().find(|(n, _)| *n == name)?;
    let style = inherit(node, base, geometry)?;
    if elements(node)?
        .iter()
        .any(|c| c.tag_name().name() != "title")
    {
        return None;
    }
    let at = |a: &str| -> Option<f64> {
        node.attribute(a)
            .map_or(Some(0.0), |v| v.trim().parse().ok())
    };
    let mut filled = style.clone();
    let path = match name {
        "rect" => {
            let (w, h) = (at("width")?, at("height")?);
            if !(w > 0.0 && h > 0.0) {
                return Some(None);
            }
            PathBuilder::from_rect(Rect::from_xywh(
                at("x")? as f32,
                at("y")? as f32,
                w as f32,
                h as f32,
            )?)
        }
        "circle" => {
            let r = at("r")?;
            if r.is_nan() || r <= 0.0 {
                return Some(None);
            }
            circle(at("cx")?, at("cy")?, r)?
        }
        "polygon" | "polyline" => {
            let points = points(node.attribute("points")?)?;
            if points.len() < 2 {
                return Some(None);
            }
            let mut b = PathBuilder::new();
            for (k, (x, y)) in points.iter().enumerate() {
                if k == 0 {
                    b.move_to(*x as f32, *y as f32);
                } else {
                    b.line_to(*x as f32, *y as f32);
                }
            }
            if name == "polygon" {
                b.close();
            }
            b.finish()?
        }
        "line" => {
            // A line has no inside to fill.
            filled.fill = None;
            let mut b = PathBuilder::new();
            b.move_to(at("x1")? as f32, at("y1")? as f32);
            b.line_to(at("x2")? as f32, at("y2")? as f32);
            b.finish()?
        }
        _ => polygon_path(node.attribute("d")?)?,
    };
    Some(Some(painted(path, &filled)))
}

/// The item of `path` painted with `style`.
fn painted(path: Path, style: &Inherited) -> Item {
    Item {
        path,
        fill: style.fill.map(|(c, o)| {
            let mut c = c;
            c.apply_opacity(o);
            c
        }),
        stroke: style
            .stroke
            .filter(|_| style.stroke_width > 0.0)
            .map(|c| Line {
                color: c,
                width: style.stroke_width as f32,
                join: style.join,
                cap: style.cap,
                dash: style.dash.clone(),
            }),
        stroke_first: style.stroke_first,
    }
}

/// A circle as usvg draws one (`ellipse_to_path`): from the rightmost
/// point, four SVG arcs through the bottom, left and top, each turned into
/// cubics by kurbo at usvg's tolerance, in usvg's f32 coordinates.
fn circle(cx: f64, cy: f64, r: f64) -> Option<Path> {
    let (cx, cy, r) = (cx as f32, cy as f32, r as f32);
    let mut b = PathBuilder::new();
    b.move_to(cx + r, cy);
    for to in [(cx, cy + r), (cx - r, cy), (cx, cy - r), (cx + r, cy)] {
        // Each arc starts where the last one's cubics ended, as in usvg.
        let from = b.last_point()?;
        let arc = kurbo::SvgArc {
            from: kurbo::Point::new(f64::from(from.x), f64::from(from.y)),
            to: kurbo::Point::new(f64::from(to.0), f64::from(to.1)),
            radii: kurbo::Vec2::new(f64::from(r), f64::from(r)),
            x_rotation: 0.0,
            large_arc: false,
            sweep: true,
        };
        match kurbo::Arc::from_svg_arc(&arc) {
            Some(arc) => arc.to_cubic_beziers(0.1, |p1, p2, p| {
                b.cubic_to(
                    p1.x as f32,
                    p1.y as f32,
                    p2.x as f32,
                    p2.y as f32,
                    p.x as f32,
                    p.y as f32,
                );
            }),
            None => b.line_to(to.0, to.1),
        }
    }
    b.close();
    b.finish()
}

/// The pairs of a `points` list (numbers separated by commas or white
/// space); `None` for an odd count or a number that does not parse.
fn points(list: &str) -> Option<Vec<(f64, f64)>> {
    let numbers: Vec<f64> = list
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().ok())
        .collect::<Option<_>>()?;
    (numbers.len() % 2 == 0).then(|| numbers.chunks_exact(2).map(|c| (c[0], c[1])).collect())
}

/// A `stroke-dasharray` value: `Some(None)` for a solid line (`none`, or
/// lengths that sum to nothing), the lengths doubled to an even count as
/// SVG says; `None` for a negative or unreadable length.
fn dashes(value: &str) -> Option<Option<Vec<f32>>> {
    if value.trim() == "none" {
        return Some(None);
    }
    let mut lengths: Vec<f32> = value
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().ok().filter(|v: &f32| *v >= 0.0 && v.is_finite()))
        .collect::<Option<_>>()?;
    if lengths.iter().sum::<f32>() <= 0.0 {
        return Some(None);
    }
    if lengths.len() % 2 == 1 {
        lengths.extend_from_within(..);
    }
    Some(Some(lengths))
}

fn number(node: roxmltree::Node, name: &str) -> Option<f64> {
    node.attribute(name)?.trim().parse().ok()
}

/// Appends one line's glyph outlines, placed as usvg places them: shaped as
/// one run, moved left by `anchor` of its advance, baseline at `y`.
fn push_line(
    builder: &mut PathBuilder,
    text: &str,
    x: f64,
    y: f64,
    style: &Inherited,
) -> Option<()> {
    if !plain_content(text) {
        return None;
    }
    let shaped = text::shape(text);
    let s = (style.size / f64::from(text::units_per_em())) as f32;
    let x0 = x as f32 - style.anchor as f32 * shaped.advance * s;
    for g in &shaped.glyphs {
        if let Some(outline) = text::outline(g.id) {
            let ts = Transform::from_row(s, 0.0, 0.0, -s, x0 + g.x * s, y as f32 - g.y * s);
            if let Some(p) = outline.as_ref().clone().transform(ts) {
                builder.push_path(&p);
            }
        }
    }
    Some(())
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
