//! The stages of a build, for every command that makes pictures (`build`,
//! `watch`, `layout`, `eval`, `bench`): **read** a dataset's files, **parse**
//! them with its format from the registry, **lay out**, **render** every output
//! in memory, **write** the outputs that changed. Writing is its own stage, so
//! a failure anywhere before it leaves every existing output untouched. No
//! loop, no watcher, no printing; the stage graph (`crate::graph`) composes
//! them, memoised, and callers decide what to say.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::config::{
    ConfigFileError, DatasetConfig, OutputConfig, DEFAULT_EXEC_TIMEOUT, EXEC_FORMAT,
    MAX_EXEC_TIMEOUT,
};
use crate::exec::{self, ExecError};
use crate::layout::{compute, Computed, LayoutError, Previous, Request};
use crate::render::{OutputError, Parts, Style};
#[cfg(feature = "png")]
use crate::render::PngError;
use crate::workspace::FileError;
use crate::{layout_json, state, store, workspace};
use nptreemap_formats::{registry, suggest, Dataset, Inputs};

/// Why a build could not be made. [`BuildError::fault`] says whose fault it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// The config file cannot be read or used.
    #[error(transparent)]
    Config(#[from] ConfigFileError),
    /// The config names a format that is not registered.
    #[error("dataset {dataset:?}: unknown format {format:?}{hint} (known: {known})")]
    UnknownFormat {
        /// The dataset's name.
        dataset: String,
        /// The format named.
        format: String,
        /// "; did you mean ...?" for a likely misspelling, else empty.
        hint: String,
        /// The registered names.
        known: String,
    },
    /// The format needs an input the config does not give.
    #[error("dataset {dataset:?}: format {format:?} needs `files: {{{role}: ...}}`")]
    MissingFile {
        /// The dataset's name.
        dataset: String,
        /// The format.
        format: String,
        /// The missing role.
        role: String,
    },
    /// The config gives an input the format does not read.
    #[error(
        "dataset {dataset:?}: format {format:?} reads no file called {role:?}{hint} (it reads: {roles})"
    )]
    UnknownRole {
        /// The dataset's name.
        dataset: String,
        /// The format.
        format: String,
        /// The extra role.
        role: String,
        /// "; did you mean ...?" for a likely misspelling, else empty.
        hint: String,
        /// The roles it reads.
        roles: String,
    },
    /// An input file could not be read or parsed.
    #[error(transparent)]
    File(#[from] FileError),
    /// A previous layout given to start from is not layout JSON.
    #[error("{}: not a usable previous layout: {source}", .path.display())]
    Previous {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the field.
        source: layout_json::ReadError,
    },
    /// The layout could not be made.
    #[error("dataset {dataset:?}: {source}")]
    Layout {
        /// The dataset's name.
        dataset: String,
        /// Why.
        source: LayoutError,
    },
    /// A `format: exec` command did not produce a dataset.
    #[error("dataset {dataset:?}: {source}")]
    Exec {
        /// The dataset.
        dataset: String,
        /// What went wrong.
        source: ExecError,
    },
    /// The PNG renderer refused the picture (see [`PngError`]).
    #[cfg(feature = "png")]
    #[error("{}: {source}", .path.display())]
    Png {
        /// The output.
        path: PathBuf,
        /// Why.
        source: PngError,
    },
    /// An output needs a Cargo feature this build was compiled without
    /// (so with every feature on, nothing constructs it).
    #[cfg_attr(feature = "png", allow(dead_code))]
    #[error(
        "{}: {what} needs nptreemap built with the `{feature}` feature \
         (it is on by default: cargo install nptreemap, or --features {feature})",
        .path.display()
    )]
    Unsupported {
        /// The output.
        path: PathBuf,
        /// What it asks for (`PNG output`).
        what: &'static str,
        /// The feature that provides it.
        feature: &'static str,
    },
    /// An output could not be written.
    #[error("{}: cannot write: {source}", .path.display())]
    Write {
        /// The output.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// An output names a file the run reads, or another output (checked
    /// before anything is written, after resolving links and `..`).
    #[error(
        "{}: {what} is the same file as {other_what} ({}); refusing to overwrite it",
        .path.display(),
        .other.display()
    )]
    OutputClash {
        /// The output, as configured.
        path: PathBuf,
        /// Which output it is (`datasets[0].outputs[1]`, `--out`).
        what: String,
        /// The other file, as configured.
        other: PathBuf,
        /// What the other file is (`the config`, an input, an output).
        other_what: String,
    },
    /// An output's path holds something that is not a regular file (a FIFO,
    /// a device, a directory), which a rename would replace.
    #[error(
        "{}: {what} exists and is not a regular file ({kind}); refusing to replace it",
        .path.display()
    )]
    OutputSpecial {
        /// The output.
        path: PathBuf,
        /// Which output it is.
        what: String,
        /// What is there.
        kind: &'static str,
    },
}

