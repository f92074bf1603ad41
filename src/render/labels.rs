//! Labels on the map: the text of each leaf fitted into its cell (one line,
//! two lines at a word break, or cut with an ellipsis, never below the
//! minimum size, optionally with a second line for the value) and the names
//! of the top-level groups (and second-level ones where they fit) drawn large
//! and light across their cells, so the hierarchy reads without the legend
//! (issue 13, item 4). Boxes are measured with the built-in font
//! (`super::text`), the metrics usvg lays the text out with. Owns text
//! choice and placement; may not draw overlays or decide colours.

use nptreemap_formats::Dataset;

use super::label_text::{display_name, DisplayNames, LabelText};
use super::text::{ascent_em, descent_em, width_em};
use crate::geom::{cross, ConvexPolygon, Point};
use crate::layout::Layout;

/// How labels are chosen and sized: the config's `render.labels`, read
/// straight into this (a boolean turns leaf labels and group names on or
/// off together, see `crate::config`).
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct LabelStyle {
    /// Leaf labels at all. Default: true.
    pub show: bool,
    /// Smallest font size at scale 1 (a 1,000 × 1,000 canvas; canvas units
    /// scale with it). Labels that cannot reach it wrap, are cut, or are
    /// left out. Default: 9.
    pub min_size: f64,
    /// Largest leaf label font size at scale 1. Default: 24.
    pub max_size: f64,
    /// A second line with the node's value. Default: false.
    pub value: bool,
    /// Text after the value (`" KiB"`, `" %"`). Default: empty.
    pub unit: String,
    /// Group names drawn on the map. Default: true.
    pub groups: bool,
    /// Display names for ids or labels such as continent codes
    /// (`AS: Asia`); used on the map, in the legend and in the page's
    /// tooltips, and ordering the legend with `legend_order: names`.
    pub names: DisplayNames,
    /// What the labels say (`render.labels.text`): by default a path-like
    /// label without its group's name in front. `auto`, `label`, `id`,
    /// `segment`, `relative` or a template over columns (`"{name} {version}"`),
    /// refused at its line when unknown or malformed.
    #[serde(deserialize_with = "label_text")]
    pub text: LabelText,
}

fn label_text<'de, D: serde::Deserializer<'de>>(d: D) -> Result<LabelText, D::Error> {
    let text = <String as serde::Deserialize>::deserialize(d)?;
    LabelText::parse(&text).map_err(|e| serde::de::Error::custom(format_args!("labels.text: {e}")))
}

impl Default for LabelStyle {
    fn default() -> Self {
        Self {
            show: true,
            min_size: 9.0,
            max_size: 24.0,
            value: false,
            unit: String::new(),
            groups: true,
            names: DisplayNames::default(),
            text: LabelText::default(),
        }
    }
}

/// An axis-aligned box, canvas units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Left.
    pub x0: f64,
    /// Top.
    pub y0: f64,
    /// Right.
    pub x1: f64,
    /// Bottom.
    pub y1: f64,
}

impl Rect {
    /// Whether the two boxes overlap with positive area.
    pub fn overlaps(&self, other: &Rect) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }

    /// The box grown by `m` on every side.
    pub fn grown(&self, m: f64) -> Rect {
        Rect {
            x0: self.x0 - m,
            y0: self.y0 - m,
            x1: self.x1 + m,
            y1: self.y1 + m,
        }
    }

    /// Its four corners.
    pub fn corners(&self) -> [Point; 4] {
        [
            Point::new(self.x0, self.y0),
            Point::new(self.x1, self.y0),
            Point::new(self.x1, self.y1),
            Point::new(self.x0, self.y1),
        ]
    }
}

/// One line of a placed label.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// The text (already cleaned).
    pub text: String,
    /// Centre of the line, canvas units.
    pub x: f64,
    /// Its baseline.
    pub baseline: f64,
    /// Font size.
    pub size: f64,
}

