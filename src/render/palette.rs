//! Colours for the pictures: the Tableau 10 / Tableau 20 categorical palettes,
//! a colour-blind-safe palette (Okabe–Ito), a generated perceptual palette for
//! any number of groups, the assignment of palette colours to groups so that
//! adjacent groups never look alike, and lightness variations in HSL, over the
//! model's [`Rgb`] (parsed once, by the formats crate). Owns colour arithmetic
//! only; may not know about nodes, layouts or SVG (callers pass group indices
//! and which pairs touch).
//!
//! OKLab (Björn Ottosson, 2020) is written out here, a dozen lines of published
//! matrices, rather than pulling a colour-science crate for one conversion.

pub use nptreemap_formats::Rgb;

use super::color_difference::{cielab, delta_e_lab, linear};
use super::distinct::FARTHEST;

/// White, the default background and stroke colour.
pub const WHITE: Rgb = Rgb::new(0xff, 0xff, 0xff);

/// Tableau 10 (Tableau's 2016 default categorical palette), in Tableau's order.
pub const TABLEAU10: [Rgb; 10] = [
    Rgb::new(0x4e, 0x79, 0xa7), // blue
    Rgb::new(0xf2, 0x8e, 0x2b), // orange
    Rgb::new(0xe1, 0x57, 0x59), // red
    Rgb::new(0x76, 0xb7, 0xb2), // teal
    Rgb::new(0x59, 0xa1, 0x4f), // green
    Rgb::new(0xed, 0xc9, 0x48), // yellow
    Rgb::new(0xb0, 0x7a, 0xa1), // purple
    Rgb::new(0xff, 0x9d, 0xa7), // pink
    Rgb::new(0x9c, 0x75, 0x5f), // brown
    Rgb::new(0xba, 0xb0, 0xac), // grey
];

/// Tableau 20: ten hues, each as a dark/light pair, in Tableau's order.
pub const TABLEAU20: [Rgb; 20] = [
    Rgb::new(0x4e, 0x79, 0xa7),
    Rgb::new(0xa0, 0xcb, 0xe8), // blue
    Rgb::new(0xf2, 0x8e, 0x2b),
    Rgb::new(0xff, 0xbe, 0x7d), // orange
    Rgb::new(0x59, 0xa1, 0x4f),
    Rgb::new(0x8c, 0xd1, 0x7d), // green
    Rgb::new(0xb6, 0x99, 0x2d),
    Rgb::new(0xf1, 0xce, 0x63), // yellow
    Rgb::new(0x49, 0x98, 0x94),
    Rgb::new(0x86, 0xbc, 0xb6), // teal
    Rgb::new(0xe1, 0x57, 0x59),
    Rgb::new(0xff, 0x9d, 0x9a), // red
    Rgb::new(0x79, 0x70, 0x6e),
    Rgb::new(0xba, 0xb0, 0xac), // grey
    Rgb::new(0xd3, 0x72, 0x95),
    Rgb::new(0xfa, 0xbf, 0xd2), // pink
    Rgb::new(0xb0, 0x7a, 0xa1),
    Rgb::new(0xd4, 0xa6, 0xc8), // purple
    Rgb::new(0x9d, 0x76, 0x60),
    Rgb::new(0xd7, 0xb5, 0xa6), // brown
];

/// The Okabe–Ito palette (Okabe & Ito 2008, "Color Universal Design"), safe
/// for the common colour-vision deficiencies, without its black (labels are
/// dark) and in its usual order.
pub const OKABE_ITO: [Rgb; 7] = [
    Rgb::new(0xe6, 0x9f, 0x00), // orange
    Rgb::new(0x56, 0xb4, 0xe9), // sky blue
    Rgb::new(0x00, 0x9e, 0x73), // bluish green
    Rgb::new(0xf0, 0xe4, 0x42), // yellow
    Rgb::new(0x00, 0x72, 0xb2), // blue
    Rgb::new(0xd5, 0x5e, 0x00), // vermillion
    Rgb::new(0xcc, 0x79, 0xa7), // reddish purple
];

/// Which categorical palette the top-level groups take.
#[derive(serde::Serialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum PaletteKind {
    /// Tableau 10 up to ten groups, Tableau 20 up to twenty, then a generated
    /// perceptual palette: every group its own colour.
    #[default]
    Tableau,
    /// Okabe–Ito's seven colours, reused across groups that do not touch.
    Colorblind,
}

impl PaletteKind {
    /// The name used in configs.
    pub fn name(self) -> &'static str {
        match self {
            PaletteKind::Tableau => "tableau",
            PaletteKind::Colorblind => "colorblind",
        }
    }

    /// Parses a config name.
    pub fn from_name(name: &str) -> Option<Self> {
        [PaletteKind::Tableau, PaletteKind::Colorblind]
            .into_iter()
            .find(|k| k.name() == name)
    }
}

/// The colours `groups` top-level groups choose from: for [`PaletteKind::Tableau`]
/// Tableau 10 or 20, or as many distinct colours as `groups`
/// ([`extended`]: Tableau 20, then colours picked farthest
/// apart, then the generated palette) up to what the generated palette
/// holds, after which [`assign`] reuses colours, keeping touching groups
/// apart; for [`PaletteKind::Colorblind`] always Okabe–Ito.
pub fn group_palette(kind: PaletteKind, groups: usize) -> Vec<Rgb> {
    match kind {
        PaletteKind::Colorblind => OKABE_ITO.to_vec(),
        PaletteKind::Tableau if groups <= TABLEAU10.len() => TABLEAU10.to_vec(),
        PaletteKind::Tableau if groups <= TABLEAU20.len() => TABLEAU20.to_vec(),
        PaletteKind::Tableau => extended(groups),
    }
}