/// Whose fault a failed build is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The input's or the config's: the user can fix it (exit code 2; the
    /// daemon keeps the last good outputs and waits for the next edit).
    Input,
    /// The system's: a disk that refuses a write, a bug (exit code 1).
    System,
}

impl BuildError {
    /// Whose fault this is: the one place that decides it, for exit codes and
    /// for the daemon alike.
    pub fn fault(&self) -> Fault {
        match self {
            BuildError::Config(_)
            | BuildError::UnknownFormat { .. }
            | BuildError::MissingFile { .. }
            | BuildError::UnknownRole { .. }
            | BuildError::File(_)
            | BuildError::Previous { .. }
            | BuildError::Layout { .. }
            | BuildError::Unsupported { .. }
            | BuildError::Exec { .. }
            | BuildError::OutputClash { .. }
            | BuildError::OutputSpecial { .. } => Fault::Input,
            // A size is the user's `scale:`; anything else means our own SVG
            // did not parse or encode, which is a bug.
            #[cfg(feature = "png")]
            BuildError::Png { source, .. } => match source {
                PngError::Size { .. } => Fault::Input,
                PngError::Svg(_) | PngError::Encode(_) => Fault::System,
            },
            BuildError::Write { .. } => Fault::System,
        }
    }

    /// The input file this error says is missing, if that is what it says.
    pub fn missing_file(&self) -> Option<&Path> {
        match self {
            BuildError::File(FileError::Read { path, source })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                Some(path)
            }
            _ => None,
        }
    }
}

/// One input file of a dataset, read.
#[derive(Clone, Debug, PartialEq)]
pub struct InputFile {
    /// The format's name for it (`nodes`, `pairs`, ...).
    pub role: String,
    /// Where it was read from.
    pub path: PathBuf,
    /// Its content.
    pub bytes: Vec<u8>,
}

/// One output, rendered and not yet written.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// Where it goes.
    pub path: PathBuf,
    /// Its bytes.
    pub bytes: Vec<u8>,
}

/// What writing a set of outputs did.
#[derive(Debug, Default)]
pub struct Written {
    /// Outputs whose bytes changed and were written, in order.
    pub written: Vec<PathBuf>,
    /// Outputs left alone because their bytes would not change.
    pub unchanged: Vec<PathBuf>,
    /// Outputs that could not be written (the others were still tried).
    pub failed: Vec<BuildError>,
}

/// Stage 1, read: a dataset's input files (after checking the config names
/// the roles its format reads), not parsed yet.
pub fn read_inputs(d: &DatasetConfig) -> Result<Vec<InputFile>, BuildError> {
    if d.format == EXEC_FORMAT {
        return run_exec(d).map(|file| vec![file]);
    }
    let format = format_of(d)?;
    let roles = format.roles();
    for role in d.files.keys() {
        if !roles.iter().any(|r| r.name == role) {
            return Err(BuildError::UnknownRole {
                dataset: d.name.clone(),
                format: d.format.clone(),
                role: role.clone(),
                hint: suggest::did_you_mean(role, roles.iter().map(|r| r.name)),
                roles: roles.iter().map(|r| r.name).collect::<Vec<_>>().join(", "),
            });
        }
    }
    if let Some(r) = roles
        .iter()
        .find(|r| r.required && !d.files.contains_key(r.name))
    {
        return Err(BuildError::MissingFile {
            dataset: d.name.clone(),
            format: d.format.clone(),
            role: r.name.to_string(),
        });
    }
    d.files
        .iter()
        .map(|(role, path)| {
            Ok(InputFile {
                role: role.clone(),
                path: path.clone(),
                bytes: workspace::read_input(path, &d.fields.limits)?,
            })
        })
        .collect()
}

