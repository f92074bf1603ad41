//! One build of a configured dataset: read its files, parse them with its
//! format, lay it out, render every output in memory. Writing is a separate
//! step (`write_outputs`), so a failure anywhere leaves every existing output
//! untouched. No loop, no watcher, no printing.

use std::path::PathBuf;
use std::sync::Arc;

use crate::config::{Config, DatasetConfig, OutputConfig, OutputKind};
use crate::layout::{compute, Computed, LayoutError, Previous};
use crate::neighborhood::adjacency::level_adjacency;
use crate::render::html::{html, HtmlData, HtmlFrame, HtmlNode};
use crate::render::overlay::Link;
use crate::render::{layout_json, png, ConstraintOut, JsonExtras, PngError, Style};
use crate::{metrics, render, store, workspace};
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

/// One input file of a dataset, read.
#[derive(Clone, Debug, PartialEq)]
pub struct InputFile {
    /// The format's name for it (`nodes`, `pairs`, ...).
    pub role: String,
    /// Where it was read from.
    pub path: PathBuf,
    /// Its content.
    pub bytes: Vec<u8>,
}

/// Reads and parses one configured dataset.
pub fn load(d: &DatasetConfig) -> Result<Dataset, BuildError> {
    parse_inputs(d, &read_inputs(d)?)
}

/// Reads a dataset's input files (after checking the config names the roles
/// its format reads), without parsing them.
pub fn read_inputs(d: &DatasetConfig) -> Result<Vec<InputFile>, BuildError> {
    let format = format_of(d)?;
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
    d.files
        .iter()
        .map(|(role, path)| {
            Ok(InputFile {
                role: role.clone(),
                path: path.clone(),
                bytes: workspace::read_bytes(path)?,
            })
        })
        .collect()
}

fn format_of(d: &DatasetConfig) -> Result<&'static dyn nptreemap_formats::Format, BuildError> {
    registry::find(&d.format).ok_or_else(|| BuildError::UnknownFormat {
        dataset: d.name.clone(),
        format: d.format.clone(),
        known: registry::names().join(", "),
    })
}

/// Parses a dataset from its read input files with its format and field mapping.
pub fn parse_inputs(d: &DatasetConfig, files: &[InputFile]) -> Result<Dataset, BuildError> {
    let format = format_of(d)?;
    let mut inputs = Inputs::new();
    for f in files {
        inputs = inputs.with(&f.role, &f.bytes);
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
        let path = files
            .iter()
            .find(|f| f.role == e.role)
            .map(|f| f.path.clone())
            .unwrap_or_else(|| PathBuf::from(&e.role));
        BuildError::Input(workspace::InputError::Parse {
            path,
            source: Box::new(e.error),
        })
    })
}

/// Loads, lays out and renders one dataset, writing nothing. The layout
/// starts warm from the one stored beside the outputs ([`stored_layout`])
/// unless `cold`.
pub fn build(config: &Config, d: &DatasetConfig, cold: bool) -> Result<Built, BuildError> {
    let dataset = load(d)?;
    let previous = if cold { None } else { stored_layout(d) };
    let computed = lay_out(config, d, &dataset, previous)?;
    let outputs = render_all(config, d, &computed)?;
    Ok(Built {
        name: d.name.clone(),
        computed,
        outputs,
    })
}

/// Lays a parsed dataset out, warm from `previous` when given (and when it
/// fits: same canvas and outline, at least half the nodes surviving; else
/// cold, see [`Computed::start`]).
pub fn lay_out(
    config: &Config,
    d: &DatasetConfig,
    dataset: &Dataset,
    previous: Option<Arc<Previous>>,
) -> Result<Computed, BuildError> {
    let mut request = config.request(d);
    request.previous = previous;
    compute(dataset, &request).map_err(|source| BuildError::Layout {
        dataset: d.name.clone(),
        source,
    })
}

/// The layout stored for a dataset by [`store_layout`], if there is one.
/// A stored layout that cannot be read is not an error the user must act on
/// (the next build replaces it): it is logged and the layout starts cold.
pub fn stored_layout(d: &DatasetConfig) -> Option<Arc<Previous>> {
    let path = state_path(d)?;
    let text = store::read_state(&path)?;
    match Previous::from_layout_json(&text) {
        Ok(previous) => Some(Arc::new(previous)),
        Err(e) => {
            tracing::warn!(path = %path.display(), error = %e, "stored layout unreadable; laying out cold");
            None
        }
    }
}

