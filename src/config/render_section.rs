//! The `render:` section of a config: how SVG, PNG and HTML pictures look
//! (title, legend, colours, labels, tabs), with the deserializers that check
//! each value as it is read and name the key. Split from `config.rs`, which
//! owns the file, the datasets and the limits, and turns this section into
//! the renderers' [`Style`](crate::render::Style).

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer};

use super::ConfigError;
use crate::render::{ColorScale, LabelStyle, LegendOrder, PaletteKind, Rgb, Style};

/// The `render` section: how SVG, PNG and HTML pictures look. Colours are
/// `#rrggbb` or `#rgb`, parsed when the config is read.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderConfig {
    /// Title above every picture; a dataset's own `title` wins. Default: none.
    pub title: Option<String>,
    /// Legend band under the map (top-level groups, tab and marker keys). Default: true.
    pub legend: bool,
    /// Order of the legend's groups: `weight`, `data` or `names`. Default: weight.
    #[serde(deserialize_with = "legend_order")]
    pub legend_order: LegendOrder,
    /// Palette of the top-level groups: `tableau` or `colorblind`. Default: tableau.
    #[serde(deserialize_with = "palette")]
    pub palette: PaletteKind,
    /// Pinned colours of top-level groups, by the group's id or its label
    /// (`{Europe: "#1f77b4"}`): a pinned group keeps its colour whatever the
    /// edit, and the other groups are coloured around it. Default: none.
    #[serde(deserialize_with = "group_colors")]
    pub colors: BTreeMap<String, Rgb>,
    /// Canvas background colour, or `none` for transparent. Default: `#ffffff`.
    #[serde(deserialize_with = "background")]
    pub background: Option<Rgb>,
    /// Colour of the line around the root outline. Default: `#4d4d4d`.
    #[serde(deserialize_with = "border_color")]
    pub border_color: Rgb,
    /// Width of that line; 0 draws none. Default: 0.
    pub border_width: f64,
    /// Colour of cell outlines and label halos. Default: `#ffffff`.
    #[serde(deserialize_with = "stroke")]
    pub stroke: Rgb,
    /// Outline width between top-level groups; each level down halves it. Default: 3.
    pub stroke_width: f64,
    /// Leaf labels and group names: `true`, `false`, or their settings.
    #[serde(deserialize_with = "labels")]
    pub labels: LabelStyle,
    /// Interlocking tabs on the shared edges of similar neighbours. Default: true.
    pub tabs: bool,
    /// Dashed red links between similar cells that are not neighbours. Default: false.
    pub unrealized_links: bool,
    /// Count markers on cells with similar cells that are not neighbours. Default: true.
    pub unlinked_markers: bool,
    /// Largest share of the map the count markers may cover together. Default: 0.015.
    pub unlinked_markers_share: f64,    /// Colour the leaves by this numeric column (hierarchy JSON: node
    /// property) instead of by group. Default: none.
    pub color_by: Option<String>,
    /// The scale of `color_by`: `sequential` or `diverging`. Default: sequential.
    #[serde(deserialize_with = "color_scale")]
    pub color_scale: ColorScale,
    /// The value a diverging scale centres on. Default: 0.
    pub color_midpoint: f64,
}

fn color_scale<'de, D: Deserializer<'de>>(d: D) -> Result<ColorScale, D::Error> {
    let text = String::deserialize(d)?;
    ColorScale::from_name(&text).ok_or_else(|| {
        serde::de::Error::custom(format_args!(
            "color_scale: unknown scale {text:?}, expected sequential or diverging"
        ))
    })
}

/// `render.labels`: a boolean (all labels on or off) or the settings.
fn labels<'de, D: Deserializer<'de>>(d: D) -> Result<LabelStyle, D::Error> {
    struct Visitor;
    impl<'de> serde::de::Visitor<'de> for Visitor {
        type Value = LabelStyle;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("true, false or a map of label settings")
        }
        fn visit_bool<E: serde::de::Error>(self, on: bool) -> Result<LabelStyle, E> {
            Ok(LabelStyle {
                show: on,
                groups: on,
                ..LabelStyle::default()
            })
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<LabelStyle, A::Error> {
            LabelStyle::deserialize(serde::de::value::MapAccessDeserializer::new(map))
        }
    }
    d.deserialize_any(Visitor)
}

