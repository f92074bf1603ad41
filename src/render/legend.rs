//! The legend band under the map: one entry per top-level group (colour swatch
//! and name) and a key for each overlay glyph the picture shows (interlocking
//! tab, unlinked marker). Owns the legend's entries and their row layout; may
//! not decide what is listed (the [`picture`](super::picture) does) or touch the
//! map.

use super::palette::Rgb;
use super::svg::{escape, num, SvgStyle};

/// One legend entry.
#[derive(Clone, Debug, PartialEq)]
pub enum LegendItem {
    /// A top-level group: its fill colour and label.
    Swatch {
        /// The group's colour.
        color: Rgb,
        /// The group's label (any text; escaped).
        label: String,
    },
    /// The interlocking tab drawn on shared edges of constrained neighbours.
    Tab,
    /// The marker counting a cell's constraint partners that are not neighbours.
    Unlinked,
}

/// Legend font size per unit of canvas scale: 14 px on a 1,000 × 1,000 canvas,
/// the size of body text next to the map.
const FONT: f64 = 14.0;
/// Row height in font sizes: the swatch plus air between rows.
const ROW_EM: f64 = 1.7;
/// Space after an entry before the next one, in font sizes.
const GAP_EM: f64 = 1.4;
/// Estimated text advance per character, in font sizes (wide on purpose, as
/// for labels in svg.rs, so entries never overlap).
const CHAR_EM: f64 = 0.6;
/// Longest group name kept whole; longer ones end in an ellipsis so one long
/// name cannot push every other entry out of the row.
const MAX_CHARS: usize = 40;

impl LegendItem {
    fn text(&self) -> String {
        match self {
            LegendItem::Swatch { label, .. } => {
                if label.chars().count() > MAX_CHARS {
                    let cut: String = label.chars().take(MAX_CHARS - 1).collect();
                    format!("{cut}…")
                } else {
                    label.clone()
                }
            }
            LegendItem::Tab => "similar and adjacent (tab on the shared edge)".to_string(),
            LegendItem::Unlinked => "similar cells that are not adjacent (count)".to_string(),
        }
    }
}

