//! Colour by a numeric field (issue 24 item 5): the leaves take their colour
//! from one of the data's own columns on a perceptual scale instead of from
//! their group, in every output. Owns the scale (cividis for sequential
//! values; for diverging ones an OKLab scale of two hues through a light
//! neutral at a midpoint), the reading of the values from the nodes' carried
//! fields and the colour of a leaf without a value; may not draw (the
//! legend and the pictures do) or read files.

use nptreemap_formats::Dataset;

use super::palette::{from_oklch, Rgb};

/// How values map to colours.
#[derive(serde::Serialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum ColorScale {
    /// Low to high, dark blue to yellow (cividis: even in lightness, readable
    /// with any colour vision).
    #[default]
    Sequential,
    /// Below and above a midpoint, blue and red, light at the midpoint.
    Diverging,
}

impl ColorScale {
    /// The name used in configs.
    pub fn name(self) -> &'static str {
        match self {
            ColorScale::Sequential => "sequential",
            ColorScale::Diverging => "diverging",
        }
    }

    /// The scale called `name` in a config.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "sequential" => Some(ColorScale::Sequential),
            "diverging" => Some(ColorScale::Diverging),
            _ => None,
        }
    }
}

/// Colour the leaves by `field` (a column carried into the nodes' fields).
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct ColorBy {
    /// The column (or hierarchy JSON property) holding a number per leaf.
    pub field: String,
    /// The scale.
    pub scale: ColorScale,
    /// A diverging scale's centre (the light colour). Default 0.
    pub midpoint: f64,
}

/// The colour of a leaf without a (numeric) value: a mid grey the scales
/// never produce (cividis has colour at every step; the diverging scale's
/// neutral is light), named in the legend.
pub const MISSING: Rgb = Rgb::new(0x9e, 0x9e, 0x9e);

/// Colour stops of a scale drawn in a legend.
pub const LEGEND_STOPS: usize = 24;

/// The scale as applied to one dataset: its value range.
#[derive(Clone, Debug, PartialEq)]
pub struct Applied {
    /// The column's name.
    pub field: String,
    /// Smallest and largest value among the leaves (the diverging scale's
    /// range always includes the midpoint).
    pub lo: f64,
    /// See `lo`.
    pub hi: f64,
    /// Colours from `lo` to `hi`, evenly spaced, for the legend's bar.
    pub stops: Vec<Rgb>,
    /// True when some leaf has no value (the legend then names the grey).
    pub missing: bool,
    /// True when the scale is logarithmic (see `LOG_SPAN`).
    pub log: bool,
    /// True when `lo` and `hi` are not the values' extremes but the ends of
    /// the values inside the outlier fences (see `OUTLIER_STRETCH`): values
    /// beyond them take the scale's end colours, and the legend says so.
    pub clipped: bool,
}