fn legend_order<'de, D: Deserializer<'de>>(d: D) -> Result<LegendOrder, D::Error> {
    let text = String::deserialize(d)?;
    LegendOrder::from_name(&text).ok_or_else(|| {
        serde::de::Error::custom(format_args!(
            "legend_order: unknown order {text:?}, expected weight, data or names"
        ))
    })
}

/// `render.colors`: a map of group to colour, each colour parsed here so the
/// error names the group.
fn group_colors<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, Rgb>, D::Error> {
    let text: BTreeMap<String, String> = BTreeMap::deserialize(d)?;
    text.into_iter()
        .map(|(group, color)| {
            let rgb = color.parse().map_err(|e| {
                serde::de::Error::custom(format_args!("colors: {group:?}: {e}"))
            })?;
            Ok((group, rgb))
        })
        .collect()
}

fn palette<'de, D: Deserializer<'de>>(d: D) -> Result<PaletteKind, D::Error> {
    let text = String::deserialize(d)?;
    PaletteKind::from_name(&text).ok_or_else(|| {
        serde::de::Error::custom(format_args!(
            "palette: unknown palette {text:?}, expected tableau or colorblind"
        ))
    })
}

impl Default for RenderConfig {
    fn default() -> Self {
        let style = Style::default();
        let cells = &style.cells;
        Self {
            title: None,
            legend: style.legend,
            legend_order: style.legend_order,
            palette: cells.palette,
            colors: BTreeMap::new(),
            background: cells.background,
            border_color: DEFAULT_BORDER_COLOR,
            border_width: 0.0,
            stroke: cells.stroke,
            stroke_width: cells.stroke_width,
            labels: LabelStyle::default(),
            tabs: style.tabs,
            unrealized_links: style.overlay.show_unrealized,
            unlinked_markers: style.overlay.unlinked_markers,
            unlinked_markers_share: style.overlay.marker_share,
            color_by: None,
            color_scale: ColorScale::default(),
            color_midpoint: 0.0,
        }
    }
}

impl RenderConfig {
    /// Checks colours and sizes; the error names the key.
    pub(super) fn validate(&self) -> Result<(), ConfigError> {
        let bad = |key: &str, message: String| ConfigError::Value {
            field: format!("render.{key}"),
            message,
        };
        for (key, v) in [
            ("border_width", self.border_width),
            ("stroke_width", self.stroke_width),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(key, format!("{v} must be a number >= 0")));
            }
        }
        for (key, v) in [
            ("labels.min_size", self.labels.min_size),
            ("labels.max_size", self.labels.max_size),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(key, format!("{v} must be a positive number")));
            }
        }
        if self.labels.min_size > self.labels.max_size {
            return Err(bad(
                "labels.min_size",
                format!(
                    "{} is larger than labels.max_size {}",
                    self.labels.min_size, self.labels.max_size
                ),
            ));
        }
        if !self.color_midpoint.is_finite() {
            return Err(bad(
                "color_midpoint",
                format!("{} must be a number", self.color_midpoint),
            ));
        }
        if self.color_by.as_deref().is_some_and(|c| c.trim().is_empty()) {
            return Err(bad("color_by", "must name a column".to_string()));
        }
        let share = self.unlinked_markers_share;
        if !(share.is_finite() && (0.0..=1.0).contains(&share)) {
            return Err(bad(
                "unlinked_markers_share",
                format!("{share} must be a share between 0 and 1"),
            ));
        }
        Ok(())
    }
}

/// The colour of the border line when `render.border_width` is set.
const DEFAULT_BORDER_COLOR: Rgb = Rgb::new(0x4d, 0x4d, 0x4d);

/// A colour of the `render` section, the key named in the error (the YAML
/// error's own path stops at the section).
fn color_of<'de, D: Deserializer<'de>>(d: D, key: &str) -> Result<Rgb, D::Error> {
    let text = String::deserialize(d)?;
    text.parse()
        .map_err(|e| serde::de::Error::custom(format_args!("{key}: {e}")))
}

/// `render.background`: `none` (transparent) or a colour.
fn background<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Rgb>, D::Error> {
    let text = String::deserialize(d)?;
    if text == "none" {
        return Ok(None);
    }
    text.parse().map(Some).map_err(|e| {
        serde::de::Error::custom(format_args!("background: {e}, or none for transparent"))
    })
}

fn border_color<'de, D: Deserializer<'de>>(d: D) -> Result<Rgb, D::Error> {
    color_of(d, "border_color")
}

fn stroke<'de, D: Deserializer<'de>>(d: D) -> Result<Rgb, D::Error> {
    color_of(d, "stroke")
}
