//! The `nptreemap` binary's code (feature `cli`): the argument parser and the
//! exit codes in `app`, the subcommands one file each, plus what the
//! single-dataset commands (`layout`, `eval`, `bench`) share: where the data
//! comes from (a hierarchy JSON file, or a dataset of a config) and the layout
//! flags that override the config's settings. It lives in the library so that
//! everything it uses can stay `pub(crate)`; `src/main.rs` only calls
//! `main`. Not part of the library's API.

mod app;
pub use app::main;

pub(crate) mod bench;
#[cfg(feature = "serve")]
mod browser;
pub(crate) mod build;
mod config_file;
pub(crate) mod defaults;
pub(crate) mod eval;
pub(crate) mod init;
pub(crate) mod layout;
pub(crate) mod man;
mod progress;
pub(crate) mod shell;
#[cfg(feature = "watch")]
pub(crate) mod watch;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::config::{Config, DatasetConfig};
use crate::layout::{Method, Outline, Previous, Request, ZeroWeights};
use crate::neighborhood::SimilarityKind;
use crate::pipeline::{self, BuildError, Fault, Named};
use crate::render::Style;
use crate::Dataset;
use clap::builder::TypedValueParser as _;
use clap::Args;

/// Where a single-dataset command's data comes from, and the layout flags.
#[derive(Debug, Clone, Args)]
pub(crate) struct LayoutOptions {
    /// Hierarchy JSON file (the paper's format or d3-hierarchy style); or
    /// give --config and --dataset instead.
    #[arg(required_unless_present = "config", conflicts_with = "config")]
    pub(crate) input: Option<PathBuf>,
    /// A YAML config whose dataset (--dataset) to read, with any format and
    /// field mapping it declares; its `layout:` and `render:` settings apply
    /// unless a flag below overrides them.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// The dataset of --config (may be left out when the config has one).
    #[arg(long, value_name = "NAME", requires = "config")]
    pub(crate) dataset: Option<String>,
    /// Leaf field holding the weight (default: the file's `weightAttribute`, else value/weight/size).
    #[arg(long, value_name = "FIELD", conflicts_with = "config")]
    pub(crate) weight: Option<String>,
    /// Canvas width [default: 1000, or the config's].
    #[arg(long)]
    pub(crate) width: Option<f64>,
    /// Canvas height [default: 1000, or the config's].
    #[arg(long)]
    pub(crate) height: Option<f64>,
    /// Seed for every random choice; the same seed gives byte-identical output [default: 1].
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    /// Shape of the root cell: rect, circle or ngon [default: rect].
    #[arg(
        long,
        value_name = "SHAPE",
        // Possible values, so that completions offer them (not file names).
        value_parser = clap::builder::PossibleValuesParser::new(["rect", "circle", "ngon"])
            .try_map(|name: String| name.parse::<Outline>())
    )]
    pub(crate) outline: Option<Outline>,
    /// Per-diagram area-error target Σ|A − A*| / A(parent) [default: 0.01].
    #[arg(long)]
    pub(crate) convergence: Option<f64>,
    /// Iteration cap per diagram [default: 200].
    #[arg(long)]
    pub(crate) max_iterations: Option<usize>,
    /// Items of weight 0: hide (no cell) or floor (a cell at the floor of
    /// min_weight_ratio) [default: hide, or the config's].
    #[arg(long, value_enum, value_name = "HOW")]
    pub(crate) zero_weights: Option<ZeroWeights>,
    /// Similarity between nodes (default: what the data declares).
    #[arg(long, value_enum)]
    pub(crate) similarity: Option<SimilarityKind>,
    /// Run the paper prototype's optimiser (its tick schedule, weight growth in
    /// the last 30% and pixel constants) instead of ours, for comparisons.
    #[arg(long)]
    pub(crate) prototype: bool,
    /// Snapshots per level to keep for the HTML page's optimisation slider
    /// (similarity layouts; 0 = none).
    #[arg(long, value_name = "N")]
    pub(crate) frames: Option<usize>,
    /// Layout JSON of a previous run to start from (warm start): surviving
    /// nodes keep their place, so a small data change moves the picture little.
    /// Not used if its canvas or outline differs or most nodes are gone.
    #[arg(long, value_name = "FILE.json")]
    pub(crate) previous: Option<PathBuf>,
    /// Lay out from scratch even when --previous is given.
    #[arg(long, requires = "previous")]
    pub(crate) cold: bool,
}

/// A single dataset resolved from [`LayoutOptions`]: read and parsed, with the
/// request and style its source and the flags give.
pub(crate) struct Resolved {
    /// The dataset as configured (a one-file dataset for INPUT).
    pub(crate) config: DatasetConfig,
    /// Its parsed data.
    pub(crate) dataset: Dataset,
    /// The layout request (without a previous layout).
    pub(crate) request: Request,
    /// The picture style.
    pub(crate) style: Style,
    /// Every file the job reads (the config, the inputs, `--previous`), which
    /// no output may overwrite.
    pub(crate) reads: Vec<Named>,
}

impl Resolved {
    /// Refuses outputs over what the job reads, over each other or over
    /// special files, then removes temp files killed runs left beside them.
    pub(crate) fn check_outputs(&self, outputs: &[PathBuf]) -> Result<(), BuildError> {
        let writes: Vec<Named> = outputs
            .iter()
            .map(|p| Named::new(p, format!("the output --out {}", p.display())))
            .collect();
        pipeline::check_outputs(&self.reads, &writes)?;
        pipeline::remove_stale_temps(&writes);
        Ok(())
    }
}