/// Every colour `kind` can give one of up to `groups` groups, whatever
/// their number: a group keeps a colour of the last build while it is
/// among these, so adding or removing groups (Tableau 10 → 20 → generated)
/// recolours none, while a change of `render.palette` does.
pub fn family(kind: PaletteKind, groups: usize) -> std::collections::HashSet<Rgb> {
    match kind {
        PaletteKind::Colorblind => OKABE_ITO.into_iter().collect(),
        PaletteKind::Tableau => TABLEAU10
            .into_iter()
            .chain(extended(groups.max(TABLEAU20.len())))
            .collect(),
    }
}

/// Up to `n` distinct colours: Tableau 20, [`FARTHEST`], then the generated
/// palette without the colours already given. A shorter palette is a prefix
/// of a longer one, so a group keeps its colour when groups are added.
pub fn extended(n: usize) -> Vec<Rgb> {
    let mut out: Vec<Rgb> = TABLEAU20.into_iter().chain(FARTHEST).take(n).collect();
    if out.len() < n {
        let given: std::collections::HashSet<Rgb> = out.iter().copied().collect();
        // The generated palette is a bounded search; asking it for `n`
        // beyond the given colours is enough, as they are among its colours
        // or Tableau's.
        let rest = generated(n.saturating_add(given.len()));
        out.extend(
            rest.into_iter()
                .filter(|c| !given.contains(c))
                .take(n - out.len()),
        );
    }
    out
}

/// Rings of the generated palette: per ring, three lightness levels cycled
/// with the hue and a chroma. Mid-tones throughout, on which dark labels with
/// a white halo read and whose lighter child shades stay off white. The
/// first ring is the palette's original one (so maps of up to about 1,800
/// groups keep their colours); each further ring sits between the earlier
/// ones in lightness and chroma, so its colours round to new 8-bit values.
const RINGS: [([f64; 3], f64); 4] = [
    ([0.72, 0.60, 0.82], 0.11),
    ([0.66, 0.78, 0.56], 0.08),
    ([0.69, 0.57, 0.79], 0.14),
    ([0.75, 0.63, 0.84], 0.06),
];
/// Candidates tried per ring: the bound of [`generated`]'s search. One ring's
/// hues by the golden angle, rounded to 8 bits, stop giving new colours (the
/// first ring has only 2,370 in all; searching for a 2,371st never ended:
/// issue 21); 4,096 candidates give about 1,800 of a ring's colours, and the
/// four rings together about 6,600, more than anyone tells apart on one map.
const RING_CANDIDATES: usize = 4096;
/// Hue step of the generated palette, degrees: the golden angle, so any run
/// of consecutive colours spreads round the hue circle.
const GOLDEN_ANGLE: f64 = 137.507_764;

/// Up to `n` distinct colours spread over OKLCH: within each of the `RINGS`,
/// hues by the golden angle, lightness cycling through the ring's three
/// levels, the ring's chroma (reduced where sRGB cannot show it). A fixed,
/// bounded search (`RING_CANDIDATES` per ring): past the colours it finds,
/// the palette is shorter than `n` and [`assign`] reuses colours.
/// Deterministic; a shorter palette is a prefix of a longer one.
pub fn generated(n: usize) -> Vec<Rgb> {
    let mut out: Vec<Rgb> = Vec::with_capacity(n.min(RINGS.len() * RING_CANDIDATES));
    let mut seen = std::collections::HashSet::new();
    for (ring, (levels, chroma)) in RINGS.iter().enumerate() {
        // Each ring starts half a step round from the previous one.
        let offset = ring as f64 * 0.5 * GOLDEN_ANGLE;
        for k in 0..RING_CANDIDATES {
            if out.len() >= n {
                return out;
            }
            let h = (k as f64 * GOLDEN_ANGLE + offset).rem_euclid(360.0);
            let c = from_oklch(levels[k % levels.len()], *chroma, h);
            // Rounding to 8 bits makes close candidates equal.
            if seen.insert(c) {
                out.push(c);
            }
        }
    }
    out
}

/// OKLab distance under which two colours count as alike for neighbouring
/// groups: about the step between Tableau's orange and yellow (0.13), the
/// palette's closest pair of different hues.
pub const ALIKE: f64 = 0.1;

