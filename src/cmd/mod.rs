//! Subcommands of the binary, one file each, plus the options they share.

pub(crate) mod bench;
pub(crate) mod build;
pub(crate) mod eval;
pub(crate) mod layout;
mod progress;
pub(crate) mod watch;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context;
use clap::{Args, ValueEnum};
use nptreemap::layout::{Canvas, Method, NeighborParams, Outline, Params, Previous, Request};
use nptreemap::neighborhood::SimilarityKind;
use nptreemap::workspace::InputError;

/// Layout options shared by every subcommand that makes a layout.
#[derive(Debug, Clone, Args)]
pub(crate) struct LayoutOptions {
    /// Leaf field holding the weight (default: the file's `weightAttribute`, else value/weight/size).
    #[arg(long, value_name = "FIELD")]
    pub(crate) weight: Option<String>,
    /// Canvas width.
    #[arg(long, default_value_t = 1000.0)]
    pub(crate) width: f64,
    /// Canvas height.
    #[arg(long, default_value_t = 1000.0)]
    pub(crate) height: f64,
    /// Seed for every random choice; the same seed gives byte-identical output.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Shape of the root cell.
    #[arg(long, value_enum, default_value_t = OutlineArg::Rect)]
    pub(crate) outline: OutlineArg,
    /// Per-diagram area-error target Σ|A − A*| / A(parent).
    #[arg(long, default_value_t = 0.01)]
    pub(crate) convergence: f64,
    /// Iteration cap per diagram.
    #[arg(long, default_value_t = 200)]
    pub(crate) max_iterations: usize,
    /// Layout method (default: neighbor when the data has a similarity, else plain).
    #[arg(long, value_enum)]
    pub(crate) method: Option<MethodArg>,
    /// Similarity between nodes (default: what the data declares).
    #[arg(long, value_enum)]
    pub(crate) similarity: Option<SimilarityArg>,
    /// Run the paper prototype's optimiser (its tick schedule, weight growth in
    /// the last 30% and pixel constants) instead of ours, for comparisons.
    #[arg(long)]
    pub(crate) prototype: bool,
    /// Snapshots per level to keep for the HTML page's optimisation slider
    /// (similarity layouts; 0 = none).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub(crate) frames: usize,
    /// Layout JSON of a previous run to start from (warm start): surviving
    /// nodes keep their place, so a small data change moves the picture little.
    /// Not used if its canvas or outline differs or most nodes are gone.
    #[arg(long, value_name = "FILE.json")]
    pub(crate) previous: Option<PathBuf>,
    /// Lay out from scratch even when --previous is given.
    #[arg(long)]
    pub(crate) cold: bool,
}

/// Layout methods on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum MethodArg {
    /// The classic Voronoi treemap; similarity ignored.
    Plain,
    /// Random assignment to a CVT, then classic optimisation (Yao et al.).
    RandomCvt,
    /// Projection shrunk into the parent, then classic optimisation (Nocaj and Brandes).
    ProjScale,
    /// CVT, Kuhn–Munkres matching and swaps only.
    MatchSwap,
    /// The full neighbourhood-preserving method.
    Neighbor,
    /// Every method, one after the other (`eval` only).
    All,
}

impl MethodArg {
    /// The one method named, or `None` for `all`.
    pub(crate) fn method(self) -> Option<Method> {
        match self {
            MethodArg::Plain => Some(Method::Plain),
            MethodArg::RandomCvt => Some(Method::RandomCvt),
            MethodArg::ProjScale => Some(Method::ProjScale),
            MethodArg::MatchSwap => Some(Method::MatchSwap),
            MethodArg::Neighbor => Some(Method::Neighbor),
            MethodArg::All => None,
        }
    }
}

/// Similarity functions on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SimilarityArg {
    /// Cosine of feature vectors, rescaled to [0, 1].
    Cosine,
    /// Jaccard index of the vectors' non-zero supports.
    Jaccard,
    /// 1 for identical vectors (e.g. identical genre sets), else 0.
    Binary,
    /// 1 for nodes listed as each other's neighbours (shared borders), else 0.
    Neighbors,
    /// Pearson correlation of the vectors (time series), rescaled to [0, 1].
    Pearson,
}

