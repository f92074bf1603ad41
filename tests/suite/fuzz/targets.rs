//! The fuzz targets (issue 11): structure-aware random inputs plus byte
//! mutations for every parser (CSV tables through each table format,
//! hierarchy JSON, the YAML config, layout JSON state files) and random small
//! datasets for the layout, each run by proptest with a per-case time bound
//! and a per-case allocation bound. Shared by the suite's short run
//! (`tests/suite/fuzz/mod.rs`) and the long run (`benches/fuzz.rs`), which
//! include this file by path; it uses only the libraries' public API.
//!
//! Written by hand on proptest rather than with a fuzzing engine because the
//! engines (cargo-fuzz, afl) need nightly Rust or an external toolchain; the
//! generators know each format's shape (headers, ids, numbers at the edges of
//! f64, quoting, BOMs, nesting) so random inputs get past the first syntax
//! check, and the mutations then break them in the places a hand-written
//! case would not think of.

// `pub` so both including binaries (the suite and the bench) can use them.
#![allow(unreachable_pub)]

use std::cell::Cell;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config as RunnerConfig, RngSeed, TestCaseError, TestRunner};

use nptreemap::config::Config;
use nptreemap::layout::{compute, Canvas, Method, Outline, Request};
use nptreemap::neighborhood::SimilarityKind;
use nptreemap_formats::{
    registry, Dataset, DatasetBuilder, FormatOptions, Inputs, Limits, NodeSpec,
};

// ---------------------------------------------------------------------------
// Allocation accounting: a global allocator that counts, per thread, the bytes
// currently allocated and the peak since the last reset. Each binary that
// uses the targets installs it (`#[global_allocator] static A: Counting`).

thread_local! {
    static CURRENT: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

/// The counting allocator (thread-local figures; the parsers are
/// single-threaded, the layout's worker threads are not counted).
pub struct Counting;

// SAFETY: every call is forwarded to the system allocator unchanged; the
// counters are plain thread-local cells that never allocate (const-initialised,
// no destructor), and `try_with` tolerates threads being torn down.
unsafe impl std::alloc::GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) };
        shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { std::alloc::System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            shrink(layout.size());
            grow(new_size);
        }
        p
    }
}

fn grow(bytes: usize) {
    let _ = CURRENT.try_with(|c| {
        let now = c.get().saturating_add(bytes);
        c.set(now);
        let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
    });
}

fn shrink(bytes: usize) {
    let _ = CURRENT.try_with(|c| c.set(c.get().saturating_sub(bytes)));
}

/// Runs `f` and returns its result with the peak of this thread's
/// allocations above their level at the start.
pub fn peak_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let base = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(base));
    let r = f();
    let peak = PEAK.with(Cell::get);
    (r, peak.saturating_sub(base))
}

// ---------------------------------------------------------------------------
// The driver: proptest's runner, a watchdog for the time bound, the figures.

/// What a run found.
#[derive(Debug, Default, Clone)]
pub struct Summary {
    /// The target.
    pub target: &'static str,
    /// Cases run.
    pub cases: u64,
    /// Cases the parser accepted (the rest were refused with an error).
    pub accepted: u64,
    /// Cases that failed a property (panic, limit, invariant); the run stops
    /// at the first, shrunk.
    pub failure: Option<String>,
    /// Slowest case, ms.
    pub max_case_ms: f64,
    /// Largest per-case allocation peak, bytes.
    pub max_case_bytes: usize,
    /// Wall time, s.
    pub seconds: f64,
}

/// Time and allocation bounds per case.
#[derive(Clone, Copy, Debug)]
pub struct Bounds {
    /// A case running longer than this is a hang: the watchdog reports the
    /// case's number and aborts the process (a hung case cannot be
    /// interrupted); [`Run::replay`] with that number prints its input.
    pub time: Duration,
    /// A case allocating more than this (on its own thread) fails.
    pub bytes: usize,
}

/// One run of a target.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    /// Cases to run.
    pub cases: u32,
    /// The seed of proptest's generator: the same seed gives the same cases.
    pub seed: u64,
    /// Per-case bounds.
    pub bounds: Bounds,
    /// Replay one case (1-based, as a hang report numbers it): the cases
    /// before it are generated but not checked, it is printed, then checked.
    pub replay: Option<u64>,
}

/// State the watchdog watches.
struct Watch {
    /// Start of the running case (ms since the run began), 0 when idle.
    started_ms: AtomicU64,
    /// The running case's number (1-based).
    case: AtomicU64,
    done: AtomicBool,
}