/// Colours for groups `0..count` from `palette`, so that groups that touch
/// (`adjacent` pairs) get colours at least [`ALIKE`] apart whenever the
/// palette allows, and every group its own colour while the palette has
/// enough (past that, colours are reused evenly). `order` lists the groups by
/// priority: earlier groups get earlier palette colours.
/// `fixed[g]` is a group's own colour, kept as given. Deterministic greedy:
/// each group takes, among the first `WINDOW` least-used colours in palette
/// order, the first far enough from its coloured neighbours, else the one
/// farthest from them; then `improve` repairs what is left. Near-linear in
/// the groups: a flat table is a map of up to `max_nodes` top-level groups.
pub fn assign(
    palette: &[Rgb],
    order: &[usize],
    adjacent: &[(usize, usize)],
    fixed: &[Option<Rgb>],
) -> Vec<Rgb> {
    let count = fixed.len();
    let fallback = palette.first().copied().unwrap_or(TABLEAU10[0]);
    let mut neighbors: Vec<Vec<usize>> = vec![Vec::new(); count];
    for &(a, b) in adjacent {
        if a < count && b < count && a != b {
            neighbors[a].push(b);
            neighbors[b].push(a);
        }
    }
    let lab: Vec<[f64; 3]> = palette.iter().map(|c| group_lab(*c)).collect();
    let index: std::collections::HashMap<Rgb, usize> =
        palette.iter().enumerate().map(|(k, &c)| (c, k)).collect();
    let mut colors: Vec<Option<Rgb>> = fixed.to_vec();
    let mut used = vec![0usize; palette.len()];
    // A kept colour the palette does not hold counts the palette colours it
    // looks like as used (in a palette of up to `NEAR_PALETTE`): Tableau
    // 10's brown `#9c755f` is kept when a map grows past ten groups, and
    // Tableau 20's `#9d7660` (ΔE00 0.4) must not go to a new group while
    // another colour is free.
    let mut near: Option<Vec<[f64; 3]>> = None;
    for c in fixed.iter().flatten() {
        if let Some(&k) = index.get(c) {
            used[k] += 1;
        } else if palette.len() <= NEAR_PALETTE {
            let near = near.get_or_insert_with(|| palette.iter().map(|&c| cielab(c)).collect());
            let lab = cielab(*c);
            for (k, p) in near.iter().enumerate() {
                if delta_e_lab(lab, *p) < LEGEND_ALIKE {
                    used[k] += 1;
                }
            }
        }
    }
    let mut least = LeastUsed::new(&used);
    for &g in order.iter().filter(|&&g| g < count) {
        if colors[g].is_some() {
            continue;
        }
        let near: Vec<[f64; 3]> = neighbors[g]
            .iter()
            .filter_map(|&n| colors[n].map(group_lab))
            .collect();
        let gap = |k: usize| {
            near.iter()
                .map(|n| distance_lab(lab[k], *n))
                .fold(f64::INFINITY, f64::min)
        };
        let window: Vec<usize> = least.first(WINDOW);
        let pick = window
            .iter()
            .copied()
            .find(|&k| gap(k) >= ALIKE)
            .or_else(|| {
                window
                    .iter()
                    .copied()
                    .max_by(|&a, &b| gap(a).total_cmp(&gap(b)).then(b.cmp(&a)))
            });
        colors[g] = Some(match pick {
            Some(k) => {
                used[k] += 1;
                least.take(k, &used);
                palette[k]
            }
            None => fallback,
        });
    }
    let mut colors: Vec<Rgb> = colors.into_iter().map(|c| c.unwrap_or(fallback)).collect();
    improve(&mut colors, palette, &neighbors, fixed);
    colors
}

/// Largest palette whose colours are compared by likeness with a kept
/// colour it does not hold, in [`assign`]: Tableau's palettes up to
/// [`super::distinct::FARTHEST`] and then some, at most one CIEDE2000 per
/// such kept colour and palette colour.
const NEAR_PALETTE: usize = 256;
/// CIEDE2000 under which [`assign`] takes a palette colour for a kept one:
/// below the closest pair of Tableau 20 (9.1), above Tableau 10's colours
/// against their nearest in Tableau 20 (0.4 to 4.4).
const LEGEND_ALIKE: f64 = 5.0;

/// Least-used colours a group may take at once: enough that every hue of a
/// generated palette is among them (its consecutive colours step round the
/// hue circle by the golden angle), few enough that a group's choice stays
/// cheap. Also the bound of that choice's search.
const WINDOW: usize = 64;

/// The palette colours used least so far, in palette order: the only ones a
/// group may take, so no colour is used twice while another is unused, and
/// past that colours are reused evenly.
struct LeastUsed {
    /// Palette indices used least so far.
    at_level: std::collections::BTreeSet<usize>,
}

impl LeastUsed {
    fn new(used: &[usize]) -> Self {
        let level = used.iter().copied().min().unwrap_or(0);
        Self {
            at_level: (0..used.len()).filter(|&k| used[k] == level).collect(),
        }
    }

    /// The first `n` least-used colours in palette order.
    fn first(&self, n: usize) -> Vec<usize> {
        self.at_level.iter().copied().take(n).collect()
    }

    /// Colour `k` was used once more (`used` already counts it). When every
    /// colour of the level is taken the next level starts, which happens at
    /// most once per palette length of groups.
    fn take(&mut self, k: usize, used: &[usize]) {
        self.at_level.remove(&k);
        if self.at_level.is_empty() {
            *self = Self::new(used);
        }
    }
}

