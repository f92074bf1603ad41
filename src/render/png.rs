//! PNG output: the SVG text painted with tiny-skia and a font built into the
//! program (DejaVu Sans, `super::text`), so labels render the same on
//! machines without fonts. Sees only the SVG text, the single source of truth
//! for every picture: `png_plan` reads it into items painted as resvg paints
//! them (the picture writer's cells, shapes and text: usvg is not involved),
//! `png_bands` paints them in bands and repaints only the bands an edit
//! touched, and anything the items do not draw goes to usvg and resvg.
//! Owns the entry point, the font database for usvg and the encoding.

use std::sync::{Arc, OnceLock};

use rayon::prelude::*;
use resvg::tiny_skia::{self, Transform};
use resvg::usvg;

use super::display::{Cells, Picture};
use super::png_bands::{paint, Drawn};
pub use super::png_bands::{BandCounts, Painted};
use super::png_plan::{plan, plan_drawn, Layer, Plan, View};
use super::text::{FAMILY, FONT};

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
/// The document is read into layers, in paint order (`png_plan`): the
/// elements the items draw (cells, shapes, plain text) and, for anything
/// else, runs of elements usvg parses (up to a few documents, in parallel).
/// The pixels are painted in bands in parallel (`png_bands`).
pub fn png(svg: &str, scale: f64) -> Result<Vec<u8>, PngError> {
    Ok(png_with(svg, None, scale, None)?.0)
}

/// The PNG of a picture from the picture writer: its cells painted from
/// their shapes, the rest of its text read back (`super::display`); the
/// bytes of [`png()`] of its text.
pub fn picture_png(picture: &Picture, scale: f64) -> Result<Vec<u8>, PngError> {
    Ok(png_with(&picture.text, picture.cells.as_ref(), scale, None)?.0)
}

