//! The YAML configuration of `nptreemap build` and `watch`: datasets (format,
//! files, field mapping, similarity), layout settings and outputs. `from_str`
//! parses text; `from_path` is a thin reader over it. The only module that
//! names the YAML crate. Unknown keys are rejected with their line and column;
//! relative paths are resolved against the config file's directory.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer};

use crate::layout::{Canvas, Method, NeighborParams, Outline, Params, Request, ZeroWeights};
use crate::neighborhood::SimilarityKind;
use crate::render::overlay::OverlayStyle;
use crate::render::{Border, ColorBy, OutputKind, PageFields, Style, SvgStyle};
use nptreemap_formats::{Carry, FormatOptions, Limits};

/// The `render:` section.
pub mod render_section;
pub use render_section::RenderConfig;

/// The built-in defaults, every key documented (`config/default.yaml`); the
/// tests check that every key parses and matches [`Config`]'s defaults.
#[cfg(any(test, feature = "cli"))]
pub(crate) const DEFAULT_YAML: &str = include_str!("../config/default.yaml");

/// A parsed, path-resolved configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Layout settings shared by every dataset.
    pub layout: LayoutConfig,
    /// How the pictures look, for every dataset.
    pub render: RenderConfig,
    /// How large an input may be (nodes, depth, dimensions, file size), for
    /// every dataset; each dataset's readers get them as `fields.limits`.
    pub limits: Limits,
    /// Where the stored layouts live (`state_dir:`, resolved), or `None` for
    /// the default, a `.nptreemap/` folder beside each dataset's outputs (`crate::state::dir`).
    pub state_dir: Option<PathBuf>,
    /// How many past layouts of a `watch --serve` session a served page keeps
    /// to step back through (`history:`); 0 keeps none.
    pub history: usize,
    /// The datasets, in file order.
    pub datasets: Vec<DatasetConfig>,
}

/// The `layout` section.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LayoutConfig {
    /// Canvas width. Default: 1000.
    pub width: f64,
    /// Canvas height. Default: 1000.
    pub height: f64,
    /// Root outline: `rect`, `circle` or `ngon`. Default: `rect`.
    pub outline: Outline,
    /// Seed for every random choice. Default: 1.
    pub seed: u64,
    /// Layout method; `None` = `neighbor` with a similarity, else `plain`.
    pub method: Option<Method>,
    /// Per-diagram area-error target. Default: 0.01.
    pub convergence_ratio: f64,
    /// Iteration cap per diagram. Default: 200.
    pub max_iterations: usize,
    /// Relaxation ticks before a diagram may stop. Default: 8.
    pub min_iterations: usize,
    /// Lightest sibling share laid out. Default: 0.001.
    pub min_weight_ratio: f64,
    /// Items of weight 0: `hide` (no cell) or `floor` (a cell at the floor of
    /// `min_weight_ratio`). Default: hide.
    pub zero_weights: ZeroWeights,
    /// Run the paper prototype's optimiser. Default: false.
    pub prototype: bool,
    /// Snapshots per level kept for the HTML page's optimisation slider
    /// (similarity layouts only); 0 keeps none. Default: 0.
    pub frames: usize,
}

impl Default for LayoutConfig {
    fn default() -> Self {
        let p = Params::default();
        Self {
            width: p.canvas.width,
            height: p.canvas.height,
            outline: p.outline,
            seed: p.seed,
            method: None,
            convergence_ratio: p.convergence_ratio,
            max_iterations: p.max_iterations,
            min_iterations: p.min_iterations,
            min_weight_ratio: p.min_weight_ratio,
            zero_weights: p.zero_weights,
            prototype: false,
            frames: NeighborParams::default().frames,
        }
    }
}

