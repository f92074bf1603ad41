//! One build of a configured dataset: read its files, parse them with its
//! format, lay it out, render every output in memory. Writing is a separate
//! step (`write_outputs`), so a failure anywhere leaves every existing output
//! untouched. No loop, no watcher, no printing.

use std::path::PathBuf;

use crate::config::{Config, DatasetConfig, OutputKind};
use crate::layout::{compute, Computed, LayoutError};
use crate::neighborhood::adjacency::level_adjacency;
use crate::render::html::{html, HtmlData, HtmlNode};
use crate::render::overlay::{overlay, with_overlay, Link, OverlayStyle};
use crate::render::{layout_json, png, svg, ConstraintOut, JsonExtras, PngError, SvgStyle};
use crate::{metrics, store, workspace};
use nptreemap_formats::{registry, Dataset, FormatOptions, Inputs};

/// Why a dataset could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The config names a format that is not registered.
    #[error("dataset {dataset:?}: unknown format {format:?} (known: {known})")]
    UnknownFormat {
        /// The dataset's name.
        dataset: String,
        /// The format named.
        format: String,
        /// The registered names.
        known: String,
    },
    /// The format needs an input the config does not give.
    #[error("dataset {dataset:?}: format {format:?} needs `files: {{{role}: ...}}`")]
    MissingFile {
        /// The dataset's name.
        dataset: String,
        /// The format.
        format: String,
        /// The missing role.
        role: String,
    },
    /// The config gives an input the format does not read.
    #[error(
        "dataset {dataset:?}: format {format:?} reads no file called {role:?} (it reads: {roles})"
    )]
    UnknownRole {
        /// The dataset's name.
        dataset: String,
        /// The format.
        format: String,
        /// The extra role.
        role: String,
        /// The roles it reads.
        roles: String,
    },
    /// An input file could not be read or parsed.
    #[error(transparent)]
    Input(#[from] workspace::InputError),
    /// The layout could not be made.
    #[error("dataset {dataset:?}: {source}")]
    Layout {
        /// The dataset's name.
        dataset: String,
        /// Why.
        source: LayoutError,
    },
    /// The PNG renderer refused the picture (see [`PngError`]).
    #[error("{}: {source}", .path.display())]
    Png {
        /// The output.
        path: PathBuf,
        /// Why.
        source: PngError,
    },
}

/// A dataset laid out and rendered, not yet written.
#[derive(Debug)]
pub struct Built {
    /// The dataset's name.
    pub name: String,
    /// The layout and its constraints.
    pub computed: Computed,
    /// Every output's path and bytes.
    pub outputs: Vec<(PathBuf, Vec<u8>)>,
}

/// Reads and parses one configured dataset.
pub fn load(d: &DatasetConfig) -> Result<Dataset, BuildError> {
    let format = registry::find(&d.format).ok_or_else(|| BuildError::UnknownFormat {
        dataset: d.name.clone(),
        format: d.format.clone(),
        known: registry::names().join(", "),
    })?;
    let roles = format.roles();
    for role in d.files.keys() {
        if !roles.iter().any(|r| r.name == role) {
            return Err(BuildError::UnknownRole {
                dataset: d.name.clone(),
                format: d.format.clone(),
                role: role.clone(),
                roles: roles.iter().map(|r| r.name).collect::<Vec<_>>().join(", "),
            });
        }
    }
    if let Some(r) = roles
        .iter()
        .find(|r| r.required && !d.files.contains_key(r.name))
    {
        return Err(BuildError::MissingFile {
            dataset: d.name.clone(),
            format: d.format.clone(),
            role: r.name.to_string(),
        });
    }
    let mut bytes = Vec::new();
    for (role, path) in &d.files {
        bytes.push((role.as_str(), path, workspace::read_bytes(path)?));
    }
    let mut inputs = Inputs::new();
    for (role, _, b) in &bytes {
        inputs = inputs.with(role, b);
    }
    let f = &d.fields;
    let options = FormatOptions {
        id: f.id.clone(),
        label: f.label.clone(),
        weight: f.weight.clone(),
        color: f.color.clone(),
        parent: f.parent.clone(),
        path: f.path.clone(),
        groups: f.groups.clone(),
        strength: f.strength.clone(),
        genres: f.genres.clone(),
        separator: f.separator,
        genre_columns: f.genre_columns.clone(),
        fill_missing: f.fill_missing,
        ..FormatOptions::default()
    };
    format.parse(&inputs, &options).map_err(|e| {
        let path = bytes
            .iter()
            .find(|(role, _, _)| *role == e.role)
            .map(|(_, p, _)| (*p).clone())
            .unwrap_or_else(|| PathBuf::from(&e.role));
        BuildError::Input(workspace::InputError::Parse {
            path,
            source: Box::new(e.error),
        })
    })
}

