//! `nptreemap man [SUBCOMMAND]`: the man pages, generated from the same clap
//! definition as the parser (clap_mangen): `nptreemap(1)`, which lists the
//! subcommands' pages, and each `nptreemap-SUBCOMMAND(1)`; plus the sections
//! clap cannot know: EXIT STATUS, ENVIRONMENT and FILES, written with roff.

use clap::Args;
use clap_mangen::Man;
use roff::{bold, italic, roman, Inline, Roff};

use super::UsageError;
use nptreemap_formats::suggest::did_you_mean;

/// The id of `man`'s SUBCOMMAND argument (`app.rs` gives it the
/// subcommands' names as possible values).
pub(crate) const SUBCOMMAND_ARG: &str = "subcommand";

/// Arguments of `nptreemap man`.
#[derive(Debug, Args)]
pub(crate) struct ManArgs {
    /// The subcommand whose page to print (`nptreemap man build` is
    /// nptreemap-build(1)); none for nptreemap(1).
    #[arg(value_name = "SUBCOMMAND")]
    subcommand: Option<String>,
}

/// One `.TP` entry: a tag and its paragraph.
fn entry(roff: &mut Roff, tag: Inline, text: &str) {
    roff.control("TP", []).text([tag]).text([roman(text)]);
}

/// The exit codes, as `super::exit_code` and clap give them.
fn exit_status(roff: &mut Roff) {
    roff.control("SH", ["EXIT STATUS"]);
    entry(
        roff,
        bold("0"),
        "Success. For build --check: every output is up to date. For watch: stopped by \
         SIGINT or SIGTERM.",
    );
    entry(
        roff,
        bold("1"),
        "A failure that is not the input's fault (an output that cannot be written, an \
         internal error); for build --check: some outputs are out of date (named on stdout).",
    );
    entry(
        roff,
        bold("2"),
        "Bad input, config or arguments: the message names the file, line and column or the \
         node, and what is wrong; a limit exceeded names its key; existing outputs are left \
         as they were.",
    );
}

/// The environment variables the binary reads.
fn environment(roff: &mut Roff) {
    roff.control("SH", ["ENVIRONMENT"]);
    entry(
        roff,
        bold("RUST_LOG"),
        "Which log lines reach stderr, in tracing's filter syntax (debug, \
         nptreemap=debug,notify=warn); when set, it decides instead of -q and -v.",
    );
    entry(
        roff,
        bold("NO_COLOR"),
        "When set to anything but the empty string, log lines carry no colour codes. \
         Without it they are coloured only when stderr is a terminal.",
    );
    entry(
        roff,
        bold("NPTREEMAP_PROGRESS_AFTER_MS"),
        "Milliseconds a layout runs before its progress bar appears (default 1000; 0 shows it \
         at once). The bar is drawn only when stderr is a terminal, and never with -q.",
    );
    entry(
        roff,
        bold("NPTREEMAP_THREADS"),
        "The most threads a command uses (a whole number from 1; -j N decides instead). \
         Without either, one per core. The outputs are the same bytes whatever the number.",
    );
    entry(
        roff,
        bold("NPTREEMAP_NO_CACHE"),
        "When set to anything but the empty string or 0, build, layout and eval reuse \
         nothing: no stage result, no state manifest, no constraint cache, no stored layout \
         (a cold build from scratch, as the first one).",
    );
}

/// The files the commands read and write besides those a config names.
fn files(roff: &mut Roff) {
    roff.control("SH", ["FILES"]);
    entry(
        roff,
        italic("nptreemap.yaml"),
        "The config of build, check and watch: the one named (CONFIG or --config), else the \
         first nptreemap.yaml in the working directory or a folder above it. nptreemap init \
         writes one; nptreemap config --defaults prints every key with its default.",
    );
    entry(
        roff,
        italic("OUTPUT_FOLDER/.nptreemap/DATASET.layout.json"),
        "The last layout of each dataset, beside its outputs (in the output folder whose \
         path sorts first, or in the folder the config's state_dir names), with the \
         fingerprint of its layout settings: the warm start of the next build or watch. For \
         a config not named nptreemap.yaml the name starts with the config's (CONFIG.DATASET), \
         so two configs writing into one folder keep their own. Deleting it costs only a \
         cold start.",
    );
    entry(
        roff,
        italic("OUTPUT_FOLDER/.nptreemap/DATASET.manifest.json"),
        "Fingerprints of the inputs, layout settings and outputs of the last build (or watch \
         rebuild): a build or build --check that finds them unchanged stops there, and watch \
         starts without laying out. Commit it with the outputs and the stored layout.",
    );
    entry(
        roff,
        italic("OUTPUT_FOLDER/.nptreemap/cache/"),
        "The constraints of the last similarity inputs (so a weight edit computes none). \
         Local only: it holds its own .gitignore.",
    );
    entry(
        roff,
        italic(".NAME.PID.RANDOM.tmp"),
        "A temp file beside an output while it is written (then renamed over it); one left \
         by a killed run is removed by the next build or watch.",
    );
}

/// The `nptreemap` command with its subcommands' names and display names
/// (`nptreemap-build`) filled in.
fn built(mut cli: clap::Command) -> clap::Command {
    cli = cli.disable_help_subcommand(true);
    cli.build();
    cli
}