/// A label placed in its cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Placed {
    /// The node labelled.
    pub node: usize,
    /// Its lines, top to bottom.
    pub lines: Vec<Line>,
    /// The box its text occupies (usvg's line boxes, united), canvas units.
    pub rect: Rect,
    /// Rotation about the box centre, degrees (group names only; 0 for leaves).
    pub angle: f64,
}

/// Free space left and right of a label, in font sizes.
const SIDE_PAD_EM: f64 = 0.3;
/// Free space above and below, in font sizes.
const END_PAD_EM: f64 = 0.08;
/// Lines of one label are this far apart, baseline to baseline, in font sizes:
/// the font's line box, so the boxes of two lines just touch.
pub fn line_step_em() -> f64 {
    ascent_em() + descent_em()
}
/// The value line's size relative to the label's.
const VALUE_SCALE: f64 = 0.85;
/// A wrapped label must be this much larger than the one-line one to be
/// preferred (two lines read slower than one).
const WRAP_GAIN: f64 = 1.25;
/// Fewest characters kept before an ellipsis: a stub such as `gcl…` names
/// nothing, so a label keeps four or more, or is left out (issue 24 item 8).
const MIN_KEPT: usize = 4;

/// A text block to fit: lines (text, relative size) and their extents in ems
/// of the first line's size.
struct Block {
    lines: Vec<(String, f64)>,
    width: f64,
    height: f64,
}

impl Block {
    fn new(lines: Vec<(String, f64)>) -> Block {
        let width = lines
            .iter()
            .map(|(t, k)| k * width_em(t))
            .fold(0.0, f64::max);
        let height = lines.iter().map(|(_, k)| k * line_step_em()).sum();
        Block {
            lines,
            width,
            height,
        }
    }
}

/// The largest scale `s` at which a box of half extents `half * s` centred at
/// `center` lies in `polygon` (convex, containing `center`). Each corner moves
/// along a ray from `center`; where it leaves the polygon is a closed-form
/// minimum over the edges.
pub(crate) fn fit_scale(polygon: &ConvexPolygon, center: Point, half: Point) -> f64 {
    let corners = [
        Point::new(half.x, half.y),
        Point::new(-half.x, half.y),
        Point::new(half.x, -half.y),
        Point::new(-half.x, -half.y),
    ];
    let pts = polygon.points();
    let mut best = f64::INFINITY;
    for (k, &a) in pts.iter().enumerate() {
        let e = pts[(k + 1) % pts.len()] - a;
        // Positive orientation: the inside is where cross(e, p - a) >= 0.
        let slack = cross(e, center - a);
        if slack < 0.0 {
            return 0.0;
        }
        for u in corners {
            let towards = cross(e, u);
            if towards < 0.0 {
                best = best.min(slack / -towards);
            }
        }
    }
    if best.is_finite() {
        best.max(0.0)
    } else {
        0.0
    }
}