/// Runs `run.cases` cases of `strategy` through `check` (which returns
/// whether the input was accepted), under `run.bounds`, from `run.seed`.
///
/// A case's input is not formatted unless it fails: formatting every input
/// for a possible hang report cost a third of the run, so a hang reports the
/// case's number, and [`Run::replay`] regenerates and prints it.
pub fn drive<S: Strategy>(
    target: &'static str,
    strategy: S,
    check: impl Fn(&S::Value) -> Result<bool, String>,
    run: Run,
) -> Summary
where
    S::Value: std::fmt::Debug,
{
    let Run {
        cases,
        seed,
        bounds,
        replay,
    } = run;
    let begun = Instant::now();
    let watch = Arc::new(Watch {
        started_ms: AtomicU64::new(0),
        case: AtomicU64::new(0),
        done: AtomicBool::new(false),
    });
    let dog = {
        let watch = watch.clone();
        std::thread::spawn(move || {
            while !watch.done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(50));
                let started = watch.started_ms.load(Ordering::Relaxed);
                if started == 0 {
                    continue;
                }
                let now = begun.elapsed().as_millis() as u64;
                if now.saturating_sub(started) > bounds.time.as_millis() as u64 {
                    let case = watch.case.load(Ordering::Relaxed);
                    eprintln!(
                        "fuzz {target}: HANG: case {case} of seed {seed} ran over {:?}; \
                         replay it with `--seed {seed} --replay {case}` to print its input",
                        bounds.time
                    );
                    std::process::abort();
                }
            }
        })
    };
    let config = RunnerConfig {
        cases: replay.map_or(cases, |k| k.min(u64::from(u32::MAX)) as u32),
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(seed),
        max_shrink_iters: 2_000,
        ..RunnerConfig::default()
    };
    let mut runner = TestRunner::new(config);
    let accepted = AtomicUsize::new(0);
    let ran = AtomicU64::new(0);
    let max_ms = Mutex::new(0.0f64);
    let max_bytes = AtomicUsize::new(0);
    let result = runner.run(&strategy, |value| {
        let case = ran.fetch_add(1, Ordering::Relaxed) + 1;
        match replay {
            Some(k) if case < k => return Ok(()),
            Some(_) => eprintln!("fuzz {target}: case {case} of seed {seed}:\n{value:#?}"),
            None => {}
        }
        watch.case.store(case, Ordering::Relaxed);
        let t0 = Instant::now();
        watch
            .started_ms
            .store(begun.elapsed().as_millis().max(1) as u64, Ordering::Relaxed);
        let (outcome, bytes) = peak_during(|| check(&value));
        watch.started_ms.store(0, Ordering::Relaxed);
        let ms = t0.elapsed().as_secs_f64() * 1000.0;
        if let Ok(mut m) = max_ms.lock() {
            *m = m.max(ms);
        }
        max_bytes.fetch_max(bytes, Ordering::Relaxed);
        let accepted_now = outcome.map_err(TestCaseError::fail)?;
        if accepted_now {
            accepted.fetch_add(1, Ordering::Relaxed);
        }
        if bytes > bounds.bytes {
            return Err(TestCaseError::fail(format!(
                "allocated {bytes} bytes, over the bound of {}",
                bounds.bytes
            )));
        }
        Ok(())
    });
    watch.done.store(true, Ordering::Relaxed);
    let _ = dog.join();
    let failure = result.err().map(|e| e.to_string());
    Summary {
        target,
        cases: ran.load(Ordering::Relaxed),
        accepted: accepted.load(Ordering::Relaxed) as u64,
        failure,
        max_case_ms: max_ms.lock().map(|m| *m).unwrap_or(0.0),
        max_case_bytes: max_bytes.load(Ordering::Relaxed),
        seconds: begun.elapsed().as_secs_f64(),
    }
}

// ---------------------------------------------------------------------------
// Mutations, applied to a rendered input.

/// One byte-level edit at a position taken modulo the input's length.
#[derive(Clone, Debug)]
pub enum Mutation {
    /// Replace a byte.
    Set(usize, u8),
    /// Insert a byte.
    Insert(usize, u8),
    /// Delete up to n bytes.
    Delete(usize, u8),
    /// Repeat a slice of up to n bytes in place.
    Repeat(usize, u8),
    /// Cut the input here (a truncated file).
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let interesting = prop::sample::select(vec![
        b'"', b',', b'\n', b'\r', b'\t', b'{', b'}', b'[', b']', b':', b'\\', 0u8, 0xff, 0xc3,
        b'-', b'e', b'.', b'0', b'9', b'#', b'|', b'/', b'&', b'*', b'!', b' ',
    ]);
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Set(i, b)),
        (any::<usize>(), interesting).prop_map(|(i, b)| Mutation::Insert(i, b)),
        (any::<usize>(), 1u8..8).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (any::<usize>(), 1u8..32).prop_map(|(i, n)| Mutation::Repeat(i, n)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

pub fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    // Most inputs stay well-formed so the deeper checks run; some get edits.
    prop_oneof![
        3 => Just(Vec::new()),
        2 => prop::collection::vec(mutation(), 1..4),
    ]
}

/// Applies `edits` to `bytes`.
pub fn mutate(mut bytes: Vec<u8>, edits: &[Mutation]) -> Vec<u8> {
    for edit in edits {
        let len = bytes.len();
        let at = |i: usize| if len == 0 { 0 } else { i % len };
        match *edit {
            Mutation::Set(i, b) if len > 0 => bytes[at(i)] = b,
            Mutation::Set(..) => {}
            Mutation::Insert(i, b) => bytes.insert(if len == 0 { 0 } else { i % (len + 1) }, b),
            Mutation::Delete(i, n) if len > 0 => {
                let s = at(i);
                let e = (s + n as usize).min(len);
                bytes.drain(s..e);
            }
            Mutation::Delete(..) => {}
            Mutation::Repeat(i, n) if len > 0 => {
                let s = at(i);
                let e = (s + n as usize).min(len);
                let piece: Vec<u8> = bytes[s..e].to_vec();
                bytes.splice(e..e, piece);
            }
            Mutation::Repeat(..) => {}
            Mutation::Truncate(i) => bytes.truncate(if len == 0 { 0 } else { i % (len + 1) }),
        }
    }
    bytes
}

// ---------------------------------------------------------------------------
// Values at the edges, shared by the generators.