/// `format: exec`: the command's stdout, as the `hierarchy` input of
/// hierarchy JSON, named after the command. The declared files must exist
/// (a missing one is reported as a missing file, as for any format); the
/// command gets their paths as they are valid in its folder, the config's,
/// wherever nptreemap was started.
fn run_exec(d: &DatasetConfig) -> Result<InputFile, BuildError> {
    if let Some(missing) = d.files.values().find(|f| !workspace::exists(f)) {
        return Err(BuildError::File(FileError::Read {
            path: missing.clone(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        }));
    }
    let dir = if d.base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        d.base.as_path()
    };
    let files: Vec<PathBuf> = d.files.values().map(|f| in_folder(f, &d.base)).collect();
    // The config keeps the timeout within a day; a dataset made in code
    // gets the longest rather than a panic.
    let seconds = d.timeout.unwrap_or(DEFAULT_EXEC_TIMEOUT);
    let bounds = exec::Bounds {
        timeout: Duration::try_from_secs_f64(seconds.min(MAX_EXEC_TIMEOUT))
            .unwrap_or(Duration::from_secs_f64(MAX_EXEC_TIMEOUT)),
        max_mb: d.max_adapter_mb,
    };
    let bytes = exec::run(&d.command, &files, dir, bounds).map_err(|source| BuildError::Exec {
        dataset: d.name.clone(),
        source,
    })?;
    Ok(adapter_input(d, bytes))
}

/// `path` (the config's folder `base` joined with what the config says) as
/// it is valid inside `base`: what the config says when that was relative,
/// so the adapter sees the names the user wrote; else the path itself. A
/// name that would read as an option (`-x.csv`) gets `./` in front.
fn in_folder(path: &Path, base: &Path) -> PathBuf {
    match path.strip_prefix(base) {
        Ok(inner) if inner.as_os_str().as_encoded_bytes().starts_with(b"-") => {
            Path::new(".").join(inner)
        }
        Ok(inner) if !inner.as_os_str().is_empty() => inner.to_path_buf(),
        _ => path.to_path_buf(),
    }
}

/// An adapter's stdout as the `hierarchy` input its dataset is parsed from.
fn adapter_input(d: &DatasetConfig, stdout: Vec<u8>) -> InputFile {
    let files: Vec<PathBuf> = d.files.values().map(|f| in_folder(f, &d.base)).collect();
    InputFile {
        role: "hierarchy".to_string(),
        path: PathBuf::from(format!("`{}` (stdout)", exec::display(&d.command, &files))),
        bytes: stdout,
    }
}

/// Parses what the adapter of `d` (a `format: exec` dataset) printed into
/// its dataset, exactly as [`read_inputs`] and [`parse_inputs`] do after
/// running it: the fuzz harness's target for "the adapter's output".
#[cfg(any(test, feature = "internals"))]
pub fn parse_adapter_output(d: &DatasetConfig, stdout: Vec<u8>) -> Result<Dataset, BuildError> {
    parse_inputs(d, &[adapter_input(d, stdout)])
}

fn format_of(d: &DatasetConfig) -> Result<&'static dyn nptreemap_formats::Format, BuildError> {
    // An exec command prints hierarchy JSON.
    let name = if d.format == EXEC_FORMAT {
        "hierarchy-json"
    } else {
        &d.format
    };
    registry::find(name).ok_or_else(|| BuildError::UnknownFormat {
        dataset: d.name.clone(),
        format: d.format.clone(),
        hint: suggest::did_you_mean(
            &d.format,
            registry::names().into_iter().chain([EXEC_FORMAT]),
        ),
        known: format!("{}, {EXEC_FORMAT}", registry::names().join(", ")),
    })
}