/// The anchor and scale at which a box of half extents `half` (per unit of
/// scale) fits `polygon` best: a compass search from the centroid, which for
/// the convex cells here finds the optimum to a hundredth of the cell's size.
/// At most [`COMPASS_ROUNDS`] rounds, then the best found so far.
fn best_fit(polygon: &ConvexPolygon, half: Point) -> (Point, f64) {
    let mut at = polygon.centroid();
    let mut best = fit_scale(polygon, at, half);
    let (lo, hi) = polygon.bbox();
    let mut step = 0.25 * (hi.x - lo.x).min(hi.y - lo.y);
    let floor = 0.01 * (hi.x - lo.x).min(hi.y - lo.y);
    for _ in 0..COMPASS_ROUNDS {
        if step.is_nan() || step <= floor {
            break;
        }
        let mut moved = false;
        for d in [
            Point::new(step, 0.0),
            Point::new(-step, 0.0),
            Point::new(0.0, step),
            Point::new(0.0, -step),
        ] {
            let p = at + d;
            let s = fit_scale(polygon, p, half);
            if s > best * (1.0 + 1e-9) {
                at = p;
                best = s;
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    (at, best)
}

/// Most rounds of [`best_fit`]'s compass search. The step halves from a
/// quarter to a hundredth of the cell's smaller extent (five halvings), and
/// at each step the anchor can move at most about a cell's width, four steps
/// of a quarter, 100 of a hundredth, before leaving the cell (where the fit
/// is 0): some 200 rounds in all. A move needs a strictly better fit, so the
/// search cannot cycle, but a fit that creeps up by rounding could keep it
/// moving; past this many rounds the best anchor so far is kept.
const COMPASS_ROUNDS: usize = 400;

/// Fits `block` into `polygon` with padding; returns the anchor and font size.
fn fit_block(polygon: &ConvexPolygon, block: &Block) -> (Point, f64) {
    let half = Point::new(
        0.5 * block.width + SIDE_PAD_EM,
        0.5 * block.height + END_PAD_EM,
    );
    best_fit(polygon, half)
}

/// Lays `block` out at `size` centred on `at`.
fn lay_out(node: usize, block: &Block, at: Point, size: f64) -> Placed {
    let mut y = at.y - 0.5 * block.height * size;
    let mut lines = Vec::with_capacity(block.lines.len());
    for (text, k) in &block.lines {
        let s = size * k;
        lines.push(Line {
            text: text.clone(),
            x: at.x,
            baseline: y + ascent_em() * s,
            size: s,
        });
        y += line_step_em() * s;
    }
    let (hw, hh) = (0.5 * block.width * size, 0.5 * block.height * size);
    Placed {
        node,
        lines,
        rect: Rect {
            x0: at.x - hw,
            y0: at.y - hh,
            x1: at.x + hw,
            y1: at.y + hh,
        },
        angle: 0.0,
    }
}

/// The two halves of `text` split at the word break nearest its middle (a
/// space, or after `-`, `_`, `/`, `.`), if it has one.
fn wrap(text: &str) -> Option<(String, String)> {
    let chars: Vec<char> = text.chars().collect();
    let mid = chars.len() as f64 / 2.0;
    let mut best: Option<(f64, usize, bool)> = None;
    for (k, c) in chars.iter().enumerate().skip(1) {
        let (cut, space) = match c {
            ' ' => (k, true),
            '-' | '_' | '/' | '.' if k + 1 < chars.len() => (k + 1, false),
            _ => continue,
        };
        let d = (cut as f64 - mid).abs();
        if best.is_none_or(|(b, _, _)| d < b) {
            best = Some((d, cut, space));
        }
    }
    let (_, cut, space) = best?;
    let first: String = chars[..cut].iter().collect();
    let second: String = chars[cut + usize::from(space)..].iter().collect();
    let (first, second) = (first.trim().to_owned(), second.trim().to_owned());
    (!first.is_empty() && !second.is_empty()).then_some((first, second))
}

/// Beyond this magnitude a value is written in scientific notation: its
/// digits past the 15th are noise of the binary fraction, and 1e300 written
/// out would be 301 digits wide.
const SCIENTIFIC_ABOVE: f64 = 1e15;
/// Below this magnitude (other than zero) too: two decimals would round it
/// to 0.
const SCIENTIFIC_BELOW: f64 = 0.005;

/// `value` with thousands separators (at most two decimals, trailing zeros
/// dropped) and the unit; a magnitude of at least 10^15, or a non-zero one
/// under 0.005, in scientific notation with three significant digits
/// (`1.23e308`, `4e-7`).
pub fn format_value(value: f64, unit: &str) -> String {
    let magnitude = value.abs();
    if magnitude >= SCIENTIFIC_ABOVE || (magnitude > 0.0 && magnitude < SCIENTIFIC_BELOW) {
        return format!("{}{unit}", scientific(value));
    }
    let rounded = (value * 100.0).round() / 100.0;
    let negative = rounded < 0.0;
    let whole = rounded.abs().trunc();
    let frac = ((rounded.abs() - whole) * 100.0).round() as u64;
    let digits = format!("{whole:.0}");
    let mut out = String::new();
    for (k, d) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(d);
    }
    if frac > 0 {
        let f = format!("{frac:02}");
        out.push('.');
        out.push_str(f.trim_end_matches('0'));
    }
    if negative && out.chars().any(|c| c != '0' && c != ',' && c != '.') {
        out.insert(0, '-');
    }
    out.push_str(unit);
    out
}

/// `value` (finite) as `d.dde±x` with trailing zeros of the mantissa
/// dropped.
fn scientific(value: f64) -> String {
    let text = format!("{value:.2e}");
    match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exponent}")
        }
        None => text,
    }
}

