//! `nptreemap init [TABLE…]`: sniffs the given CSV/TSV tables (and `.npy`
//! matrices) and writes a commented `nptreemap.yaml` that builds at once: the
//! node table (the one the others refer to; its id, label, numeric weight and
//! grouping columns), and what makes nodes similar: a pairs table (`a,b`), a
//! vectors table (`id,v1..`) or `.npy` matrix, a series table (a date column,
//! then one column per id) or a multi-valued column (`Drama|Crime`). It reads
//! a bounded sample of each table (`sample`), guesses the fields from it
//! (`guess`; flags override), decides the config and refuses what `build`
//! would refuse under the default limits (`plan`), and writes it (`yaml`)
//! only where it may (`output`).

mod guess;
mod output;
mod plan;
mod sample;
mod yaml;

use std::path::{Path, PathBuf};

use clap::Args;
use nptreemap_formats::Limits;

use super::config_file::CONFIG_NAME;
use guess::Overrides;
use sample::Input;

/// Arguments of `nptreemap init`.
#[derive(Debug, Args)]
pub(crate) struct InitArgs {
    /// The tables (CSV or TSV with a header): the node table and, optionally,
    /// a pairs, vectors or series table referring to its ids, or a `.npy`
    /// matrix with one vector per row of the node table.
    #[arg(required = true, value_name = "TABLE")]
    tables: Vec<PathBuf>,
    /// Where to write the config (never over one of the TABLEs, a FIFO or
    /// through a dangling link).
    #[arg(long, short, default_value = CONFIG_NAME, value_name = "FILE")]
    output: PathBuf,
    /// Replace an existing config.
    #[arg(long)]
    force: bool,
    /// The node table's label column (default: `label`, `name` or `title`,
    /// else the first short text column unique per row).
    #[arg(long, value_name = "COLUMN")]
    label: Option<String>,
    /// The node table's weight column, a number >= 0 per row: the cell areas
    /// (default: `weight`, `value` or `size`, else the first such column).
    #[arg(long, value_name = "COLUMN")]
    weight: Option<String>,
    /// Grouping columns, outermost first, comma-separated; `--groups=` for
    /// none (default: up to two text columns whose values repeat).
    #[arg(long, value_name = "COLUMN,..", value_delimiter = ',')]
    groups: Option<Vec<String>>,
    /// A column listing several values per row (`Drama|Crime`): nodes are
    /// similar when their sets overlap (the genre-table format).
    #[arg(long, value_name = "COLUMN")]
    genres: Option<String>,
}

impl InitArgs {
    fn overrides(&self) -> Overrides {
        Overrides {
            label: self.label.clone(),
            weight: self.weight.clone(),
            groups: self.groups.as_ref().map(|g| {
                g.iter()
                    .map(|c| c.trim().to_owned())
                    .filter(|c| !c.is_empty())
                    .collect()
            }),
            genres: self.genres.clone(),
        }
    }
}

pub(crate) fn run(args: &InitArgs) -> anyhow::Result<()> {
    // Before anything is read: where the config goes must be safe to write.
    output::check(&args.output, &args.tables, args.force)?;
    // The limits a config without a `limits:` section gets, as init writes it.
    let limits = Limits::default();
    let inputs = args
        .tables
        .iter()
        .map(|p| Input::read(p, &limits))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let request = plan::Request {
        output: &args.output,
        overrides: args.overrides(),
        command_line: command_line(),
        limits,
    };
    let plan = plan::plan(&inputs, &request)?;
    let text = yaml::config_text(&plan)
        .map_err(|e| anyhow::anyhow!("cannot write the config as YAML: {e}"))?;
    // Checked as the build will read it, before anything is written.
    let base = args.output.parent().unwrap_or(Path::new(""));
    crate::config::Config::from_str(&text, base).map_err(|e| {
        anyhow::anyhow!(
            "init wrote a config that does not parse ({e}); please report this:\n{text}"
        )
    })?;
    output::write(&args.output, &text)?;
    super::status(format_args!(
        "wrote {}; build it with `nptreemap build {}`",
        args.output.display(),
        args.output.display()
    ));
    Ok(())
}

/// `nptreemap init …` as typed, for the config's first comment.
fn command_line() -> String {
    std::iter::once("nptreemap".to_owned())
        .chain(
            std::env::args_os()
                .skip(1)
                .map(|a| a.to_string_lossy().into_owned()),
        )
        .collect::<Vec<_>>()
        .join(" ")
}