/// Where a dataset's last layout is kept between runs: a hidden folder beside
/// its first output (`out/.nptreemap/<name>.layout.json`), so it travels
/// with the outputs and a restarted daemon or `build` starts warm. `None` for
/// a dataset without outputs.
pub fn state_path(d: &DatasetConfig) -> Option<PathBuf> {
    let first = d.outputs.first()?;
    let dir = first.path.parent().unwrap_or(std::path::Path::new("."));
    // The dataset name is free text; keep the file name portable.
    let safe: String = d
        .name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    Some(dir.join(".nptreemap").join(format!("{safe}.layout.json")))
}

/// Stores a dataset's layout at its [`state_path`] (atomically; unchanged
/// bytes are not rewritten).
pub fn store_layout(d: &DatasetConfig, computed: &Computed) -> std::io::Result<()> {
    let Some(path) = state_path(d) else {
        return Ok(());
    };
    let mut extras = json_extras(computed);
    extras.exact = true;
    let json = layout_json(&computed.dataset, &computed.layout, &extras);
    store::write_if_changed(&path, json.as_bytes()).map(|_| ())
}

/// Every output of a dataset for a computed layout, in config order.
pub fn render_all(
    config: &Config,
    d: &DatasetConfig,
    computed: &Computed,
) -> Result<Vec<(PathBuf, Vec<u8>)>, BuildError> {
    render_outputs(computed, &config.style(d), &d.outputs)
}

/// The bytes of each of `outputs` for a computed layout, in order. The
/// picture is drawn once for every SVG and PNG output (it is the same text).
pub fn render_outputs(
    computed: &Computed,
    style: &Style,
    outputs: &[OutputConfig],
) -> Result<Vec<(PathBuf, Vec<u8>)>, BuildError> {
    let mut svg_text: Option<String> = None;
    outputs
        .iter()
        .map(|out| {
            let bytes = match out.kind.unwrap_or(OutputKind::Svg) {
                OutputKind::Svg => svg_text
                    .get_or_insert_with(|| picture(computed, style))
                    .clone()
                    .into_bytes(),
                OutputKind::Png => {
                    let text = svg_text.get_or_insert_with(|| picture(computed, style));
                    png(text, out.scale).map_err(|source| BuildError::Png {
                        path: out.path.clone(),
                        source,
                    })?
                }
                OutputKind::Json => {
                    layout_json(&computed.dataset, &computed.layout, &json_extras(computed))
                        .into_bytes()
                }
                OutputKind::Html => html_page(computed, style).into_bytes(),
            };
            Ok((out.path.clone(), bytes))
        })
        .collect()
}

/// The interactive page: the picture (its unrealised links drawn, for the
/// page's checkbox to show or hide), and per cell its path from the root,
/// weight, neighbours and constraint partners for the hover highlight.
pub fn html_page(computed: &Computed, style: &Style) -> String {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
    // The links are always drawn on the page; its checkbox shows or hides them.
    let mut page_style = style.clone();
    page_style.overlay.show_unrealized = true;
    let svg_text = picture(computed, &page_style);
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
    let title = style
        .title
        .clone()
        .unwrap_or_else(|| dataset.node(dataset.root()).label.clone());
    let colors = crate::render::svg::cell_colors(dataset);
    let frames = computed
        .report
        .frames
        .iter()
        .map(|f| HtmlFrame {
            label: format!("level {}: {}", f.depth, f.label),
            cells: f
                .cells
                .iter()
                .map(|(i, polygon)| {
                    let mut d = String::new();
                    crate::render::svg::path_data(&mut d, polygon);
                    let fill = colors[*i].map_or("#cccccc".to_string(), |c| c.to_string());
                    (dataset.node(*i).id.clone(), d, fill)
                })
                .collect(),
        })
        .collect();
    html(
        &svg_text,
        &HtmlData {
            title,
            nodes,
            frames,
        },
    )
}

/// The SVG picture: the treemap with, when there are constraints, the
/// interlocking tabs and unrealised-link markers of its deepest level (where the
/// paper draws them, method-reference §8.2–8.4): the tabs under the labels, the
/// rest over them; framed as `style` says.
pub fn picture(computed: &Computed, style: &Style) -> String {
    let (dataset, layout) = (&computed.dataset, &computed.layout);
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
    render::picture(dataset, layout, &links, style)
}

/// Writes a built dataset's outputs atomically; an output whose bytes would
/// not change is left alone. Returns the paths written. (The stored layout
/// is written separately, by [`store_layout`].)
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
        exact: false,
    }
}