/// The legend's SVG elements, placed below a canvas of `width` × `height`, and
/// the band's height (0 and no text when there are no items). `u` is the
/// canvas scale (1 on a 1,000-unit canvas). Entries flow left to right and
/// wrap into rows.
pub fn legend(
    items: &[LegendItem],
    width: f64,
    height: f64,
    u: f64,
    style: &SvgStyle,
) -> (String, f64) {
    if items.is_empty() {
        return (String::new(), 0.0);
    }
    let font = FONT * u;
    let pad = 16.0 * u;
    let row = ROW_EM * font;
    let swatch = 0.9 * font;
    let mut out = format!(
        "<g class=\"np-legend\" font-family=\"{}\" font-size=\"{}\" fill=\"{}\">\n",
        escape(&style.font_family),
        num(font),
        style.text_color
    );
    let (mut x, mut y) = (pad, height + pad);
    for item in items {
        let text = item.text();
        let w = swatch + 0.4 * font + CHAR_EM * font * text.chars().count() as f64;
        if x > pad && x + w > width - pad {
            x = pad;
            y += row;
        }
        // Glyphs sit in a swatch-sized box whose centre is on the text's middle.
        let (gx, gy) = (x, y + 0.5 * (row - swatch));
        out.push_str("<g class=\"np-legend-item\">");
        match item {
            LegendItem::Swatch { color, .. } => out.push_str(&format!(
                "<rect x=\"{}\" y=\"{}\" width=\"{s}\" height=\"{s}\" fill=\"{color}\"/>",
                num(gx),
                num(gy),
                s = num(swatch)
            )),
            LegendItem::Tab => {
                let h = 0.5 * swatch;
                out.push_str(&format!(
                    "<g class=\"np-legend-tab\"><rect x=\"{}\" y=\"{}\" width=\"{h2}\" height=\"{s}\" fill=\"#9c9c9c\"/><rect x=\"{}\" y=\"{}\" width=\"{h2}\" height=\"{s}\" fill=\"#cfcfcf\"/><polyline points=\"{},{} {},{} {},{} {},{} {},{} {},{}\" fill=\"none\" stroke=\"#ffffff\" stroke-width=\"{}\"/></g>",
                    num(gx),
                    num(gy),
                    num(gx + h),
                    num(gy),
                    num(gx + h), num(gy),
                    num(gx + h), num(gy + 0.3 * swatch),
                    num(gx + 0.25 * swatch), num(gy + 0.3 * swatch),
                    num(gx + 0.75 * swatch), num(gy + 0.7 * swatch),
                    num(gx + h), num(gy + 0.7 * swatch),
                    num(gx + h), num(gy + swatch),
                    num(0.08 * swatch),
                    h2 = num(h),
                    s = num(swatch)
                ));
            }
            LegendItem::Unlinked => out.push_str(&format!(
                "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#ffffff\" stroke=\"#d62728\" stroke-width=\"{}\"/>",
                num(gx + 0.5 * swatch),
                num(gy + 0.5 * swatch),
                num(0.45 * swatch),
                num(0.12 * swatch)
            )),
        }
        out.push_str(&format!(
            "<text x=\"{}\" y=\"{}\">{}</text></g>\n",
            num(x + swatch + 0.4 * font),
            num(y + 0.5 * row + 0.35 * font),
            escape(&text)
        ));
        x += w + GAP_EM * font;
    }
    out.push_str("</g>\n");
    (out, y + row + pad - height)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn swatch(label: &str) -> LegendItem {
        LegendItem::Swatch {
            color: Rgb::new(1, 2, 3),
            label: label.to_string(),
        }
    }

    #[test]
    fn nothing_to_list_draws_nothing() {
        assert_eq!(
            legend(&[], 1000.0, 1000.0, 1.0, &SvgStyle::default()),
            (String::new(), 0.0)
        );
    }

    #[test]
    fn entries_wrap_into_rows_inside_the_width() {
        let items: Vec<LegendItem> = (0..12)
            .map(|i| swatch(&format!("Group number {i}")))
            .collect();
        let (one_row, h1) = legend(&items[..1], 1000.0, 500.0, 1.0, &SvgStyle::default());
        let (many, h12) = legend(&items, 1000.0, 500.0, 1.0, &SvgStyle::default());
        assert!(h12 > 2.0 * h1 - 40.0, "several rows: {h1} vs {h12}");
        assert_eq!(many.matches("np-legend-item").count(), 12);
        assert_eq!(one_row.matches("np-legend-item").count(), 1);
        // Every entry starts inside the canvas width and below the map.
        for line in many.lines().filter(|l| l.contains("<rect")) {
            let x: f64 = line
                .split("x=\"")
                .nth(1)
                .and_then(|s| s.split('"').next())
                .and_then(|s| s.parse().ok())
                .expect("x");
            let y: f64 = line
                .split("y=\"")
                .nth(1)
                .and_then(|s| s.split('"').next())
                .and_then(|s| s.parse().ok())
                .expect("y");
            assert!((0.0..1000.0).contains(&x) && y > 500.0, "{x} {y}");
        }
    }

    #[test]
    fn long_names_are_cut_and_text_is_escaped() {
        let long = "x".repeat(100);
        let (text, _) = legend(
            &[swatch(&long), swatch("<i>&")],
            1000.0,
            10.0,
            1.0,
            &SvgStyle::default(),
        );
        assert!(text.contains(&format!("{}…", "x".repeat(MAX_CHARS - 1))));
        assert!(!text.contains(&"x".repeat(MAX_CHARS)));
        assert!(text.contains("&lt;i&gt;&amp;"));
    }
}