/// [`png()`] of `svg` (whose cells' group, when `cells` is given, is drawn
/// from its shapes) repainting, over `last` (the picture painted before at
/// the same scale), only the bands whose items changed; returns the bytes,
/// the picture to keep for the next repaint, and how many bands were
/// painted.
pub(crate) fn png_with(
    svg: &str,
    cells: Option<&Cells>,
    scale: f64,
    last: Option<Painted>,
) -> Result<(Vec<u8>, Option<Painted>, BandCounts), PngError> {
    let digest = xxhash_rust::xxh3::xxh3_128(svg.as_bytes());
    if let Some(p) = last
        .as_ref()
        .filter(|p| p.svg == digest && p.scale() == scale)
    {
        let (bytes, counts) = (p.bytes.clone(), p.unchanged());
        return Ok((bytes, last, counts));
    }
    // Should the rest of the text not read (it always does for the picture
    // writer's), the whole text is read as for any SVG.
    let planned = cells
        .and_then(|cells| plan_drawn(svg, cells))
        .or_else(|| plan(svg));
    let plan = planned.unwrap_or_else(|| Plan {
        layers: vec![Layer::Svg(svg.to_owned())],
        view: None,
    });
    let layers = plan
        .layers
        .par_iter()
        .map(|layer| match layer {
            Layer::Svg(part) => usvg::Tree::from_str(part, options()).map(|tree| {
                Drawn::Tree(Box::new(tree), xxhash_rust::xxh3::xxh3_128(part.as_bytes()))
            }),
            Layer::Items(items) => Ok(Drawn::Items(items)),
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PngError::Svg(e.to_string()))?;
    let tree_size = layers.iter().find_map(|l| match l {
        Drawn::Tree(tree, _) => Some(tree.size()),
        Drawn::Items(_) => None,
    });
    let size = match (&plan.view, tree_size) {
        (_, Some(size)) => (f64::from(size.width()), f64::from(size.height())),
        (Some(view), None) => (view.width, view.height),
        (None, None) => return Err(PngError::Svg("no SVG document".to_string())),
    };
    let (width, height) = (size.0 * scale, size.1 * scale);
    let too_big = PngError::Size { width, height };
    if !(width >= 1.0 && height >= 1.0 && width * height <= 2.5e8) {
        return Err(too_big);
    }
    let (w, h) = (width.round() as u32, height.round() as u32);
    let user = plan
        .view
        .as_ref()
        .map_or(Transform::identity(), View::transform);
    let (mut painted, counts) = paint(&layers, (w, h), scale, user, last).ok_or(too_big)?;
    let bytes = encode(painted.pixmap())?;
    painted.svg = digest;
    painted.bytes = bytes.clone();
    Ok((bytes, painted.worth_keeping(), counts))
}

/// A straight channel `c` of a pixel of alpha `a` < 255: the one
/// premultiplied value in `0..=a` that [`straight`] turns into it, if any.
fn premultiplied(c: u8, a: u8) -> Option<u8> {
    if a == 0 {
        return (c == 0).then_some(0);
    }
    let guess = (u16::from(c) * u16::from(a) + 127) / 255;
    (guess.saturating_sub(1)..=(guess + 1).min(u16::from(a)))
        .map(|p| p as u8)
        .find(|&p| straight(p, a) == c)
}

/// A premultiplied channel `c` of a pixel of alpha `a` (0 < a < 255) as
/// the PNG holds it: demultiplied, rounded to the nearest.
fn straight(c: u8, a: u8) -> u8 {
    ((u16::from(c) * 255 + u16::from(a) / 2) / u16::from(a)).min(255) as u8
}

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
                *c = straight(*c, a);
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

/// The picture a PNG of ours holds, to repaint over in a later process
/// (a one-shot `build` after an edit, issue 32 item 2): `bytes` decoded,
/// with the scale, SVG digest and band digests it was painted with (kept
/// beside it by the caller). Exact: the encoder writes straight RGBA, and
/// its rounding maps the premultiplied channels `0..=a` of a pixel of
/// alpha `a` to distinct straight values (each step of a premultiplied
/// channel moves the straight one by 255 / a ≥ 1), so each painted pixel
/// is the one premultiplied value that encodes to what the file holds.
/// `None` for a pixel no painted value encodes to (not a PNG of ours),
/// anything but 8-bit RGBA, or a picture too large to keep.
pub fn read_back(bytes: Vec<u8>, scale: f64, svg: u128, bands: Vec<u128>) -> Option<Painted> {
    let limits = ::png::Limits {
        bytes: (4 * super::png_bands::KEEP_PIXELS) as usize,
    };
    let decoder = ::png::Decoder::new_with_limits(std::io::Cursor::new(&bytes), limits);
    let mut reader = decoder.read_info().ok()?;
    let info = reader.info();
    if info.color_type != ::png::ColorType::Rgba || info.bit_depth != ::png::BitDepth::Eight {
        return None;
    }
    let size = tiny_skia::IntSize::from_wh(info.width, info.height)?;
    let mut data = vec![0; reader.output_buffer_size()?];
    let frame = reader.next_frame(&mut data).ok()?;
    data.truncate(frame.buffer_size());
    for px in data.chunks_exact_mut(4) {
        let a = px[3];
        if a == 255 {
            continue;
        }
        for c in &mut px[..3] {
            *c = premultiplied(*c, a)?;
        }
    }
    let pixmap = tiny_skia::Pixmap::from_vec(data, size)?;
    Painted::from_parts(pixmap, scale, svg, bands, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every premultiplied channel of every alpha is read back from its
    /// straight value exactly, and a straight value that no channel encodes
    /// to is refused.
    #[test]
    fn every_painted_channel_is_read_back_from_its_straight_value() {
        let mut refused = 0;
        for a in 1..=254u8 {
            let mut seen = [false; 256];
            for c in 0..=a {
                let s = straight(c, a);
                assert_eq!(premultiplied(s, a), Some(c), "c {c} a {a}");
                seen[usize::from(s)] = true;
            }
            for s in (0..=255u8).filter(|s| !seen[usize::from(*s)]) {
                assert_eq!(premultiplied(s, a), None);
                refused += 1;
            }
        }
        assert!(refused > 0);
        assert_eq!((premultiplied(0, 0), premultiplied(9, 0)), (Some(0), None));
    }

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
                Layer::Items(_) => "items",
            })
            .collect();
        // The translucent group is usvg's (the items draw no group opacity).
        assert_eq!(kinds, ["items", "svg", "items", "items"]);
        let layered = tiny_skia::Pixmap::decode_png(&png(svg, 2.0).expect("layered")).expect("png");
        // The same paths as usvg's, painted in bands: a curve that crosses a
        // band's edge is cut there and its halves flattened apart, which
        // moves the anti-aliasing of a few edge pixels (here the green
        // circle crosses the edge at row 32).
        let share = differing(&layered, &one_pass(svg, 2.0), 2);
        assert!(share < 0.01, "{:.3}% of the pixels differ", 100.0 * share);
        let without_band_edge = svg.replace("cy=\"15\" r=\"9\"", "cy=\"7\" r=\"5\"");
        let layered =
            tiny_skia::Pixmap::decode_png(&png(&without_band_edge, 2.0).expect("layered"))
                .expect("png");
        assert_eq!(
            differing(&layered, &one_pass(&without_band_edge, 2.0), 0),
            0.0
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
        assert!(
            planned.layers.iter().all(|l| matches!(l, Layer::Items(_))),
            "title, names and labels are items"
        );
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
        assert!(planned.layers.iter().all(|l| matches!(l, Layer::Items(_))));
        let cells = svg.find("class=\"np-cells\"").expect("cells");
        let cells_end = cells + svg[cells..].find("\n<g class=").expect("the next group");
        assert_eq!(
            svg[cells..cells_end].matches("<path").count(),
            ds.len() - 1,
            "every cell but the root's"
        );
        // The same document with the cell group given a transform (which
        // the items do not draw) goes to usvg.
        let through_usvg = svg.replace(
            "class=\"np-cells\"",
            "class=\"np-cells\" transform=\"translate(0 0)\"",
        );
        let planned = plan(&through_usvg).expect("parses");
        assert_eq!(
            planned
                .layers
                .iter()
                .filter(|l| matches!(l, Layer::Svg(_)))
                .count(),
            1
        );
        for scale in [1.0, 2.5] {
            assert_eq!(
                png(&svg, scale).expect("straight"),
                png(&through_usvg, scale).expect("usvg"),
                "scale {scale}"
            );
        }
    }

    /// Issue 32, item 2: after a weight edit the repaint paints only the
    /// bands whose items changed, and its bytes are a whole paint's; the
    /// picture is painted without usvg.
    #[test]
    fn a_repaint_after_an_edit_paints_the_changed_bands_and_gives_a_whole_paints_bytes() {
        use crate::layout::warm::layout_warm;
        use crate::layout::{layout, Params, Previous};
        use crate::render::picture::{compose, Style};
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let tree = |factor: f64| {
            let mut builder = DatasetBuilder::new();
            builder.add(NodeSpec::new("root"));
            for g in 0..8 {
                builder.add(NodeSpec::new(format!("g{g}")).parent("root"));
                for k in 0..40 {
                    let mut weight = 1.0 + ((g * 40 + k) * 7919 % 97) as f64;
                    if (g, k) == (3, 7) {
                        weight *= factor;
                    }
                    builder.add(
                        NodeSpec::new(format!("g{g}/{k}"))
                            .parent(format!("g{g}"))
                            .weight(weight),
                    );
                }
            }
            builder.build().expect("valid")
        };
        let (before, after) = (tree(1.0), tree(1.3));
        let params = Params::default();
        let (old, _) = layout(&before, &params).expect("cold");
        let prev = Previous::from_layout(&before, &old);
        let (new, _) = layout_warm(&after, &params, &prev, None).expect("warm");
        let style = Style {
            title: Some("A title".to_string()),
            ..Style::default()
        };
        let first = compose(&before, &old, &[], &[], &style);
        let second = compose(&after, &new, &[], &[], &style);
        assert_ne!(first, second);
        let (bytes, painted, counts) = png_with(&first, None, 1.5, None).expect("whole");
        assert_eq!(counts.documents, 0, "painted without usvg");
        assert_eq!(counts.kept, 0);
        assert_eq!(bytes, png(&first, 1.5).expect("png"));
        let (again, painted, counts) = png_with(&second, None, 1.5, painted).expect("repaint");
        assert_eq!(
            again,
            png(&second, 1.5).expect("whole"),
            "a whole paint's bytes"
        );
        let bands = counts.painted + counts.kept;
        assert!(
            counts.painted >= 2 && 2 * counts.painted < bands,
            "{counts:?}: only one group's cells moved (over more than one band: \
             the repaint's two halves at once)"
        );
        // Nothing changed: nothing painted, the same bytes.
        let (same, _, counts) = png_with(&second, None, 1.5, painted).expect("no change");
        assert_eq!((counts.painted, counts.kept), (0, bands));
        assert_eq!(same, again);
    }

    /// Issue 32, item 1: the cells painted from the picture writer's shapes
    /// are the items its text reads back to, item for item, and the PNG is
    /// that of the text, byte for byte: on a map of three levels with
    /// labels, group names, tabs, a title and a legend (so elements on both
    /// sides of the cells' group), unit and odd scales.
    #[test]
    fn the_cells_from_the_writers_shapes_are_the_cells_its_text_reads_back_to() {
        use crate::layout::{layout, Params};
        use crate::render::display::Picture;
        use crate::render::overlay::Link;
        use crate::render::picture::{compose_noted, Style};
        use crate::render::Parts;
        use nptreemap_formats::{DatasetBuilder, NodeSpec};
        let mut builder = DatasetBuilder::new();
        builder.add(NodeSpec::new("root"));
        for g in 0..5 {
            builder.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for s in 0..4 {
                builder.add(NodeSpec::new(format!("g{g}/{s}")).parent(format!("g{g}")));
                for k in 0..6 {
                    let weight = 1.0 + ((g * 24 + s * 6 + k) * 7919 % 89) as f64;
                    builder.add(
                        NodeSpec::new(format!("g{g}/{s}/{k}"))
                            .parent(format!("g{g}/{s}"))
                            .weight(weight),
                    );
                }
            }
        }
        let ds = builder.build().expect("valid");
        let (laid, _) = layout(&ds, &Params::default()).expect("laid out");
        // Links between neighbouring leaves, for tabs and markers.
        let leaves: Vec<usize> = (0..ds.len()).filter(|&i| ds.is_leaf(i)).collect();
        let links: Vec<Link> = leaves
            .windows(2)
            .map(|w| Link {
                a: w[0],
                b: w[1],
                similarity: 0.8,
                realized: w[0] % 3 != 0,
            })
            .collect();
        let style = Style {
            title: Some("Shapes and text".to_string()),
            ..Style::default()
        };
        let picture = compose_noted(&ds, &laid, &links, &[], &style, None, &Parts::new())
            .with_shapes(&ds, &laid, &style);
        let cells = picture.cells.as_ref().expect("shapes kept");
        assert_eq!(
            cells.shapes.len(),
            ds.len() - 1,
            "every cell but the root's"
        );
        let text = &picture.text;
        assert!(text[cells.range.clone()].starts_with("<g class=\"np-cells\""));
        assert!(cells.range.start > text.find("np-background").expect("background"));
        assert!(cells.range.end < text.find("np-labels").expect("labels"));
        let digests = |plan: &Plan| -> Vec<Vec<u128>> {
            plan.layers
                .iter()
                .map(|layer| match layer {
                    Layer::Items(items) => items
                        .iter()
                        .map(|item| {
                            let mut h = xxhash_rust::xxh3::Xxh3::new();
                            item.digest(&mut h);
                            h.digest128()
                        })
                        .collect(),
                    Layer::Svg(t) => vec![xxhash_rust::xxh3::xxh3_128(t.as_bytes())],
                })
                .collect()
        };
        let read = plan(text).expect("parses");
        let drawn = plan_drawn(text, cells).expect("parses");
        assert!(
            read.layers.len() >= 5,
            "background, title, cells, tabs, labels..."
        );
        assert_eq!(digests(&drawn), digests(&read));
        for scale in [1.0, 1.7] {
            assert_eq!(
                picture_png(&picture, scale).expect("from shapes"),
                png(text, scale).expect("from text"),
                "scale {scale}"
            );
        }
        // A picture known only by its text is read whole, to the same bytes.
        let plain = Picture::from_text(text.clone());
        assert_eq!(
            picture_png(&plain, 1.0).expect("text"),
            png(text, 1.0).expect("text")
        );
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
