//! Colours for the pictures: the Tableau 10 / Tableau 20 categorical palettes
//! and lightness variations in HSL, over the model's [`Rgb`] (parsed once, by
//! the formats crate). Owns colour arithmetic only; may not know about nodes,
//! layouts or SVG.

pub use nptreemap_formats::Rgb;

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

/// Lightness offset (see [`lighten`]) of the darkest sibling in [`child_shade`].
const SHADE_DARKEST: f64 = -0.18;
/// Lightness offset of the lightest sibling in [`child_shade`]. Asymmetric
/// towards light because dark text with a white halo reads on light fills.
const SHADE_LIGHTEST: f64 = 0.32;

/// Relative luminance (WCAG 2), 0 for black to 1 for white.
pub fn luminance(c: Rgb) -> f64 {
    let lin = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    0.2126 * lin(c.r) + 0.7152 * lin(c.g) + 0.0722 * lin(c.b)
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

/// The categorical palette for `groups` top-level groups: Tableau 10 up to ten
/// groups, Tableau 20 above (colours repeat past twenty).
pub fn categorical(groups: usize) -> &'static [Rgb] {
    if groups <= TABLEAU10.len() {
        &TABLEAU10
    } else {
        &TABLEAU20
    }
}

#[cfg(test)]
mod tests {
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
        assert_eq!(categorical(10).len(), 10);
        assert_eq!(categorical(11).len(), 20);
    }

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
}
