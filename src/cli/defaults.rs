//! `nptreemap config [--defaults]`: prints `config/default.yaml`, every config
//! key with its default and what it does, built into the binary so that a
//! `cargo install` user, who has no copy of the repository, can read it.

use clap::Args;

use crate::config::DEFAULT_YAML;

/// Arguments of `nptreemap config`.
#[derive(Debug, Args)]
pub(crate) struct ConfigArgs {
    /// Print every config key with its default and what it does (a config
    /// that builds nothing: `nptreemap config --defaults > nptreemap.yaml`,
    /// then add datasets). The same as `nptreemap config` alone, the only
    /// thing it prints for now.
    #[arg(long)]
    defaults: bool,
}

/// Prints what `args` asks for.
pub(crate) fn run(args: &ConfigArgs) -> anyhow::Result<()> {
    // `--defaults` or nothing: there is nothing else to print yet, and a
    // bare `nptreemap config` is no mistake worth an error.
    let _ = args.defaults;
    super::write_stdout(DEFAULT_YAML.as_bytes())
}