fn number_text() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "0",
            "1",
            "2.5",
            "-1",
            "-0",
            "1e308",
            "1.7976931348623157e308",
            "1e309",
            "1e-400",
            "5e-324",
            "NaN",
            "nan",
            "inf",
            "-inf",
            "Infinity",
            "0x10",
            "1_000",
            " 3 ",
            "+4",
            "1e",
            ".5",
            "5.",
            "1,5",
            "007",
            "18446744073709551616",
            "1e100",
            "1e-100",
            "",
        ])
        .prop_map(str::to_string),
        any::<f64>().prop_map(|v| v.to_string()),
        (0u32..1000).prop_map(|v| v.to_string()),
    ]
}

fn id_text() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => (0u8..8).prop_map(|i| format!("n{i}")),
        1 => prop::sample::select(vec![
            "root", "group:x", "", " ", "a/b", "a\\/b", "é", "日本", "__proto__", "constructor",
            "n0 ", "\"q\"", "a,b", "line\nbreak", "\u{feff}n1",
        ])
        .prop_map(str::to_string),
    ]
}

// ---------------------------------------------------------------------------
// Target 1: CSV tables, through every table format.

/// A generated table input and the options to read it with.
#[derive(Clone, Debug)]
pub struct CsvCase {
    /// The node table's bytes.
    pub nodes: Vec<u8>,
    /// The second input's bytes (pairs, vectors or series).
    pub other: Vec<u8>,
    /// The field mapping and limits.
    pub options: FormatOptions,
    /// Whether optional roles (the `ids` of a .npy matrix) get `other` too.
    pub optional: bool,
}

fn column_name() -> impl Strategy<Value = String> {
    prop_oneof![
        10 => prop::sample::select(vec![
            "id", "name", "label", "weight", "value", "size", "parent", "group", "region", "path",
            "color", "a", "b", "strength", "genres", "drama", "crime", "date", "v1", "v2", "n0",
            "n1", "n2", "ID", "Weight",
        ])
        .prop_map(str::to_string),
        1 => "[a-z \"é]{0,4}",
    ]
}

fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => id_text(),
        4 => number_text(),
        1 => prop::sample::select(vec![
            "#fff", "#12", "#a0b0c0", "#zzzzzz", "Drama|Crime", "Drama||", "|", "yes", "no",
            "true", "maybe", "Asia", "Asia/East", "a/b/c", "/", "x\"y", "\"", "a\u{0}b", "\r",
            "Europe", "  ",
        ])
        .prop_map(str::to_string),
    ]
}

/// Renders rows as CSV text with the given delimiter, line end, BOM and quoting.
fn render_csv(rows: &[Vec<String>], delimiter: u8, crlf: bool, bom: bool, quote: bool) -> Vec<u8> {
    let mut out = Vec::new();
    if bom {
        out.extend_from_slice(b"\xEF\xBB\xBF");
    }
    for row in rows {
        for (k, field) in row.iter().enumerate() {
            if k > 0 {
                out.push(delimiter);
            }
            let needs = field.contains(['"', '\n', '\r']) || field.as_bytes().contains(&delimiter);
            if quote && needs {
                out.push(b'"');
                out.extend_from_slice(field.replace('"', "\"\"").as_bytes());
                out.push(b'"');
            } else {
                out.extend_from_slice(field.as_bytes());
            }
        }
        out.extend_from_slice(if crlf { b"\r\n" } else { b"\n" });
    }
    out
}

fn table_bytes() -> impl Strategy<Value = Vec<u8>> {
    (
        prop::collection::vec(column_name(), 1..6),
        prop::collection::vec(prop::collection::vec(cell(), 6), 0..14),
        prop::sample::select(vec![b',', b',', b',', b'\t', b';']),
        any::<(bool, bool, bool, bool)>(),
        mutations(),
    )
        .prop_map(
            |(header, body, delimiter, (crlf, bom, quote, ragged), edits)| {
                let width = header.len();
                let mut rows = vec![header];
                for (k, mut row) in body.into_iter().enumerate() {
                    // Mostly as wide as the header; a ragged table now and then.
                    let keep = if ragged && k % 3 == 1 {
                        (width + k) % 7
                    } else {
                        width
                    };
                    row.truncate(keep);
                    rows.push(row);
                }
                mutate(render_csv(&rows, delimiter, crlf, bom, quote), &edits)
            },
        )
}

pub fn small_limits() -> impl Strategy<Value = Limits> {
    prop_oneof![
        3 => Just(Limits::default()),
        1 => (1usize..40, 1usize..6, 1usize..8).prop_map(|(n, d, k)| Limits {
            max_nodes: n,
            max_depth: d,
            max_dimensions: k,
            max_set_members: k,
            max_file_mb: 1,
        }),
    ]
}

fn options() -> impl Strategy<Value = FormatOptions> {
    let opt = |names: Vec<&'static str>| {
        prop::option::weighted(0.4, prop::sample::select(names).prop_map(str::to_string))
    };
    (
        (
            opt(vec!["id", "name", "n0", "missing"]),
            opt(vec!["label", "name"]),
            opt(vec!["weight", "value", "a", "missing"]),
            opt(vec!["color"]),
        ),
        prop_oneof![
            3 => Just((None, None, Vec::new())),
            1 => Just((Some("parent".to_string()), None, Vec::new())),
            1 => Just((None, Some("path".to_string()), Vec::new())),
            1 => Just((None, None, vec!["group".to_string()])),
            1 => Just((None, None, vec!["group".to_string(), "region".to_string()])),
            1 => Just((Some("parent".to_string()), None, vec!["group".to_string()])),
        ],
        (
            prop::option::weighted(0.2, prop::sample::select(vec!['/', '|', 'é'])),
            opt(vec!["strength", "b"]),
            opt(vec!["genres", "drama"]),
            prop_oneof![
                4 => Just(Vec::new()),
                1 => Just(vec!["drama".to_string(), "crime".to_string()]),
            ],
            any::<bool>(),
            small_limits(),
        ),
    )
        .prop_map(
            |((id, label, weight, color), (parent, path, groups), rest)| {
                let (path_separator, strength, genres, genre_columns, fill_missing, limits) = rest;
                FormatOptions {
                    id,
                    label,
                    weight,
                    color,
                    parent,
                    path,
                    path_separator,
                    groups,
                    strength,
                    genres,
                    separator: None,
                    genre_columns,
                    fill_missing,
                    limits,
                    ..FormatOptions::default()
                }
            },
        )
}

