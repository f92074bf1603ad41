//! `nptreemap completions SHELL`: shell completion scripts (clap_complete),
//! generated from the same clap definition as the parser, printed on stdout.
//! Flags that take one of a few names declare them as possible values, so
//! the scripts complete them (the man pages are `man.rs`).

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
