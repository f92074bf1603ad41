//! Tests for `.npy` embedding matrices, on files written by NumPy itself
//! (`data/npy/make.py`, numpy 2.4): the 20 foods of `data/foods.csv` with the
//! vectors of `data/foods_vectors.tsv` saved in every dtype, byte order, memory
//! order and header version the reader accepts, must give the same dataset as the
//! TSV; the files it must refuse give messages naming what is wrong.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use nptreemap_formats::npy::read_npy;
use nptreemap_formats::{
    Dataset, EmbeddingMatrix, Format, FormatOptions, InputError, Inputs, Limits,
};

const FOODS: &[u8] = include_bytes!("data/foods.csv");
const VECTORS: &[u8] = include_bytes!("data/foods_vectors.tsv");

fn npy(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/npy")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn options() -> FormatOptions {
    FormatOptions {
        weight: Some("kcal".into()),
        groups: vec!["group".into()],
        ..FormatOptions::default()
    }
}

fn parse_with(nodes: &[u8], vectors: &[u8], ids: Option<&[u8]>) -> Result<Dataset, InputError> {
    let mut inputs = Inputs::new().with("nodes", nodes).with("vectors", vectors);
    if let Some(ids) = ids {
        inputs = inputs.with("ids", ids);
    }
    EmbeddingMatrix.parse(&inputs, &options())
}

fn failure(vectors: &[u8], ids: Option<&[u8]>) -> (InputError, String) {
    let error = parse_with(FOODS, vectors, ids).expect_err("must fail");
    let text = error.to_string();
    (error, text)
}

/// The TSV's vectors, the reference every .npy variant must reproduce.
fn reference() -> Dataset {
    parse_with(FOODS, VECTORS, None).expect("the TSV is valid")
}