/// The label of leaf `node` in `polygon`, at font sizes within
/// `[min, max]` (canvas units): the whole text on one line if it fits, on two
/// lines if that is clearly larger, else cut with an ellipsis; `None` when not
/// even four characters and the ellipsis fit.
pub fn place_leaf(
    node: usize,
    text: &str,
    value: Option<&str>,
    polygon: &ConvexPolygon,
    min: f64,
    max: f64,
) -> Option<Placed> {
    if text.is_empty() {
        return None;
    }
    let with_value = |lines: Vec<(String, f64)>| {
        let mut lines = lines;
        if let Some(v) = value {
            lines.push((v.to_owned(), VALUE_SCALE));
        }
        Block::new(lines)
    };
    // The value line is smaller; the label's own size must keep it legible.
    let min_first = if value.is_some() {
        min / VALUE_SCALE
    } else {
        min
    };
    let one = with_value(vec![(text.to_owned(), 1.0)]);
    let (at1, s1) = fit_block(polygon, &one);
    let mut choice = (s1 >= min_first).then_some((one, at1, s1));
    if choice.as_ref().is_none_or(|(_, _, s)| *s < max) {
        if let Some((a, b)) = wrap(text) {
            let two = with_value(vec![(a, 1.0), (b, 1.0)]);
            let (at2, s2) = fit_block(polygon, &two);
            let better = match &choice {
                None => s2 >= min_first,
                Some((_, _, s)) => s2 >= WRAP_GAIN * s.min(max) && s2 >= min_first,
            };
            if better {
                choice = Some((two, at2, s2));
            }
        }
    }
    if choice.is_none() {
        // The longest prefix (at least MIN_KEPT characters) that fits with "…".
        let chars: Vec<char> = text.chars().collect();
        let (mut lo, mut hi) = (MIN_KEPT, chars.len().saturating_sub(1));
        let mut found = None;
        while lo <= hi {
            let k = (lo + hi) / 2;
            let cut: String = chars[..k].iter().collect::<String>().trim_end().to_owned() + "…";
            let block = with_value(vec![(cut, 1.0)]);
            let (at, s) = fit_block(polygon, &block);
            if s >= min_first {
                found = Some((block, at, s));
                lo = k + 1;
            } else if k == 0 {
                break;
            } else {
                hi = k - 1;
            }
        }
        choice = found;
    }
    let (block, at, s) = choice?;
    Some(lay_out(node, &block, at, s.min(max)))
}

/// A label shrunk about its centre by `factor` (to step clear of something).
pub fn shrink(placed: &Placed, factor: f64) -> Placed {
    let cx = 0.5 * (placed.rect.x0 + placed.rect.x1);
    let cy = 0.5 * (placed.rect.y0 + placed.rect.y1);
    let scale = |v: f64, c: f64| c + (v - c) * factor;
    Placed {
        node: placed.node,
        lines: placed
            .lines
            .iter()
            .map(|l| Line {
                text: l.text.clone(),
                x: scale(l.x, cx),
                baseline: scale(l.baseline, cy),
                size: l.size * factor,
            })
            .collect(),
        rect: Rect {
            x0: scale(placed.rect.x0, cx),
            y0: scale(placed.rect.y0, cy),
            x1: scale(placed.rect.x1, cx),
            y1: scale(placed.rect.y1, cy),
        },
        angle: placed.angle,
    }
}

