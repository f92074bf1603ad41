//! [`Rgb`]: an opaque sRGB colour, parsed once from the CSS hex forms `#rgb`
//! and `#rrggbb` wherever a colour enters the program (a node's `color` field,
//! the config's `render:` colours) and written back as `#rrggbb`. Owns parsing
//! and formatting only; colour arithmetic (palettes, shades) is the renderer's.

use std::fmt;
use std::str::FromStr;

/// An opaque sRGB colour, 8 bits per channel.
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(try_from = "String")]
pub struct Rgb {
    /// Red, 0..=255.
    pub r: u8,
    /// Green, 0..=255.
    pub g: u8,
    /// Blue, 0..=255.
    pub b: u8,
}

impl Rgb {
    /// A colour from its three channels.
    pub const fn new(r: u8, g: u8, b: u8) -> Self {
        Self { r, g, b }
    }

    /// Parses `#rrggbb` or `#rgb` (either case; the `#` is required); `None`
    /// for anything else.
    pub fn from_hex(s: &str) -> Option<Self> {
        let hex = s.strip_prefix('#')?;
        if !hex.bytes().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        let digit = |i: usize| u8::from_str_radix(&hex[i..=i], 16).ok();
        match hex.len() {
            3 => Some(Self::new(digit(0)? * 17, digit(1)? * 17, digit(2)? * 17)),
            6 => {
                let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
                Some(Self::new(byte(0)?, byte(2)?, byte(4)?))
            }
            _ => None,
        }
    }

    /// `#rrggbb` in lower case; the same as `to_string()`.
    pub fn to_hex(self) -> String {
        self.to_string()
    }
}

impl fmt::Display for Rgb {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{:02x}{:02x}{:02x}", self.r, self.g, self.b)
    }
}

/// A string that is not a hex colour.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0:?} is not a colour (#rrggbb or #rgb)")]
pub struct ColorError(pub String);

impl FromStr for Rgb {
    type Err = ColorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Rgb::from_hex(s).ok_or_else(|| ColorError(s.to_string()))
    }
}

impl TryFrom<String> for Rgb {
    type Error = ColorError;

    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_forms_parse_and_print_lower_case() {
        assert_eq!(Rgb::from_hex("#4E79A7"), Some(Rgb::new(0x4e, 0x79, 0xa7)));
        assert_eq!(Rgb::from_hex("#fa0"), Some(Rgb::new(0xff, 0xaa, 0x00)));
        assert_eq!(Rgb::new(0x4e, 0x79, 0xa7).to_hex(), "#4e79a7");
        for bad in ["4e79a7", "#4e79a", "#ggg", "#ééé", "", "#", "red"] {
            assert_eq!(Rgb::from_hex(bad), None, "{bad}");
            assert_eq!(
                bad.parse::<Rgb>(),
                Err(ColorError(bad.to_string())),
                "{bad}"
            );
        }
    }
}