#[test]
fn every_layout_numpy_writes_gives_the_tsv_dataset() {
    let want = reference();
    // float64 files hold the TSV's decimal values exactly as parsed.
    for name in [
        "foods_f8.npy",
        "foods_f8_be.npy",
        "foods_fortran.npy",
        "foods_v2.npy",
        "foods_v3.npy",
    ] {
        let got = parse_with(FOODS, &npy(name), None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(got, want, "{name}");
    }
    // float32 files hold the nearest float32: compare with the TSV rounded so.
    for name in ["foods_f4.npy", "foods_f4_be.npy"] {
        let got = parse_with(FOODS, &npy(name), None).unwrap_or_else(|e| panic!("{name}: {e}"));
        for leaf in want.leaves() {
            let id = &want.node(leaf).id;
            let expected: Vec<f64> = want
                .node(leaf)
                .features
                .as_ref()
                .and_then(|f| f.as_dense())
                .expect("vector")
                .iter()
                .map(|&v| f64::from(v as f32))
                .collect();
            let node = got.node(got.find(id).expect("same ids"));
            assert_eq!(node.features, Some(expected.into()), "{name}: {id}");
        }
    }
}

#[test]
fn the_matrix_alone_reads_numpys_values() {
    let bytes = npy("foods_fortran.npy");
    let m = read_npy(&bytes, &Limits::default()).expect("valid");
    assert_eq!((m.rows, m.cols), (20, 4));
    // walnut is row 17 of foods.csv: 4 g water, 14 carbs, 15 protein, 65 fat.
    assert_eq!(m.row(16), [4.0, 14.0, 15.0, 65.0]);
    assert_eq!(m.row(0), [86.0, 14.0, 0.3, 0.2], "apple");
}

#[test]
fn an_ids_file_names_the_row_order() {
    let ids = npy("foods_shuffled_ids.txt");
    let shuffled = npy("foods_shuffled.npy");
    assert_eq!(
        parse_with(FOODS, &shuffled, Some(&ids)).expect("with ids"),
        reference()
    );
    // The same without the header line, and as a CSV column with more fields.
    let text = String::from_utf8(ids.clone()).expect("utf8");
    let bare: String = text.lines().skip(1).map(|l| format!("{l}\n")).collect();
    assert_eq!(
        parse_with(FOODS, &shuffled, Some(bare.as_bytes())).expect("no header"),
        reference()
    );
    let csv: String = text.lines().map(|l| format!("{l},x\n")).collect();
    assert_eq!(
        parse_with(FOODS, &shuffled, Some(csv.as_bytes())).expect("csv"),
        reference()
    );
    // Without the ids, the shuffled rows are taken in table order: a different
    // (still valid) dataset, so the ids really were used.
    assert_ne!(
        parse_with(FOODS, &shuffled, None).expect("table order"),
        reference()
    );
}

#[test]
fn bad_ids_name_the_line() {
    let shuffled = npy("foods_shuffled.npy");
    let text = String::from_utf8(npy("foods_shuffled_ids.txt")).expect("utf8");
    let lines: Vec<&str> = text.lines().collect();
    let with = |i: usize, id: &str| {
        let mut l = lines.clone();
        l[i] = id;
        l.join("\n") + "\n"
    };
    let (error, message) = failure(&shuffled, Some(with(3, "kiwi").as_bytes()));
    assert_eq!(error.role, "ids");
    assert_eq!(error.error.line(), Some(4));
    assert!(message.contains("unknown id \"kiwi\""), "{message}");
    // `lines[1]` is apple: naming it again on line 5.
    let (error, message) = failure(&shuffled, Some(with(4, "apple").as_bytes()));
    assert_eq!(error.error.line(), Some(5));
    assert!(
        message.contains("\"apple\" is named twice (first on line 2)"),
        "{message}"
    );
    let short: String = lines[..15].iter().map(|l| format!("{l}\n")).collect();
    let (_, message) = failure(&shuffled, Some(short.as_bytes()));
    assert!(
        message.contains("14 ids for a matrix of 20 rows (shape (20, 4))"),
        "{message}"
    );
    // Without a header, a typo in the first id makes it one: the count says so.
    let typo = with(1, "appel");
    let bare = typo.split_once('\n').expect("header line").1;
    let (_, message) = failure(&shuffled, Some(bare.as_bytes()));
    assert!(
        message.contains("19 ids for a matrix of 20 rows")
            && message.contains("line 1, \"appel\", names no node and was taken for a header"),
        "{message}"
    );
    // ids beside a TSV are a mistake, not silently ignored.
    let (error, message) = failure(VECTORS, Some(text.as_bytes()));
    assert_eq!(error.role, "ids");
    assert!(
        message.contains("ids are for a .npy vectors file"),
        "{message}"
    );
}

#[test]
fn files_numpy_wrote_that_are_not_float_matrices() {
    for (name, wanted) in [
        (
            "foods_i8.npy",
            "unsupported dtype \"<i8\" (signed integers): vectors must be float32 or float64",
        ),
        ("foods_f2.npy", "unsupported dtype \"<f2\" (a float of another size)"),
        ("foods_1d.npy", "an array of shape (20,); vectors must be a 2-D matrix"),
        ("foods_3d.npy", "an array of shape (20, 2, 2)"),
        ("foods_record.npy", "structured (record) array"),
        (
            "foods_19rows.npy",
            "the matrix has 19 rows (shape (19, 4)) but the node table has 20 rows",
        ),
        (
            "foods_nan.npy",
            "matrix row 5 (node \"strawberry\"), column 3: NaN; every value must be a finite number",
        ),
    ] {
        let (error, message) = failure(&npy(name), None);
        assert_eq!(error.role, "vectors", "{name}");
        assert!(message.contains(wanted), "{name}: {message}");
    }
}

#[test]
fn cut_and_corrupt_files() {
    let good = npy("foods_f8.npy");
    let (_, message) = failure(&good[..good.len() - 8], None);
    assert!(
        message.contains("cut short: shape (20, 4) float64 needs 640 bytes, the file has 632"),
        "{message}"
    );
    let (_, message) = failure(&good[..40], None);
    assert!(message.contains("cut short inside its header"), "{message}");
    let mut zero = good.clone();
    // Row 3 (orange) starts at 128 + 2 * 32 bytes.
    zero[192..224].fill(0);
    let (_, message) = failure(&zero, None);
    assert!(
        message.contains("matrix row 3 (node \"orange\"): the vector is all zeros"),
        "{message}"
    );
    // A file that starts like a .npy but is not one is read as one (and
    // refused), not as a CSV.
    let (_, message) = failure(b"\x93NUMPY\x01\x00\xff\xff{", None);
    assert!(message.contains("cut short inside its header"), "{message}");
}