/// Largest group name size at scale 1: a heading, not a poster.
const GROUP_MAX: f64 = 64.0;
/// Smallest group name size at scale 1: below this a name is left to the legend.
const GROUP_MIN: f64 = 13.0;
/// Second-level names are at most this share of the top-level maximum.
const SUBGROUP_SHARE: f64 = 0.5;
/// A group name fills at most this share of the largest box its cell holds.
const GROUP_FILL: f64 = 0.8;
/// Rotate a name along its cell only when that makes it this much larger.
const ROTATE_GAIN: f64 = 1.3;

/// A group name's fit in `polygon`, level or turned along the cell's long
/// axis, at most `max` (canvas units): the text, its anchor, size and angle.
fn fit_group(polygon: &ConvexPolygon, text: &str, max: f64) -> Option<(Point, f64, f64)> {
    let block = Block::new(vec![(text.to_owned(), 1.0)]);
    let half = Point::new(0.5 * block.width + 0.1, 0.5 * block.height);
    let (at, s) = best_fit(polygon, half);
    let mut best = (at, s, 0.0);
    let angle = long_axis(polygon);
    if angle.abs() > 12.0 {
        // Fit in the frame turned by -angle, then turn the anchor back.
        let c = polygon.centroid();
        let (sin, cos) = (-angle).to_radians().sin_cos();
        let turn = |p: Point, sin: f64, cos: f64| {
            let d = p - c;
            c + Point::new(d.x * cos - d.y * sin, d.x * sin + d.y * cos)
        };
        let turned: Vec<Point> = polygon
            .points()
            .iter()
            .map(|p| turn(*p, sin, cos))
            .collect();
        if let Some(poly) = ConvexPolygon::from_convex(turned) {
            let (at_r, s_r) = best_fit(&poly, half);
            if s_r > ROTATE_GAIN * s {
                best = (turn(at_r, -sin, cos), s_r, angle);
            }
        }
    }
    let size = (best.1 * GROUP_FILL).min(max);
    Some((best.0, size, best.2))
}

/// The direction of a convex polygon's long axis, degrees in `(-90, 90]`
/// (0 = level), from the second moments of its vertices.
fn long_axis(polygon: &ConvexPolygon) -> f64 {
    let c = polygon.centroid();
    let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
    for p in polygon.points() {
        let d = *p - c;
        xx += d.x * d.x;
        yy += d.y * d.y;
        xy += d.x * d.y;
    }
    let elongation = {
        let tr = xx + yy;
        let det = xx * yy - xy * xy;
        let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
        let (l1, l2) = (0.5 * tr + disc, 0.5 * tr - disc);
        if l2 > 0.0 {
            l1 / l2
        } else {
            f64::INFINITY
        }
    };
    if elongation < 2.5 {
        return 0.0;
    }
    let mut a = 0.5 * (2.0 * xy).atan2(xx - yy).to_degrees();
    if a <= -90.0 {
        a += 180.0;
    }
    if a > 90.0 {
        a -= 180.0;
    }
    // Steeper than 60°: read bottom to top rather than top to bottom.
    if a > 60.0 {
        a -= 180.0;
        if a <= -90.0 {
            a += 180.0;
        }
    }
    a
}

/// The corners of a placed (possibly turned) label's box.
pub fn outline(p: &Placed) -> [Point; 4] {
    let c = Point::new(0.5 * (p.rect.x0 + p.rect.x1), 0.5 * (p.rect.y0 + p.rect.y1));
    let (sin, cos) = p.angle.to_radians().sin_cos();
    p.rect.corners().map(|q| {
        let d = q - c;
        c + Point::new(d.x * cos - d.y * sin, d.x * sin + d.y * cos)
    })
}

/// The bounding box of a quadrilateral (lowest and highest corner).
fn quad_box(q: &[Point; 4]) -> (Point, Point) {
    let lo = q.iter().fold(q[0], |m, p| m.min(*p));
    let hi = q.iter().fold(q[0], |m, p| m.max(*p));
    (lo, hi)
}