/// What a shaped case's second table is.
#[derive(Clone, Copy, Debug)]
enum Other {
    Pairs,
    Vectors,
    Series,
    Genres,
}

/// How a shaped node table gives its hierarchy.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Flat,
    Parent,
    Path,
    Groups,
}

/// A weight cell: mostly a plain positive number, now and then one at the
/// edges of f64 (so the shaped tables reach the weight checks too).
fn weight_cell() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => (1u32..100_000).prop_map(|v| v.to_string()),
        3 => (0.001f64..1e6).prop_map(|v| format!("{v}")),
        1 => number_text(),
    ]
}

/// A node table whose header and rows agree, with its options and a second
/// table (pairs, vectors, series) over the same ids: most of these parse, so
/// the deeper paths (hierarchy building, weights, similarity, warnings) run,
/// and the mutations then break them one edit at a time.
fn shaped_case() -> impl Strategy<Value = CsvCase> {
    (
        1usize..14,
        prop::sample::select(vec![Shape::Flat, Shape::Parent, Shape::Path, Shape::Groups]),
        prop::sample::select(vec![
            Other::Pairs,
            Other::Vectors,
            Other::Series,
            Other::Genres,
        ]),
        prop::collection::vec(weight_cell(), 14),
        prop::collection::vec((0usize..14, 0usize..14, 0.0f64..1.0), 0..20),
        prop::collection::vec(-5.0f64..5.0, 14 * 3),
        (
            any::<(bool, bool, bool)>(),
            prop::sample::select(vec![b',', b',', b'\t', b';']),
        ),
        (mutations(), mutations()),
        prop::option::weighted(0.05, id_text()),
    )
        .prop_map(
            |(
                n,
                shape,
                other,
                weights,
                pairs,
                coords,
                ((crlf, bom, label), delimiter),
                edits,
                odd,
            )| {
                let groups = ["Asia", "Europe", "Asia/East"];
                let ids: Vec<String> = (0..n)
                    .map(|i| match (&odd, i) {
                        (Some(id), 0) => id.clone(),
                        _ => format!("n{i}"),
                    })
                    .collect();
                let mut header = vec!["id".to_string()];
                if label {
                    header.push("label".to_string());
                }
                header.push("weight".to_string());
                match shape {
                    Shape::Flat => {}
                    Shape::Parent => header.push("parent".to_string()),
                    Shape::Path => header.push("path".to_string()),
                    Shape::Groups => header.extend(["group".to_string(), "region".to_string()]),
                }
                if matches!(other, Other::Genres) {
                    header.push("genres".to_string());
                }
                let mut rows = vec![header];
                for (i, id) in ids.iter().enumerate() {
                    let mut row = vec![id.clone()];
                    if label {
                        row.push(format!("Node {i}"));
                    }
                    row.push(weights[i].clone());
                    match shape {
                        Shape::Flat => {}
                        // A tree: each node's parent is an earlier node (or none).
                        Shape::Parent => row.push(if i == 0 {
                            String::new()
                        } else {
                            ids[(i * 7) % i].clone()
                        }),
                        Shape::Path => row.push(format!("{}/{id}", groups[i % 3])),
                        Shape::Groups => {
                            row.push(groups[i % 3].to_string());
                            row.push(format!("r{}", i % 2));
                        }
                    }
                    if matches!(other, Other::Genres) {
                        row.push(["Drama|Crime", "Crime", "Drama|Comedy", ""][i % 4].to_string());
                    }
                    rows.push(row);
                }
                let second: Vec<Vec<String>> = match other {
                    Other::Pairs => {
                        std::iter::once(vec!["a".into(), "b".into(), "strength".into()])
                            .chain(pairs.iter().map(|&(a, b, w)| {
                                vec![ids[a % n].clone(), ids[b % n].clone(), format!("{w:.3}")]
                            }))
                            .collect()
                    }
                    Other::Vectors => {
                        std::iter::once(vec!["id".into(), "v1".into(), "v2".into(), "v3".into()])
                            .chain(ids.iter().enumerate().map(|(i, id)| {
                                let mut row = vec![id.clone()];
                                row.extend((0..3).map(|k| format!("{:.4}", coords[i * 3 + k])));
                                row
                            }))
                            .collect()
                    }
                    Other::Series => {
                        let mut head = vec!["date".to_string()];
                        head.extend(ids.iter().cloned());
                        std::iter::once(head)
                            .chain((0..4).map(|d| {
                                let mut row = vec![format!("2024-01-0{}", d + 1)];
                                row.extend((0..n).map(|i| {
                                    format!("{:.3}", 100.0 + coords[(i * 3 + d) % coords.len()])
                                }));
                                row
                            }))
                            .collect()
                    }
                    Other::Genres => Vec::new(),
                };
                let options = FormatOptions {
                    id: Some("id".to_string()),
                    weight: Some("weight".to_string()),
                    parent: matches!(shape, Shape::Parent).then(|| "parent".to_string()),
                    path: matches!(shape, Shape::Path).then(|| "path".to_string()),
                    groups: if matches!(shape, Shape::Groups) {
                        vec!["group".to_string(), "region".to_string()]
                    } else {
                        Vec::new()
                    },
                    ..FormatOptions::default()
                };
                CsvCase {
                    nodes: mutate(render_csv(&rows, delimiter, crlf, bom, true), &edits.0),
                    other: mutate(render_csv(&second, delimiter, crlf, false, true), &edits.1),
                    options,
                    optional: false,
                }
            },
        )
}