/// Loads, lays out and renders one dataset, writing nothing.
pub fn build(config: &Config, d: &DatasetConfig) -> Result<Built, BuildError> {
    let dataset = load(d)?;
    let computed = compute(&dataset, &config.request(d)).map_err(|source| BuildError::Layout {
        dataset: d.name.clone(),
        source,
    })?;
    let mut outputs = Vec::new();
    for out in &d.outputs {
        let kind = out.kind.unwrap_or(OutputKind::Svg);
        outputs.push((
            out.path.clone(),
            render(&computed, kind, out.scale, &out.path)?,
        ));
    }
    Ok(Built {
        name: d.name.clone(),
        computed,
        outputs,
    })
}

/// One output's bytes for a computed layout (`path` only names it in errors).
pub fn render(
    computed: &Computed,
    kind: OutputKind,
    scale: f64,
    path: &std::path::Path,
) -> Result<Vec<u8>, BuildError> {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    Ok(match kind {
        OutputKind::Json => layout_json(dataset, layout, &json_extras(computed)).into_bytes(),
        OutputKind::Svg => picture(computed).into_bytes(),
        OutputKind::Png => png(&picture(computed), scale).map_err(|source| BuildError::Png {
            path: path.to_path_buf(),
            source,
        })?,
        OutputKind::Html => html_page(computed).into_bytes(),
    })
}

/// The interactive page: the picture (its unrealised links drawn, for the
/// page's checkbox to show or hide), and per cell its path from the root,
/// weight, neighbours and constraint partners for the hover highlight.
pub fn html_page(computed: &Computed) -> String {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    let style = OverlayStyle {
        show_unrealized: true,
        ..OverlayStyle::default()
    };
    let svg_text = picture_with(computed, &style);
    let mut by_depth: Vec<Vec<usize>> = vec![Vec::new(); dataset.max_depth() + 1];
    for (i, node) in dataset.nodes().iter().enumerate() {
        by_depth[node.depth].push(i);
    }
    let adjacency: Vec<_> = by_depth
        .iter()
        .map(|nodes| level_adjacency(layout, nodes, 1e-6))
        .collect();
    let mut partners: Vec<Vec<(String, bool)>> = vec![Vec::new(); dataset.len()];
    for (c, r) in computed.constraints.iter().zip(&computed.realized) {
        partners[c.a].push((dataset.node(c.b).id.clone(), *r));
        partners[c.b].push((dataset.node(c.a).id.clone(), *r));
    }
    let nodes = dataset
        .nodes()
        .iter()
        .enumerate()
        .map(|(i, node)| {
            let path: Vec<String> = dataset
                .path(i)
                .iter()
                .map(|k| dataset.node(*k).label.clone())
                .collect();
            HtmlNode {
                id: node.id.clone(),
                label: node.label.clone(),
                path,
                weight: node.value,
                depth: node.depth,
                leaf: node.children.is_empty(),
                neighbours: adjacency[node.depth]
                    .neighbours(i)
                    .iter()
                    .map(|j| dataset.node(*j).id.clone())
                    .collect(),
                partners: std::mem::take(&mut partners[i]),
            }
        })
        .collect();
    let title = dataset.node(dataset.root()).label.clone();
    html(&svg_text, &HtmlData { title, nodes })
}

/// The SVG picture: the treemap with, when there are constraints, the
/// interlocking tabs and unrealised-link markers of its deepest level (where the
/// paper draws them, method-reference §8.2–8.4) on top, the tabs under the labels.
pub fn picture(computed: &Computed) -> String {
    picture_with(computed, &OverlayStyle::default())
}

fn picture_with(computed: &Computed, style: &OverlayStyle) -> String {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    let base = svg(dataset, layout, &SvgStyle::default());
    if computed.constraints.is_empty() {
        return base;
    }
    let deepest = dataset.max_depth();
    let links: Vec<Link> = computed
        .constraints
        .iter()
        .zip(&computed.realized)
        .filter(|(c, _)| dataset.node(c.a).depth == deepest)
        .map(|(c, r)| Link {
            a: c.a,
            b: c.b,
            similarity: c.similarity,
            realized: *r,
        })
        .collect();
    with_overlay(&base, &overlay(dataset, layout, &links, style))
}

/// Writes a built dataset's outputs atomically; an output whose bytes would
/// not change is left alone. Returns the paths written.
pub fn write_outputs(built: &Built) -> std::io::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    for (path, bytes) in &built.outputs {
        if store::write_if_changed(path, bytes)? {
            written.push(path.clone());
        }
    }
    Ok(written)
}

/// The layout JSON's constraints and metrics for a computed layout.
pub fn json_extras(computed: &Computed) -> JsonExtras {
    let ds = &computed.dataset;
    let q = metrics::quality(ds, &computed.layout);
    JsonExtras {
        constraints: computed
            .constraints
            .iter()
            .zip(&computed.realized)
            .map(|(c, r)| ConstraintOut {
                a: ds.node(c.a).id.clone(),
                b: ds.node(c.b).id.clone(),
                similarity: c.similarity,
                strength: c.strength,
                realized: *r,
            })
            .collect(),
        metrics: vec![
            (
                "area_error_diagram_mean".to_string(),
                q.area_error_diagram_mean,
            ),
            (
                "area_error_diagram_max".to_string(),
                q.area_error_diagram_max,
            ),
            ("aspect_ratio_mean".to_string(), q.aspect_ratio_mean),
        ],
    }
}