/// The SYNOPSIS section: as clap_mangen writes it, but an option that
/// takes a value shows it (`[--config <FILE>]`, clap's own usage line), where
/// clap_mangen's shows the bare flag.
fn synopsis(cmd: &clap::Command) -> Roff {
    let name = cmd.get_bin_name().unwrap_or_else(|| cmd.get_name());
    let mut line = vec![bold(name), roman(" ")];
    let mut opts: Vec<&clap::Arg> = cmd
        .get_arguments()
        .filter(|a| !a.is_hide_set() && !a.is_positional())
        .collect();
    // clap_mangen's order: the options with a short name first, by it.
    opts.sort_by_key(|a| (a.get_short().is_none(), a.get_short(), a.get_long()));
    let marks = |a: &clap::Arg| {
        if a.is_required_set() {
            ("", "")
        } else {
            ("[", "]")
        }
    };
    for opt in opts {
        let (lhs, rhs) = marks(opt);
        line.push(roman(lhs));
        match (opt.get_short(), opt.get_long()) {
            (Some(short), Some(long)) => {
                line.push(bold(format!("-{short}")));
                line.push(roman("|"));
                line.push(bold(format!("--{long}")));
            }
            (Some(short), None) => line.push(bold(format!("-{short}"))),
            (None, Some(long)) => line.push(bold(format!("--{long}"))),
            (None, None) => continue,
        }
        let takes = opt.get_num_args().is_some_and(|n| n.takes_values());
        if takes {
            let value = opt
                .get_value_names()
                .map_or_else(|| opt.get_id().as_str().to_uppercase(), |v| v.join(" "));
            let optional = opt.get_num_args().is_some_and(|n| n.min_values() == 0);
            line.push(roman(" "));
            line.push(italic(if optional {
                format!("[<{value}>]")
            } else {
                format!("<{value}>")
            }));
        }
        line.push(roman(rhs));
        if matches!(opt.get_action(), clap::ArgAction::Count) {
            line.push(roman("..."));
        }
        line.push(roman(" "));
    }
    for arg in cmd.get_positionals().filter(|a| !a.is_hide_set()) {
        let (lhs, rhs) = marks(arg);
        let value = arg
            .get_value_names()
            .map_or_else(|| arg.get_id().as_str().to_string(), |v| v.join(" "));
        line.extend([roman(lhs), italic(value), roman(rhs), roman(" ")]);
    }
    if cmd.has_subcommands() {
        line.push(italic("SUBCOMMAND"));
    }
    let mut roff = Roff::new();
    roff.control("SH", ["SYNOPSIS"]).text(line);
    roff
}

/// The sections every page opens with: title, NAME, SYNOPSIS, DESCRIPTION,
/// OPTIONS.
fn head(man: &Man, cmd: &clap::Command, out: &mut Vec<u8>) -> std::io::Result<()> {
    man.render_title(out)?;
    man.render_name_section(out)?;
    synopsis(cmd).to_writer(out)?;
    man.render_description_section(out)?;
    man.render_options_section(out)
}

/// Prints the man page of `args.subcommand`, or of `nptreemap` itself
/// (`nptreemap man > nptreemap.1; man ./nptreemap.1`).
pub(crate) fn man(args: &ManArgs, cli: clap::Command) -> anyhow::Result<()> {
    let cli = built(cli);
    let mut out = Vec::new();
    match &args.subcommand {
        None => {
            let man = Man::new(cli.clone());
            head(&man, &cli, &mut out)?;
            man.render_subcommands_section(&mut out)?;
            let mut roff = Roff::new();
            roff.control("PP", []).text([
                roman("Each subcommand's page: "),
                bold("nptreemap man SUBCOMMAND"),
                roman("."),
            ]);
            exit_status(&mut roff);
            environment(&mut roff);
            files(&mut roff);
            roff.to_writer(&mut out)?;
            man.render_version_section(&mut out)?;
        }
        Some(name) => {
            let sub = cli
                .get_subcommands()
                .find(|s| s.get_name() == name && !s.is_hide_set())
                .ok_or_else(|| {
                    let names: Vec<&str> = cli.get_subcommands().map(|s| s.get_name()).collect();
                    UsageError(format!(
                        "no subcommand {name:?}{}; the pages are: {}",
                        did_you_mean(name, names.iter().copied()),
                        names.join(", ")
                    ))
                })?;
            let version = cli.get_version().unwrap_or_default();
            let man = Man::new(sub.clone()).source(format!("nptreemap {version}"));
            head(&man, sub, &mut out)?;
            let mut roff = Roff::new();
            exit_status(&mut roff);
            roff.control("SH", ["SEE ALSO"]);
            roff.text([bold("nptreemap"), roman("(1)")]);
            roff.to_writer(&mut out)?;
            man.render_version_section(&mut out)?;
        }
    }
    super::write_stdout(&once_preamble(&out))
}

/// The page with the roff preamble that clap_mangen writes before each
/// section kept only at the top.
fn once_preamble(page: &[u8]) -> Vec<u8> {
    let text = String::from_utf8_lossy(page);
    let preamble = ".ie \\n(.g .ds Aq \\(aq\n.el .ds Aq '\n";
    match text.strip_prefix(preamble) {
        Some(rest) => format!("{preamble}{}", rest.replace(preamble, "")).into_bytes(),
        None => page.to_vec(),
    }
}