/// The CSV target's inputs: half free-form tables (mostly refused, for the
/// error paths), half shaped ones (mostly accepted, for the rest).
pub fn csv_cases() -> impl Strategy<Value = CsvCase> {
    let free = (table_bytes(), table_bytes(), options(), any::<bool>()).prop_map(
        |(nodes, other, options, optional)| CsvCase {
            nodes,
            other,
            options,
            optional,
        },
    );
    prop_oneof![free, shaped_case()]
}

/// Checks that a parsed dataset honours the limits and the model's invariants.
pub fn check_dataset(dataset: &Dataset, limits: &Limits) -> Result<(), String> {
    if dataset.len() > limits.max_nodes {
        return Err(format!(
            "{} nodes over max_nodes {}",
            dataset.len(),
            limits.max_nodes
        ));
    }
    if dataset.max_depth() > limits.max_depth {
        return Err(format!(
            "depth {} over max_depth {}",
            dataset.max_depth(),
            limits.max_depth
        ));
    }
    for node in dataset.nodes() {
        if !node.value.is_finite() || node.value < 0.0 {
            return Err(format!("node {:?}: value {}", node.id, node.value));
        }
        if let Some(f) = &node.features {
            // Dense vectors are capped by max_dimensions, sets by max_set_members.
            let cap = if f.as_dense().is_some() {
                limits.max_dimensions
            } else {
                limits.max_set_members
            };
            if f.len() > cap {
                return Err(format!("node {:?}: {} dimensions", node.id, f.len()));
            }
            if f.to_dense().iter().any(|v| !v.is_finite()) {
                return Err(format!("node {:?}: non-finite feature", node.id));
            }
        }
    }
    Ok(())
}

/// Parses one CSV case with every table format; Ok(true) when any accepted it.
pub fn check_csv(case: &CsvCase) -> Result<bool, String> {
    let mut any = false;
    for format in registry::formats() {
        let roles = format.roles();
        if roles.iter().any(|r| r.name == "hierarchy") {
            continue;
        }
        let mut inputs = Inputs::new();
        for (k, role) in roles.iter().enumerate() {
            if !role.required && !case.optional {
                continue;
            }
            inputs = inputs.with(role.name, if k == 0 { &case.nodes } else { &case.other });
        }
        match format.parse(&inputs, &case.options) {
            Ok(dataset) => {
                check_dataset(&dataset, &case.options.limits)
                    .map_err(|e| format!("{}: {e}", format.name()))?;
                any = true;
            }
            Err(e) => {
                // The message must render (and name the input).
                let text = e.to_string();
                if text.is_empty() {
                    return Err(format!("{}: empty error message", format.name()));
                }
            }
        }
    }
    Ok(any)
}

// ---------------------------------------------------------------------------
// Target 2: hierarchy JSON.

fn json_number() -> impl Strategy<Value = serde_json::Value> {
    prop_oneof![
        any::<f64>().prop_map(|v| serde_json::Number::from_f64(v)
            .map_or(serde_json::Value::Null, serde_json::Value::Number)),
        prop::sample::select(vec![
            0.0,
            1.0,
            2.5,
            -3.0,
            1e308,
            1.7976931348623157e308,
            5e-324,
            1e100
        ])
        .prop_map(|v| serde_json::json!(v)),
        any::<i64>().prop_map(|v| serde_json::json!(v)),
        any::<u64>().prop_map(|v| serde_json::json!(v)),
    ]
}

fn json_scalar() -> impl Strategy<Value = serde_json::Value> {
    prop_oneof![
        3 => json_number(),
        2 => id_text().prop_map(serde_json::Value::String),
        1 => Just(serde_json::Value::Null),
        1 => any::<bool>().prop_map(serde_json::Value::Bool),
        1 => Just(serde_json::json!([])),
        1 => Just(serde_json::json!({})),
    ]
}

fn json_node() -> impl Strategy<Value = serde_json::Value> {
    let leaf = (
        prop::option::weighted(0.8, id_text()),
        prop::option::weighted(0.5, id_text()),
        prop::option::weighted(0.8, json_scalar()),
        prop::option::weighted(0.3, prop::collection::vec(json_scalar(), 0..4)),
        prop::option::weighted(0.3, prop::collection::vec(json_scalar(), 0..3)),
        prop::option::weighted(0.1, prop::sample::select(vec!["#fff", "#1234", "red"])),
    )
        .prop_map(|(id, name, value, embeddings, neighbors, color)| {
            let mut m = serde_json::Map::new();
            if let Some(id) = id {
                m.insert("id".into(), id.into());
            }
            if let Some(name) = name {
                m.insert("name".into(), name.into());
            }
            if let Some(v) = value {
                m.insert("value".into(), v);
            }
            if let Some(e) = embeddings {
                m.insert("embeddings".into(), e.into());
            }
            if let Some(n) = neighbors {
                m.insert("neighbors".into(), n.into());
            }
            if let Some(c) = color {
                m.insert("color".into(), c.into());
            }
            serde_json::Value::Object(m)
        });
    leaf.prop_recursive(5, 60, 6, |inner| {
        (
            prop::option::weighted(0.8, id_text()),
            prop_oneof![
                8 => prop::collection::vec(inner, 0..6).prop_map(serde_json::Value::Array),
                1 => json_scalar(),
            ],
        )
            .prop_map(|(id, children)| {
                let mut m = serde_json::Map::new();
                if let Some(id) = id {
                    m.insert("id".into(), id.into());
                }
                m.insert("children".into(), children);
                serde_json::Value::Object(m)
            })
    })
}