/// Whether two convex quadrilaterals overlap (separating axes).
pub fn quads_overlap(a: &[Point; 4], b: &[Point; 4]) -> bool {
    for poly in [a, b] {
        for k in 0..4 {
            let e = poly[(k + 1) % 4] - poly[k];
            let n = Point::new(-e.y, e.x);
            let project = |q: &[Point; 4]| {
                q.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                        let v = n.dot(*p);
                        (lo.min(v), hi.max(v))
                    })
            };
            let (a0, a1) = project(a);
            let (b0, b1) = project(b);
            if a1 <= b0 || b1 <= a0 {
                return false;
            }
        }
    }
    true
}

/// The group names drawn on the map: the top-level groups with children of
/// their own (virtual copies and the leaves heading a chain of them aside:
/// those are leaves, labelled as such), then the second-level groups, each
/// whose name fits at `GROUP_MIN` or more without overlapping another name
/// or any leaf label (`leaves`). `u` is the canvas scale (1 at
/// 1,000 × 1,000).
pub fn place_groups(
    dataset: &Dataset,
    layout: &Layout,
    style: &LabelStyle,
    leaves: &[Placed],
    u: f64,
) -> Vec<Placed> {
    let root = dataset.root();
    let mut out: Vec<Placed> = Vec::new();
    let named = |i: usize| {
        let n = dataset.node(i);
        !n.is_virtual
            && !n.children.is_empty()
            && i < layout.cells.len()
            && super::chains::drawn_leaf(dataset, i).is_none()
    };
    let leaf_quads: Vec<[Point; 4]> = leaves.iter().map(|l| l.rect.corners()).collect();
    // A name over a leaf's label makes both hard to read (a faint "South
    // America" across "Brazil"): the best fit is kept when it is clear of
    // every label and every name placed before it, else the largest clear
    // level spot in the cell, else the name is left to the legend.
    let place = |i: usize, max: f64, out: &mut Vec<Placed>| {
        let text = display_name(dataset, i, &style.names, &style.text);
        if text.is_empty() {
            return;
        }
        let polygon = &layout.cells[i].polygon;
        let Some((at, size, angle)) = fit_group(polygon, &text, max) else {
            return;
        };
        let min = GROUP_MIN * u;
        if size < min {
            return;
        }
        let block = Block::new(vec![(text.clone(), 1.0)]);
        // Each with its box: a quad clear of the box is clear of the quad
        // (the separating axes find the gap the boxes show), and the boxes
        // reject most of a map's labels in four comparisons.
        let avoid: Vec<([Point; 4], (Point, Point))> = leaf_quads
            .iter()
            .copied()
            .chain(out.iter().map(outline))
            .map(|q| (q, quad_box(&q)))
            .collect();
        // A margin around the name (a share of its line height), so a name
        // just above a label does not read as that label's first line.
        let clear = |p: &Placed| {
            let pad = NAME_MARGIN * (p.rect.y1 - p.rect.y0);
            let mut padded = p.clone();
            padded.rect = Rect {
                x0: p.rect.x0 - pad,
                y0: p.rect.y0 - pad,
                x1: p.rect.x1 + pad,
                y1: p.rect.y1 + pad,
            };
            let quad = outline(&padded);
            let (lo, hi) = quad_box(&quad);
            !avoid.iter().any(|(a, (alo, ahi))| {
                let apart = ahi.x < lo.x || hi.x < alo.x || ahi.y < lo.y || hi.y < alo.y;
                !apart && quads_overlap(a, &quad)
            })
        };
        let mut placed = lay_out(i, &block, at, size);
        placed.angle = angle;
        if !clear(&placed) {
            let Some((at, size)) = clear_spot(polygon, &block, i, max, min, &clear) else {
                return;
            };
            placed = lay_out(i, &block, at, size);
        }
        out.push(placed);
    };
    let top: Vec<usize> = dataset
        .node(root)
        .children
        .iter()
        .copied()
        .filter(|&c| named(c))
        .collect();
    if top.len() < 2 && top.iter().all(|&t| dataset.node(t).children.len() < 2) {
        return out;
    }
    for &g in &top {
        place(g, GROUP_MAX * u, &mut out);
    }
    for &g in &top {
        for &c in &dataset.node(g).children {
            if named(c) {
                place(c, SUBGROUP_SHARE * GROUP_MAX * u, &mut out);
            }
        }
    }
    out
}

