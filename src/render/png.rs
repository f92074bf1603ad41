//! PNG output: the SVG text rendered through usvg and resvg with a font built
//! into the program (DejaVu Sans, `fonts/LICENSE-DejaVu.txt`), so labels render
//! the same on machines without fonts. Sees only the SVG text: the SVG is the
//! single source of truth for every picture.

use std::sync::{Arc, OnceLock};

use rayon::prelude::*;
use resvg::{tiny_skia, usvg};

/// The built-in font.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");
/// Its family name, used for every generic family too.
const FAMILY: &str = "DejaVu Sans";

/// Rendering an SVG to PNG failed; with SVG from [`super::svg`] this means a
/// bug, not bad input.
#[derive(Debug, thiserror::Error)]
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
/// Two kinds of parallel work, both invisible in the result: the document is
/// parsed as up to [`LAYERS`] layer documents at once (text shaping in usvg's
/// parse is most of a labelled picture's cost, issue 5's 1 s budget at
/// 10,000 leaves and issue 6's 150 ms at 500), and the pixels are rendered in
/// horizontal strips. Layers are drawn in document order onto the same
/// pixels, exactly as one pass would draw the same elements.
pub fn png(svg: &str, scale: f64) -> Result<Vec<u8>, PngError> {
    let parts = layers(svg).unwrap_or_else(|| vec![svg.to_owned()]);
    let trees = parts
        .par_iter()
        .map(|part| usvg::Tree::from_str(part, options()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PngError::Svg(e.to_string()))?;
    let Some(first) = trees.first() else {
        return Err(PngError::Svg("no SVG document".to_string()));
    };
    let size = first.size();
    let (width, height) = (
        f64::from(size.width()) * scale,
        f64::from(size.height()) * scale,
    );
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
    let (w, h) = (pixmap.width(), pixmap.height());
    // Each strip is the same picture shifted up by a whole number of pixels, so
    // every pixel is sampled exactly as in one pass. The strip count is fixed,
    // not taken from the machine, so the bytes never depend on the core count.
    let rows = h.div_ceil(STRIPS).max(1);
    let strips: Vec<(u32, u32)> = (0..h)
        .step_by(rows as usize)
        .map(|y0| (y0, rows.min(h - y0)))
        .collect();
    let rendered: Vec<Option<tiny_skia::Pixmap>> = strips
        .par_iter()
        .map(|&(y0, rows)| {
            let mut strip = tiny_skia::Pixmap::new(w, rows)?;
            let shift = tiny_skia::Transform::from_row(s, 0.0, 0.0, s, 0.0, -(y0 as f32));
            for tree in &trees {
                resvg::render(tree, shift, &mut strip.as_mut());
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

/// Most layer documents [`png`] parses at once.
const LAYERS: usize = 3;

/// Splits SVG text as [`super::svg`] and [`super::picture`] write it (the
/// root element's start tag on the first line, then top-level elements each
/// starting on a new line) into up to [`LAYERS`] documents with the same root
/// element, each holding a run of consecutive top-level elements, balanced by
/// an estimate of their parsing cost (text elements dominate). `None` when the
/// text does not have that shape; it is then parsed whole.
fn layers(svg: &str) -> Option<Vec<String>> {
    let header_end = svg.find('\n')? + 1;
    let header = &svg[..header_end];
    if !header.starts_with("<svg") {
        return None;
    }
    let close = svg.rfind("</svg>")?;
    let body = svg.get(header_end..close)?;
    // Top-level elements: runs of lines after which no <g> is open. User text
    // is escaped, so "<g" only ever starts a group element.
    let mut chunks: Vec<&str> = Vec::new();
    let (mut depth, mut start, mut at) = (0i64, 0usize, 0usize);
    for line in body.split_inclusive('\n') {
        at += line.len();
        let opens = line.matches("<g ").count() + line.matches("<g>").count();
        depth += opens as i64 - line.matches("</g>").count() as i64;
        if depth < 0 {
            return None;
        }
        if depth == 0 {
            chunks.push(&body[start..at]);
            start = at;
        }
    }
    if depth != 0 || start != body.len() {
        return None;
    }
    // A text element costs about as much to parse as 2 kB of path data.
    let cost = |c: &str| c.len() + 2000 * c.matches("<text").count();
    let total: usize = chunks.iter().map(|c| cost(c)).sum();
    let share = total / LAYERS + 1;
    let mut parts: Vec<String> = Vec::new();
    let (mut part, mut acc) = (String::from(header), 0usize);
    for chunk in chunks {
        part.push_str(chunk);
        acc += cost(chunk);
        if acc >= share && parts.len() + 1 < LAYERS {
            part.push_str("</svg>\n");
            parts.push(std::mem::replace(&mut part, String::from(header)));
            acc = 0;
        }
    }
    if part.len() > header.len() || parts.is_empty() {
        part.push_str("</svg>\n");
        parts.push(part);
    }
    Some(parts)
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

    #[test]
    fn layers_keep_every_element_in_order() {
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" height=\"10\">\n\
                   <rect width=\"10\" height=\"10\" fill=\"#fff\"/>\n\
                   <g stroke=\"#fff\">\n<g><path d=\"M0,0L5,0L5,5Z\"/></g>\n</g>\n\
                   <g class=\"np-labels\">\n<text x=\"1\" y=\"1\">a &lt;g b</text>\n</g>\n\
                   <text x=\"2\" y=\"2\">c</text>\n</svg>\n";
        let parts = layers(svg).expect("our shape");
        assert!(parts.len() > 1 && parts.len() <= LAYERS, "{parts:?}");
        // Taking the root tags off, the parts concatenate to the body.
        let header = svg.lines().next().expect("header");
        let body: String = parts
            .iter()
            .map(|p| {
                p.trim_start_matches(header)
                    .trim_start_matches('\n')
                    .trim_end_matches("</svg>\n")
            })
            .collect();
        assert_eq!(format!("{header}\n{body}</svg>\n"), svg);
        // Not our shape: parsed whole.
        assert_eq!(layers("<svg><g></svg>"), None);
    }

    #[test]
    fn layered_rendering_equals_one_pass() {
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"40\" height=\"30\">\n\
                   <rect width=\"40\" height=\"30\" fill=\"#336699\"/>\n\
                   <text x=\"5\" y=\"25\" font-size=\"9\">Ab</text>\n\
                   <g fill=\"#ff0000\" opacity=\"0.5\">\n<circle cx=\"10\" cy=\"10\" r=\"8\"/>\n</g>\n\
                   <text x=\"15\" y=\"12\" font-size=\"9\">Cd</text>\n\
                   <g fill=\"#00ff00\">\n<circle cx=\"18\" cy=\"15\" r=\"9\"/>\n</g>\n</svg>\n";
        assert!(layers(svg).is_some_and(|p| p.len() > 1));
        let layered = png(svg, 2.0).expect("layered");
        let tree = usvg::Tree::from_str(svg, options()).expect("parse");
        let mut whole = tiny_skia::Pixmap::new(80, 60).expect("pixmap");
        resvg::render(
            &tree,
            tiny_skia::Transform::from_scale(2.0, 2.0),
            &mut whole.as_mut(),
        );
        assert_eq!(layered, encode(&whole).expect("encode"));
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
