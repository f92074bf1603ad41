//! Subcommands of the binary, one file each, plus the options they share.

pub(crate) mod bench;
pub(crate) mod layout;

use clap::{Args, ValueEnum};
use nptreemap::layout::{Canvas, Outline, Params};
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

    pub(crate) fn read_options(&self) -> nptreemap::workspace::ReadOptions {
        nptreemap::workspace::ReadOptions {
            weight_field: self.weight.clone(),
        }
    }
}

/// Marks an error as the user's (bad input or arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct UsageError(pub(crate) String);

/// Exit code for an error: 2 when the input or the arguments are at fault.
pub(crate) fn exit_code(err: &anyhow::Error) -> u8 {
    let user = err.chain().any(|e| {
        e.is::<InputError>() || e.is::<UsageError>() || e.is::<nptreemap::layout::LayoutError>()
    });
    if user {
        2
    } else {
        1
    }
}