/// Free space kept around a group name, as a share of its line height.
const NAME_MARGIN: f64 = 0.35;

/// Anchors tried per side of a cell's bounding box when a group name's best
/// fit covers a label.
const CLEAR_GRID: usize = 16;

/// The largest level placement of `block` (node `node`) in `polygon`, from
/// `min` to `max`, that `clear` accepts: anchors on a grid over the cell,
/// each at the size the cell allows there, shrunk (by bisection: a box
/// centred on its anchor only grows with its size, so clear sizes form an
/// interval from `min`) until clear. `None` when no anchor is clear at `min`.
fn clear_spot(
    polygon: &ConvexPolygon,
    block: &Block,
    node: usize,
    max: f64,
    min: f64,
    clear: &dyn Fn(&Placed) -> bool,
) -> Option<(Point, f64)> {
    let half = Point::new(0.5 * block.width + 0.1, 0.5 * block.height);
    let (lo, hi) = polygon.bbox();
    let mut best: Option<(Point, f64)> = None;
    for i in 0..CLEAR_GRID {
        for j in 0..CLEAR_GRID {
            let f = |k: usize| (k as f64 + 0.5) / CLEAR_GRID as f64;
            let p = Point::new(lo.x + f(i) * (hi.x - lo.x), lo.y + f(j) * (hi.y - lo.y));
            let room = (fit_scale(polygon, p, half) * GROUP_FILL).min(max);
            if room < min || best.is_some_and(|(_, s)| room <= s) {
                continue;
            }
            let fits = |s: f64| clear(&lay_out(node, block, p, s));
            let size = if fits(room) {
                room
            } else if fits(min) {
                let (mut ok, mut over) = (min, room);
                for _ in 0..16 {
                    let mid = 0.5 * (ok + over);
                    if fits(mid) {
                        ok = mid;
                    } else {
                        over = mid;
                    }
                }
                ok
            } else {
                continue;
            };
            if best.is_none_or(|(_, s)| size > s) {
                best = Some((p, size));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_get_thousands_separators() {
        assert_eq!(format_value(1_411_778_724.0, ""), "1,411,778,724");
        assert_eq!(format_value(999.0, " KiB"), "999 KiB");
        assert_eq!(format_value(1234.5, ""), "1,234.5");
        assert_eq!(format_value(0.125, "%"), "0.13%");
        // Readable at any magnitude (issue 30 item 13): 1e300 is not 301
        // digits, 1e308 not `inf`, and a tiny value not 0.
        assert_eq!(format_value(1e300, ""), "1e300");
        assert_eq!(format_value(-1e308, ""), "-1e308");
        assert_eq!(format_value(f64::MAX, ""), "1.8e308");
        assert_eq!(format_value(1.2345e15, " B"), "1.23e15 B");
        assert_eq!(format_value(0.000042, ""), "4.2e-5");
        assert_eq!(
            format_value(999_999_999_999_999.0, ""),
            "999,999,999,999,999"
        );
        assert_eq!(format_value(0.0, ""), "0");
        assert_eq!(format_value(-1000.0, ""), "-1,000");
    }

    #[test]
    fn words_break_near_the_middle() {
        assert_eq!(
            wrap("Democratic Republic of the Congo"),
            Some(("Democratic Republic".into(), "of the Congo".into()))
        );
        assert_eq!(
            wrap("google-cloud-cli"),
            Some(("google-".into(), "cloud-cli".into()))
        );
        assert_eq!(wrap("nobreak"), None);
        assert_eq!(crate::render::label_text::clean("  a \n\t b\u{1} "), "a b");
    }

    #[test]
    fn a_long_label_wraps_or_is_cut_but_never_shrinks_below_the_minimum() {
        // 120 × 60: "Democratic Republic of the Congo" on one line would need
        // about 7 px; on two lines it reaches the minimum.
        let cell = ConvexPolygon::rectangle(0.0, 0.0, 120.0, 60.0).expect("rect");
        let p = place_leaf(
            0,
            "Democratic Republic of the Congo",
            None,
            &cell,
            9.0,
            24.0,
        )
        .expect("placed");
        assert_eq!(p.lines.len(), 2, "{p:?}");
        assert!(p.lines.iter().all(|l| l.size >= 9.0));
        for c in p.rect.corners() {
            assert!(cell.contains(c), "{c:?} inside");
        }
        // Too narrow for two lines: cut with an ellipsis.
        let thin = ConvexPolygon::rectangle(0.0, 0.0, 60.0, 14.0).expect("rect");
        let p = place_leaf(
            0,
            "Democratic Republic of the Congo",
            None,
            &thin,
            9.0,
            24.0,
        )
        .expect("cut");
        assert_eq!(p.lines.len(), 1);
        assert!(p.lines[0].text.ends_with('…'), "{p:?}");
        assert!(p.lines[0].size >= 9.0);
        // Too small for three characters: no label.
        let tiny = ConvexPolygon::rectangle(0.0, 0.0, 12.0, 8.0).expect("rect");
        assert_eq!(place_leaf(0, "Congo", None, &tiny, 9.0, 24.0), None);
        // A value line comes under the label, smaller.
        let big = ConvexPolygon::rectangle(0.0, 0.0, 200.0, 200.0).expect("rect");
        let p = place_leaf(0, "Congo", Some("99,010,212"), &big, 9.0, 24.0).expect("placed");
        assert_eq!(p.lines.len(), 2);
        assert!(p.lines[1].size < p.lines[0].size && p.lines[1].size >= 9.0);
        assert!(p.lines[1].baseline > p.lines[0].baseline);
    }

    #[test]
    fn the_fit_agrees_with_containment() {
        let hex = ConvexPolygon::regular(Point::new(50.0, 50.0), 40.0, 6).expect("hex");
        let c = hex.centroid();
        let half = Point::new(1.6, 0.6);
        let s = fit_scale(&hex, c, half);
        let inside = |s: f64| {
            [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
                .iter()
                .all(|&(x, y)| hex.contains(c + Point::new(x * half.x, y * half.y) * s))
        };
        assert!(inside(s * 0.999) && !inside(s * 1.01));
        // The search never does worse than the centroid.
        let tri = ConvexPolygon::new(vec![
            Point::new(0.0, 0.0),
            Point::new(100.0, 0.0),
            Point::new(0.0, 100.0),
        ])
        .expect("triangle");
        let (_, best) = best_fit(&tri, half);
        assert!(best >= fit_scale(&tri, tri.centroid(), half));
    }

    #[test]
    fn turned_boxes_overlap_by_separating_axes() {
        let square = |x: f64, y: f64| {
            [
                Point::new(x, y),
                Point::new(x + 1.0, y),
                Point::new(x + 1.0, y + 1.0),
                Point::new(x, y + 1.0),
            ]
        };
        assert!(quads_overlap(&square(0.0, 0.0), &square(0.5, 0.5)));
        assert!(!quads_overlap(&square(0.0, 0.0), &square(1.5, 0.0)));
        let diamond = [
            Point::new(2.0, 0.5),
            Point::new(2.6, 1.1),
            Point::new(2.0, 1.7),
            Point::new(1.4, 1.1),
        ];
        assert!(!quads_overlap(&square(0.0, 0.0), &diamond));
    }
}
