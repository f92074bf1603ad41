//! PNG output: the SVG text rendered through usvg and resvg with a font built
//! into the program (DejaVu Sans, `super::text`), so labels render the same
//! on machines without fonts. Sees only the SVG text: the SVG is the single
//! source of truth for every picture. Groups of plain text (the labels, group
//! names, counts, legend text, title) are drawn from the shared shaping and
//! glyph caches of `super::text`, exactly where usvg would draw them, the
//! map's cells straight from their paths (`super::cell_paint`, issue 32: the
//! same bytes as resvg's, without usvg's tree), and everything else by resvg
//! (issue 13, item 7: usvg's set-up per text element was most of a labelled
//! picture's time).

use std::sync::{Arc, OnceLock};

use rayon::prelude::*;
use resvg::tiny_skia::{self, FillRule, LineJoin, Paint, Path, PathBuilder, Stroke, Transform};
use resvg::usvg::{self, roxmltree};

use super::cell_paint::{cell_group, CellPaint};
use super::text::{self, FAMILY, FONT};

/// Rendering an SVG to PNG failed; with SVG from [`super::svg()`] this means a
/// bug, not bad input.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PngError {
    /// usvg did not accept the SVG text.
    #[error("cannot read the SVG: {0}")]
    Svg(String),
    /// The picture has no pixels or is too large for one pixmap.
    #[error("cannot make a {width} x {height} pixel image")]
    Size {
        /// Requested width in pixels.
        width: f64,
        /// Requested height in pixels.
        height: f64,
    },
    /// PNG encoding failed.
    #[error("cannot encode the PNG: {0}")]
    Encode(String),
}

/// The parsing options with the built-in font, made once per process (loading
/// a font database is the expensive part, as resvg's own CLI notes).
fn options() -> &'static usvg::Options<'static> {
    static OPTIONS: OnceLock<usvg::Options<'static>> = OnceLock::new();
    OPTIONS.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(FONT.to_vec());
        db.set_sans_serif_family(FAMILY);
        db.set_serif_family(FAMILY);
        db.set_monospace_family(FAMILY);
        db.set_cursive_family(FAMILY);
        db.set_fantasy_family(FAMILY);
        usvg::Options {
            font_family: FAMILY.to_string(),
            fontdb: Arc::new(db),
            ..usvg::Options::default()
        }
    })
}