/// One dataset: where its files are, how to read them, where its pictures go.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetConfig {
    /// Name used in messages and status lines.
    pub name: String,
    /// Input format, a name from the format registry (e.g. `hierarchy-json`).
    pub format: String,
    /// The format's input files by role (e.g. `nodes`, `pairs`), relative to
    /// the config file.
    pub files: std::collections::BTreeMap<String, PathBuf>,
    /// Field mapping: which columns hold the id, label, weight, groups, ….
    #[serde(default)]
    pub fields: FormatOptions,
    /// Similarity between nodes; default: what the format declares.
    #[serde(default)]
    pub similarity: Option<SimilarityKind>,
    /// Title above this dataset's pictures; default: `render.title`.
    #[serde(default)]
    pub title: Option<String>,
    /// What the HTML page shows of the data's own columns.
    #[serde(default)]
    pub page: PageConfig,
    /// What to write.
    #[serde(default)]
    pub outputs: Vec<OutputConfig>,
    /// `format: exec` only: the adapter command (program and arguments) that
    /// prints the dataset as hierarchy JSON; it gets the `files:` paths as
    /// further arguments, in the order of their role names.
    #[serde(default)]
    pub command: Vec<String>,
    /// `format: exec` only: seconds the command may run (default 60), more
    /// than 0 and at most [`MAX_EXEC_TIMEOUT`] (checked as it is read, so the
    /// error has its line).
    #[serde(default, deserialize_with = "exec_timeout")]
    pub timeout: Option<f64>,
    /// `format: exec` only: the most its adapter may print, in MiB
    /// (`limits.max_adapter_mb`, else `limits.max_file_mb`). Not a dataset key.
    #[serde(skip)]
    pub max_adapter_mb: u64,
    /// The folder relative paths were resolved against (the config's), where
    /// an exec command runs.
    #[serde(skip)]
    pub base: PathBuf,
    /// The config's `state_dir:` (resolved): where this dataset's stored
    /// layout lives instead of beside its outputs. Not a dataset key.
    #[serde(skip)]
    pub state_dir: Option<PathBuf>,
    /// The name of the config file it was read from, without its extension
    /// (`site` for `site.yaml`; `None` for a config not read from a file):
    /// part of its state files' names (`crate::state::key`). Not a dataset key.
    #[serde(skip)]
    pub config_stem: Option<String>,
}

/// A dataset's `page:` section: its own columns in the HTML page (issue 24
/// item 4).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PageConfig {
    /// Columns (hierarchy JSON: node properties) shown in the tooltip, in
    /// this order, each as `name: value`.
    pub fields: Vec<String>,
    /// A column whose value is each cell's link: a click on the cell shows
    /// it above the map as a link (`http:`, `https:` or relative URLs only;
    /// any other value is shown as text, never followed).
    pub link: Option<String>,
    /// Where the link opens: `new-tab` or `same-tab`. Default: new-tab.
    pub link_target: LinkTarget,
}

/// `page.link_target`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinkTarget {
    /// A new tab (the map stays open).
    #[default]
    NewTab,
    /// The page's own tab.
    SameTab,
}

/// 1-based lines of `text` whose key (the first word before a colon, after
/// any `- `) is `key`, in order: where a config says `page:` or `color_by:`,
/// for errors about the columns they name (serde keeps no positions of
/// values that parse).
fn key_lines(text: &str, key: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, line)| {
            let t = line.trim_start();
            let t = t.strip_prefix("- ").unwrap_or(t).trim_start();
            t.strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with(':'))
        })
        .map(|(k, _)| k + 1)
        .collect()
}

/// The columns a dataset's pictures need carried into the model: its
/// `page` fields and link, `render.color_by` and the columns of a
/// `render.labels.text` template, each once, each with what asked for it
/// (config line, when found) for the reader's error.
fn carried(
    d: &DatasetConfig,
    i: usize,
    page_line: Option<usize>,
    render: &RenderConfig,
    lines: (Option<usize>, Option<usize>),
) -> Vec<Carry> {
    let (color_line, text_line) = lines;
    let at = |line: Option<usize>| line.map_or(String::new(), |l| format!(", config line {l}"));
    let mut out: Vec<Carry> = Vec::new();
    let mut add = |column: &str, asked_by: String| {
        if !out.iter().any(|c| c.column == column) {
            out.push(Carry {
                column: column.to_string(),
                asked_by,
            });
        }
    };
    for (k, f) in d.page.fields.iter().enumerate() {
        add(f, format!("datasets[{i}].page.fields[{k}]{}", at(page_line)));
    }
    if let Some(link) = &d.page.link {
        add(link, format!("datasets[{i}].page.link{}", at(page_line)));
    }
    if let Some(c) = &render.color_by {
        add(c, format!("render.color_by{}", at(color_line)));
    }
    for c in render.labels.text.columns() {
        add(c, format!("render.labels.text{}", at(text_line)));
    }
    out
}

/// The format name of the runtime plugin: an external command produces the
/// dataset.
pub const EXEC_FORMAT: &str = "exec";

/// How long an exec command may run when the config does not say.
pub const DEFAULT_EXEC_TIMEOUT: f64 = 60.0;

/// The longest `timeout:` an exec dataset may ask for: a day. An adapter
/// that needs longer belongs in a scheduled job writing a file; and the
/// bound keeps every timeout a valid [`std::time::Duration`].
pub const MAX_EXEC_TIMEOUT: f64 = 86_400.0;

/// `timeout:`, refused at its line when it is not a usable number of
/// seconds (`1e20`, `-1`, `.nan` would overflow a `Duration` or mean nothing).
fn exec_timeout<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Ok(Option::<Seconds>::deserialize(d)?.map(|s| s.0))
}

/// A timeout in seconds, checked by the visitor itself: an error raised
/// while the YAML scalar is read carries the scalar's line and column.
struct Seconds(f64);