/// A generated hierarchy JSON input.
#[derive(Clone, Debug)]
pub struct JsonCase {
    /// The bytes.
    pub bytes: Vec<u8>,
    /// The weight field option.
    pub options: FormatOptions,
}

/// The hierarchy JSON target's inputs.
pub fn json_cases() -> impl Strategy<Value = JsonCase> {
    (
        json_node(),
        prop::collection::vec(
            (
                prop::sample::select(vec![
                    "weightAttribute",
                    "simAttribute",
                    "similarityMeasure",
                    "useNeighborLeafs",
                ]),
                prop_oneof![
                    prop::sample::select(vec![
                        "value",
                        "none",
                        "cosine",
                        "jaccard",
                        "binary",
                        "x",
                        "embeddings"
                    ])
                    .prop_map(serde_json::Value::from),
                    json_scalar(),
                ],
            ),
            0..3,
        ),
        any::<bool>(),
        mutations(),
        prop::option::weighted(0.2, prop::sample::select(vec!["value", "none", "weight"])),
        small_limits(),
        // Now and then a plain chain, deeper than the limits.
        prop::option::weighted(0.05, 1usize..200),
    )
        .prop_map(|(mut root, flags, pretty, edits, weight, limits, chain)| {
            if let Some(depth) = chain {
                let mut node = serde_json::json!({"id": "leaf", "value": 1});
                for i in 0..depth {
                    node = serde_json::json!({"id": format!("c{i}"), "children": [node]});
                }
                root = node;
            }
            if let serde_json::Value::Object(m) = &mut root {
                for (k, v) in flags {
                    m.insert(k.to_string(), v);
                }
            }
            let text = if pretty {
                serde_json::to_string_pretty(&root)
            } else {
                serde_json::to_string(&root)
            }
            .unwrap_or_default();
            JsonCase {
                bytes: mutate(text.into_bytes(), &edits),
                options: FormatOptions {
                    weight: weight.map(str::to_string),
                    limits,
                    ..FormatOptions::default()
                },
            }
        })
}

/// Parses one hierarchy JSON case.
pub fn check_json(case: &JsonCase) -> Result<bool, String> {
    let format = registry::find("hierarchy-json").ok_or("no hierarchy-json format")?;
    let inputs = Inputs::new().with("hierarchy", &case.bytes);
    match format.parse(&inputs, &case.options) {
        Ok(dataset) => {
            check_dataset(&dataset, &case.options.limits)?;
            Ok(true)
        }
        Err(e) => {
            let _ = e.to_string();
            Ok(false)
        }
    }
}

// ---------------------------------------------------------------------------
// Target 3: the YAML config.

/// A generated config text.
#[derive(Clone, Debug)]
pub struct YamlCase {
    /// The text's bytes (the config reader takes UTF-8 text; invalid UTF-8 is
    /// refused before it, so mutations are re-decoded lossily).
    pub text: String,
}

fn yaml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => number_text(),
        2 => prop::sample::select(vec![
            "true", "false", "null", "~", "rect", "circle", "ngon", "neighbor", "plain",
            "match-swap", "cosine", "jaccard", "\"#fff\"", "none", "[]", "{}", "[a, b]",
            "{path: out/a.svg}", "\"\"", "'x'", "!!binary aGVsbG8=", "*anchor", "&anchor 3",
            "|\n    text", ">-\n    folded", "\"\\u0000\"", "0o17", "0x1f", ".inf", "-.inf", ".nan",
            "[[[[[[[[[[[[]]]]]]]]]]]]", "1e100", "1e-100",
        ])
        .prop_map(str::to_string),
        1 => id_text().prop_map(|s| format!("{s:?}")),
    ]
}

fn yaml_key() -> impl Strategy<Value = String> {
    prop_oneof![
        10 => prop::sample::select(vec![
            "width", "height", "outline", "seed", "method", "convergence_ratio", "max_iterations",
            "min_iterations", "min_weight_ratio", "prototype", "frames", "title", "legend",
            "background", "border_color", "border_width", "stroke", "stroke_width", "labels",
            "min_font_size", "max_font_size", "tabs", "unrealized_links", "unlinked_markers",
            "max_nodes", "max_depth", "max_dimensions", "max_file_mb",
        ])
        .prop_map(str::to_string),
        1 => "[a-z_]{1,8}",
        1 => Just("<<".to_string()),
    ]
}

