//! `nptreemap completions SHELL` and `nptreemap man`: shell completion scripts
//! (clap_complete) and the man page (clap_mangen, roff), both generated from
//! the same clap definition as the parser, printed on stdout.

use clap::Args;
use clap_complete::Shell;

/// Arguments of `nptreemap completions`.
#[derive(Debug, Args)]
pub(crate) struct CompletionsArgs {
    /// The shell: bash, zsh, fish, powershell or elvish. For bash:
    /// `nptreemap completions bash > ~/.local/share/bash-completion/completions/nptreemap`.
    shell: Shell,
}

/// Prints the completion script for `args.shell`.
pub(crate) fn completions(args: &CompletionsArgs, mut cli: clap::Command) -> anyhow::Result<()> {
    let name = cli.get_name().to_string();
    let mut out = Vec::new();
    clap_complete::generate(args.shell, &mut cli, name, &mut out);
    super::write_stdout(&out)
}

/// Prints the man page, `nptreemap.1` (`nptreemap man > nptreemap.1; man ./nptreemap.1`).
pub(crate) fn man(cli: clap::Command) -> anyhow::Result<()> {
    let mut out = Vec::new();
    clap_mangen::Man::new(cli).render(&mut out)?;
    super::write_stdout(&out)
}