/// The number of each node's `field` (leaves only); a virtual leaf (method
/// reference §2.2) takes its real node's. Text that is not a finite number
/// counts as no value.
pub fn values(dataset: &Dataset, field: &str) -> Vec<Option<f64>> {
    (0..dataset.len())
        .map(|i| {
            if !dataset.is_leaf(i) {
                return None;
            }
            let real = super::chains::original(dataset, i);
            dataset
                .node(real)
                .fields
                .iter()
                .find(|(name, _)| name == field)
                .and_then(|(_, text)| text.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
        })
        .collect()
}

/// Where a sequential scale goes logarithmic: when the values (none
/// negative) span this many times their smallest positive one, a linear
/// scale would give one outlier all the colour and every other leaf the
/// same dark one (lines of code, file sizes, downloads).
const LOG_SPAN: f64 = 100.0;

/// How far the values' whole range may stretch beyond the range inside
/// Tukey's far-out fences (three interquartile ranges past the quartiles)
/// before the linear scale is clipped to the fenced range: past 10x, nine
/// tenths of the colours would go to a few outliers and every other leaf
/// would share one colour.
const OUTLIER_STRETCH: f64 = 10.0;

/// `(v - a) / (b - a)`, computed on halves so that no difference of two
/// finite values overflows (with `a = -1e308` and `b = 1e308` the plain
/// difference is infinite and the quotient NaN); NaN-free for finite input.
fn fraction(a: f64, b: f64, v: f64) -> f64 {
    let span = b / 2.0 - a / 2.0;
    if span > 0.0 {
        ((v / 2.0 - a / 2.0) / span).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// A sequential scale's position of `v` in `[lo, hi]`, from 0 to 1:
/// linear, or `ln(v + shift)` when `shift` (the smallest positive value)
/// is given.
fn position(lo: f64, hi: f64, v: f64, shift: Option<f64>) -> f64 {
    let f = |x: f64| shift.map_or(x, |s| (x + s).ln());
    fraction(f(lo), f(hi), f(v))
}

/// The value a fraction `t` of the way from `a` to `b` (no overflow).
fn between(a: f64, b: f64, t: f64) -> f64 {
    a * (1.0 - t) + b * t
}

/// The colour of value `v` on `by`'s scale over `[lo, hi]` (linear).
pub fn color_at(by: &ColorBy, lo: f64, hi: f64, v: f64) -> Rgb {
    color_on(by, lo, hi, v, None)
}

/// [`color_at`], a sequential scale logarithmic when `shift` is given.
fn color_on(by: &ColorBy, lo: f64, hi: f64, v: f64, shift: Option<f64>) -> Rgb {
    match by.scale {
        ColorScale::Sequential => {
            let t = position(lo, hi, v, shift);
            let c = colorous::CIVIDIS.eval_continuous(t);
            Rgb::new(c.r, c.g, c.b)
        }
        ColorScale::Diverging => {
            // Each side spans from the midpoint to the farther end, so equal
            // distances from the midpoint get equal strengths of colour.
            // On halves, so that no finite range overflows.
            let m = by.midpoint / 2.0;
            let reach = (hi / 2.0 - m).abs().max((m - lo / 2.0).abs());
            let t = if reach > 0.0 {
                (v / 2.0 - m) / reach
            } else {
                0.0
            };
            let t = t.clamp(-1.0, 1.0);
            // A straight line in OKLab from a light neutral to each hue.
            let (l_end, c_end, hue) = if t < 0.0 {
                (0.45, 0.14, 255.0)
            } else {
                (0.50, 0.17, 30.0)
            };
            let s = t.abs();
            from_oklch(0.96 + (l_end - 0.96) * s, c_end * s, hue)
        }
    }
}

/// Recolours the leaves of `colors` (indexed like `dataset`) by `by`; the
/// scale as applied, or `None` when no leaf has a value (the colours are
/// then left as they are).
pub fn apply(dataset: &Dataset, colors: &mut [Option<Rgb>], by: &ColorBy) -> Option<Applied> {
    let values = values(dataset, &by.field);
    let mut range: Option<(f64, f64)> = None;
    for v in values.iter().flatten() {
        range = Some(range.map_or((*v, *v), |(lo, hi)| (lo.min(*v), hi.max(*v))));
    }
    let (mut lo, mut hi) = range?;
    let smallest = smallest_positive(&values);
    let shift = (by.scale == ColorScale::Sequential
        && lo >= 0.0
        && smallest.is_finite()
        && hi >= LOG_SPAN * smallest)
        .then_some(smallest);
    // A logarithmic scale already spreads a heavy tail; a linear one whose
    // range a few outliers stretch is clipped to the values inside the
    // fences.
    let mut clipped = false;
    if let (None, Some((flo, fhi))) = (shift, fenced(&values)) {
        let inner = fhi / 2.0 - flo / 2.0;
        if inner > 0.0 && hi / 2.0 - lo / 2.0 > OUTLIER_STRETCH * inner {
            (lo, hi, clipped) = (flo, fhi, true);
        }
    }
    if by.scale == ColorScale::Diverging {
        lo = lo.min(by.midpoint);
        hi = hi.max(by.midpoint);
    }
    let mut missing = false;
    for (i, color) in colors.iter_mut().enumerate().take(dataset.len()) {
        if !dataset.is_leaf(i) {
            continue;
        }
        *color = Some(match values[i] {
            Some(v) => color_on(by, lo, hi, v, shift),
            None => {
                missing = true;
                MISSING
            }
        });
    }
    // Evenly spaced along the bar, so on a logarithmic scale the bar's
    // middle is the values' geometric middle.
    let stops = (0..LEGEND_STOPS)
        .map(|k| {
            let t = k as f64 / (LEGEND_STOPS - 1) as f64;
            let v = match shift {
                Some(s) => between((lo + s).ln(), (hi + s).ln(), t).exp() - s,
                None => between(lo, hi, t),
            };
            color_on(by, lo, hi, v, shift)
        })
        .collect();
    Some(Applied {
        log: shift.is_some(),
        clipped,
        field: by.field.clone(),
        lo,
        hi,
        stops,
        missing,
    })
}

/// The smallest positive value (infinity when there is none).
fn smallest_positive(values: &[Option<f64>]) -> f64 {
    values
        .iter()
        .flatten()
        .copied()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min)
}

/// The smallest and largest values inside Tukey's far-out fences (three
/// interquartile ranges beyond the quartiles; computed on halves so that
/// no finite value overflows), or `None` with fewer than four values.
fn fenced(values: &[Option<f64>]) -> Option<(f64, f64)> {
    let mut sorted: Vec<f64> = values.iter().flatten().copied().collect();
    if sorted.len() < 4 {
        return None;
    }
    sorted.sort_by(f64::total_cmp);
    let quartile = |q: usize| sorted[(sorted.len() - 1) * q / 4] / 2.0;
    let (q1, q3) = (quartile(1), quartile(3));
    let iqr = q3 - q1;
    let (low_fence, high_fence) = (q1 - 3.0 * iqr, q3 + 3.0 * iqr);
    let mut inside = sorted
        .iter()
        .copied()
        .filter(|v| *v / 2.0 >= low_fence && *v / 2.0 <= high_fence);
    let first = inside.next()?;
    Some((first, inside.next_back().unwrap_or(first)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::palette::oklab;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn leaf(id: &str, value: Option<&str>) -> NodeSpec {
        let mut spec = NodeSpec::new(id).parent("r").weight(1.0);
        if let Some(v) = value {
            spec.fields = vec![("score".to_owned(), v.to_owned())];
        }
        spec
    }

    /// The leaves' colours and the scale, by `score` on the sequential scale.
    fn sequential(ds: &Dataset) -> (Vec<Option<Rgb>>, Applied) {
        let by = ColorBy {
            field: "score".into(),
            scale: ColorScale::Sequential,
            midpoint: 0.0,
        };
        let mut colors = vec![None; ds.len()];
        let applied = apply(ds, &mut colors, &by).expect("values");
        (colors, applied)
    }

    #[test]
    fn sequential_runs_dark_to_light_and_missing_is_grey() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for (id, v) in [
            ("a", Some("1")),
            ("b", Some("5")),
            ("c", Some("x")),
            ("d", None),
        ] {
            b.add(leaf(id, v));
        }
        let ds = b.build().expect("valid");
        let (colors, applied) = sequential(&ds);
        assert_eq!((applied.lo, applied.hi), (1.0, 5.0));
        assert!(applied.missing);
        let at = |id: &str| colors[ds.find(id).expect("node")].expect("leaf colour");
        assert!(
            oklab(at("a"))[0] < oklab(at("b"))[0],
            "lightness grows with the value"
        );
        assert_eq!(at("c"), MISSING);
        assert_eq!(at("d"), MISSING);
        // Lightness grows at every stop (a perceptual sequential scale).
        let l: Vec<f64> = applied.stops.iter().map(|c| oklab(*c)[0]).collect();
        assert!(l.windows(2).all(|w| w[1] > w[0] - 0.005), "{l:?}");
    }

    #[test]
    fn values_over_orders_of_magnitude_get_a_logarithmic_scale() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for (k, v) in ["0", "10", "100", "1000", "100000"].iter().enumerate() {
            b.add(leaf(&format!("n{k}"), Some(v)));
        }
        let ds = b.build().expect("valid");
        let (colors, applied) = sequential(&ds);
        assert!(applied.log);
        // 10, 100 and 1,000 are told apart (a linear scale over 0..100,000
        // would draw them all as dark as 0).
        let l = |id: &str| oklab(colors[ds.find(id).expect("node")].expect("colour"))[0];
        assert!(
            l("n1") + 0.05 < l("n2") && l("n2") + 0.05 < l("n3"),
            "{} {} {}",
            l("n1"),
            l("n2"),
            l("n3")
        );
    }

    #[test]
    fn diverging_is_light_at_the_midpoint_and_symmetric() {
        let by = ColorBy {
            field: "f".into(),
            scale: ColorScale::Diverging,
            midpoint: 10.0,
        };
        let mid = oklab(color_at(&by, 0.0, 30.0, 10.0));
        let below = oklab(color_at(&by, 0.0, 30.0, 0.0));
        let above = oklab(color_at(&by, 0.0, 30.0, 20.0));
        assert!(mid[0] > 0.9 && mid[1].hypot(mid[2]) < 0.02, "{mid:?}");
        assert!(below[0] < 0.75 && above[0] < 0.75);
        // The two sides differ in hue: blue has b < 0, red a > 0.
        assert!(below[2] < 0.0 && above[1] > 0.0, "{below:?} {above:?}");
    }

    /// A dataset of leaves with these scores, and their colours on `scale`.
    fn coloured(scores: &[&str], scale: ColorScale) -> (Dataset, Vec<Option<Rgb>>, Applied) {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for (k, v) in scores.iter().enumerate() {
            b.add(leaf(&format!("n{k}"), Some(v)));
        }
        let ds = b.build().expect("valid");
        let by = ColorBy {
            field: "score".into(),
            scale,
            midpoint: 0.0,
        };
        let mut colors = vec![None; ds.len()];
        let applied = apply(&ds, &mut colors, &by).expect("values");
        (ds, colors, applied)
    }

    #[test]
    fn the_widest_finite_range_keeps_its_ends_on_the_scale() {
        // Issue 30 item 13: hi - lo overflowed to infinity, so 1e308 was
        // drawn black (NaN on the scale) and -1e308 a middle colour.
        let (ds, colors, applied) = coloured(&["-1e308", "0", "1e308"], ColorScale::Sequential);
        let at = |id: &str| colors[ds.find(id).expect("node")].expect("colour");
        assert_eq!(
            at("n0"),
            applied.stops[0],
            "the lowest value is the first stop"
        );
        assert_eq!(
            at("n2"),
            applied.stops[LEGEND_STOPS - 1],
            "the highest the last"
        );
        assert_ne!(at("n2"), Rgb::new(0, 0, 0));
        assert!(applied.lo.is_finite() && applied.hi.is_finite());
        let light = |id: &str| oklab(at(id))[0];
        assert!(light("n0") < light("n1") && light("n1") < light("n2"));

        let (ds, colors, _) = coloured(&["-1e308", "0", "1e308"], ColorScale::Diverging);
        let at = |id: &str| oklab(colors[ds.find(id).expect("node")].expect("colour"));
        assert!(at("n1")[0] > 0.9, "the midpoint is light: {:?}", at("n1"));
        for end in ["n0", "n2"] {
            assert!(
                at(end)[0] < 0.6,
                "{end} is a full end colour: {:?}",
                at(end)
            );
        }
    }

    #[test]
    fn a_few_outliers_clip_a_linear_scale_and_say_so() {
        // Most values within -5..5, two far outliers: a linear scale over
        // the whole range would give every ordinary leaf the middle colour.
        let mut scores: Vec<String> = (-5..=5).map(|v| v.to_string()).collect();
        scores.push("1e12".into());
        scores.push("-3e9".into());
        let refs: Vec<&str> = scores.iter().map(String::as_str).collect();
        let (ds, colors, applied) = coloured(&refs, ColorScale::Sequential);
        assert!(applied.clipped && !applied.log);
        assert_eq!((applied.lo, applied.hi), (-5.0, 5.0));
        let at = |k: usize| colors[ds.find(&format!("n{k}")).expect("node")].expect("colour");
        // The ordinary values spread over the scale; the outliers take its ends.
        assert_eq!(at(0), applied.stops[0]);
        assert_eq!(at(10), applied.stops[LEGEND_STOPS - 1]);
        assert_eq!(at(11), at(10));
        assert_eq!(at(12), at(0));
        let l: Vec<f64> = (0..=10).map(|k| oklab(at(k))[0]).collect();
        assert!(l.windows(2).all(|w| w[1] > w[0]), "{l:?}");

        // Without outliers, no clipping.
        let (_, _, applied) = coloured(&["-5", "-1", "0", "2", "5"], ColorScale::Sequential);
        assert!(!applied.clipped);
        // A heavy tail of non-negative values is logarithmic, not clipped.
        let (_, _, applied) = coloured(&["1", "2", "3", "4", "1e9"], ColorScale::Sequential);
        assert!(applied.log && !applied.clipped);
    }
}
