//! The fuzz targets of `.npy` vectors and of an exec adapter's output (issue
//! 21): generated `.npy` files (dtypes, byte and memory orders, header versions,
//! shapes up to absurd declared sizes, nesting, padding, truncation) through the
//! embedding-matrix format, and the bytes an adapter may print (du_tree-like
//! trees with neighbour lists, Python's `NaN`, debug lines, two documents, BOMs,
//! CRLF, deep folders) through the parse the pipeline gives an exec dataset's
//! stdout. Byte mutations break both further. Shared, like `targets.rs`, by the
//! suite's short slice and `benches/fuzz.rs`.

#![allow(unreachable_pub)]

use std::path::Path;
use std::sync::OnceLock;

use proptest::prelude::*;

use nptreemap::config::{Config, DatasetConfig};
use nptreemap::pipeline::{self, Fault};
use nptreemap_formats::npy::read_npy;
use nptreemap_formats::{EmbeddingMatrix, Format, FormatOptions, Inputs, Limits};

use super::targets::{check_dataset, mutate, mutations, small_limits};

// ---------------------------------------------------------------------------
// Target: `.npy` vectors.

/// A generated `.npy` case: the matrix, the node table it belongs to and an
/// optional `ids` input.
#[derive(Clone, Debug)]
pub struct NpyCase {
    /// The node table.
    pub nodes: Vec<u8>,
    /// The `.npy` file.
    pub npy: Vec<u8>,
    /// The `ids` input, when given.
    pub ids: Option<Vec<u8>>,
    /// The limits to read within.
    pub limits: Limits,
}

/// The dtype as written in the header (quoted, or a structured dtype's list).
fn descr() -> impl Strategy<Value = String> {
    prop_oneof![
        24 => prop::sample::select(vec!["<f8", "<f4", ">f8", ">f4"]).prop_map(|d| format!("'{d}'")),
        2 => prop::sample::select(vec![
            "=f8", "|f8", "<f2", "<f16", "<i8", "|u1", "|b1", "<c16", "<U5", "|S3", "|O", "f8", "",
            "<", "<f", "<f8 ",
        ])
        .prop_map(|d| format!("'{d}'")),
        1 => prop::sample::select(vec![
            "[('a', '<f8'), ('b', '<f4')]",
            "('<f8', (2,))",
            "'<f8'L",
            "\"<f8\"",
            "<f8",
            "None",
            "{'x': 1}",
        ])
        .prop_map(str::to_string),
    ]
}

/// One dimension of the shape, as written.
fn dimension() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => (0usize..8).prop_map(|d| d.to_string()),
        1 => prop::sample::select(vec![
            "20", "1025", "1000000000", "99999999999", "18446744073709551615",
            "99999999999999999999", "3L", "-1", "2.0", "0x10", "", "True",
        ])
        .prop_map(str::to_string),
    ]
}

/// The shape: usually 2-D, now and then of another rank, bracketed oddly or
/// nested deep.
fn shape() -> impl Strategy<Value = (String, Option<(usize, usize)>)> {
    (
        prop::collection::vec(dimension(), 0..4),
        prop_oneof![
            6 => (1usize..6, 1usize..5).prop_map(|(r, c)| Some((r, c))),
            1 => Just(None),
        ],
        prop::sample::select(vec!["()", "()", "()", "[]"]),
        // Now and then nested deep, once in a while as deep as the probe
        // that overflowed the stack (30,000 brackets).
        prop::option::weighted(0.05, prop_oneof![40 => 1usize..40, 1 => Just(30_000usize)]),
    )
        .prop_map(|(dims, plain, brackets, nesting)| {
            let (open, close) = (&brackets[..1], &brackets[1..]);
            let (mut text, rc) = match plain {
                // A plain 2-D shape the data will match.
                Some((r, c)) => (format!("{open}{r}, {c}{close}"), Some((r, c))),
                None => match dims.len() {
                    1 => (format!("{open}{},{close}", dims[0]), None),
                    _ => (format!("{open}{}{close}", dims.join(", ")), None),
                },
            };
            if let Some(depth) = nesting {
                text = format!("{}{text}{}", "[".repeat(depth), "]".repeat(depth));
            }
            (text, rc)
        })
}

