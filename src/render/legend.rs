//! The legend band under the map: a key for each overlay glyph the picture
//! shows (interlocking tab, unlinked marker) and one entry per top-level group
//! (colour swatch and name), wrapped to the width and cut after a few rows
//! with a count of the groups left out (the names are on the map too). Owns
//! the legend's entries and their row layout; may not decide what is listed
//! (the `picture` does) or touch the map.

use super::palette::Rgb;
use super::svg::{escape, num, SvgStyle};
use super::text::width_em;

/// One legend entry.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum LegendItem {
    /// A top-level group: its fill colour and label.
    Swatch {
        /// The group's colour.
        color: Rgb,
        /// The group's label (any text; escaped).
        label: String,
        /// The group's node id, when the swatch stands for one (the page's
        /// legend hover-highlights and zooms to it).
        group: Option<String>,
    },
    /// The interlocking tab drawn on shared edges of constrained neighbours.
    Tab,
    /// The marker counting a cell's constraint partners that are not neighbours.
    Unlinked,
    /// How many entries did not fit.
    More(usize),
    /// A sentence about the picture as a whole, without a glyph (what it
    /// leaves out: "12 items of weight 0 not drawn").
    Note(String),
    /// Colours by a field's value: the field's name, the lowest and highest
    /// values as the picture writes numbers, the colours between them.
    Scale {
        /// The field (column) name.
        field: String,
        /// The lowest value, formatted.
        low: String,
        /// The highest value, formatted.
        high: String,
        /// Colours from low to high, evenly spaced.
        stops: Vec<Rgb>,
    },
}

/// Width of a scale's colour bar, in font sizes.
const BAR_EM: f64 = 8.0;

/// Legend font size per unit of canvas scale: 14 px on a 1,000 × 1,000 canvas,
/// the size of body text next to the map.
const FONT: f64 = 14.0;
/// Row height in font sizes: the swatch plus air between rows.
const ROW_EM: f64 = 1.7;
/// Space after an entry before the next one, in font sizes.
const GAP_EM: f64 = 1.4;
/// Most rows of entries: a band of at most about an eighth of a square map.
const MAX_ROWS: usize = 5;
/// Longest group name kept whole; longer ones end in an ellipsis so one long
/// name cannot push every other entry out of the row.
const MAX_CHARS: usize = 40;

impl LegendItem {
    pub(crate) fn text(&self) -> String {
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
            LegendItem::More(n) => format!("and {n} more group{}", if *n == 1 { "" } else { "s" }),
            LegendItem::Note(text) => text.clone(),
            LegendItem::Scale {
                field, low, high, ..
            } => format!("{field}: {low} to {high}"),
        }
    }
}

/// The legend's SVG elements, placed below a canvas of `width` × `height`, and
/// the band's height (0 and no text when there are no items). `u` is the
/// canvas scale (1 on a 1,000-unit canvas). Entries flow left to right and
/// wrap into rows; past `MAX_ROWS` rows the entries left are counted in a
/// last one.
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
    let entry_width = |item: &LegendItem| {
        if let LegendItem::Scale {
            field, low, high, ..
        } = item
        {
            return font * (width_em(&format!("{field}: {low}")) + BAR_EM + 0.8)
                + font * width_em(high);
        }
        let glyph = if matches!(item, LegendItem::More(_) | LegendItem::Note(_)) {
            0.0
        } else {
            swatch + 0.4 * font
        };
        glyph + font * width_em(&item.text())
    };
    // Flow every entry into rows: (row, x) per entry.
    let flow = |items: &[LegendItem]| -> Vec<(usize, f64)> {
        let (mut x, mut r) = (pad, 0usize);
        items
            .iter()
            .map(|item| {
                let w = entry_width(item);
                if x > pad && x + w > width - pad {
                    x = pad;
                    r += 1;
                }
                let at = (r, x);
                x += w + GAP_EM * font;
                at
            })
            .collect()
    };
    let mut shown: Vec<LegendItem> = items.to_vec();
    let mut places = flow(&shown);
    if places.last().is_some_and(|(r, _)| *r >= MAX_ROWS) {
        // Keep what fits in MAX_ROWS rows with the count after it.
        let mut keep = places.iter().filter(|(r, _)| *r < MAX_ROWS).count();
        loop {
            let mut trial: Vec<LegendItem> = items[..keep].to_vec();
            trial.push(LegendItem::More(items.len() - keep));
            let p = flow(&trial);
            if p.last().is_some_and(|(r, _)| *r < MAX_ROWS) || keep == 0 {
                shown = trial;
                places = p;
                break;
            }
            keep -= 1;
        }
    }
    let top = height + pad;
    // Glyphs and texts in two groups (entries never overlap, so the order is
    // free): the PNG draws a group of plain text from its glyph cache.
    let mut texts = format!(
        "<g class=\"np-legend-labels\" font-family=\"{}\" font-size=\"{}\" fill=\"{}\">\n",
        escape(&style.font_family),
        num(font),
        style.text_color
    );
    for (item, (r, x)) in shown.iter().zip(&places) {
        push_entry(
            &mut out,
            &mut texts,
            item,
            *x,
            top + *r as f64 * row,
            row,
            swatch,
            font,
        );
    }
    let rows = places.last().map_or(1, |(r, _)| r + 1);
    out.push_str("</g>\n");
    texts.push_str("</g>\n");
    out.push_str(&texts);
    (out, rows as f64 * row + 2.0 * pad)
}