/// Stage 2, parse: the read files into a validated dataset, with the
/// dataset's format and field mapping. Errors name the file, line and column.
pub fn parse_inputs(d: &DatasetConfig, files: &[InputFile]) -> Result<Dataset, BuildError> {
    let format = format_of(d)?;
    let mut inputs = Inputs::new();
    for f in files {
        inputs = inputs.with(&f.role, &f.bytes);
    }
    format.parse(&inputs, &d.fields).map_err(|e| {
        let path = files
            .iter()
            .find(|f| f.role == e.role)
            .map(|f| f.path.clone())
            .unwrap_or_else(|| PathBuf::from(&e.role));
        BuildError::File(FileError::Parse {
            path,
            source: Box::new(e.error),
        })
    })
}

/// Stages 1 and 2: reads and parses one dataset.
pub fn load(d: &DatasetConfig) -> Result<Dataset, BuildError> {
    parse_inputs(d, &read_inputs(d)?)
}

/// Stage 3, lay out: a parsed dataset by `request` (warm when it carries a
/// previous layout that fits: same canvas and outline, at least half the
/// nodes surviving; else cold, see [`Computed::start`]).
pub fn lay_out(
    d: &DatasetConfig,
    dataset: &Dataset,
    request: &Request,
) -> Result<Computed, BuildError> {
    compute(dataset, request).map_err(|source| BuildError::Layout {
        dataset: d.name.clone(),
        source,
    })
}

/// Stage 4, render: the bytes of each of `outputs` for a computed layout, in
/// order. The picture is drawn once for every SVG and PNG output (it is the
/// same text).
pub fn render_outputs(
    computed: &Computed,
    style: &Style,
    outputs: &[OutputConfig],
) -> Result<Vec<Rendered>, BuildError> {
    let (mut picture, parts) = (None, Parts::new());
    outputs
        .iter()
        .map(|out| {
            let bytes = render_output(computed, style, out, &[], &mut picture, &parts)?;
            Ok(Rendered {
                path: out.path.clone(),
                bytes,
            })
        })
        .collect()
}

/// One output of [`render_outputs`] (its kind's renderer,
/// [`OutputKind::render`]), with the `past` layouts an HTML page shows;
/// `picture` keeps the picture between the outputs of one layout.
pub fn render_output(
    computed: &Computed,
    style: &Style,
    out: &OutputConfig,
    past: &[std::sync::Arc<Computed>],
    picture: &mut Option<std::sync::Arc<crate::render::Picture>>,
    parts: &Parts,
) -> Result<Vec<u8>, BuildError> {
    let path = out.path.clone();
    out.kind()
        .render(computed, style, out.scale, past, picture, parts)
        .map_err(|e| match e {
            #[cfg(feature = "png")]
            OutputError::Png(source) => BuildError::Png { path, source },
            OutputError::Unsupported { what, feature } => BuildError::Unsupported {
                path,
                what,
                feature,
            },
        })
}

/// The input warnings of a parsed dataset (a header without rows, a column
/// named twice, a self pair, a pair repeated with another strength), one
/// line each, `file: line L: message`; past the first few of a kind the
/// dataset carries one `file: and N more ...` line instead
/// ([`nptreemap_formats::Warnings`]), so a flood never reaches the journal.
pub fn warnings(files: &[InputFile], dataset: &Dataset) -> Vec<String> {
    dataset
        .warnings()
        .iter()
        .map(|w| {
            let file = files
                .iter()
                .find(|f| f.role == w.role)
                .map_or_else(|| w.role.clone(), |f| f.path.display().to_string());
            format!("{file}: {w}")
        })
        .collect()
}

/// Stage 5, write: every output atomically (temp file + rename), except those
/// whose bytes would not change. A failure does not stop the others. Holds
/// [`store::writing`] throughout, so a forced exit never lands between two
/// outputs of one set.
pub fn write_outputs(outputs: &[Rendered]) -> Written {
    let files: Vec<(&Path, &[u8])> = outputs
        .iter()
        .map(|r| (r.path.as_path(), r.bytes.as_slice()))
        .collect();
    let writing = store::writing();
    write_files(&files, &writing, true)
}