/// The YAML config target's inputs.
pub fn yaml_cases() -> impl Strategy<Value = YamlCase> {
    let section = (
        prop::sample::select(vec!["layout", "render", "limits", "layout", "bogus"]),
        prop::collection::vec((yaml_key(), yaml_value()), 0..5),
    );
    let dataset = (
        id_text(),
        prop::sample::select(vec![
            "border-list",
            "hierarchy-json",
            "embedding-matrix",
            "genre-table",
            "time-series",
            "nope",
        ]),
        prop::collection::vec(
            (
                prop::sample::select(vec![
                    "nodes",
                    "pairs",
                    "vectors",
                    "hierarchy",
                    "series",
                    "x",
                ]),
                prop::sample::select(vec![
                    "a.csv",
                    "../b.csv",
                    "/dev/null",
                    "",
                    "日本.csv",
                    "dir/",
                ]),
            ),
            0..3,
        ),
        prop::collection::vec(
            (
                prop::sample::select(vec![
                    "out/a.svg",
                    "out/a.png",
                    "a.json",
                    "b.html",
                    "c.bmp",
                    "",
                    ".",
                ]),
                prop::option::of(number_text()),
            ),
            0..3,
        ),
        prop::option::weighted(0.3, prop::collection::vec((yaml_key(), yaml_value()), 0..3)),
    );
    (
        prop::collection::vec(section, 0..3),
        prop::collection::vec(dataset, 0..3),
        any::<bool>(),
        mutations(),
    )
        .prop_map(|(sections, datasets, flow, edits)| {
            let mut text = String::new();
            for (name, keys) in sections {
                if flow {
                    let body: Vec<String> = keys.iter().map(|(k, v)| format!("{k}: {v}")).collect();
                    text.push_str(&format!("{name}: {{{}}}\n", body.join(", ")));
                } else {
                    text.push_str(&format!("{name}:\n"));
                    for (k, v) in keys {
                        text.push_str(&format!("  {k}: {v}\n"));
                    }
                }
            }
            if !datasets.is_empty() {
                text.push_str("datasets:\n");
            }
            for (name, format, files, outputs, fields) in datasets {
                text.push_str(&format!(
                    "  - name: {name:?}\n    format: {format}\n    files: {{"
                ));
                let files: Vec<String> = files.iter().map(|(r, p)| format!("{r}: {p:?}")).collect();
                text.push_str(&files.join(", "));
                text.push_str("}\n    outputs:\n");
                for (path, scale) in outputs {
                    match scale {
                        Some(s) => {
                            text.push_str(&format!("      - {{path: {path:?}, scale: {s}}}\n"))
                        }
                        None => text.push_str(&format!("      - path: {path:?}\n")),
                    }
                }
                if let Some(fields) = fields {
                    text.push_str("    fields:\n");
                    for (k, v) in fields {
                        text.push_str(&format!("      {k}: {v}\n"));
                    }
                }
            }
            let bytes = mutate(text.into_bytes(), &edits);
            YamlCase {
                text: String::from_utf8_lossy(&bytes).into_owned(),
            }
        })
}

/// Parses one config text.
pub fn check_yaml(case: &YamlCase) -> Result<bool, String> {
    match Config::from_str(&case.text, Path::new("/fuzz")) {
        Ok(config) => {
            // A config that parses names a usable canvas.
            let p = config.params();
            if !(p.canvas.width.is_finite() && p.canvas.height.is_finite()) {
                return Err(format!("accepted a canvas of {:?}", p.canvas));
            }
            Ok(true)
        }
        Err(e) => {
            let _ = e.to_string();
            Ok(false)
        }
    }
}

// ---------------------------------------------------------------------------
// Target 4: layout JSON state files.

/// A small dataset for the layout and state targets: leaves in groups, with
/// weights at the edges, optional vectors and relations.
#[derive(Clone, Debug)]
pub struct SmallDataset {
    /// Leaves per group.
    pub groups: Vec<Vec<(f64, Option<Vec<f64>>)>>,
    /// Relations between leaves, by leaf number.
    pub pairs: Vec<(usize, usize)>,
}

impl SmallDataset {
    /// The dataset, or None when the generator made an invalid one (the
    /// builder's errors are the formats' concern, tested above).
    pub fn build(&self) -> Option<Dataset> {
        let leaves: usize = self.groups.iter().map(Vec::len).sum();
        let mut relations: Vec<Vec<String>> = vec![Vec::new(); leaves];
        for &(x, y) in &self.pairs {
            if x < leaves && y < leaves {
                relations[x].push(format!("l{y}"));
            }
        }
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        let mut leaf = 0;
        for (g, members) in self.groups.iter().enumerate() {
            let gid = format!("g{g}");
            b.add(NodeSpec::new(gid.clone()).parent("root"));
            for (w, features) in members {
                let mut spec = NodeSpec::new(format!("l{leaf}"))
                    .parent(gid.clone())
                    .weight(*w);
                spec.features = features.clone().map(Into::into);
                spec.relations = std::mem::take(&mut relations[leaf]);
                b.add(spec);
                leaf += 1;
            }
        }
        b.build().ok()
    }
}

fn weight() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => 0.1f64..100.0,
        1 => Just(0.0),
        1 => prop::sample::select(vec![1e-300, 1e-9, 1e9, 1e300, 5e-324]),
    ]
}

fn small_dataset() -> impl Strategy<Value = SmallDataset> {
    let member = (
        weight(),
        prop::option::weighted(0.5, prop::collection::vec(-5.0f64..5.0, 3)),
    );
    (
        prop::collection::vec(prop::collection::vec(member, 1..7), 1..5),
        prop::collection::vec((0usize..20, 0usize..20), 0..10),
    )
        .prop_map(|(mut groups, pairs)| {
            // Vectors on all leaves or on none (a cosine layout needs them all).
            let all = groups.iter().flatten().all(|(_, f)| f.is_some());
            if !all {
                for m in groups.iter_mut().flatten() {
                    m.1 = None;
                }
            }
            SmallDataset { groups, pairs }
        })
}

