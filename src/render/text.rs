//! The built-in font (DejaVu Sans, `fonts/LICENSE-DejaVu.txt`) as the pictures
//! use it: its bytes, its vertical metrics, text shaped exactly as usvg shapes
//! it (harfrust, kerning on, one left-to-right run) and glyph outlines, both
//! cached for the life of the process. Label placement measures with it, so a
//! label's box is the box usvg lays out; the PNG draws simple labels from it
//! without usvg's per-element shaping set-up (issue 13, item 7). Owns text
//! metrics and glyph geometry only; may not know about nodes or SVG.
//!
//! Written by hand over harfrust and skrifa (the crates usvg itself shapes and
//! outlines with) because usvg builds a new shaper for every text element and
//! offers no way to share one; that set-up was most of a labelled PNG's cost.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

#[cfg(feature = "png")]
use resvg::tiny_skia::{Path, PathBuilder};

/// The built-in font.
pub(crate) const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");
/// Its family name, used for every generic family too.
// The SVG names the family; only the PNG needs the constant.
#[cfg_attr(not(feature = "png"), allow(dead_code))]
pub(crate) const FAMILY: &str = "DejaVu Sans";

/// One glyph of shaped text, in font units from the start of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Glyph {
    /// Glyph id in the font; 0 is `.notdef` (a character the font lacks).
    pub id: u32,
    /// Pen position plus the glyph's own offset, font units.
    pub x: f32,
    /// Vertical offset, font units, up.
    pub y: f32,
}

/// A shaped run of text.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Shaped {
    /// The glyphs in visual order.
    pub glyphs: Vec<Glyph>,
    /// Total advance, font units.
    pub advance: f32,
}

struct Font {
    shaper_font: harfrust::FontRef<'static>,
    shaper_data: harfrust::ShaperData,
    #[cfg_attr(not(feature = "png"), allow(dead_code))]
    outline_font: skrifa::FontRef<'static>,
    units_per_em: f32,
    ascent: f32,
    descent: f32,
    shaped: Mutex<HashMap<String, Arc<Shaped>>>,
    #[cfg(feature = "png")]
    outlines: Mutex<HashMap<u32, Option<Arc<Path>>>>,
}

/// Entries kept in the shaping cache before it starts afresh (a daemon
/// renders for days; labels repeat across rebuilds).
const SHAPED_CACHE: usize = 50_000;

fn font() -> &'static Font {
    static FONT_DATA: OnceLock<Font> = OnceLock::new();
    FONT_DATA.get_or_init(|| {
        let shaper_font = harfrust::FontRef::new(FONT).expect("the built-in font parses");
        let shaper_data = harfrust::ShaperData::new(&shaper_font);
        let outline_font = skrifa::FontRef::new(FONT).expect("the built-in font parses");
        use skrifa::MetadataProvider;
        let metrics = outline_font.metrics(
            skrifa::instance::Size::unscaled(),
            skrifa::instance::LocationRef::default(),
        );
        Font {
            shaper_font,
            shaper_data,
            units_per_em: f32::from(metrics.units_per_em),
            ascent: metrics.ascent,
            descent: metrics.descent,
            outline_font,
            shaped: Mutex::new(HashMap::new()),
            #[cfg(feature = "png")]
            outlines: Mutex::new(HashMap::new()),
        }
    })
}

/// Font units per em.
pub(crate) fn units_per_em() -> f32 {
    font().units_per_em
}

/// Height above the baseline of the box usvg gives a line of text, in ems.
pub fn ascent_em() -> f64 {
    f64::from(font().ascent / font().units_per_em)
}

/// Depth below the baseline of that box, in ems (positive).
pub(crate) fn descent_em() -> f64 {
    f64::from(-font().descent / font().units_per_em)
}