/// [`write_outputs`] of borrowed bytes (a build's outputs are written from
/// where the render left them, not from a copy: tens of megabytes at
/// thousands of leaves) that are known to differ from their files (their
/// fingerprints against the files' when the build began: none is read
/// back to compare, which at 6,000 headers read 30 MB of the same size
/// after a weight edit), with `beside` run at the same time (the build's
/// state files, which vouch for no output). The write lock is taken here,
/// on the caller's thread, never inside a rayon job: a pool thread that
/// held it while waiting on the pool could take up another build's write
/// and wait for the lock it holds itself.
pub fn write_files_beside<R: Send>(
    outputs: &[(&Path, &[u8])],
    beside: impl FnOnce() -> R + Send,
) -> (Written, R) {
    let writing = store::writing();
    rayon::join(|| write_files(outputs, &writing, false), beside)
}

/// The writes of [`write_outputs`], each file compared with its bytes first
/// when `compare`; the caller holds [`store::writing`].
fn write_files(outputs: &[(&Path, &[u8])], _writing: &store::Writing, compare: bool) -> Written {
    let mut out = Written::default();
    // Each file is compared, written and synced on its own (tens of
    // megabytes at thousands of leaves); the lists keep the outputs' order.
    let results: Vec<std::io::Result<bool>> = {
        use rayon::prelude::*;
        outputs
            .par_iter()
            .map(|(path, bytes)| match compare {
                true => store::write_if_changed(path, bytes),
                false => store::write_atomic(path, bytes).map(|()| true),
            })
            .collect()
    };
    for ((path, _), result) in outputs.iter().zip(results) {
        match result {
            Ok(true) => out.written.push(path.to_path_buf()),
            Ok(false) => out.unchanged.push(path.to_path_buf()),
            Err(source) => out.failed.push(BuildError::Write {
                path: path.to_path_buf(),
                source,
            }),
        }
    }
    out
}

/// Reads a previous layout (layout JSON) to start from.
pub fn read_previous(path: &Path) -> Result<Previous, BuildError> {
    let text = workspace::read_text(path)?;
    layout_json::read(&text).map_err(|source| BuildError::Previous {
        path: path.to_path_buf(),
        source,
    })
}

/// A file a run reads or writes, with the words a message names it by.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    /// The path, as configured.
    pub path: PathBuf,
    /// What it is: `the config`, `an input of dataset "d"`, `datasets[0].outputs[1]`.
    pub what: String,
}

impl Named {
    /// A path with its description.
    pub fn new(path: impl Into<PathBuf>, what: impl Into<String>) -> Self {
        Named {
            path: path.into(),
            what: what.into(),
        }
    }
}

/// The files building `datasets` of the config at `config_path` reads (the
/// config, every input) and writes (every output, every stored layout).
pub fn files_of(config_path: &Path, datasets: &[DatasetConfig]) -> (Vec<Named>, Vec<Named>) {
    let mut reads = vec![Named::new(config_path, "the config")];
    let mut writes = Vec::new();
    for (i, d) in datasets.iter().enumerate() {
        for (role, path) in &d.files {
            reads.push(Named::new(
                path,
                format!("the {role} input of dataset {:?}", d.name),
            ));
        }
        for (k, out) in d.outputs.iter().enumerate() {
            writes.push(Named::new(
                &out.path,
                format!("datasets[{i}].outputs[{k}] (dataset {:?})", d.name),
            ));
        }
        for (path, what) in [
            (state::layout_path(d), "the stored layout"),
            (state::manifest_path(d), "the state manifest"),
            (state::constraints_path(d), "the constraint cache"),
        ] {
            if let Some(path) = path {
                writes.push(Named::new(path, format!("{what} of dataset {:?}", d.name)));
            }
        }
    }
    (reads, writes)
}

