//! How different two colours look: CIELAB (D65) and the CIEDE2000 colour
//! difference, the measure the legend's distinctness is stated in (issue 32:
//! no two groups of a map closer than a stated ΔE00). Colour arithmetic only.
//!
//! Written out here, as OKLab is in [`palette`](crate::render::palette):
//! one published formula (Sharma, Wu & Dalal, "The CIEDE2000
//! color-difference formula", 2005), checked below against their test data,
//! rather than a colour-science crate with its own colour types for one
//! function.

use nptreemap_formats::Rgb;

/// The D65 white point in XYZ (Y = 1), as sRGB defines it.
const WHITE: [f64; 3] = [0.950_47, 1.0, 1.088_83];

/// An 8-bit sRGB channel decoded to linear light, 0 to 1 (the sRGB
/// transfer function; OKLab and WCAG luminance start from it too).
pub fn linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB (8 bits per channel) to CIELAB `[L*, a*, b*]` under D65: L* is 0 for
/// black and 100 for white.
pub fn cielab(c: Rgb) -> [f64; 3] {
    let (r, g, b) = (linear(c.r), linear(c.g), linear(c.b));
    let xyz = [
        0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b,
        0.212_672_9 * r + 0.715_152_2 * g + 0.072_175_0 * b,
        0.019_333_9 * r + 0.119_192_0 * g + 0.950_304_1 * b,
    ];
    // The cube root, with CIE's linear segment near black.
    let f = |t: f64| {
        const D: f64 = 6.0 / 29.0;
        if t > D * D * D {
            t.cbrt()
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    };
    let [fx, fy, fz] = [0, 1, 2].map(|k| f(xyz[k] / WHITE[k]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// The CIEDE2000 difference of two sRGB colours: about 1 is a just
/// noticeable difference, about 10 two colours no one takes for one.
pub fn delta_e(a: Rgb, b: Rgb) -> f64 {
    delta_e_lab(cielab(a), cielab(b))
}

/// The CIEDE2000 difference of two CIELAB colours (kL = kC = kH = 1),
/// step by step as in Sharma et al. (2005), equations 2–22.
pub fn delta_e_lab([l1, a1, b1]: [f64; 3], [l2, a2, b2]: [f64; 3]) -> f64 {
    const POW25_7: f64 = 6_103_515_625.0; // 25⁷
    let c_bar = (a1.hypot(b1) + a2.hypot(b2)) / 2.0;
    let g = 0.5 * (1.0 - (c_bar.powi(7) / (c_bar.powi(7) + POW25_7)).sqrt());
    let (a1, a2) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1, c2) = (a1.hypot(b1), a2.hypot(b2));
    let hue = |b: f64, a: f64| {
        if a == 0.0 && b == 0.0 {
            0.0
        } else {
            b.atan2(a).to_degrees().rem_euclid(360.0)
        }
    };
    let (h1, h2) = (hue(b1, a1), hue(b2, a2));
    let achromatic = c1 * c2 == 0.0;
    let dh = if achromatic {
        0.0
    } else {
        let d = h2 - h1;
        if d.abs() <= 180.0 {
            d
        } else if d > 180.0 {
            d - 360.0
        } else {
            d + 360.0
        }
    };
    let (dl, dc) = (l2 - l1, c2 - c1);
    let dh_big = 2.0 * (c1 * c2).sqrt() * (dh / 2.0).to_radians().sin();
    let l_mean = (l1 + l2) / 2.0;
    let c_mean = (c1 + c2) / 2.0;
    let h_mean = if achromatic {
        h1 + h2
    } else if (h1 - h2).abs() <= 180.0 {
        (h1 + h2) / 2.0
    } else if h1 + h2 < 360.0 {
        (h1 + h2 + 360.0) / 2.0
    } else {
        (h1 + h2 - 360.0) / 2.0
    };
    let cos = |deg: f64| deg.to_radians().cos();
    let t =
        1.0 - 0.17 * cos(h_mean - 30.0) + 0.24 * cos(2.0 * h_mean) + 0.32 * cos(3.0 * h_mean + 6.0)
            - 0.20 * cos(4.0 * h_mean - 63.0);
    let d_theta = 30.0 * (-((h_mean - 275.0) / 25.0).powi(2)).exp();
    let r_c = 2.0 * (c_mean.powi(7) / (c_mean.powi(7) + POW25_7)).sqrt();
    let l50 = (l_mean - 50.0).powi(2);
    let s_l = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let s_c = 1.0 + 0.045 * c_mean;
    let s_h = 1.0 + 0.015 * c_mean * t;
    let r_t = -(2.0 * d_theta).to_radians().sin() * r_c;
    let (l, c, h) = (dl / s_l, dc / s_c, dh_big / s_h);
    (l * l + c * c + h * h + r_t * c * h).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_sharma_wu_dalals_test_data() {
        // Pairs 1, 2, 7, 17 and 25 of the paper's Table 1 (with their
        // published ΔE00 to four decimals): a blue pair, a grey against a
        // near-grey, a large difference and a green pair.
        let pairs = [
            ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
            ([50.0, 3.1571, -77.2803], [50.0, 0.0, -82.7485], 2.8615),
            ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
            ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
            (
                [60.2574, -34.0099, 36.2677],
                [60.4626, -34.1751, 39.4387],
                1.2644,
            ),
        ];
        for (a, b, expected) in pairs {
            let got = delta_e_lab(a, b);
            assert!((got - expected).abs() < 5e-5, "{a:?} {b:?}: {got}");
            // The formula is symmetric.
            assert!((delta_e_lab(b, a) - got).abs() < 1e-9);
        }
        assert_eq!(delta_e_lab([40.0, 10.0, -5.0], [40.0, 10.0, -5.0]), 0.0);
    }

    #[test]
    fn cielab_of_white_and_red_are_the_published_values() {
        let white = cielab(Rgb::new(255, 255, 255));
        assert!((white[0] - 100.0).abs() < 1e-3 && white[1].abs() < 1e-3 && white[2].abs() < 1e-3);
        // sRGB red: L* 53.24, a* 80.09, b* 67.20 (the usual reference value).
        let red = cielab(Rgb::new(255, 0, 0));
        for (got, want) in red.iter().zip([53.24, 80.09, 67.20]) {
            assert!((got - want).abs() < 0.01, "{red:?}");
        }
        assert!(delta_e(Rgb::new(0, 0, 0), Rgb::new(255, 255, 255)) > 99.0);
    }
}