impl LayoutOptions {
    /// Resolves the source, reads and parses the dataset, and applies the
    /// flags to the source's settings. `method` is the method asked for, if
    /// any (each command has its own `--method`).
    pub(crate) fn job(&self, method: Option<Method>) -> anyhow::Result<Resolved> {
        let mut reads = Vec::new();
        let (config, mut request, style) = match (&self.input, &self.config) {
            (Some(input), _) => (
                DatasetConfig::hierarchy_file(input, self.weight.clone()),
                Request::default(),
                Style::default(),
            ),
            (None, Some(path)) => {
                let config = Config::from_path(path).map_err(BuildError::from)?;
                let d = pick_dataset(&config, self.dataset.as_deref(), path)?;
                reads.push(Named::new(path, "the config"));
                (d.clone(), config.request(d), config.style(d))
            }
            (None, None) => {
                return Err(UsageError("give an INPUT file, or --config".to_string()).into())
            }
        };
        let p = &mut request.params;
        if let Some(w) = self.width {
            p.canvas.width = w;
        }
        if let Some(h) = self.height {
            p.canvas.height = h;
        }
        if let Some(seed) = self.seed {
            p.seed = seed;
        }
        if let Some(outline) = &self.outline {
            p.outline = outline.clone();
        }
        if let Some(c) = self.convergence {
            p.convergence_ratio = c;
        }
        if let Some(m) = self.max_iterations {
            p.max_iterations = m;
        }
        if let Some(z) = self.zero_weights {
            p.zero_weights = z;
        }
        if method.is_some() {
            request.method = method;
        }
        if self.similarity.is_some() {
            request.similarity = self.similarity;
        }
        request.neighbor.prototype |= self.prototype;
        if let Some(frames) = self.frames {
            request.neighbor.frames = frames;
        }
        let dataset = pipeline::load(&config)?;
        for (role, path) in &config.files {
            reads.push(Named::new(path, format!("the {role} input")));
        }
        if let Some(previous) = &self.previous {
            reads.push(Named::new(previous, "the --previous layout"));
        }
        Ok(Resolved {
            config,
            dataset,
            request,
            style,
            reads,
        })
    }

    /// The `--previous` layout, read even with `--cold` (eval and bench
    /// compare both starts with it).
    pub(crate) fn previous_layout(&self) -> anyhow::Result<Option<Arc<Previous>>> {
        match &self.previous {
            Some(path) => Ok(Some(Arc::new(pipeline::read_previous(path)?))),
            None => Ok(None),
        }
    }

    /// The layout to start warm from: `--previous` unless `--cold` (the
    /// graph's one decision, [`crate::graph::start::given`]).
    pub(crate) fn warm_start(&self) -> anyhow::Result<Option<Arc<Previous>>> {
        Ok(
            crate::graph::start::given(self.cold, || self.previous_layout())
                .transpose()?
                .flatten(),
        )
    }
}

/// The dataset named `name` in `config`, or its only one.
fn pick_dataset<'a>(
    config: &'a Config,
    name: Option<&str>,
    path: &Path,
) -> Result<&'a DatasetConfig, UsageError> {
    let names = || {
        config
            .datasets
            .iter()
            .map(|d| d.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match name {
        Some(name) => config
            .datasets
            .iter()
            .find(|d| d.name == name)
            .ok_or_else(|| {
                UsageError(format!(
                    "{}: no dataset {name:?} (it has: {})",
                    path.display(),
                    names()
                ))
            }),
        None => match config.datasets.as_slice() {
            [one] => Ok(one),
            [] => Err(UsageError(format!("{}: has no datasets", path.display()))),
            _ => Err(UsageError(format!(
                "{}: pick one with --dataset (it has: {})",
                path.display(),
                names()
            ))),
        },
    }
}

/// Marks an error as the user's (bad arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct UsageError(pub(crate) String);

/// Exit code for an error: 2 when the input, the config or the arguments are
/// at fault ([`BuildError::fault`] decides for every build error), else 1.
pub(crate) fn exit_code(err: &anyhow::Error) -> u8 {
    let user = err.chain().any(|e| {
        e.is::<UsageError>()
            || e.downcast_ref::<BuildError>()
                .is_some_and(|b| b.fault() == Fault::Input)
            || daemon_fault(e) == Some(Fault::Input)
    });
    if user {
        2
    } else {
        1
    }
}

/// Whose fault a daemon error is (there is none without the `watch` feature).
fn daemon_fault(e: &(dyn std::error::Error + 'static)) -> Option<Fault> {
    #[cfg(feature = "watch")]
    if let Some(d) = e.downcast_ref::<crate::daemon::DaemonError>() {
        return Some(d.fault());
    }
    let _ = e;
    None
}

/// Prints one warning line on stderr: something in the input that was read
/// but probably not meant (a header without rows, a self pair).
pub(crate) fn warn(line: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "warning: {line}");
}

/// `-q`: status lines, notes and progress are left out.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Sets `-q` for the whole run.
pub(crate) fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// True under `-q`.
pub(crate) fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Prints one line on stderr, for a fact the user should know but that is
/// not an error (a previous layout that was not used). Silent under `-q`.
pub(crate) fn note(line: impl std::fmt::Display) {
    use std::io::Write;
    if !quiet() {
        let _ = writeln!(std::io::stderr().lock(), "note: {line}");
    }
}

/// Prints one line of a command's result on stdout. A closed pipe
/// (`nptreemap build | head`) is not an error worth a panic: the line is
/// dropped.
pub(crate) fn say(line: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{line}");
}

/// Writes a generated document on stdout; a closed pipe ends it quietly.
pub(crate) fn write_stdout(bytes: &[u8]) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// Prints one status line on stdout (what a build wrote), unless `-q`.
pub(crate) fn status(line: impl std::fmt::Display) {
    if !quiet() {
        say(line);
    }
}
