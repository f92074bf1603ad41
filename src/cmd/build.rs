//! `nptreemap build [CONFIG]` and `nptreemap check [CONFIG]`: every output of a
//! config, or only the validation of config and data. All datasets are built in
//! memory before anything is written, so a bad input leaves every output as it was.

use std::path::PathBuf;

use clap::Args;

use super::progress::Progress;
use nptreemap::config::Config;
use nptreemap::pipeline::{self, BuildError};

/// Arguments of `nptreemap build` and `nptreemap check`.
#[derive(Debug, Args)]
pub(crate) struct BuildArgs {
    /// The config file.
    #[arg(default_value = "nptreemap.yaml")]
    config: PathBuf,
    /// Lay out from scratch instead of warm from the layout stored beside
    /// the outputs by the last build or watch.
    #[arg(long)]
    cold: bool,
}

pub(crate) fn build(args: &BuildArgs) -> anyhow::Result<()> {
    let config = Config::from_path(&args.config).map_err(BuildError::from)?;
    // Before anything is read or written: no output may land on an input,
    // the config, another output or a special file.
    let (reads, writes) = pipeline::files_of(&args.config, &config.datasets);
    pipeline::check_outputs(&reads, &writes)?;
    pipeline::remove_stale_temps(&writes);
    let progress = Progress::new(config.datasets.len());
    let mut built = Vec::new();
    for (i, d) in config.datasets.iter().enumerate() {
        progress.step(i, &d.name);
        let result = pipeline::build(d, &config.request(d), &config.style(d), args.cold);
        if result.is_err() {
            progress.finish();
        }
        built.push((d, result?));
    }
    progress.finish();
    for (d, b) in &built {
        for line in &b.warnings {
            super::warn(line);
        }
        let written = pipeline::write_outputs(&b.outputs);
        if let Some(e) = written.failed.into_iter().next() {
            return Err(e.into());
        }
        // Losing the stored layout only costs the next build its warm start.
        if let Err(e) = pipeline::store_layout(d, &b.computed) {
            tracing::warn!(dataset = %b.name, error = %e, "cannot store the layout for warm starts");
        }
        for out in &b.outputs {
            let state = if written.written.contains(&out.path) {
                "wrote"
            } else {
                "unchanged"
            };
            super::say(format_args!(
                "{state} {} ({} bytes, dataset {})",
                out.path.display(),
                out.bytes.len(),
                b.name
            ));
        }
    }
    Ok(())
}

pub(crate) fn check(args: &BuildArgs) -> anyhow::Result<()> {
    let config = Config::from_path(&args.config).map_err(BuildError::from)?;
    let (reads, writes) = pipeline::files_of(&args.config, &config.datasets);
    pipeline::check_outputs(&reads, &writes)?;
    for d in &config.datasets {
        let files = pipeline::read_inputs(d)?;
        let dataset = pipeline::parse_inputs(d, &files)?;
        for line in pipeline::warnings(&files, &dataset) {
            super::warn(line);
        }
        if !args.cold {
            if let Some(line) = pipeline::stored_layout(d).warning {
                super::warn(line);
            }
        }
        super::say(format_args!(
            "ok {}: {} nodes, {} leaves, {} outputs",
            d.name,
            dataset.len(),
            dataset.leaves().count(),
            d.outputs.len()
        ));
    }
    Ok(())
}