/// Root outline choices on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum OutlineArg {
    /// The whole canvas.
    Rect,
    /// The largest centred circle.
    Circle,
    /// The largest centred regular 32-gon (the paper's prototype outline).
    Ngon,
}

impl LayoutOptions {
    pub(crate) fn params(&self) -> Params {
        Params {
            canvas: Canvas {
                width: self.width,
                height: self.height,
            },
            outline: match self.outline {
                OutlineArg::Rect => Outline::Rectangle,
                OutlineArg::Circle => Outline::Circle,
                OutlineArg::Ngon => Outline::Regular(32),
            },
            seed: self.seed,
            convergence_ratio: self.convergence,
            max_iterations: self.max_iterations,
            ..Params::default()
        }
    }

    /// The layout request; `--method all` is refused here (only `eval` takes it).
    pub(crate) fn request(&self) -> Result<Request, UsageError> {
        match self.method {
            Some(MethodArg::All) => Err(UsageError(
                "--method all is for `nptreemap eval`; pick one method here".to_string(),
            )),
            other => Ok(self.request_with(other.and_then(MethodArg::method))),
        }
    }

    /// The layout request for one method (`None`: the default for the data).
    pub(crate) fn request_with(&self, method: Option<Method>) -> Request {
        Request {
            params: self.params(),
            method,
            similarity: self.similarity.map(|s| match s {
                SimilarityArg::Cosine => SimilarityKind::Cosine,
                SimilarityArg::Jaccard => SimilarityKind::Jaccard,
                SimilarityArg::Binary => SimilarityKind::Binary,
                SimilarityArg::Neighbors => SimilarityKind::NeighborList,
                SimilarityArg::Pearson => SimilarityKind::Pearson,
            }),
            neighbor: NeighborParams {
                prototype: self.prototype,
                frames: self.frames,
                ..NeighborParams::default()
            },
            previous: None,
        }
    }

    /// The previous layout to start from: the `--previous` file, unless
    /// `--cold` is given.
    pub(crate) fn warm_start(&self) -> anyhow::Result<Option<Arc<Previous>>> {
        match &self.previous {
            Some(path) if !self.cold => Ok(Some(Arc::new(read_previous(path)?))),
            _ => Ok(None),
        }
    }

    pub(crate) fn read_options(&self) -> nptreemap::workspace::ReadOptions {
        nptreemap::workspace::ReadOptions {
            weight_field: self.weight.clone(),
        }
    }
}

/// Reads and parses a previous layout JSON file.
pub(crate) fn read_previous(path: &Path) -> anyhow::Result<Previous> {
    let bytes = nptreemap::workspace::read_bytes(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| UsageError(format!("{}: not UTF-8 text: {e}", path.display())))?;
    Previous::from_layout_json(text)
        .with_context(|| format!("{}: not a usable previous layout", path.display()))
}

/// Marks an error as the user's (bad input or arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct UsageError(pub(crate) String);

/// Exit code for an error: 2 when the input or the arguments are at fault.
pub(crate) fn exit_code(err: &anyhow::Error) -> u8 {
    // A failure to write is the machine's, not the input's: it keeps code 1.
    let user = err.chain().any(|e| {
        e.is::<InputError>()
            || e.is::<UsageError>()
            || e.is::<nptreemap::layout::LayoutError>()
            || e.is::<nptreemap::config::ConfigFileError>()
            || e.is::<nptreemap::pipeline::BuildError>()
            || matches!(
                e.downcast_ref::<nptreemap::daemon::DaemonError>(),
                Some(nptreemap::daemon::DaemonError::Config(_))
            )
            || e.is::<nptreemap::previous::PreviousError>()
    });
    if user {
        2
    } else {
        1
    }
}

/// Prints one line on stderr, for a fact the user should know but that is
/// not an error (a previous layout that was not used).
pub(crate) fn note(line: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "note: {line}");
}

/// Prints one line on stdout. A closed pipe (`nptreemap build | head`) is not
/// an error worth a panic: the line is dropped.
pub(crate) fn say(line: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{line}");
}