/// Refuses, before anything is written, an output that is the same file as
/// something the run reads or as another output (after resolving links and
/// `..`), and an output whose path holds something other than a regular file
/// (a FIFO, a device, a directory: a rename would replace it). Outputs outside
/// the config's folder are allowed (`../site/static/` for a docs site).
pub fn check_outputs(reads: &[Named], writes: &[Named]) -> Result<(), BuildError> {
    let mut seen: std::collections::HashMap<PathBuf, &Named> = Default::default();
    for r in reads {
        seen.entry(workspace::resolve(&r.path)).or_insert(r);
    }
    for w in writes {
        if let Some(kind) = workspace::special_at(&w.path) {
            return Err(BuildError::OutputSpecial {
                path: w.path.clone(),
                what: w.what.clone(),
                kind,
            });
        }
        let real = workspace::resolve(&w.path);
        if let Some(other) = seen.get(&real) {
            return Err(BuildError::OutputClash {
                path: w.path.clone(),
                what: w.what.clone(),
                other: other.path.clone(),
                other_what: other.what.clone(),
            });
        }
        seen.insert(real, w);
    }
    Ok(())
}

/// Removes the temp files killed runs left beside `writes` (see
/// [`store::remove_stale_temps`]), logging each.
pub fn remove_stale_temps(writes: &[Named]) {
    let paths: Vec<PathBuf> = writes.iter().map(|w| w.path.clone()).collect();
    for path in store::remove_stale_temps(&paths) {
        tracing::info!(?path, "removed a temp file left by an interrupted run");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn computed() -> Computed {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        for (id, w) in [("a", 1.0), ("b", 2.0), ("c", 3.0)] {
            b.add(NodeSpec::new(id).parent("root").weight(w));
        }
        compute(&b.build().expect("valid"), &Request::default()).expect("laid out")
    }

    /// The adapter's output is parsed as a `hierarchy-json` file of the
    /// dataset would be, and its errors name the command line and the line.
    #[test]
    fn adapter_output_parses_as_hierarchy_json_naming_the_command() {
        let config = crate::config::Config::from_str(
            "datasets:\n  - {name: a, format: exec, command: [python3, t.py], files: {x: in.csv}}\n",
            Path::new("/base"),
        )
        .expect("config");
        let d = &config.datasets[0];
        let tree = br#"{"name": "r", "children": [{"name": "a", "value": 1}, {"name": "b", "value": 3}]}"#;
        let dataset = parse_adapter_output(d, tree.to_vec()).expect("a tree");
        assert_eq!(dataset.leaves().count(), 2);
        let e = parse_adapter_output(d, b"{\n  \"children\": 3}".to_vec()).expect_err("not a tree");
        assert_eq!(e.fault(), Fault::Input);
        let text = e.to_string();
        assert!(text.starts_with("`python3 t.py in.csv` (stdout): line 2"), "{text}");
    }

    /// An adapter gets its files as the config wrote them (they are valid in
    /// its folder, the config's), never as an option.
    #[test]
    fn adapter_files_are_valid_in_the_config_folder() {
        let base = Path::new("examples/exec");
        for (written, given) in [
            ("sizes.du", "sizes.du"),
            ("../data/x.csv", "../data/x.csv"),
            ("-x.csv", "./-x.csv"),
            ("/abs/x.csv", "/abs/x.csv"),
        ] {
            assert_eq!(in_folder(&base.join(written), base), Path::new(given));
        }
        assert_eq!(in_folder(Path::new("x.csv"), Path::new("")), Path::new("x.csv"));
    }

    /// Without the `png` feature a PNG output is the user's error naming the
    /// output and the feature; the other outputs of the build still render.
    #[test]
    fn png_output_needs_the_png_feature() {
        let out = |path: &str| OutputConfig {
            path: PathBuf::from(path),
            kind: crate::render::OutputKind::of_path(Path::new(path)),
            scale: 1.0,
        };
        let computed = computed();
        let style = Style::default();
        let svg = render_outputs(&computed, &style, &[out("out/a.svg")]).expect("svg");
        assert!(String::from_utf8_lossy(&svg[0].bytes).starts_with("<svg"));
        let png = render_outputs(&computed, &style, &[out("out/a.svg"), out("out/a.png")]);
        if cfg!(feature = "png") {
            let png = png.expect("png");
            assert!(png[1].bytes.starts_with(b"\x89PNG"));
        } else {
            let e = png.expect_err("no png feature");
            assert_eq!(e.fault(), Fault::Input);
            assert_eq!(
                e.to_string(),
                "out/a.png: PNG output needs nptreemap built with the `png` feature (it is on \
                 by default: cargo install nptreemap, or --features png)"
            );
        }
    }
}