/// Layout parameters for the layout target.
#[derive(Clone, Debug)]
pub struct LayoutCase {
    /// The dataset.
    pub data: SmallDataset,
    /// Canvas width and height.
    pub canvas: (f64, f64),
    /// 0 rect, 1 circle, 2 ngon.
    pub outline: u8,
    /// The method.
    pub method: u8,
    /// The seed.
    pub seed: u64,
}

/// The layout target's inputs.
pub fn layout_cases() -> impl Strategy<Value = LayoutCase> {
    (
        small_dataset(),
        (
            prop_oneof![Just(1.0), Just(1e6), 1.0f64..5000.0],
            prop_oneof![Just(1.0), Just(1e6), 1.0f64..5000.0],
        ),
        0u8..3,
        0u8..5,
        any::<u64>(),
    )
        .prop_map(|(data, canvas, outline, method, seed)| LayoutCase {
            data,
            canvas,
            outline,
            method,
            seed,
        })
}

fn request_of(case: &LayoutCase, has_features: bool) -> Request {
    let outline = match case.outline {
        0 => Outline::Rectangle,
        1 => Outline::Circle,
        _ => Outline::Regular(32),
    };
    let method = [
        Method::Plain,
        Method::RandomCvt,
        Method::ProjScale,
        Method::MatchSwap,
        Method::Neighbor,
    ][case.method as usize % 5];
    let mut request = Request::default();
    request.params.canvas = Canvas {
        width: case.canvas.0,
        height: case.canvas.1,
    };
    request.params.outline = outline;
    request.params.seed = case.seed;
    request.method = Some(if has_features { method } else { Method::Plain });
    request.similarity = has_features.then_some(SimilarityKind::Cosine);
    request
}

/// Lays one case out: it must succeed (or refuse with an error) and pass the
/// layout's sanity check.
pub fn check_layout(case: &LayoutCase) -> Result<bool, String> {
    let Some(dataset) = case.data.build() else {
        return Ok(false);
    };
    let has_features = dataset.leaves().all(|l| dataset.node(l).features.is_some());
    let request = request_of(case, has_features);
    match compute(&dataset, &request) {
        Ok(computed) => {
            computed
                .layout
                .sanity_check(&computed.dataset)
                .map_err(|e| format!("sanity check: {e}"))?;
            Ok(true)
        }
        Err(e) => {
            let _ = e.to_string();
            Ok(false)
        }
    }
}

/// A layout JSON state document to mutate: made from a small dataset's layout.
#[derive(Clone, Debug)]
pub struct StateCase {
    /// The document's bytes, mutated.
    pub text: String,
}

/// Structure-level edits of a layout JSON document: walks to a pseudo-random
/// node of the tree (a base-7 digit of `pick` per level) and replaces it.
fn edit_value(node: &mut serde_json::Value, pick: usize, replacement: serde_json::Value) {
    let len = match node {
        serde_json::Value::Object(m) => m.len(),
        serde_json::Value::Array(a) => a.len(),
        _ => 0,
    };
    if len == 0 {
        *node = replacement;
        return;
    }
    let k = pick % len;
    let child = match node {
        serde_json::Value::Object(m) => m.values_mut().nth(k),
        serde_json::Value::Array(a) => a.get_mut(k),
        _ => None,
    };
    let Some(child) = child else { return };
    let rest = pick / 7;
    if rest > 0 {
        edit_value(child, rest, replacement);
    } else {
        *child = replacement;
    }
}

/// The state target's inputs: real state documents (of `seeds`), edited.
pub fn state_cases(seeds: Arc<Vec<String>>) -> impl Strategy<Value = StateCase> {
    (
        0usize..seeds.len().max(1),
        prop::collection::vec((any::<usize>(), json_scalar()), 0..3),
        mutations(),
    )
        .prop_map(move |(k, edits, bytes)| {
            let base = seeds.get(k).cloned().unwrap_or_default();
            let text = match serde_json::from_str::<serde_json::Value>(&base) {
                Ok(mut doc) if !edits.is_empty() => {
                    for (pick, value) in edits {
                        edit_value(&mut doc, pick, value);
                    }
                    doc.to_string()
                }
                _ => base,
            };
            StateCase {
                text: String::from_utf8_lossy(&mutate(text.into_bytes(), &bytes)).into_owned(),
            }
        })
}

/// Reads one state document.
pub fn check_state(case: &StateCase) -> Result<bool, String> {
    match nptreemap::layout_json::read(&case.text) {
        Ok(previous) => {
            let _ = previous.nodes().len();
            Ok(true)
        }
        Err(e) => {
            let _ = e.to_string();
            Ok(false)
        }
    }
}

/// State documents of a few small layouts, the seeds of the state target.
pub fn state_seeds() -> Vec<String> {
    let mut runner = TestRunner::new(RunnerConfig {
        rng_seed: RngSeed::Fixed(7),
        ..RunnerConfig::default()
    });
    let strategy = layout_cases();
    let mut seeds = Vec::new();
    for _ in 0..40 {
        if seeds.len() >= 4 {
            break;
        }
        let Ok(tree) = strategy.new_tree(&mut runner) else {
            continue;
        };
        let case = tree.current();
        let Some(dataset) = case.data.build() else {
            continue;
        };
        let has_features = dataset.leaves().all(|l| dataset.node(l).features.is_some());
        if let Ok(computed) = compute(&dataset, &request_of(&case, has_features)) {
            seeds.push(nptreemap::layout_json::state(&computed));
        }
    }
    seeds
}