impl<'de> Deserialize<'de> for Seconds {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Seconds;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "seconds, more than 0 and at most {MAX_EXEC_TIMEOUT}")
            }
            fn visit_f64<E: serde::de::Error>(self, t: f64) -> Result<Seconds, E> {
                if t > 0.0 && t <= MAX_EXEC_TIMEOUT {
                    Ok(Seconds(t))
                } else {
                    Err(E::custom(format_args!(
                        "{t:?} is out of range: the seconds an adapter may run are more than 0 \
                         and at most {MAX_EXEC_TIMEOUT} (a day)"
                    )))
                }
            }
            fn visit_i64<E: serde::de::Error>(self, t: i64) -> Result<Seconds, E> {
                self.visit_f64(t as f64)
            }
            fn visit_u64<E: serde::de::Error>(self, t: u64) -> Result<Seconds, E> {
                self.visit_f64(t as f64)
            }
        }
        d.deserialize_f64(Visitor)
    }
}

/// One output file. In a config, either a map (`{path: out/a.png, scale:
/// 2}`) or just the path (`out/a.svg`): `outputs: [out/a.svg, out/a.png]`.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputConfig {
    /// Where to write, relative to the config file.
    pub path: PathBuf,
    /// `svg`, `png`, `json` or `html`; default: the path's extension.
    pub kind: Option<OutputKind>,
    /// Pixel scale for PNG. Default: 1.
    pub scale: f64,
}

impl OutputConfig {
    /// Its kind: as given, else by its path's extension, else SVG (a
    /// config always gives or implies one; this is for outputs built in code).
    pub fn kind(&self) -> OutputKind {
        self.kind
            .or_else(|| OutputKind::of_path(&self.path))
            .unwrap_or(OutputKind::Svg)
    }
}

fn one() -> f64 {
    1.0
}

/// The full form of an `outputs:` entry.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FullOutput {
    path: PathBuf,
    #[serde(default)]
    kind: Option<OutputKind>,
    #[serde(default = "one")]
    scale: f64,
}

/// Reads either form by hand rather than with `#[serde(untagged)]`, which
/// would replace the map form's own errors ("unknown field `scael`") with a
/// generic one.
impl<'de> Deserialize<'de> for OutputConfig {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Entry;
        impl<'de> serde::de::Visitor<'de> for Entry {
            type Value = OutputConfig;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a path such as out/a.svg, or a map with `path` (and `kind`, `scale`)")
            }
            fn visit_str<E: serde::de::Error>(self, path: &str) -> Result<OutputConfig, E> {
                Ok(OutputConfig {
                    path: PathBuf::from(path),
                    kind: None,
                    scale: 1.0,
                })
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<OutputConfig, A::Error> {
                let f = FullOutput::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(OutputConfig {
                    path: f.path,
                    kind: f.kind,
                    scale: f.scale,
                })
            }
        }
        deserializer.deserialize_any(Entry)
    }
}

/// What the raw file holds (before paths are resolved).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    #[serde(default)]
    layout: LayoutConfig,
    #[serde(default)]
    render: RenderConfig,
    #[serde(default)]
    limits: LimitsSection,
    #[serde(default)]
    state_dir: Option<PathBuf>,
    #[serde(default = "default_history")]
    history: usize,
    #[serde(default)]
    datasets: Vec<DatasetConfig>,
}

/// The `limits:` section as written: the readers' [`Limits`] (the same keys
/// and defaults), plus `max_adapter_mb`, the cap on what an exec adapter
/// prints, which only the adapter runner reads (the formats never see an
/// adapter; `None`: `max_file_mb`). Its own struct rather than a wrapper
/// around `Limits`' reader, so that unknown keys and bad values are refused
/// at their line, with every key listed.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct LimitsSection {
    max_nodes: usize,
    max_depth: usize,
    max_dimensions: usize,
    max_set_members: usize,
    max_file_mb: u64,
    max_adapter_mb: Option<u64>,
}

impl Default for LimitsSection {
    fn default() -> Self {
        let l = Limits::default();
        LimitsSection {
            max_nodes: l.max_nodes,
            max_depth: l.max_depth,
            max_dimensions: l.max_dimensions,
            max_set_members: l.max_set_members,
            max_file_mb: l.max_file_mb,
            max_adapter_mb: None,
        }
    }
}

impl LimitsSection {
    /// The limits of the formats' readers.
    fn readers(&self) -> Limits {
        Limits {
            max_nodes: self.max_nodes,
            max_depth: self.max_depth,
            max_dimensions: self.max_dimensions,
            max_set_members: self.max_set_members,
            max_file_mb: self.max_file_mb,
        }
    }