/// Renders SVG text to PNG bytes at `scale` pixels per SVG unit.
///
/// The document is split by its structure into layers, in paint order:
/// runs of top-level elements parsed by usvg (up to `LAYERS` documents, in
/// parallel) and groups of plain text drawn from the glyph cache. The pixels
/// are rendered in horizontal strips in parallel. Layers are drawn in
/// document order onto the same pixels, exactly as one pass would draw the
/// same elements; the strip count is fixed, so the bytes never depend on the
/// machine.
pub fn png(svg: &str, scale: f64) -> Result<Vec<u8>, PngError> {
    let plan = plan(svg).unwrap_or_else(|| Plan {
        layers: vec![Layer::Svg(svg.to_owned())],
        view: None,
    });
    let trees = plan
        .layers
        .par_iter()
        .map(|layer| match layer {
            Layer::Svg(part) => usvg::Tree::from_str(part, options()).map(Drawn::Tree),
            Layer::Text(texts) => Ok(Drawn::Text(texts)),
            Layer::Cells(cells) => Ok(Drawn::Cells(cells)),
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PngError::Svg(e.to_string()))?;
    let size = match (&plan.view, trees.iter().find_map(Drawn::tree)) {
        (_, Some(tree)) => (
            f64::from(tree.size().width()),
            f64::from(tree.size().height()),
        ),
        (Some(view), None) => (view.width, view.height),
        (None, None) => return Err(PngError::Svg("no SVG document".to_string())),
    };
    let (width, height) = (size.0 * scale, size.1 * scale);
    let too_big = !(width >= 1.0 && height >= 1.0 && width * height <= 2.5e8);
    let pixmap = if too_big {
        None
    } else {
        tiny_skia::Pixmap::new(width.round() as u32, height.round() as u32)
    };
    let Some(mut pixmap) = pixmap else {
        return Err(PngError::Size { width, height });
    };
    let s = scale as f32;
    let user = plan
        .view
        .as_ref()
        .map_or(Transform::identity(), View::transform);
    let (w, h) = (pixmap.width(), pixmap.height());
    // Each strip is the same picture shifted up by a whole number of pixels, so
    // every pixel is sampled exactly as in one pass.
    let rows = h.div_ceil(STRIPS).max(1);
    let strips: Vec<(u32, u32)> = (0..h)
        .step_by(rows as usize)
        .map(|y0| (y0, rows.min(h - y0)))
        .collect();
    let rendered: Vec<Option<tiny_skia::Pixmap>> = strips
        .par_iter()
        .map(|&(y0, rows)| {
            let mut strip = tiny_skia::Pixmap::new(w, rows)?;
            let shift = Transform::from_row(s, 0.0, 0.0, s, 0.0, -(y0 as f32));
            for drawn in &trees {
                match drawn {
                    Drawn::Tree(tree) => resvg::render(tree, shift, &mut strip.as_mut()),
                    Drawn::Text(texts) => {
                        let ts = shift.pre_concat(user);
                        for t in texts.iter() {
                            t.draw(&mut strip, ts);
                        }
                    }
                    Drawn::Cells(cells) => {
                        let ts = shift.pre_concat(user);
                        for c in cells.iter() {
                            c.draw(&mut strip, ts);
                        }
                    }
                }
            }
            Some(strip)
        })
        .collect();
    let data = pixmap.data_mut();
    let mut at = 0;
    for strip in rendered {
        let strip = strip.ok_or(PngError::Size { width, height })?;
        data[at..at + strip.data().len()].copy_from_slice(strip.data());
        at += strip.data().len();
    }
    encode(&pixmap)
}

/// Most usvg documents [`png`] parses at once: runs of shapes between text
/// layers are merged until there are at most this many.
const LAYERS: usize = 3;

/// What [`png`] draws, in paint order.
struct Plan {
    layers: Vec<Layer>,
    /// The root element's size and view box (for the text layers).
    view: Option<View>,
}

enum Layer {
    /// A document usvg parses: the root element with a run of its children.
    Svg(String),
    /// Plain text drawn from the glyph cache.
    Text(Vec<TextPaint>),
    /// The map's cells painted straight from their paths (`cell_paint`).
    Cells(Vec<CellPaint>),
}

// A parsed tree is large, but only a handful of these live at once (one per
// layer), so boxing would buy nothing.
#[allow(clippy::large_enum_variant)]
enum Drawn<'a> {
    Tree(usvg::Tree),
    Text(&'a [TextPaint]),
    Cells(&'a [CellPaint]),
}

impl Drawn<'_> {
    fn tree(&self) -> Option<&usvg::Tree> {
        match self {
            Drawn::Tree(t) => Some(t),
            Drawn::Text(_) | Drawn::Cells(_) => None,
        }
    }
}

/// The root element's `width`, `height` and `viewBox`.
struct View {
    width: f64,
    height: f64,
    view_box: [f64; 4],
}

impl View {
    /// User units to the image's units (`preserveAspectRatio` xMidYMid meet,
    /// the default).
    fn transform(&self) -> Transform {
        let [x, y, w, h] = self.view_box;
        let s = (self.width / w).min(self.height / h);
        let tx = 0.5 * (self.width - w * s) - x * s;
        let ty = 0.5 * (self.height - h * s) - y * s;
        Transform::from_row(s as f32, 0.0, 0.0, s as f32, tx as f32, ty as f32)
    }
}

/// One text element ready to paint: its glyph outlines in user units.
struct TextPaint {
    path: Path,
    fill: Option<tiny_skia::Color>,
    stroke: Option<(tiny_skia::Color, f32, LineJoin)>,
    stroke_first: bool,
}

impl TextPaint {
    fn draw(&self, pixmap: &mut tiny_skia::Pixmap, ts: Transform) {
        let paint = |c: tiny_skia::Color| {
            let mut p = Paint::default();
            p.set_color(c);
            p.anti_alias = true;
            p
        };
        let fill = |pixmap: &mut tiny_skia::Pixmap| {
            if let Some(c) = self.fill {
                pixmap.fill_path(&self.path, &paint(c), FillRule::Winding, ts, None);
            }
        };
        let stroke = |pixmap: &mut tiny_skia::Pixmap| {
            if let Some((c, width, join)) = self.stroke {
                let st = Stroke {
                    width,
                    line_join: join,
                    ..Stroke::default()
                };
                pixmap.stroke_path(&self.path, &paint(c), &st, ts, None);
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
}

/// Splits SVG text into layers by its XML structure (the parsed document's
/// element ranges), never by text lines: a title or label may hold a line
/// break (issue 11, item 7). A top-level element made only of plain text
/// becomes a text layer; runs of the others become documents with the same
/// root element, merged to at most [`LAYERS`] and balanced by size. `None`
/// when the text does not parse; it is then parsed whole, and usvg reports
/// the error.
fn plan(svg: &str) -> Option<Plan> {
    let doc = roxmltree::Document::parse(svg).ok()?;
    let root = doc.root_element();
    let elements: Vec<roxmltree::Node> = root.children().filter(|n| n.is_element()).collect();
    let first = elements.first()?.range().start;
    let last = elements.last()?.range().end;
    let header = &svg[..first];
    let footer = &svg[last..];
    let view = view_of(root);
    // Runs of elements: Err(a layer we paint) or Ok(source range).
    let mut runs: Vec<Result<std::ops::Range<usize>, Layer>> = Vec::new();
    for (k, el) in elements.iter().enumerate() {
        let end = elements.get(k + 1).map_or(last, |n| n.range().start);
        let painted = view.as_ref().and_then(|_| {
            cell_group(*el, color)
                .map(Layer::Cells)
                .or_else(|| plain_text(*el).map(Layer::Text))
        });
        match (painted, runs.last_mut()) {
            (Some(layer), _) => runs.push(Err(layer)),
            (None, Some(Ok(r))) => r.end = end,
            (None, _) => runs.push(Ok(el.range().start..end)),
        }
    }
    // Merge the shortest gaps between shape runs while there are too many:
    // a text layer between two merged runs moves into the document instead.
    let shape_runs =
        |runs: &[Result<std::ops::Range<usize>, Layer>]| runs.iter().filter(|r| r.is_ok()).count();
    while shape_runs(&runs) > LAYERS {
        // Fold the smallest text layer that separates two shape runs back
        // into them (as SVG, which usvg then shapes itself).
        let candidate = (1..runs.len().saturating_sub(1))
            .filter(|&i| {
                matches!(runs[i], Err(Layer::Text(_))) && runs[i - 1].is_ok() && runs[i + 1].is_ok()
            })
            .min_by_key(|&i| match &runs[i] {
                Err(Layer::Text(t)) => t.len(),
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
            Ok(range) => Layer::Svg(format!("{header}{}{footer}", &svg[range])),
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
            stroke_first: false,
        }
    }
}

/// Attributes a plain text element or group may carry: presentation the
/// drawing below reproduces, and attributes without effect on pixels.
const PLAIN: [&str; 17] = [
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
];

fn color(value: &str) -> Option<Option<tiny_skia::Color>> {
    if value == "none" {
        return Some(None);
    }
    let rgb: super::palette::Rgb = value.parse().ok()?;
    Some(Some(tiny_skia::Color::from_rgba8(rgb.r, rgb.g, rgb.b, 255)))
}

/// Applies `node`'s own presentation attributes to `base`; `None` when one is
/// outside what the text layer draws.
fn inherit(node: roxmltree::Node, base: &Inherited) -> Option<Inherited> {
    let mut out = base.clone();
    for a in node.attributes() {
        let (name, v) = (a.name(), a.value());
        if a.namespace().is_some() || !PLAIN.contains(&name) {
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

/// The text paints of `el` when it holds nothing but plain text: `<text>`
/// elements (content, or `<tspan x y>` lines) in groups, all with attributes
/// the text layer draws; `None` otherwise.
fn plain_text(el: roxmltree::Node) -> Option<Vec<TextPaint>> {
    let mut out = Vec::new();
    collect_text(el, &Inherited::default(), &mut out)?;
    (!out.is_empty()).then_some(out)
}

fn collect_text(node: roxmltree::Node, base: &Inherited, out: &mut Vec<TextPaint>) -> Option<()> {
    match node.tag_name().name() {
        "g" => {
            if node.attribute("transform").is_some() {
                return None;
            }
            let style = inherit(node, base)?;
            for child in node.children() {
                if child.is_element() {
                    collect_text(child, &style, out)?;
                } else if child.is_text() && !child.text()?.trim().is_empty() {
                    return None;
                }
            }
            Some(())
        }
        "title" => Some(()),
        "text" => {
            let style = inherit(node, base)?;
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
                    let own = inherit(span, &style)?;
                    let (x, y) = (number(span, "x")?, number(span, "y")?);
                    push_line(&mut builder, span.text()?, x, y, &own)?;
                }
            }
            let Some(path) = builder.finish() else {
                return Some(());
            };
            let path = path.transform(turn)?;
            out.push(TextPaint {
                path,
                fill: style.fill.map(|(c, o)| {
                    let mut c = c;
                    c.apply_opacity(o);
                    c
                }),
                stroke: style
                    .stroke
                    .filter(|_| style.stroke_width > 0.0)
                    .map(|c| (c, style.stroke_width as f32, style.join)),
                stroke_first: style.stroke_first,
            });
            Some(())
        }
        _ => None,
    }
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

/// Strips rendered in parallel (see [`png`]).
const STRIPS: u32 = 2;

/// PNG bytes of a pixmap: straight (not premultiplied) RGBA, compressed with
/// the png crate's `Fastest` level (fdeflate). tiny-skia's own `encode_png`
/// uses the default level, which took half of a 2,000 × 2,000 render (issue
/// 5's 1 s budget) and a third of a 500-leaf rebuild (issue 6's 150 ms);
/// `Fastest` is ~20× quicker for files about 30% larger, and the daemon
/// rewrites these files on every edit.
fn encode(pixmap: &tiny_skia::Pixmap) -> Result<Vec<u8>, PngError> {
    let mut rgba = pixmap.data().to_vec();
    for px in rgba.chunks_exact_mut(4) {
        let a = px[3];
        if a != 255 && a != 0 {
            for c in &mut px[..3] {
                *c = ((u16::from(*c) * 255 + u16::from(a) / 2) / u16::from(a)).min(255) as u8;
            }
        }
    }
    let mut out = Vec::new();
    let mut encoder = ::png::Encoder::new(&mut out, pixmap.width(), pixmap.height());
    encoder.set_color(::png::ColorType::Rgba);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_compression(::png::Compression::Fastest);
    let mut writer = encoder
        .write_header()
        .map_err(|e| PngError::Encode(e.to_string()))?;
    writer
        .write_image_data(&rgba)
        .map_err(|e| PngError::Encode(e.to_string()))?;
    writer
        .finish()
        .map_err(|e| PngError::Encode(e.to_string()))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One pass of resvg over the whole document, for comparison.
    fn one_pass(svg: &str, scale: f32) -> tiny_skia::Pixmap {
        let tree = usvg::Tree::from_str(svg, options()).expect("parse");
        let size = tree.size().to_int_size().scale_by(scale).expect("size");
        let mut whole = tiny_skia::Pixmap::new(size.width(), size.height()).expect("pixmap");
        resvg::render(
            &tree,
            Transform::from_scale(scale, scale),
            &mut whole.as_mut(),
        );
        whole
    }

    #[test]
    fn shape_layers_keep_every_element_in_order() {
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"40\" height=\"30\" viewBox=\"0 0 40 30\">\n\
                   <rect width=\"40\" height=\"30\" fill=\"#336699\"/>\n\
                   <g fill=\"#ff0000\" opacity=\"0.5\">\n<circle cx=\"10\" cy=\"10\" r=\"8\"/>\n</g>\n\
                   <text x=\"15\" y=\"12\" font-size=\"9\">Cd</text>\n\
                   <g fill=\"#00ff00\">\n<circle cx=\"18\" cy=\"15\" r=\"9\"/>\n</g>\n</svg>\n";
        let planned = plan(svg).expect("parses");
        let kinds: Vec<&str> = planned
            .layers
            .iter()
            .map(|l| match l {
                Layer::Svg(_) => "svg",
                Layer::Text(_) => "text",
                Layer::Cells(_) => "cells",
            })
            .collect();
        assert_eq!(kinds, ["svg", "text", "svg"]);
        assert_eq!(
            png(svg, 2.0).expect("layered"),
            encode(&one_pass(svg, 2.0)).expect("encode")
        );
        // Not XML: parsed whole (and usvg reports the error).
        assert!(plan("<svg><g></svg>").is_none());
        assert!(png("<svg><g></svg>", 1.0).is_err());
    }

    /// Share of pixels whose channels differ by more than `tolerance`.
    fn differing(a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap, tolerance: u8) -> f64 {
        assert_eq!((a.width(), a.height()), (b.width(), b.height()));
        let n = a
            .pixels()
            .iter()
            .zip(b.pixels())
            .filter(|(p, q)| {
                let (p, q) = (p.demultiply(), q.demultiply());
                [
                    p.red().abs_diff(q.red()),
                    p.green().abs_diff(q.green()),
                    p.blue().abs_diff(q.blue()),
                    p.alpha().abs_diff(q.alpha()),
                ]
                .iter()
                .any(|d| *d > tolerance)
            })
            .count();
        n as f64 / a.pixels().len() as f64
    }

    #[test]
    fn the_text_layer_draws_what_usvg_draws() {
        // Labels with halos, two-line labels, a turned translucent group
        // name, a title above a shifted view box, kerning and accents.
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"300\" height=\"220\" viewBox=\"0 -20 300 220\">\n\
                   <rect y=\"-20\" width=\"300\" height=\"220\" fill=\"#4e79a7\"/>\n\
                   <text x=\"10\" y=\"-4\" font-family=\"Helvetica, sans-serif\" font-size=\"14\" font-weight=\"bold\" fill=\"#1a1a1a\">Title AVA Ωé</text>\n\
                   <g class=\"np-group-labels\" text-anchor=\"middle\" fill=\"#1a1a1a\" fill-opacity=\"0.40\" pointer-events=\"none\">\n\
                   <text x=\"150\" y=\"120\" font-size=\"40\" transform=\"rotate(-30 150 108)\">Europe</text>\n</g>\n\
                   <g class=\"np-labels\" text-anchor=\"middle\" fill=\"#1a1a1a\" stroke=\"#ffffff\" stroke-linejoin=\"round\" paint-order=\"stroke\" pointer-events=\"none\">\n\
                   <text x=\"60\" y=\"40\" font-size=\"12\" stroke-width=\"2.40\">Wavy Törtchen</text>\n\
                   <text font-size=\"16\" stroke-width=\"3.20\"><tspan x=\"200\" y=\"150\">Democratic</tspan><tspan x=\"200\" y=\"168\" font-size=\"13.6\" stroke-width=\"2.72\">1,234 KiB</tspan></text>\n\
                   </g>\n</svg>\n";
        let planned = plan(svg).expect("parses");
        let texts = planned
            .layers
            .iter()
            .filter(|l| matches!(l, Layer::Text(_)))
            .count();
        assert_eq!(texts, 3, "title, names and labels go to the text layer");
        let fast = tiny_skia::Pixmap::decode_png(&png(svg, 2.0).expect("renders")).expect("png");
        let slow = one_pass(svg, 2.0);
        let share = differing(&fast, &slow, 8);
        let worst = fast
            .pixels()
            .iter()
            .zip(slow.pixels())
            .map(|(p, q)| p.demultiply().red().abs_diff(q.demultiply().red()))
            .max()
            .unwrap_or(0);
        // Anti-aliasing differs at glyph edges (usvg sums advances in its own
        // order, a few hundredths of a unit apart); a label moved by half a
        // pixel changes about twice as many pixels.
        let moved = svg.replace("x=\"60\" y=\"40\"", "x=\"60.25\" y=\"40\"");
        let control = differing(&one_pass(&moved, 2.0), &slow, 8);
        assert!(
            share < 0.005 && 1.5 * share < control,
            "{:.3}% of the pixels differ, by up to {worst} (a moved label: {:.3}%)",
            100.0 * share,
            100.0 * control
        );
    }

    /// Issue 32, item 1: the cells painted straight from their paths are
    /// the cells usvg and resvg paint, byte for byte, on a map of 300
    /// cells in 12 groups (fills, outlines of every level, round joins).
    #[test]
    fn the_cells_painted_straight_are_the_cells_usvg_paints() {
        use crate::layout::{layout, Params};
        use crate::render::picture::{compose, Style};
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("root"));
        for g in 0..12 {
            builder.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for k in 0..25 {
                let weight = 1.0 + ((g * 25 + k) * 7919 % 97) as f64;
                builder.add(
                    NodeSpec::new(format!("g{g}/{k}"))
                        .parent(format!("g{g}"))
                        .weight(weight),
                );
            }
        }
        let ds = builder.build().expect("valid");
        let (laid, _) = layout(&ds, &Params::default()).expect("laid out");
        let svg = compose(&ds, &laid, &[], &[], &Style::default());
        let planned = plan(&svg).expect("parses");
        let painted: usize = planned
            .layers
            .iter()
            .map(|l| match l {
                Layer::Cells(c) => c.len(),
                _ => 0,
            })
            .sum();
        assert_eq!(painted, ds.len() - 1, "every cell but the root's");
        // The same document with the group renamed goes to usvg.
        let through_usvg = svg.replace("class=\"np-cells\"", "class=\"np-cells-usvg\"");
        let planned = plan(&through_usvg).expect("parses");
        assert!(!planned.layers.iter().any(|l| matches!(l, Layer::Cells(_))));
        for scale in [1.0, 2.5] {
            assert_eq!(
                png(&svg, scale).expect("straight"),
                png(&through_usvg, scale).expect("usvg"),
                "scale {scale}"
            );
        }
    }

    /// Issue 11, item 7: a line break inside a title or a label once cut the
    /// SVG inside a `<text>` element ("expected 'text' tag") and failed the
    /// whole build.
    #[test]
    fn line_breaks_in_text_do_not_break_the_split() {
        use crate::render::picture::{compose, Style};
        use crate::render::test_support::sample;
        let (ds, layout) = sample();
        let style = Style {
            title: Some("line one\nline two\n<g>\n</g>".to_string()),
            ..Style::default()
        };
        let picture = compose(&ds, &layout, &[], &[], &style);
        png(&picture, 1.0).expect("the picture renders");
        // Text broken over lines, wherever it comes from, with tags inside it.
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"60\" height=\"40\" viewBox=\"0 0 60 40\">\n\
                   <rect width=\"60\" height=\"40\" fill=\"#fff\"/>\n\
                   <text x=\"5\" y=\"20\" font-size=\"9\">line one\nline &lt;g&gt;\n</text>\n\
                   <g>\n<text x=\"5\" y=\"30\" font-size=\"9\">a\n<tspan>b</tspan>\n</text>\n</g>\n\
                   <circle cx=\"30\" cy=\"20\" r=\"9\"/>\n</svg>\n";
        let planned = plan(svg).expect("the SVG parses");
        for layer in &planned.layers {
            if let Layer::Svg(part) = layer {
                usvg::Tree::from_str(part, options()).expect("every layer parses");
            }
        }
        let bytes = png(svg, 1.0).expect("the PNG renders");
        let drawn = tiny_skia::Pixmap::decode_png(&bytes).expect("png");
        // Strips meet at a row where anti-aliasing may round differently.
        let share = differing(&drawn, &one_pass(svg, 1.0), 2);
        assert!(
            share < 0.002,
            "{} layers; {:.3}% of the pixels differ from one pass",
            planned.layers.len(),
            100.0 * share
        );
    }

    #[test]
    fn renders_text_with_the_built_in_font() {
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="120" height="40" viewBox="0 0 120 40"><rect width="120" height="40" fill="#ffffff"/><text x="10" y="28" font-family="sans-serif" font-size="24" fill="#000000">Hello</text></svg>"##;
        let bytes = png(svg, 1.0).expect("renders");
        assert_eq!(&bytes[1..4], b"PNG");
        let image = tiny_skia::Pixmap::decode_png(&bytes).expect("decodes");
        assert_eq!((image.width(), image.height()), (120, 40));
        let dark = image.pixels().iter().filter(|p| p.red() < 128).count();
        assert!(dark > 50, "the label left only {dark} dark pixels");
        assert_eq!(bytes, png(svg, 1.0).expect("again"), "PNG is deterministic");
    }

    /// The font database holds the built-in face and nothing else: labels
    /// cannot depend on the machine's fonts (issue 5). resvg is built without
    /// `system-fonts`, so fontdb could not even look for them.
    #[test]
    fn only_the_built_in_font_is_loaded() {
        let db = &options().fontdb;
        assert_eq!(db.len(), 1, "exactly one face");
        let face = db.faces().next().expect("one face");
        assert!(face.families.iter().any(|(name, _)| name == FAMILY));
        assert_eq!(db.family_name(&usvg::fontdb::Family::SansSerif), FAMILY);
    }

    #[test]
    fn scale_multiplies_the_pixel_size() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="50" height="20"/>"#;
        let image = tiny_skia::Pixmap::decode_png(&png(svg, 2.0).expect("renders")).expect("png");
        assert_eq!((image.width(), image.height()), (100, 40));
        assert!(png(svg, 0.0).is_err());
    }
}
