//! The kinds of output, one home for each: its names in a config and a
//! path, its content type in the preview server, whether the style and the
//! page's history shape it (its render key), and its renderer. The build's
//! stage graph, the pipeline and the server all ask an [`OutputKind`].

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{html_page_with_parts, picture_with, Parts, Picture, Style};
use crate::layout::Computed;

/// Kinds of output.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum OutputKind {
    /// A picture as SVG.
    Svg,
    /// A picture as PNG.
    Png,
    /// The layout JSON.
    Json,
    /// An interactive HTML page.
    Html,
}

/// Why an output could not be rendered.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The PNG could not be made.
    #[cfg(feature = "png")]
    #[error(transparent)]
    Png(#[from] super::PngError),
    /// The kind needs a Cargo feature this build was compiled without.
    #[error("{what} needs nptreemap built with the `{feature}` feature")]
    Unsupported {
        /// What it asks for (`PNG output`).
        what: &'static str,
        /// The feature that provides it.
        feature: &'static str,
    },
}

impl OutputKind {
    /// The kind a path's extension names (`svg`, `png`, `json`, `html` or
    /// `htm`, any case).
    pub fn of_path(path: &Path) -> Option<OutputKind> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "svg" => Some(OutputKind::Svg),
            "png" => Some(OutputKind::Png),
            "json" => Some(OutputKind::Json),
            "html" | "htm" => Some(OutputKind::Html),
            _ => None,
        }
    }

    /// Its name in a config (`kind:`) and in `-v` lines.
    pub fn name(self) -> &'static str {
        match self {
            OutputKind::Svg => "svg",
            OutputKind::Png => "png",
            OutputKind::Json => "json",
            OutputKind::Html => "html",
        }
    }

    /// The content type the preview server answers it with.
    pub fn content_type(self) -> &'static str {
        match self {
            OutputKind::Svg => "image/svg+xml",
            OutputKind::Png => "image/png",
            OutputKind::Json => "application/json",
            OutputKind::Html => "text/html; charset=utf-8",
        }
    }

    /// Whether the picture's style shapes it (the layout JSON has none).
    pub fn styled(self) -> bool {
        self != OutputKind::Json
    }

    /// Whether it draws the picture from its SVG text (the SVG and the PNG,
    /// which share that text between the outputs of one layout).
    pub fn draws_picture(self) -> bool {
        matches!(self, OutputKind::Svg | OutputKind::Png)
    }

    /// Whether it carries the past layouts (`history:`), which are then one
    /// more input of its render.
    pub fn shows_history(self) -> bool {
        self == OutputKind::Html
    }

    /// Its bytes for a finished layout. `past` are the layouts before it,
    /// oldest first (used when it [shows history](OutputKind::shows_history));
    /// `picture` keeps the picture between the outputs of one layout (the
    /// SVG and the PNG draw the same picture); `parts` the
    /// labels of this render's other outputs and of the render before.
    pub fn render(
        self,
        computed: &Computed,
        style: &Style,
        scale: f64,
        past: &[std::sync::Arc<Computed>],
        picture: &mut Option<Arc<Picture>>,
        parts: &Parts,
    ) -> Result<Vec<u8>, OutputError> {
        let mut drawn = || {
            Arc::clone(
                picture.get_or_insert_with(|| Arc::new(picture_with(computed, style, parts))),
            )
        };
        Ok(match self {
            OutputKind::Svg => drawn().text.clone().into_bytes(),
            #[cfg(feature = "png")]
            OutputKind::Png => parts.png(&drawn(), scale)?,
            #[cfg(not(feature = "png"))]
            OutputKind::Png => {
                let _ = (&mut drawn, scale);
                return Err(OutputError::Unsupported {
                    what: "PNG output",
                    feature: "png",
                });
            }
            OutputKind::Json => {
                crate::layout_json::document_with(computed, Some(parts.documents())).into_bytes()
            }
            OutputKind::Html => html_page_with_parts(computed, style, past, parts).into_bytes(),
        })
    }
}