/// One entry at `(x, y)`: its glyph in a swatch-sized box centred on the
/// text's middle, then its text.
#[allow(clippy::too_many_arguments)]
fn push_entry(
    out: &mut String,
    texts: &mut String,
    item: &LegendItem,
    x: f64,
    y: f64,
    row: f64,
    swatch: f64,
    font: f64,
) {
    let (gx, gy) = (x, y + 0.5 * (row - swatch));
    let baseline = y + 0.5 * row + 0.35 * font;
    if let LegendItem::Scale {
        field,
        low,
        high,
        stops,
    } = item
    {
        // "field: low", the bar (one rect per stop: plain shapes every
        // renderer draws alike), "high".
        let head = format!("{field}: {low}");
        let bx = x + font * (width_em(&head) + 0.4);
        let bw = BAR_EM * font;
        let step = bw / stops.len().max(1) as f64;
        out.push_str("<g class=\"np-legend-item np-legend-scale\">");
        for (k, color) in stops.iter().enumerate() {
            // Each rect overlaps the next by a hair, so no seam shows.
            out.push_str(&format!(
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{color}\"/>",
                num(bx + step * k as f64),
                num(gy),
                num(step + if k + 1 < stops.len() { 0.3 } else { 0.0 }),
                num(swatch)
            ));
        }
        out.push_str("</g>\n");
        texts.push_str(&format!(
            "<text x=\"{}\" y=\"{}\">{}</text>\n<text x=\"{}\" y=\"{}\">{}</text>\n",
            num(x),
            num(baseline),
            escape(&head),
            num(bx + bw + 0.4 * font),
            num(baseline),
            escape(high)
        ));
        return;
    }
    out.push_str("<g class=\"np-legend-item\">");
    match item {
        LegendItem::Swatch { color, .. } => out.push_str(&format!(
            "<rect x=\"{}\" y=\"{}\" width=\"{s}\" height=\"{s}\" fill=\"{color}\"/>",
            num(gx),
            num(gy),
            s = num(swatch)
        )),
        LegendItem::Tab => out.push_str(&tab_glyph(gx, gy, swatch)),
        LegendItem::Unlinked => out.push_str(&format!(
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#ffffff\" stroke=\"#d62728\" stroke-width=\"{}\"/>",
            num(gx + 0.5 * swatch),
            num(gy + 0.5 * swatch),
            num(0.45 * swatch),
            num(0.12 * swatch)
        )),
        LegendItem::More(_) | LegendItem::Note(_) | LegendItem::Scale { .. } => {}
    }
    out.push_str("</g>\n");
    let tx = if matches!(item, LegendItem::More(_) | LegendItem::Note(_)) {
        x
    } else {
        x + swatch + 0.4 * font
    };
    texts.push_str(&format!(
        "<text x=\"{}\" y=\"{}\">{}</text>\n",
        num(tx),
        num(y + 0.5 * row + 0.35 * font),
        escape(&item.text())
    ));
}

/// The tab's glyph in a swatch at `(gx, gy)`: two cells side by side, the
/// left one's dovetail in the right one, as on the map.
fn tab_glyph(gx: f64, gy: f64, swatch: f64) -> String {
    let h = 0.5 * swatch;
    let (b, hd, d) = (0.16 * swatch, 0.24 * swatch, 0.26 * swatch);
    let mid = gy + h;
    format!(
        "<g class=\"np-legend-tab\"><rect x=\"{}\" y=\"{}\" width=\"{h2}\" height=\"{s}\" fill=\"#9c9c9c\"/><rect x=\"{}\" y=\"{}\" width=\"{h2}\" height=\"{s}\" fill=\"#cfcfcf\"/><polygon points=\"{},{} {},{} {},{} {},{}\" fill=\"#9c9c9c\" stroke=\"#ffffff\" stroke-width=\"{}\" stroke-linejoin=\"round\"/></g>",
        num(gx),
        num(gy),
        num(gx + h),
        num(gy),
        num(gx + h - 0.02 * swatch),
        num(mid - b),
        num(gx + h + d),
        num(mid - hd),
        num(gx + h + d),
        num(mid + hd),
        num(gx + h - 0.02 * swatch),
        num(mid + b),
        num(0.06 * swatch),
        h2 = num(h),
        s = num(swatch)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn swatch(label: &str) -> LegendItem {
        LegendItem::Swatch {
            color: Rgb::new(1, 2, 3),
            label: label.to_string(),
            group: None,
        }
    }

    #[test]
    fn a_scale_draws_its_bar_between_its_low_and_high_values() {
        let item = LegendItem::Scale {
            field: "size <b>".into(),
            low: "1".into(),
            high: "9,000".into(),
            stops: vec![Rgb::new(0, 0, 0), Rgb::new(255, 255, 255)],
        };
        let (text, h) = legend(&[item], 1000.0, 500.0, 1.0, &SvgStyle::default());
        assert!(h > 0.0);
        assert!(text.contains(">size &lt;b&gt;: 1</text>"), "{text}");
        assert!(text.contains(">9,000</text>"), "{text}");
        assert!(text.contains("fill=\"#000000\"") && text.contains("fill=\"#ffffff\""));
        assert_eq!(text.matches("np-legend-scale").count(), 1);
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

    #[test]
    fn many_groups_stop_after_the_last_row_with_a_count() {
        let items: Vec<LegendItem> = (0..200).map(|i| swatch(&format!("group {i}"))).collect();
        let (text, h) = legend(&items, 1000.0, 1000.0, 1.0, &SvgStyle::default());
        assert!(h < 0.16 * 1000.0, "band {h}");
        let shown = text.matches("<rect").count();
        assert!(shown > 20 && shown < 200, "{shown}");
        assert!(
            text.contains(&format!("and {} more groups", 200 - shown)),
            "{text}"
        );
    }
}