    /// The cap on an adapter's output, in MiB.
    fn max_adapter_mb(&self) -> u64 {
        self.max_adapter_mb.unwrap_or(self.max_file_mb)
    }
}

/// Past layouts a served page keeps when the config does not say (`history:`).
const fn default_history() -> usize {
    0
}

/// Most past layouts a served page may keep.
const MAX_HISTORY: usize = 64;

/// A configuration that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The YAML is malformed or does not fit the schema (unknown key, wrong type).
    #[error("{}{message}", position(*.line, *.column))]
    Yaml {
        /// 1-based line, when known.
        line: Option<usize>,
        /// 1-based column, when known.
        column: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The YAML fits the schema but a value is unusable.
    #[error("{field}: {message}")]
    Value {
        /// Where, as a path such as `datasets[0].outputs[1].path`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// A config file that cannot be read or used, naming the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {message}", .path.display())]
pub struct ConfigFileError {
    /// The config file.
    pub path: PathBuf,
    /// What is wrong, with line and column where known.
    pub message: String,
}

/// serde's "unknown field `weigth`, expected one of `id`, `weight`, ..."
/// (or "unknown variant ...") with "; did you mean `weight`?" added when one
/// of the expected names is a likely fix.
fn with_hint(message: &str) -> String {
    let unknown = ["unknown field `", "unknown variant `"]
        .iter()
        .find_map(|p| message.find(p).map(|at| at + p.len()));
    let Some(start) = unknown else {
        return message.to_string();
    };
    let Some(word) = message[start..].split('`').next() else {
        return message.to_string();
    };
    let expected: Vec<&str> = message
        .split_once("expected ")
        .map(|(_, rest)| rest.split('`').skip(1).step_by(2).collect())
        .unwrap_or_default();
    match nptreemap_formats::suggest::closest(word, expected) {
        Some(best) => format!("{message}; did you mean `{best}`?"),
        None => message.to_string(),
    }
}

fn position(line: Option<usize>, column: Option<usize>) -> String {
    match (line, column) {
        (Some(l), Some(c)) => format!("line {l}, column {c}: "),
        (Some(l), None) => format!("line {l}: "),
        _ => String::new(),
    }
}

impl Config {
    /// Parses config text; relative paths are taken against `base`.
    pub fn from_str(text: &str, base: &Path) -> Result<Config, ConfigError> {
        let raw: RawConfig = if text.trim().is_empty() {
            RawConfig {
                layout: LayoutConfig::default(),
                render: RenderConfig::default(),
                limits: LimitsSection::default(),
                state_dir: None,
                history: default_history(),
                datasets: Vec::new(),
            }
        } else {
            serde_yaml::from_str(text).map_err(|e| {
                let loc = e.location();
                ConfigError::Yaml {
                    line: loc.as_ref().map(|l| l.line()),
                    column: loc.as_ref().map(|l| l.column()),
                    message: with_hint(&strip_location(&e.to_string())),
                }
            })?
        };
        let zero_adapter = (raw.limits.max_adapter_mb() == 0).then_some("max_adapter_mb");
        if let Some(key) = raw.limits.readers().zero_limit().or(zero_adapter) {
            return Err(ConfigError::Value {
                field: format!("limits.{key}"),
                message: "must be at least 1".to_string(),
            });
        }
        if raw.history > MAX_HISTORY {
            // Each kept layout is a whole page in the browser's memory.
            return Err(ConfigError::Value {
                field: "history".to_string(),
                message: format!("must be at most {MAX_HISTORY}"),
            });
        }
        let state_dir = raw.state_dir.as_ref().map(|dir| base.join(dir));
        let mut datasets = raw.datasets;
        let mut seen = std::collections::BTreeSet::new();
        // The k-th `page:` key belongs to the k-th dataset that has one
        // (no other section has such a key).
        let mut page_lines = key_lines(text, "page").into_iter();
        let color_line = key_lines(text, "color_by").first().copied();
        let text_line = key_lines(text, "text").first().copied();
        for (i, d) in datasets.iter_mut().enumerate() {
            let page_line = if d.page == PageConfig::default() {
                None
            } else {
                page_lines.next()
            };
            for (k, f) in d.page.fields.iter().enumerate() {
                if f.trim().is_empty() {
                    return Err(ConfigError::Value {
                        field: format!("datasets[{i}].page.fields[{k}]"),
                        message: "must name a column".to_string(),
                    });
                }
            }
            d.fields.carry = carried(d, i, page_line, &raw.render, (color_line, text_line));
            d.fields.limits = raw.limits.readers();
            d.max_adapter_mb = raw.limits.max_adapter_mb();
            d.state_dir = state_dir.clone();
            if !seen.insert(d.name.clone()) {
                return Err(ConfigError::Value {
                    field: format!("datasets[{i}].name"),
                    message: format!("dataset name {:?} is used twice", d.name),
                });
            }
            for path in d.files.values_mut() {
                *path = base.join(&*path);
            }
            d.base = base.to_path_buf();
            check_exec(d, i)?;
            resolve_outputs(d, i, base)?;
        }
        raw.render.validate()?;
        let config = Config {
            layout: raw.layout,
            render: raw.render,
            limits: raw.limits.readers(),
            state_dir,
            history: raw.history,
            datasets,
        };
        config.params().validate().map_err(|e| ConfigError::Value {
            field: "layout".to_string(),
            message: e.to_string(),
        })?;
        Ok(config)
    }

    /// Reads and parses a config file; paths in it are relative to its folder.
    pub fn from_path(path: &Path) -> Result<Config, ConfigFileError> {
        // Through the one reader: a FIFO or a device is refused, not read.
        let text = crate::workspace::read_text(path).map_err(|e| ConfigFileError {
            path: path.to_path_buf(),
            message: strip_path(&e.to_string(), path),
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        let mut config = Config::from_str(&text, base).map_err(|e| ConfigFileError {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        // A config file names what to build: one without datasets is a
        // mistake (or a file caught mid-save by `watch`, which then keeps
        // the previous config), never a build of nothing that succeeds.
        if config.datasets.is_empty() {
            return Err(ConfigFileError {
                path: path.to_path_buf(),
                message: "no datasets: list what to build under `datasets:` \
                          (`nptreemap init TABLE.csv` writes a config from your tables)"
                    .to_string(),
            });
        }
        // As the user names it (a link's name, not its target's).
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        for d in &mut config.datasets {
            d.config_stem.clone_from(&stem);
        }
        Ok(config)
    }

    /// The layout parameters of the `layout` section.
    pub fn params(&self) -> Params {
        let l = &self.layout;
        Params {
            canvas: Canvas {
                width: l.width,
                height: l.height,
            },
            outline: l.outline.clone(),
            seed: l.seed,
            convergence_ratio: l.convergence_ratio,
            max_iterations: l.max_iterations,
            min_iterations: l.min_iterations,
            min_weight_ratio: l.min_weight_ratio,
            zero_weights: l.zero_weights,
        }
    }

    /// The picture style for one dataset (its own title, else `render.title`).
    pub fn style(&self, dataset: &DatasetConfig) -> Style {
        let r = &self.render;
        let defaults = Style::default();
        Style {
            title: dataset.title.clone().or_else(|| r.title.clone()),
            legend: r.legend,
            legend_order: r.legend_order,
            tabs: r.tabs,
            color_by: r.color_by.as_ref().map(|field| ColorBy {
                field: field.clone(),
                scale: r.color_scale,
                midpoint: r.color_midpoint,
            }),
            page: PageFields {
                fields: dataset.page.fields.clone(),
                link: dataset.page.link.clone(),
                // Meaningful only with a link (the default style has none).
                new_tab: dataset.page.link.is_some()
                    && dataset.page.link_target == LinkTarget::NewTab,
            },
            border: (r.border_width > 0.0).then_some(Border {
                color: r.border_color,
                width: r.border_width,
            }),
            cells: SvgStyle {
                background: r.background,
                stroke: r.stroke,
                stroke_width: r.stroke_width,
                labels: r.labels.clone(),
                palette: r.palette,
                group_colors: r.colors.clone(),
                ..defaults.cells
            },
            overlay: OverlayStyle {
                show_unrealized: r.unrealized_links,
                unlinked_markers: r.unlinked_markers,
                marker_share: r.unlinked_markers_share,
            },
        }
    }

    /// The layout request for one dataset.
    pub fn request(&self, dataset: &DatasetConfig) -> Request {
        Request {
            params: self.params(),
            method: self.layout.method,
            similarity: dataset.similarity,
            neighbor: NeighborParams {
                prototype: self.layout.prototype,
                frames: self.layout.frames,
                ..NeighborParams::default()
            },
            // The caller that keeps previous layouts (the daemon) adds its own.
            previous: None,
            // So does a caller that shows progress (the command line).
            progress: None,
            // `plain` computes no constraint in a build (issue 34).
            realized: false,
        }
    }
}

impl DatasetConfig {
    /// A dataset read from one hierarchy JSON file, as `nptreemap layout FILE`
    /// reads it (`weight`: the leaf field holding the weight, else the file's
    /// own flags), with no outputs. Named after the file.
    pub fn hierarchy_file(path: &Path, weight: Option<String>) -> DatasetConfig {
        DatasetConfig {
            name: path.display().to_string(),
            format: "hierarchy-json".to_string(),
            files: [("hierarchy".to_string(), path.to_path_buf())].into(),
            fields: FormatOptions {
                weight,
                ..FormatOptions::default()
            },
            similarity: None,
            title: None,
            page: PageConfig::default(),
            outputs: Vec::new(),
            command: Vec::new(),
            timeout: None,
            max_adapter_mb: Limits::default().max_file_mb,
            base: PathBuf::new(),
            state_dir: None,
            config_stem: None,
        }
    }
}

/// Resolves dataset `i`'s output paths against `base` and checks each
/// output's kind (from its extension when not given) and scale.
fn resolve_outputs(d: &mut DatasetConfig, i: usize, base: &Path) -> Result<(), ConfigError> {
    for (k, out) in d.outputs.iter_mut().enumerate() {
        out.path = base.join(&out.path);
        if out.kind.is_none() {
            out.kind = OutputKind::of_path(&out.path);
        }
        if out.kind.is_none() {
            return Err(ConfigError::Value {
                field: format!("datasets[{i}].outputs[{k}].path"),
                message: format!(
                    "{}: cannot tell the kind from the extension; add `kind: svg|png|json|html`",
                    out.path.display()
                ),
            });
        }
        if !(out.scale.is_finite() && out.scale > 0.0) {
            return Err(ConfigError::Value {
                field: format!("datasets[{i}].outputs[{k}].scale"),
                message: "must be a positive number".to_string(),
            });
        }
    }
    Ok(())
}

/// The exec keys are given exactly when the format is `exec`.
fn check_exec(d: &DatasetConfig, i: usize) -> Result<(), ConfigError> {
    let exec = d.format == EXEC_FORMAT;
    let wrong = |key: &str, message: &str| ConfigError::Value {
        field: format!("datasets[{i}].{key}"),
        message: message.to_string(),
    };
    if exec && d.command.is_empty() {
        return Err(wrong(
            "command",
            "format exec needs `command: [program, args...]`, the adapter that prints the dataset",
        ));
    }
    if !exec && !d.command.is_empty() {
        return Err(wrong("command", "only format exec runs a command"));
    }
    if !exec && d.timeout.is_some() {
        return Err(wrong("timeout", "only format exec has a timeout"));
    }
    // Its range was checked as it was read (`exec_timeout`).
    Ok(())
}

/// The reader's messages start with the path, which [`ConfigFileError`] puts
/// in front itself.
fn strip_path(message: &str, path: &Path) -> String {
    let prefix = format!("{}: ", path.display());
    message.strip_prefix(&prefix).unwrap_or(message).to_string()
}

/// serde_yaml appends " at line L column C" to its messages; the position is
/// reported separately, so drop it from the text.
fn strip_location(message: &str) -> String {
    match message.find(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{LegendOrder, PaletteKind};

    fn parse(text: &str) -> Result<Config, ConfigError> {
        Config::from_str(text, Path::new("/base"))
    }

    #[test]
    fn default_yaml_is_the_code_default() {
        let c = parse(DEFAULT_YAML).expect("default.yaml parses");
        assert_eq!(c.layout, LayoutConfig::default());
        assert_eq!(c.render, RenderConfig::default());
        assert_eq!(c.limits, Limits::default());
        assert_eq!(c.state_dir, None);
        let d = DatasetConfig {
            name: "d".to_string(),
            format: "f".to_string(),
            files: Default::default(),
            fields: Default::default(),
            similarity: None,
            title: None,
            page: PageConfig::default(),
            outputs: Vec::new(),
            command: Vec::new(),
            timeout: None,
            max_adapter_mb: 0,
            base: PathBuf::new(),
            state_dir: None,
            config_stem: None,
        };
        assert_eq!(c.style(&d), Style::default());
        assert_eq!(c.params(), Params::default());
        assert!(c.datasets.is_empty());
    }

    #[test]
    fn paths_are_relative_to_the_config_and_kinds_come_from_extensions() {
        let c = parse(
            "datasets:\n  - name: world\n    format: hierarchy-json\n    files: {hierarchy: data/w.json}\n    outputs:\n      - path: out/w.svg\n      - {path: out/w.png, scale: 2}\n",
        )
        .expect("valid");
        let d = &c.datasets[0];
        assert_eq!(d.files["hierarchy"], Path::new("/base/data/w.json"));
        assert_eq!(d.outputs[0].path, Path::new("/base/out/w.svg"));
        assert_eq!(d.outputs[0].kind, Some(OutputKind::Svg));
        assert_eq!(d.outputs[1].kind, Some(OutputKind::Png));
        assert_eq!(d.outputs[1].scale, 2.0);
    }

    #[test]
    fn unknown_keys_are_rejected_with_line_and_column() {
        let err = parse("layout:\n  width: 800\n  colour: red\n").expect_err("unknown key");
        let text = err.to_string();
        assert!(text.starts_with("line 3, column 3: "), "{text}");
        assert!(text.contains("colour"), "{text}");
    }

    #[test]
    fn render_section_reaches_the_style() {
        let c = parse(
            "render:\n  title: All\n  background: none\n  border_width: 2\n  tabs: false\n\
             datasets:\n  - {name: a, format: x, files: {}, title: Mine}\n  - {name: b, format: x, files: {}}\n",
        )
        .expect("valid");
        let a = c.style(&c.datasets[0]);
        assert_eq!(a.title.as_deref(), Some("Mine"));
        assert_eq!(c.style(&c.datasets[1]).title.as_deref(), Some("All"));
        assert_eq!(a.cells.background, None);
        assert!(!a.tabs);
        assert_eq!(a.border.map(|b| b.width), Some(2.0));
        let c = parse(
            "render:\n  palette: colorblind\n  legend_order: names\n  labels:\n    min_size: 10\n    value: true\n    unit: \" KiB\"\n    names: {EU: Europe, AS: Asia}\n",
        )
        .expect("valid");
        let d = DatasetConfig::hierarchy_file(Path::new("x.json"), None);
        let style = c.style(&d);
        assert_eq!(style.cells.palette, PaletteKind::Colorblind);
        assert_eq!(style.legend_order, LegendOrder::Names);
        assert_eq!(style.cells.labels.min_size, 10.0);
        assert!(style.cells.labels.value);
        assert_eq!(style.cells.labels.names.get("AS"), Some("Asia"));
        assert_eq!(
            c.render.labels.names.pairs(),
            [
                ("EU".to_string(), "Europe".to_string()),
                ("AS".to_string(), "Asia".to_string())
            ]
        );
        let off = parse("render: {labels: false}\n").expect("valid");
        assert!(!off.render.labels.show && !off.render.labels.groups);
    }

    #[test]
    fn bad_render_values_name_the_key() {
        for (text, key) in [
            (
                "render:\n  background: blue\n",
                "line 2, column 3: render: background: ",
            ),
            (
                "render:\n  stroke: \"#12\"\n",
                "line 2, column 3: render: stroke: ",
            ),
            ("render: {border_width: -1}\n", "render.border_width"),
            (
                "render: {labels: {min_size: 30}}\n",
                "render.labels.min_size",
            ),
            (
                "render: {unlinked_markers_share: 2}\n",
                "render.unlinked_markers_share",
            ),
            (
                "render: {palette: rainbow}\n",
                "line 1, column 9: render: palette: unknown palette",
            ),
            (
                "render: {colors: {Europe: \"#12g\"}}\n",
                "line 1, column 9: render: colors: \"Europe\": \"#12g\" is not a colour",
            ),
        ] {
            let err = parse(text).expect_err(text).to_string();
            assert!(err.starts_with(key), "{text}: {err}");
        }
    }

    #[test]
    fn core_names_and_field_options_parse_into_the_core_types() {
        let c = parse(
            "layout: {outline: ngon, method: match-swap}\n\
             datasets:\n  - name: a\n    format: x\n    files: {}\n    similarity: neighbors\n\
             \x20   fields: {id: iso, delimiter: \";\", groups: [continent]}\n",
        )
        .expect("valid");
        assert_eq!(c.params().outline, Outline::Regular(32));
        assert_eq!(c.params().zero_weights, ZeroWeights::Hide, "the default");
        let floor = parse("layout: {zero_weights: floor}\n").expect("valid");
        assert_eq!(floor.params().zero_weights, ZeroWeights::Floor);
        assert_eq!(c.layout.method, Some(Method::MatchSwap));
        let d = &c.datasets[0];
        assert_eq!(d.similarity, Some(SimilarityKind::NeighborList));
        assert_eq!(d.fields.delimiter, Some(b';'));
        assert_eq!(d.fields.id.as_deref(), Some("iso"));
        assert_eq!(d.fields.groups, ["continent"]);
        for (text, wanted) in [
            ("layout: {outline: square}\n", "unknown outline \"square\""),
            ("layout: {method: best}\n", "unknown variant `best`"),
            (
                "datasets:\n  - {name: a, format: x, files: {}, fields: {delimiter: \";;\"}}\n",
                "delimiter \";;\": expected a single one-byte character",
            ),
            (
                "datasets:\n  - {name: a, format: x, files: {}, fields: {weigth: w}}\n",
                "unknown field `weigth`",
            ),
            (
                "datasets:\n  - {name: a, format: x, files: {}, fields: {weigth: w}}\n",
                "; did you mean `weight`?",
            ),
            ("layot: {seed: 2}\n", "; did you mean `layout`?"),
            (
                "layout: {method: neighbour}\n",
                "; did you mean `neighbor`?",
            ),
            (
                "layout:\n  zero_weights: hid\n",
                "line 2, column 17: layout.zero_weights: unknown variant `hid`, expected `hide` or `floor`; did you mean `hide`?",
            ),
        ] {
            let err = parse(text).expect_err(text).to_string();
            assert!(err.contains(wanted), "{text}: {err}");
        }
    }

    #[test]
    fn outputs_may_be_bare_paths() {
        let c = parse(
            "datasets:\n  - name: a\n    format: x\n    files: {}\n    outputs: [out/a.svg, out/a.png, {path: out/b.png, scale: 2}]\n",
        )
        .expect("short outputs parse");
        let outs = &c.datasets[0].outputs;
        assert_eq!(outs.len(), 3);
        assert_eq!(outs[0].path, Path::new("/base/out/a.svg"));
        assert_eq!(outs[0].kind, Some(OutputKind::Svg));
        assert_eq!(outs[1].kind, Some(OutputKind::Png));
        assert_eq!((outs[1].scale, outs[2].scale), (1.0, 2.0));
        // The map form keeps its own errors.
        let err = parse("datasets:\n  - name: a\n    format: x\n    files: {}\n    outputs: [{path: out/a.png, scael: 2}]\n")
            .expect_err("unknown key");
        assert!(err.to_string().contains("unknown field `scael`"), "{err}");
        assert!(err.to_string().contains("did you mean `scale`?"), "{err}");
    }

    #[test]
    fn type_errors_name_their_position() {
        let err = parse("layout:\n  seed: many\n").expect_err("bad type");
        assert!(err.to_string().starts_with("line 2, column 9: "), "{err}");
    }

    #[test]
    fn exec_timeouts_out_of_range_are_refused_at_their_line() {
        let exec = |timeout: &str| {
            parse(&format!(
                "datasets:\n  - name: a\n    format: exec\n    command: [x]\n    files: {{}}\n    timeout: {timeout}\n"
            ))
        };
        for bad in ["1e20", "-1", "0", ".nan", ".inf", "-.inf", "86400.5"] {
            let err = exec(bad).expect_err(bad).to_string();
            assert!(err.starts_with("line 6, column "), "{bad}: {err}");
            assert!(err.contains("timeout"), "{bad}: {err}");
            assert!(err.contains("at most 86400"), "{bad}: {err}");
        }
        for good in ["0.5", "60", "86400"] {
            let c = exec(good).expect(good);
            assert_eq!(c.datasets[0].timeout, Some(good.parse().expect("number")));
        }
    }

    #[test]
    fn the_adapter_cap_defaults_to_the_file_cap() {
        let with = |limits: &str| {
            parse(&format!(
                "{limits}datasets:\n  - {{name: a, format: exec, command: [x], files: {{}}}}\n"
            ))
        };
        let adapter = |limits: &str| with(limits).expect(limits).datasets[0].max_adapter_mb;
        assert_eq!(adapter(""), Limits::default().max_file_mb);
        assert_eq!(adapter("limits:\n"), Limits::default().max_file_mb);
        assert_eq!(adapter("limits: {max_file_mb: 7}\n"), 7);
        assert_eq!(adapter("limits: {max_adapter_mb: null, max_file_mb: 7}\n"), 7);
        let c = with("limits: {max_adapter_mb: 3, max_nodes: 9}\n").expect("valid");
        assert_eq!(c.datasets[0].max_adapter_mb, 3);
        assert_eq!(c.limits.max_nodes, 9);
        assert_eq!(c.limits.max_file_mb, Limits::default().max_file_mb);
        let err = with("limits: {max_adapter_mb: 0}\n").expect_err("zero");
        assert_eq!(err.to_string(), "limits.max_adapter_mb: must be at least 1");
        // The other keys keep their own errors, at their line.
        let err = with("limits:\n  max_adapter_mb: 3\n  max_nodez: 3\n").expect_err("typo");
        let text = err.to_string();
        assert!(text.starts_with("line 3, column "), "{text}");
        assert!(text.contains("unknown field `max_nodez`"), "{text}");
        let err = with("limits:\n  max_adapter_mb: lots\n").expect_err("type");
        assert!(err.to_string().starts_with("line 2, column "), "{err}");
    }

    #[test]
    fn bad_values_name_the_field() {
        let err = parse("layout:\n  width: -5\n").expect_err("negative width");
        assert!(err.to_string().contains("width"), "{err}");
        let err = parse("datasets:\n  - name: a\n    format: x\n    files: {}\n    outputs: [{path: out/a.bmp}]\n")
            .expect_err("unknown kind");
        assert!(
            err.to_string().contains("datasets[0].outputs[0].path"),
            "{err}"
        );
        let twice =
            "datasets:\n  - {name: a, format: x, files: {}}\n  - {name: a, format: x, files: {}}\n";
        assert!(parse(twice)
            .expect_err("duplicate")
            .to_string()
            .contains("used twice"));
    }
}
