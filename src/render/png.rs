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
pub fn png(svg: &str, scale: f64) -> Result<Vec<u8>, PngError> {
    let tree = usvg::Tree::from_str(svg, options()).map_err(|e| PngError::Svg(e.to_string()))?;
    let size = tree.size();
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
    // Rendered as horizontal strips in parallel (resvg itself is one thread):
    // each strip is the same picture shifted up by a whole number of pixels, so
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
            resvg::render(
                &tree,
                tiny_skia::Transform::from_row(s, 0.0, 0.0, s, 0.0, -(y0 as f32)),
                &mut strip.as_mut(),
            );
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

/// Strips rendered in parallel (see [`png`]).
const STRIPS: u32 = 2;

/// PNG bytes of a pixmap: straight (not premultiplied) RGBA, compressed with
/// the png crate's `Fast` level. tiny-skia's own `encode_png` uses the default
/// level, which took half of a 2,000 × 2,000 render (issue 5's 1 s budget);
/// `Fast` is several times quicker for a slightly larger file.
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
    encoder.set_compression(::png::Compression::Fast);
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