/// `text` shaped as one left-to-right run with the font's default features
/// (kerning, ligatures), as usvg shapes a text chunk of that content.
pub(crate) fn shape(text: &str) -> Arc<Shaped> {
    let f = font();
    if let Some(hit) = f.shaped.lock().ok().and_then(|c| c.get(text).cloned()) {
        return hit;
    }
    let shaper = f.shaper_data.shaper(&f.shaper_font).build();
    let mut buffer = harfrust::UnicodeBuffer::new();
    buffer.push_str(text);
    buffer.set_direction(harfrust::Direction::LeftToRight);
    buffer.guess_segment_properties();
    let output = shaper.shape(buffer, harfrust::ShapeOptions::new());
    let mut pen = 0i64;
    let glyphs = output
        .glyph_infos()
        .iter()
        .zip(output.glyph_positions())
        .map(|(info, pos)| {
            let g = Glyph {
                id: info.glyph_id,
                x: (pen + i64::from(pos.x_offset)) as f32,
                y: pos.y_offset as f32,
            };
            pen += i64::from(pos.x_advance);
            g
        })
        .collect();
    let shaped = Arc::new(Shaped {
        glyphs,
        advance: pen as f32,
    });
    if let Ok(mut cache) = f.shaped.lock() {
        if cache.len() >= SHAPED_CACHE {
            cache.clear();
        }
        cache.insert(text.to_owned(), Arc::clone(&shaped));
    }
    shaped
}

/// The advance width of `text` in ems.
pub fn width_em(text: &str) -> f64 {
    f64::from(shape(text).advance / units_per_em())
}

/// Whether every character of `text` has a glyph in the font.
#[cfg_attr(not(feature = "png"), allow(dead_code))]
pub(crate) fn covers(text: &str) -> bool {
    shape(text).glyphs.iter().all(|g| g.id != 0)
}

/// The outline of glyph `id` in font units, y up (`None` for blank glyphs
/// such as the space). Only the PNG draws outlines.
#[cfg(feature = "png")]
pub(crate) fn outline(id: u32) -> Option<Arc<Path>> {
    let f = font();
    if let Some(hit) = f.outlines.lock().ok().and_then(|c| c.get(&id).cloned()) {
        return hit;
    }
    use skrifa::MetadataProvider;
    let path = f
        .outline_font
        .outline_glyphs()
        .get(skrifa::GlyphId::new(id))
        .and_then(|glyph| {
            let mut pen = Pen(PathBuilder::new());
            let settings = skrifa::outline::DrawSettings::unhinted(
                skrifa::instance::Size::unscaled(),
                skrifa::instance::LocationRef::default(),
            );
            glyph.draw(settings, &mut pen).ok()?;
            pen.0.finish()
        })
        .map(Arc::new);
    if let Ok(mut cache) = f.outlines.lock() {
        cache.insert(id, path.clone());
    }
    path
}

/// Collects skrifa's outline commands into a tiny-skia path, as usvg does.
#[cfg(feature = "png")]
struct Pen(PathBuilder);

#[cfg(feature = "png")]
impl skrifa::outline::OutlinePen for Pen {
    fn move_to(&mut self, x: f32, y: f32) {
        self.0.move_to(x, y);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        self.0.line_to(x, y);
    }
    fn quad_to(&mut self, cx0: f32, cy0: f32, x: f32, y: f32) {
        self.0.quad_to(cx0, cy0, x, y);
    }
    fn curve_to(&mut self, cx0: f32, cy0: f32, cx1: f32, cy1: f32, x: f32, y: f32) {
        self.0.cubic_to(cx0, cy0, cx1, cy1, x, y);
    }
    fn close(&mut self) {
        self.0.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_are_dejavu_sans() {
        assert_eq!(units_per_em(), 2048.0);
        assert!(
            (ascent_em() - 1901.0 / 2048.0).abs() < 1e-6,
            "{}",
            ascent_em()
        );
        assert!(
            (descent_em() - 483.0 / 2048.0).abs() < 1e-6,
            "{}",
            descent_em()
        );
    }

    #[test]
    fn shaping_kerns_and_caches() {
        // DejaVu Sans kerns "AV": the pair is narrower than its letters apart.
        assert!(width_em("AV") < width_em("A") + width_em("V"));
        assert_eq!(shape("Flare"), shape("Flare"));
        assert!(covers("Ωmega ½ €") && !covers("日本"));
        #[cfg(feature = "png")]
        {
            assert!(outline(shape("A").glyphs[0].id).is_some());
            assert!(outline(shape(" ").glyphs[0].id).is_none());
        }
    }
}