/// Values at the edges, for the data block.
fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        60 => -5.0f64..5.0,
        1 => prop::sample::select(vec![
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            1e308,
            1e-300,
            5e-324,
            3.5e38,
            1e150
        ]),
    ]
}

/// The `.npy` target's inputs.
pub fn npy_cases() -> impl Strategy<Value = NpyCase> {
    (
        (
            descr(),
            prop_oneof![
                8 => prop::sample::select(vec!["False", "True"]),
                1 => prop::sample::select(vec!["0", "None", "false", "'False'"]),
            ],
            shape(),
            prop::sample::select(vec![0usize, 0, 0, 1, 1, 2, 3]),
        ),
        (
            prop_oneof![
                12 => prop::sample::select(vec![1u8, 2, 3]),
                1 => prop::sample::select(vec![0u8, 4, 255]),
            ],
            any::<bool>(),
            prop_oneof![
                12 => Just(0i64),
                1 => prop::sample::select(vec![-1i64, -8, 8, -4, -1000]),
            ],
            prop::collection::vec(value(), 64),
        ),
        (
            prop::option::weighted(0.2, 1usize..6),
            prop::option::weighted(0.2, any::<bool>()),
        ),
        small_limits(),
        mutations(),
    )
        .prop_map(
            |(
                (descr, fortran, (shape, plain), order),
                (version, pad, delta, values),
                (nodes, ids),
                limits,
                edits,
            )| {
                let entries = [
                    format!("'descr': {descr}"),
                    format!("'fortran_order': {fortran}"),
                    format!("'shape': {shape}"),
                ];
                let keys: Vec<&String> = match order {
                    0 => entries.iter().collect(),
                    1 => entries.iter().rev().collect(),
                    2 => entries.iter().skip(1).collect(),
                    _ => vec![&entries[0], &entries[2], &entries[1], &entries[0]],
                };
                let mut header = format!(
                    "{{{}, }}",
                    keys.iter()
                        .map(|k| k.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                if pad {
                    while (12 + header.len() + 1) % 64 != 0 {
                        header.push(' ');
                    }
                    header.push('\n');
                }
                let mut out = b"\x93NUMPY".to_vec();
                out.extend([version, 0]);
                if version == 1 {
                    out.extend((header.len().min(0xffff) as u16).to_le_bytes());
                } else {
                    out.extend((header.len() as u32).to_le_bytes());
                }
                out.extend(header.as_bytes());
                // The data a plain shape calls for, in the dtype it names.
                let (rows, cols) = plain.unwrap_or((2, 2));
                let f4 = descr.contains("f4");
                let big = descr.starts_with("'>");
                for k in 0..rows * cols {
                    let v = values[k % values.len()];
                    match (f4, big) {
                        (true, false) => out.extend((v as f32).to_le_bytes()),
                        (true, true) => out.extend((v as f32).to_be_bytes()),
                        (false, false) => out.extend(v.to_le_bytes()),
                        (false, true) => out.extend(v.to_be_bytes()),
                    }
                }
                let len = out.len() as i64 + delta;
                out.resize(len.max(0) as usize, 0x3f);
                // As many nodes as the matrix has rows, now and then another
                // count.
                let nodes = nodes.unwrap_or(rows);
                let table: String = std::iter::once("id,weight\n".to_string())
                    .chain((0..nodes).map(|i| format!("n{i},{}\n", i + 1)))
                    .collect();
                // An ids input naming the rows in reverse (or, now and then,
                // one id too few or unknown).
                let ids = ids.map(|complete| {
                    let mut lines: Vec<String> = (0..rows).rev().map(|i| format!("n{i}")).collect();
                    if !complete {
                        lines.pop();
                        lines.push("nobody".to_string());
                    }
                    (lines.join("\n") + "\n").into_bytes()
                });
                NpyCase {
                    nodes: table.into_bytes(),
                    npy: mutate(out, &edits),
                    ids,
                    limits,
                }
            },
        )
}

/// Reads one `.npy` case through the embedding-matrix format (and the matrix
/// alone): accepted only within the limits, refused with a message.
pub fn check_npy(case: &NpyCase) -> Result<bool, String> {
    if let Ok(matrix) = read_npy(&case.npy, &case.limits) {
        if matrix.rows > case.limits.max_nodes || matrix.cols > case.limits.max_dimensions {
            return Err(format!(
                "read_npy accepted {matrix:?} over {:?}",
                case.limits
            ));
        }
        let rows = matrix.into_rows();
        if rows.len() != matrix.rows || rows.iter().any(|r| r.len() != matrix.cols) {
            return Err(format!("{matrix:?}: rows of the wrong length"));
        }
    }
    let mut inputs = Inputs::new()
        .with("nodes", &case.nodes)
        .with("vectors", &case.npy);
    if let Some(ids) = &case.ids {
        inputs = inputs.with("ids", ids);
    }
    let options = FormatOptions {
        limits: case.limits,
        ..FormatOptions::default()
    };
    match EmbeddingMatrix.parse(&inputs, &options) {
        Ok(dataset) => {
            check_dataset(&dataset, &case.limits)?;
            if dataset.leaves().any(|l| dataset.node(l).features.is_none()) {
                return Err("a leaf without a vector".to_string());
            }
            Ok(true)
        }
        Err(e) if e.to_string().is_empty() => Err("an empty error message".to_string()),
        Err(_) => Ok(false),
    }
}

// ---------------------------------------------------------------------------
// Target: an exec adapter's output.

/// Bytes an adapter printed, and whether the config had small limits.
#[derive(Clone, Debug)]
pub struct AdapterCase {
    /// The adapter's stdout.
    pub stdout: Vec<u8>,
    /// Read with small limits (`limits:` of a config) rather than the defaults.
    pub small: bool,
}

/// One du_tree-like node: a file with a size and maybe same-named neighbours,
/// or a folder.
fn adapter_node() -> impl Strategy<Value = serde_json::Value> {
    let size = prop_oneof![
        40 => (1u64..100_000).prop_map(serde_json::Value::from),
        1 => prop::sample::select(vec![0.0, 0.5, 1e308, -1.0]).prop_map(serde_json::Value::from),
        1 => prop::sample::select(vec!["12", "", "NaN"]).prop_map(serde_json::Value::from),
    ];
    let leaf = (
        "[a-z]{1,6}(\\.rs)?",
        size,
        prop::option::weighted(
            0.4,
            prop::collection::vec(
                prop_oneof![
                    4 => "(src|tests)/[a-z]{1,3}(\\.rs)?",
                    1 => Just("missing/elsewhere.rs".to_string()),
                ],
                0..4,
            ),
        ),
    )
        .prop_map(|(name, value, neighbors)| {
            let mut m = serde_json::Map::new();
            m.insert("id".into(), format!("src/{name}").into());
            m.insert("name".into(), name.into());
            m.insert("value".into(), value);
            if let Some(n) = neighbors {
                m.insert("neighbors".into(), n.into());
            }
            serde_json::Value::Object(m)
        });
    leaf.prop_recursive(4, 40, 6, |inner| {
        ("[a-z]{1,6}", prop::collection::vec(inner, 1..6)).prop_map(|(name, children)| {
            serde_json::json!({"id": format!("src/{name}"), "name": name, "children": children})
        })
    })
}

/// The adapter target's inputs: the trees an adapter like `du_tree.py` prints,
/// with the slips real adapters make.
pub fn adapter_cases() -> impl Strategy<Value = AdapterCase> {
    (
        prop::collection::vec(adapter_node(), 0..8),
        prop::option::of(any::<bool>()),
        (any::<bool>(), any::<bool>()),
        prop::sample::select(vec![
            "",
            "",
            "",
            "",
            "",
            "debug: 3 files\n",
            "\u{feff}",
            "\n\n",
            "null",
            "[]",
        ]),
        prop::sample::select(vec![
            "",
            "",
            "",
            "",
            "",
            "",
            "",
            "\n",
            "\nDone.\n",
            "{}",
            " trailing",
            "\0",
        ]),
        prop::option::weighted(0.05, 1usize..300),
        (prop::option::weighted(0.05, Just("NaN")), any::<bool>()),
        mutations(),
    )
        .prop_map(
            |(children, flag, (indent, crlf), before, after, chain, (nan, small), edits)| {
                let mut root = serde_json::json!({"id": "root", "name": "sizes"});
                root["children"] = serde_json::Value::Array(children);
                if let Some(depth) = chain {
                    // A folder tree deeper than any limit.
                    let mut node = serde_json::json!({"id": "leaf", "value": 1});
                    for i in 0..depth {
                        node = serde_json::json!({"id": format!("d{i}"), "children": [node]});
                    }
                    root["children"] = serde_json::json!([node]);
                }
                if let Some(flag) = flag {
                    root["useNeighborLeafs"] = flag.into();
                }
                let mut text = if indent {
                    serde_json::to_string_pretty(&root)
                } else {
                    serde_json::to_string(&root)
                }
                .unwrap_or_default();
                if let Some(nan) = nan {
                    // Python's json.dump writes NaN for a float nan.
                    text = text.replacen(":1", &format!(":{nan}"), 1);
                }
                if crlf {
                    text = text.replace('\n', "\r\n");
                }
                let bytes = format!("{before}{text}{after}").into_bytes();
                AdapterCase {
                    stdout: mutate(bytes, &edits),
                    small,
                }
            },
        )
}

/// The exec dataset of `examples/exec/nptreemap.yaml`, with the default
/// limits and with small ones.
fn exec_datasets() -> &'static (DatasetConfig, DatasetConfig) {
    static DATASETS: OnceLock<(DatasetConfig, DatasetConfig)> = OnceLock::new();
    DATASETS.get_or_init(|| {
        let text = include_str!("../../../examples/exec/nptreemap.yaml");
        let dataset = |text: &str| {
            let config = Config::from_str(text, Path::new("/fuzz/exec"))
                .unwrap_or_else(|e| panic!("the exec example's config: {e}"));
            config
                .datasets
                .into_iter()
                .find(|d| d.format == "exec")
                .expect("an exec dataset")
        };
        let small = format!("limits: {{max_nodes: 30, max_depth: 4, max_dimensions: 4}}\n{text}");
        (dataset(text), dataset(&small))
    })
}

/// Parses one adapter output as the pipeline parses an exec dataset's stdout
/// (`pipeline::parse_adapter_output`, the path `run_exec` takes): accepted only within the
/// limits; refused as the input's fault, naming the command's stdout.
pub fn check_adapter(case: &AdapterCase) -> Result<bool, String> {
    let (default, small) = exec_datasets();
    let d = if case.small { small } else { default };
    match pipeline::parse_adapter_output(d, case.stdout.clone()) {
        Ok(dataset) => {
            check_dataset(&dataset, &d.fields.limits)?;
            Ok(true)
        }
        Err(e) => {
            let text = e.to_string();
            if e.fault() != Fault::Input {
                return Err(format!("not the input's fault: {text}"));
            }
            if !text.contains("(stdout)") {
                return Err(format!("the error does not name the stdout: {text}"));
            }
            Ok(false)
        }
    }
}