/// Local search after the greedy pass: each group in an alike adjacent pair
/// tries swaps with other groups and unused palette colours (any palette
/// colour when the palette is shorter than the groups), and takes the first
/// change that lowers the alike pairs among the edges it touches, or keeps
/// their count and widens their closest pair. Sweeps until a sweep changes
/// nothing, at most [`SWEEPS`] sweeps and [`TRIALS`] trials in all.
/// Deterministic.
///
/// Every trial is judged on the edges of the one or two groups it changes,
/// with each colour's OKLab computed once: judging trials on the whole map
/// made a flat map of 1,061 top-level leaves take minutes (every trial
/// re-converted every edge's colours).
fn improve(colors: &mut [Rgb], palette: &[Rgb], neighbors: &[Vec<usize>], fixed: &[Option<Rgb>]) {
    let unique = palette.len() >= colors.len();
    let mut lab: Vec<[f64; 3]> = colors.iter().map(|&c| group_lab(c)).collect();
    let palette_lab: Vec<[f64; 3]> = palette.iter().map(|&c| group_lab(c)).collect();
    let mut used: std::collections::HashMap<Rgb, usize> = std::collections::HashMap::new();
    for &c in colors.iter() {
        *used.entry(c).or_default() += 1;
    }
    // (alike pairs, closest distance) over the edges of `g`, with `g` coloured
    // `at` and the edge to `skip` left out.
    let side = |lab: &[[f64; 3]], g: usize, at: [f64; 3], skip: usize| {
        neighbors[g].iter().filter(|&&n| n != skip).fold(
            (0usize, f64::INFINITY),
            |(alike, least), &n| {
                let d = distance_lab(at, lab[n]);
                (alike + usize::from(d < ALIKE), least.min(d))
            },
        )
    };
    let join = |a: (usize, f64), b: (usize, f64)| (a.0 + b.0, a.1.min(b.1));
    let better = |after: (usize, f64), before: (usize, f64)| {
        after.0 < before.0 || (after.0 == before.0 && after.1 > before.1 + 1e-12)
    };
    let mut trials = 0usize;
    for _sweep in 0..SWEEPS {
        let mut changed = false;
        for g in (0..colors.len()).filter(|&g| fixed[g].is_none()) {
            if trials >= TRIALS {
                return;
            }
            let alike = neighbors[g]
                .iter()
                .any(|&n| distance_lab(lab[g], lab[n]) < ALIKE);
            if !alike {
                continue;
            }
            // Swaps: the edge between g and h (if any) keeps its two colours.
            let swap = |trials: &mut usize, lab: &[[f64; 3]], colors: &[Rgb]| {
                (0..colors.len())
                    .filter(|&h| h != g && fixed[h].is_none() && colors[h] != colors[g])
                    .take(TRIALS.saturating_sub(*trials))
                    .find(|&h| {
                        *trials += 1;
                        let before = join(side(lab, g, lab[g], h), side(lab, h, lab[h], g));
                        let after = join(side(lab, g, lab[h], h), side(lab, h, lab[g], g));
                        better(after, before)
                    })
            };
            // While every group has its own colour, a swap keeps it so and is
            // tried first; past that, any colour may be reused, and a new one
            // (a few thousand candidates, against every group for a swap) is.
            let swapped = if unique {
                swap(&mut trials, &lab, colors)
            } else {
                None
            };
            if let Some(h) = swapped {
                colors.swap(g, h);
                lab.swap(g, h);
                changed = true;
                continue;
            }
            let before = side(&lab, g, lab[g], usize::MAX);
            let recolour = (0..palette.len())
                .filter(|&k| palette[k] != colors[g])
                .filter(|&k| !unique || used.get(&palette[k]).is_none_or(|&u| u == 0))
                .take(TRIALS.saturating_sub(trials))
                .find(|&k| {
                    trials += 1;
                    better(side(&lab, g, palette_lab[k], usize::MAX), before)
                });
            if let Some(k) = recolour {
                if let Some(u) = used.get_mut(&colors[g]) {
                    *u -= 1;
                }
                *used.entry(palette[k]).or_default() += 1;
                colors[g] = palette[k];
                lab[g] = palette_lab[k];
                changed = true;
                continue;
            }
            if !unique {
                if let Some(h) = swap(&mut trials, &lab, colors) {
                    colors.swap(g, h);
                    lab.swap(g, h);
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}

/// Most sweeps of [`improve`]; each either changes a colour or ends the search.
const SWEEPS: usize = 16;
/// Most trials (a swap or a recolouring judged) of [`improve`] in all: its
/// swaps try every other group, so without a bound a map of 100,000 groups
/// with a few alike pairs would cost 10¹⁰ trials. Each trial reads two
/// groups' edges, a few dozen distances; 4 million stay around a second in
/// a debug build. What is still alike after it stays alike.
const TRIALS: usize = 4_000_000;

/// sRGB (8 bits per channel) to OKLab `[L, a, b]`.
pub fn oklab(c: Rgb) -> [f64; 3] {
    let (r, g, b) = (linear(c.r), linear(c.g), linear(c.b));
    let l = (0.412_221_470_8 * r + 0.536_332_536_3 * g + 0.051_445_992_9 * b).cbrt();
    let m = (0.211_903_498_2 * r + 0.680_699_545_1 * g + 0.107_396_956_6 * b).cbrt();
    let s = (0.088_302_461_9 * r + 0.281_718_837_6 * g + 0.629_978_700_5 * b).cbrt();
    [
        0.210_454_255_3 * l + 0.793_617_785_0 * m - 0.004_072_046_8 * s,
        1.977_998_495_1 * l - 2.428_592_205_0 * m + 0.450_593_709_9 * s,
        0.025_904_037_1 * l + 0.782_771_766_2 * m - 0.808_675_766_0 * s,
    ]
}

/// OKLab back to linear sRGB, unclamped.
fn oklab_to_linear([l, a, b]: [f64; 3]) -> [f64; 3] {
    let l_ = (l + 0.396_337_777_4 * a + 0.215_803_757_3 * b).powi(3);
    let m_ = (l - 0.105_561_345_8 * a - 0.063_854_172_8 * b).powi(3);
    let s_ = (l - 0.089_484_177_5 * a - 1.291_485_548_0 * b).powi(3);
    [
        4.076_741_662_1 * l_ - 3.307_711_591_3 * m_ + 0.230_969_929_2 * s_,
        -1.268_438_004_6 * l_ + 2.609_757_401_1 * m_ - 0.341_319_396_5 * s_,
        -0.004_196_086_3 * l_ - 0.703_418_614_7 * m_ + 1.707_614_701_0 * s_,
    ]
}

/// The colour of OKLCH lightness `l`, chroma `c` and hue `h` (degrees), with
/// the chroma reduced until sRGB can show it. A chroma beyond any sRGB
/// colour's (about 0.32) or not finite counts as that most; the reduction
/// runs in steps of `CHROMA_STEP`, so it ends after at most
/// `MAX_CHROMA / CHROMA_STEP` steps with chroma 0 (a grey, always shown).
pub fn from_oklch(l: f64, c: f64, h: f64) -> Rgb {
    let (sin, cos) = h.to_radians().sin_cos();
    let mut chroma = if c.is_nan() {
        0.0
    } else {
        c.clamp(0.0, MAX_CHROMA)
    };
    let enc = |v: f64| {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round().clamp(0.0, 255.0) as u8
    };
    let steps = (MAX_CHROMA / CHROMA_STEP).ceil() as usize + 1;
    let mut rgb = oklab_to_linear([l, 0.0, 0.0]);
    for _ in 0..=steps {
        rgb = oklab_to_linear([l, chroma * cos, chroma * sin]);
        if rgb.iter().all(|v| (-1e-9..=1.0 + 1e-9).contains(v)) || chroma <= 0.0 {
            break;
        }
        chroma = (chroma - CHROMA_STEP).max(0.0);
    }
    Rgb::new(enc(rgb[0]), enc(rgb[1]), enc(rgb[2]))
}

/// Largest OKLCH chroma [`from_oklch`] starts from: above every sRGB colour's.
const MAX_CHROMA: f64 = 0.4;
/// Chroma given up per step of [`from_oklch`]'s search for a showable colour.
const CHROMA_STEP: f64 = 0.005;

/// How much lightness counts when two groups' colours are compared: a
/// group's children are shaded across about half the lightness range
/// ([`child_shade`]), so two groups apart in lightness alone have children
/// that look alike side by side (misc's and java's oranges among 27 Debian
/// sections); hue and chroma are what tell them apart.
const GROUP_LIGHTNESS_WEIGHT: f64 = 0.35;

/// OKLab with lightness scaled by [`GROUP_LIGHTNESS_WEIGHT`].
fn group_lab(c: Rgb) -> [f64; 3] {
    let [l, a, b] = oklab(c);
    [GROUP_LIGHTNESS_WEIGHT * l, a, b]
}

/// The distance [`assign`] keeps between touching groups: OKLab with
/// lightness discounted (see `GROUP_LIGHTNESS_WEIGHT`).
pub fn group_distance(a: Rgb, b: Rgb) -> f64 {
    distance_lab(group_lab(a), group_lab(b))
}

/// Euclidean distance in OKLab: about 0.02 is a just noticeable difference.
pub fn distance(a: Rgb, b: Rgb) -> f64 {
    distance_lab(oklab(a), oklab(b))
}

fn distance_lab(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Lightness offset (see [`lighten`]) of the darkest sibling in [`child_shade`].
const SHADE_DARKEST: f64 = -0.18;
/// Lightness offset of the lightest sibling in [`child_shade`]. Asymmetric
/// towards light because dark text with a white halo reads on light fills.
const SHADE_LIGHTEST: f64 = 0.32;

/// Relative luminance (WCAG 2), 0 for black to 1 for white.
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * linear(c.r) + 0.7152 * linear(c.g) + 0.0722 * linear(c.b)
}

fn to_hsl(c: Rgb) -> (f64, f64, f64) {
    let r = f64::from(c.r) / 255.0;
    let g = f64::from(c.g) / 255.0;
    let b = f64::from(c.b) / 255.0;
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let l = 0.5 * (max + min);
    let d = max - min;
    if d == 0.0 {
        return (0.0, 0.0, l);
    }
    let s = d / (1.0 - (2.0 * l - 1.0).abs());
    let h = if max == r {
        ((g - b) / d).rem_euclid(6.0)
    } else if max == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    (h * 60.0, s, l)
}

fn from_hsl(h: f64, s: f64, l: f64) -> Rgb {
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let hp = h.rem_euclid(360.0) / 60.0;
    let x = c * (1.0 - (hp.rem_euclid(2.0) - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - 0.5 * c;
    // Clamped before the cast so round-off can never wrap a channel.
    let ch = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    Rgb::new(ch(r), ch(g), ch(b))
}

/// Changes the HSL lightness of `color`, keeping hue and saturation. `amount` in
/// `[-1, 1]` (clamped): positive moves lightness that fraction of the way to white,
/// negative that fraction of the way to black. Working in fractions of the
/// remaining range means repeated calls (one per hierarchy level) never leave the
/// gamut or collapse to pure white.
///
/// HSL rather than Lab: the palette hues are already chosen by Tableau, we only
/// need a monotone, cheap, dependency-free lightness knob.
pub fn lighten(color: Rgb, amount: f64) -> Rgb {
    let amount = if amount.is_finite() {
        amount.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let (h, s, l) = to_hsl(color);
    let l = if amount >= 0.0 {
        l + (1.0 - l) * amount
    } else {
        l * (1.0 + amount)
    };
    from_hsl(h, s, l.clamp(0.0, 1.0))
}

/// The colour of child `index` of `count` siblings under a parent of colour
/// `parent`: the parent's hue in lightness steps spread evenly from 18 % darker
/// to 32 % lighter (see [`lighten`]). Only children keep the parent's colour.
///
/// Consecutive indices alternate between the darker and the lighter half of the
/// range (0, 2, 4, … take the dark steps; 1, 3, 5, … the light ones), because
/// siblings next to each other in the data are often next to each other in a
/// neighbourhood-preserving layout and should not get near-identical shades.
pub fn child_shade(parent: Rgb, index: usize, count: usize) -> Rgb {
    if count <= 1 {
        return parent;
    }
    let index = index.min(count - 1);
    let half = count.div_ceil(2);
    let step = if index % 2 == 0 {
        index / 2
    } else {
        half + index / 2
    };
    let t = step as f64 / (count - 1) as f64;
    lighten(parent, SHADE_DARKEST + t * (SHADE_LIGHTEST - SHADE_DARKEST))
}

/// The colour of child `index` of `count` siblings under a parent of colour
/// `parent` whose main child (the heaviest) is `main`: as [`child_shade`],
/// except that the main child keeps the parent's colour exactly, taking the
/// lightness step nearest the parent's (the child that step was for takes
/// the main child's). So the parent's colour, the one its legend swatch
/// shows, is on the map too, on its largest cell (down the hierarchy, its
/// heaviest leaf): issue 21, a legend swatch `#8cd17d` whose largest cell was
/// `#65c151`.
pub fn sibling_shade(parent: Rgb, index: usize, count: usize, main: usize) -> Rgb {
    if count <= 1 || index == main {
        return parent;
    }
    let index = index.min(count - 1);
    let half = count.div_ceil(2);
    let step = |i: usize| if i % 2 == 0 { i / 2 } else { half + i / 2 };
    let offset =
        |s: usize| SHADE_DARKEST + s as f64 / (count - 1) as f64 * (SHADE_LIGHTEST - SHADE_DARKEST);
    let nearest = (0..count)
        .min_by(|&a, &b| offset(a).abs().total_cmp(&offset(b).abs()))
        .unwrap_or(0);
    let own = if step(index) == nearest && main < count {
        step(main)
    } else {
        step(index)
    };
    lighten(parent, offset(own))
}

#[cfg(test)]
mod tests {
    use super::super::distinct::LEGEND_DISTANCE;
    use super::*;

    #[test]
    fn hex_round_trip() {
        assert_eq!(Rgb::from_hex("#4E79A7"), Some(TABLEAU10[0]));
        assert_eq!(Rgb::from_hex("#4e79a7").unwrap().to_hex(), "#4e79a7");
        assert_eq!(Rgb::from_hex("#f0a"), Some(Rgb::new(0xff, 0x00, 0xaa)));
        for bad in [
            "", "#", "4e79a7", "#4e79a", "#12345g", "#ffff", "#+1+2+3", "#ééé",
        ] {
            assert_eq!(Rgb::from_hex(bad), None, "{bad}");
        }
    }

    #[test]
    fn palettes_are_tableau() {
        let t10: Vec<String> = TABLEAU10.iter().map(|c| c.to_hex()).collect();
        assert_eq!(
            t10.join(" "),
            "#4e79a7 #f28e2b #e15759 #76b7b2 #59a14f #edc948 #b07aa1 #ff9da7 #9c755f #bab0ac"
        );
        assert_eq!(TABLEAU20.len(), 20);
        assert_eq!(group_palette(PaletteKind::Tableau, 10).len(), 10);
        assert_eq!(group_palette(PaletteKind::Tableau, 11).len(), 20);
        assert_eq!(group_palette(PaletteKind::Tableau, 154).len(), 154);
        assert_eq!(
            group_palette(PaletteKind::Colorblind, 30),
            OKABE_ITO.to_vec()
        );
    }

    #[test]
    fn oklab_matches_published_values() {
        // Ottosson's reference: white is L = 1, a = b = 0; sRGB red is
        // (0.628, 0.225, 0.126).
        let w = oklab(WHITE);
        assert!((w[0] - 1.0).abs() < 1e-3 && w[1].abs() < 1e-3 && w[2].abs() < 1e-3);
        let r = oklab(Rgb::new(255, 0, 0));
        assert!(
            (r[0] - 0.628).abs() < 1e-3
                && (r[1] - 0.2249).abs() < 1e-3
                && (r[2] - 0.1258).abs() < 1e-3
        );
        // Round trip through OKLCH.
        for c in TABLEAU20 {
            let [l, a, b] = oklab(c);
            let back = from_oklch(l, a.hypot(b), b.atan2(a).to_degrees());
            assert!(distance(back, c) < 0.01, "{c} {back}");
        }
    }

    fn assert_all_distinct(colors: &[Rgb]) {
        let unique: std::collections::HashSet<Rgb> = colors.iter().copied().collect();
        assert_eq!(unique.len(), colors.len());
    }

    #[test]
    fn generated_colors_are_distinct_and_mid_tone() {
        let colors = generated(300);
        assert_all_distinct(&colors);
        for c in &colors {
            let l = oklab(*c)[0];
            assert!((0.55..0.85).contains(&l), "{c}: L {l}");
        }
        assert_eq!(
            generated(5),
            generated(300)[..5].to_vec(),
            "a prefix is stable"
        );
    }

    #[test]
    fn a_new_group_takes_no_colour_like_a_kept_one() {
        // Ten groups kept Tableau 10's colours; the map grows to 25, whose
        // palette (Tableau 20 and on) holds near twins of four of them.
        let n = 25;
        let fixed: Vec<Option<Rgb>> = (0..n).map(|g| TABLEAU10.get(g).copied()).collect();
        let order: Vec<usize> = (0..n).collect();
        let colors = assign(&group_palette(PaletteKind::Tableau, n), &order, &[], &fixed);
        for (g, c) in colors.iter().enumerate().skip(TABLEAU10.len()) {
            for kept in TABLEAU10 {
                let d = super::super::color_difference::delta_e(*c, kept);
                assert!(
                    d >= LEGEND_ALIKE,
                    "group {g}: {c} beside kept {kept}: ΔE00 {d}"
                );
            }
        }
    }

    #[test]
    fn adjacent_groups_get_distant_colors() {
        // A wheel: hub 0 touches 1..=12, each rim group touches the next.
        let n = 13;
        let mut adjacent: Vec<(usize, usize)> = (1..n).map(|i| (0, i)).collect();
        adjacent.extend((1..n).map(|i| (i, if i + 1 < n { i + 1 } else { 1 })));
        let order: Vec<usize> = (0..n).collect();
        for kind in [PaletteKind::Tableau, PaletteKind::Colorblind] {
            let palette = group_palette(kind, n);
            let colors = assign(&palette, &order, &adjacent, &vec![None; n]);
            for &(a, b) in &adjacent {
                assert!(
                    group_distance(colors[a], colors[b]) >= ALIKE,
                    "{kind:?}: {a} {b}"
                );
            }
            if kind == PaletteKind::Tableau {
                let mut unique = colors.clone();
                unique.sort_by_key(|c| c.to_hex());
                unique.dedup();
                assert_eq!(unique.len(), n, "every group its own colour");
            }
            if kind == PaletteKind::Tableau {
                let mut unique = colors.clone();
                unique.sort_by_key(|c| c.to_hex());
                unique.dedup();
                assert_eq!(unique.len(), n, "every group its own colour");
                assert_eq!(colors[0], TABLEAU20[0], "the first group, the first colour");
            }
        }
        // Ten groups, Tableau 10: every colour once, even where the last
        // free colour (grey) is close to a neighbour's (teal): a swap fixes it.
        let mut ring: Vec<(usize, usize)> = (0..10).map(|i| (i, (i + 1) % 10)).collect();
        ring.push((3, 9));
        let colors = assign(&TABLEAU10, &(0..10).collect::<Vec<_>>(), &ring, &[None; 10]);
        let mut unique = colors.clone();
        unique.sort_by_key(|c| c.to_hex());
        unique.dedup();
        assert_eq!(unique.len(), 10);
        for &(a, b) in &ring {
            assert!(group_distance(colors[a], colors[b]) >= ALIKE, "{a} {b}");
        }
        // A group's own colour is kept.
        let own = Rgb::new(1, 2, 3);
        let colors = assign(&TABLEAU10, &[0, 1], &[(0, 1)], &[Some(own), None]);
        assert_eq!(colors[0], own);
    }

    /// A flat map's top level is its leaves: 2,000 groups in a grid (each
    /// touching up to eight others) with a generated palette get their own
    /// colours with no alike neighbours. Before the search judged trials
    /// locally, 1,061 such groups took minutes; this runs in well under a
    /// second in a debug build.
    #[test]
    fn thousands_of_groups_are_coloured_apart() {
        let (w, h) = (50, 40);
        let adjacent = grid(w, h);
        let n = w * h;
        let palette = group_palette(PaletteKind::Tableau, n);
        let colors = assign(
            &palette,
            &(0..n).collect::<Vec<_>>(),
            &adjacent,
            &vec![None; n],
        );
        let alike = adjacent
            .iter()
            .filter(|&&(a, b)| group_distance(colors[a], colors[b]) < ALIKE)
            .count();
        assert_eq!(alike, 0, "alike neighbours among {} pairs", adjacent.len());
        let mut unique = colors.clone();
        unique.sort_by_key(|c| c.to_hex());
        unique.dedup();
        assert_eq!(unique.len(), n, "every group its own colour");
    }

    /// A `w` × `h` grid of groups, each touching up to eight others.
    fn grid(w: usize, h: usize) -> Vec<(usize, usize)> {
        let mut adjacent = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let g = y * w + x;
                for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                    if x + dx < w && y + dy < h {
                        adjacent.push((g, (y + dy) * w + x + dx));
                    }
                }
                if x > 0 && y + 1 < h {
                    adjacent.push((g, (y + 1) * w + x - 1));
                }
            }
        }
        adjacent
    }

    /// Issue 21, item 1: 2,371 top-level groups or more hung every build,
    /// because the generated palette searched for a 2,371st distinct colour
    /// that its rings do not have. Any count must be coloured, in bounded
    /// time, with touching groups apart. Each count runs on its own thread
    /// and the test waits for it with a generous bound (a hang fails the
    /// test instead of stalling the suite).
    #[test]
    fn any_number_of_groups_is_coloured_in_bounded_time() {
        for (w, h) in [(2_371, 1), (100, 50), (200, 100)] {
            let n = w * h;
            let (tx, rx) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                let adjacent = grid(w, h);
                let palette = group_palette(PaletteKind::Tableau, n);
                let colors = assign(
                    &palette,
                    &(0..n).collect::<Vec<_>>(),
                    &adjacent,
                    &vec![None; n],
                );
                let _ = tx.send((palette.len(), colors, adjacent));
            });
            let (len, colors, adjacent) = rx
                .recv_timeout(std::time::Duration::from_secs(WAIT_SECS))
                .unwrap_or_else(|_| panic!("{n} groups: no colours after {WAIT_SECS} s"));
            assert!(len > 0 && len <= n, "{n} groups: palette of {len}");
            assert_eq!(colors.len(), n);
            let alike = adjacent
                .iter()
                .filter(|&&(a, b)| group_distance(colors[a], colors[b]) < ALIKE)
                .count();
            assert_eq!(alike, 0, "{n} groups: alike neighbours");
        }
    }

    /// How long a test waits for work that must finish: far above what it
    /// takes (well under a second), so only a hang reaches it.
    const WAIT_SECS: u64 = 300;

    #[test]
    fn hsl_round_trip_is_lossless_on_the_palette() {
        for c in TABLEAU20.iter().chain([WHITE, Rgb::new(0, 0, 0)].iter()) {
            assert_eq!(lighten(*c, 0.0), *c);
        }
    }

    #[test]
    fn lighten_is_monotone_and_bounded() {
        let c = TABLEAU10[0];
        assert_eq!(lighten(c, 1.0), WHITE);
        assert_eq!(lighten(c, -1.0), Rgb::new(0, 0, 0));
        assert!(luminance(lighten(c, 0.3)) > luminance(c));
        assert!(luminance(lighten(c, -0.3)) < luminance(c));
        assert_eq!(lighten(c, f64::NAN), c);
    }

    /// Issue 21: the legend showed a group's colour that no cell had. The
    /// main child keeps it; the siblings stay distinct from it and from each
    /// other.
    #[test]
    fn the_main_child_keeps_its_parents_colour() {
        let p = TABLEAU20[5];
        for count in 2..12 {
            for main in 0..count {
                let shades: Vec<Rgb> = (0..count)
                    .map(|i| sibling_shade(p, i, count, main))
                    .collect();
                assert_eq!(shades[main], p, "{count} children, main {main}");
                for i in 0..count {
                    for j in 0..i {
                        assert_ne!(shades[i], shades[j], "{count}: {i} {j}");
                    }
                }
            }
        }
        assert_eq!(sibling_shade(p, 0, 1, 0), p);
    }

    #[test]
    fn child_shades_are_deterministic_and_distinct() {
        let p = TABLEAU10[4];
        assert_eq!(child_shade(p, 0, 1), p);
        let shades: Vec<Rgb> = (0..6).map(|i| child_shade(p, i, 6)).collect();
        let again: Vec<Rgb> = (0..6).map(|i| child_shade(p, i, 6)).collect();
        assert_eq!(shades, again);
        for i in 0..6 {
            for j in 0..i {
                assert_ne!(shades[i], shades[j], "{i} {j}");
            }
        }
        // Neighbours in index order alternate dark/light.
        assert!(luminance(shades[0]) < luminance(shades[1]));
        assert!(luminance(shades[1]) > luminance(shades[2]));
    }

    /// `count` candidates of the generated palette picked one by one, each
    /// the farthest from `seed` and the picks before it.
    fn farthest_points(seed: &[Rgb], count: usize) -> Vec<Rgb> {
        let candidates = generated(usize::MAX);
        let lab: Vec<[f64; 3]> = candidates.iter().map(|&c| cielab(c)).collect();
        let mut nearest: Vec<f64> = lab
            .iter()
            .map(|c| {
                seed.iter()
                    .map(|&s| delta_e_lab(*c, cielab(s)))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mut picks = Vec::with_capacity(count);
        for _ in 0..count {
            let k = (0..candidates.len())
                .max_by(|&a, &b| nearest[a].total_cmp(&nearest[b]).then(b.cmp(&a)))
                .expect("candidates");
            picks.push(candidates[k]);
            for (i, c) in lab.iter().enumerate() {
                nearest[i] = nearest[i].min(delta_e_lab(*c, lab[k]));
            }
        }
        picks
    }

    fn closest_pair(colors: &[Rgb]) -> f64 {
        let lab: Vec<[f64; 3]> = colors.iter().map(|&c| cielab(c)).collect();
        let mut least = f64::INFINITY;
        for i in 0..lab.len() {
            for j in 0..i {
                least = least.min(delta_e_lab(lab[i], lab[j]));
            }
        }
        least
    }

    #[test]
    fn the_table_is_the_farthest_point_picks() {
        let picks = farthest_points(&TABLEAU20, 100);
        let table: Vec<String> = picks
            .iter()
            .map(|c| format!("Rgb::new(0x{:02x}, 0x{:02x}, 0x{:02x}),", c.r, c.g, c.b))
            .collect();
        assert_eq!(FARTHEST.to_vec(), picks, "the table:\n{}", table.join("\n"));
    }

    #[test]
    fn no_two_colours_of_a_legend_look_alike() {
        // The stated distance: up to 60 groups no pair closer than Tableau
        // 20's own closest pair (ΔE00 9.1); at 120 groups, 6.5.
        let t20 = closest_pair(&TABLEAU20);
        assert!((9.0..9.2).contains(&t20), "{t20}");
        for n in [21, 30, 45, 60] {
            let got = closest_pair(&extended(n));
            assert!(got >= LEGEND_DISTANCE, "{n} groups: ΔE00 {got}");
        }
        let got = closest_pair(&extended(120));
        assert!(got >= 6.5, "120 groups: ΔE00 {got}");
        // What the generated palette alone gave 30 groups.
        assert!(closest_pair(&generated(30)) < 3.0);
    }

    #[test]
    fn a_longer_palette_extends_a_shorter_one() {
        let long = extended(400);
        assert_all_distinct(&long);
        for n in [1, 20, 21, 119, 120, 121, 300] {
            assert_eq!(extended(n), long[..n].to_vec(), "{n}");
        }
    }
}
