//! NumPy `.npy` matrices (the file `numpy.save` writes, which embedding pipelines
//! save their vectors as): the magic bytes, a version 1, 2 or 3 preamble, the
//! Python-dict header (`descr`, `fortran_order`, `shape`) and the raw values, seen
//! as a [`Matrix`](crate::npy::Matrix) whose rows decode to `f64`. Float32 and
//! float64 in either byte order and either memory order are read; anything else is
//! an error saying what the file holds and what to save instead.
//!
//! Every step is bounded before it costs anything: the header's length
//! ([`MAX_HEADER_BYTES`](crate::npy::MAX_HEADER_BYTES)) and nesting
//! ([`MAX_HEADER_NESTING`](crate::npy::MAX_HEADER_NESTING)), the declared shape
//! against [`Limits`](crate::Limits) (rows against `max_nodes`, columns against
//! `max_dimensions`, as for a CSV of vectors) and against the bytes present; only
//! then are values decoded, straight into the vectors the caller keeps.
//!
//! Written by hand rather than with a crate: the format is a ten-byte preamble, a
//! header with three keys and a block of floats (numpy's `format.py` documents it
//! in a page), while the maintained reader, `npyz`, parses the header with a full
//! Python-literal parser (`py_literal`, which brings `pest`, `pest_derive`,
//! `num-bigint` and `num-complex`): a larger dependency tree than this file, for
//! the three keys we read.

use std::fmt;

use crate::dataset::ModelError;
use crate::error::FormatError;
use crate::limits::{Limit, Limits};

/// The first six bytes of every `.npy` file.
pub const MAGIC: &[u8] = b"\x93NUMPY";

/// The longest header read, in bytes: numpy's own `numpy.load` refuses longer
/// ones (its `max_header_size`), and a float matrix's header is under 128.
/// Checked before the header is decoded, so a hostile length costs nothing.
pub const MAX_HEADER_BYTES: usize = 10_000;

/// The deepest nesting of brackets, braces and parentheses in a header: the
/// dict and its shape tuple are two levels, numpy's structured dtypes (refused
/// anyway, with their own message) a few more. The header reader is recursive,
/// so this bound is what keeps 30,000 `[` from overflowing the stack.
pub const MAX_HEADER_NESTING: usize = 16;

/// True when `bytes` start like a `.npy` file.
pub fn is_npy(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// A 2-D float matrix in a `.npy` file: its shape and its data, decoded to
/// `f64` only when asked, so reading a matrix costs the `f64`s the caller
/// keeps and nothing more (no copy of the whole file).
#[derive(Clone, Copy)]
pub struct Matrix<'a> {
    /// Number of rows (the first dimension of the shape).
    pub rows: usize,
    /// Number of columns (the second dimension).
    pub cols: usize,
    float: Float,
    big_endian: bool,
    fortran_order: bool,
    /// Exactly `rows * cols` values of `float`, in the file's order.
    data: &'a [u8],
}

impl Matrix<'_> {
    /// Element (`i`, `j`), 0-based; both must be in range.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        // Column-major (Fortran order): element (i, j) is the (j * rows + i)-th.
        let k = if self.fortran_order {
            j * self.rows + i
        } else {
            i * self.cols + j
        };
        let size = self.float.size();
        self.decode(&self.data[k * size..(k + 1) * size])
    }

    /// Row `i` (0-based) as `f64`s.
    pub fn row(&self, i: usize) -> Vec<f64> {
        (0..self.cols).map(|j| self.get(i, j)).collect()
    }

    /// Every row as `f64`s: the one allocation of the values a reader keeps.
    /// The file's data is read in its own order (a column-major file column by
    /// column), so a large matrix streams through the cache once.
    pub fn into_rows(self) -> Vec<Vec<f64>> {
        let size = self.float.size();
        let values = self.data.chunks_exact(size).map(|chunk| self.decode(chunk));
        if !self.fortran_order {
            let mut values = values;
            return (0..self.rows)
                .map(|_| values.by_ref().take(self.cols).collect())
                .collect();
        }
        let mut rows: Vec<Vec<f64>> = (0..self.rows)
            .map(|_| Vec::with_capacity(self.cols))
            .collect();
        for (k, value) in values.enumerate() {
            rows[k % self.rows].push(value);
        }
        rows
    }

    fn decode(&self, chunk: &[u8]) -> f64 {
        match (self.float, self.big_endian) {
            (Float::F32, false) => f64::from(f32::from_le_bytes(array(chunk))),
            (Float::F32, true) => f64::from(f32::from_be_bytes(array(chunk))),
            (Float::F64, false) => f64::from_le_bytes(array(chunk)),
            (Float::F64, true) => f64::from_be_bytes(array(chunk)),
        }
    }

    /// The shape as numpy prints it, for messages.
    fn describe(rows: usize, cols: usize) -> String {
        format!("shape ({rows}, {cols})")
    }
}

/// Two matrices are equal when they hold the same values, whatever their
/// dtype, byte order or memory order.
impl PartialEq for Matrix<'_> {
    fn eq(&self, other: &Self) -> bool {
        (self.rows, self.cols) == (other.rows, other.cols)
            && (0..self.rows).all(|i| (0..self.cols).all(|j| self.get(i, j) == other.get(i, j)))
    }
}

impl fmt::Debug for Matrix<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Matrix({}, {}{}{})",
            Matrix::describe(self.rows, self.cols),
            dtype_name(self.float),
            if self.big_endian { ", big-endian" } else { "" },
            if self.fortran_order {
                ", Fortran order"
            } else {
                ""
            }
        )
    }
}

/// A float type a `.npy` file may hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Float {
    F32,
    F64,
}

impl Float {
    fn size(self) -> usize {
        match self {
            Float::F32 => 4,
            Float::F64 => 8,
        }
    }
}

/// The `.npy` header's three keys.
struct Header {
    float: Float,
    big_endian: bool,
    fortran_order: bool,
    shape: Vec<usize>,
}

/// An error of the file as a whole (a binary file has no lines).
fn bad(message: impl Into<String>) -> FormatError {
    FormatError::Structure {
        line: None,
        column: None,
        message: message.into(),
    }
}

/// Reads a `.npy` file holding a 2-D float32 or float64 matrix of at most
/// `limits.max_nodes` rows and `limits.max_dimensions` columns. The header is
/// checked whole (length, nesting, keys, shape against the limits, data size)
/// before any value is decoded.
pub fn read_npy<'a>(bytes: &'a [u8], limits: &Limits) -> Result<Matrix<'a>, FormatError> {
    if !is_npy(bytes) {
        return Err(bad(
            "not a .npy file: it does not start with the magic bytes \\x93NUMPY",
        ));
    }
    let (header_text, data) = split_header(bytes)?;
    let header = parse_header(&header_text)?;
    let [rows, cols] = header.shape[..] else {
        return Err(bad(format!(
            "the .npy file holds an array of shape {}; vectors must be a 2-D matrix \
             (one row per node, one column per dimension)",
            shape_text(&header.shape)
        )));
    };
    if rows == 0 || cols == 0 {
        return Err(bad(format!(
            "the .npy matrix is empty ({}): there are no vectors",
            Matrix::describe(rows, cols)
        )));
    }
    // The same limits as a CSV of vectors, from the declared shape: one row
    // per node, one column per dimension.
    let too_large = |source| FormatError::Model {
        line: None,
        column: None,
        source: ModelError::TooLarge(source),
    };
    if rows > limits.max_nodes {
        return Err(too_large(limits.exceeded(
            Limit::Nodes,
            format_args!(
                "the .npy matrix has {rows} rows ({}), one per node",
                Matrix::describe(rows, cols)
            ),
        )));
    }
    limits
        .check_dimensions(cols, "the vectors")
        .map_err(too_large)?;
    let size = header.float.size();
    let expected = rows
        .checked_mul(cols)
        .and_then(|n| n.checked_mul(size))
        .filter(|&n| n <= data.len())
        .ok_or_else(|| truncated(rows, cols, header.float, data.len()))?;
    if data.len() != expected {
        return Err(bad(format!(
            "the .npy file has {} bytes after its {} {} values; expected exactly {expected} \
             (one array per file, as numpy.save writes)",
            data.len() - expected,
            Matrix::describe(rows, cols),
            dtype_name(header.float),
        )));
    }
    Ok(Matrix {
        rows,
        cols,
        float: header.float,
        big_endian: header.big_endian,
        fortran_order: header.fortran_order,
        data,
    })
}

/// The first `N` bytes of `chunk` as an array (chunks are exactly `N` long).
fn array<const N: usize>(chunk: &[u8]) -> [u8; N] {
    let mut out = [0; N];
    out.copy_from_slice(&chunk[..N]);
    out
}

fn truncated(rows: usize, cols: usize, float: Float, found: usize) -> FormatError {
    bad(format!(
        "the .npy data is cut short: {} {} needs {} bytes, the file has {found}",
        Matrix::describe(rows, cols),
        dtype_name(float),
        rows.saturating_mul(cols).saturating_mul(float.size())
    ))
}

fn dtype_name(float: Float) -> &'static str {
    match float {
        Float::F32 => "float32",
        Float::F64 => "float64",
    }
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The header text and the data after it, from the version's preamble: version
/// 1.0 has a 2-byte header length, 2.0 and 3.0 a 4-byte one (little endian);
/// 3.0 headers are UTF-8, older ones Latin-1 (ASCII in practice).
fn split_header(bytes: &[u8]) -> Result<(String, &[u8]), FormatError> {
    let short = || bad("the .npy file is cut short inside its header");
    let version = bytes.get(6..8).ok_or_else(short)?;
    let (length, start): (usize, usize) = match version[0] {
        1 => {
            let b = bytes.get(8..10).ok_or_else(short)?;
            (usize::from(u16::from_le_bytes([b[0], b[1]])), 10)
        }
        2 | 3 => {
            let b = bytes.get(8..12).ok_or_else(short)?;
            let length = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            (usize::try_from(length).map_err(|_| short())?, 12)
        }
        major => {
            return Err(bad(format!(
                "unsupported .npy version {major}.{}: versions 1.0, 2.0 and 3.0 are read",
                version[1]
            )))
        }
    };
    let end = start.checked_add(length).ok_or_else(short)?;
    let raw = bytes.get(start..end).ok_or_else(short)?;
    if length > MAX_HEADER_BYTES {
        return Err(bad(format!(
            "the .npy header of {length} bytes is too long: headers are read up to \
             {MAX_HEADER_BYTES} bytes (numpy.load's own limit; a float matrix's header is \
             under 128)"
        )));
    }
    let text = if version[0] == 3 {
        String::from_utf8(raw.to_vec())
            .map_err(|_| bad("the .npy header (version 3.0) is not UTF-8"))?
    } else {
        raw.iter().copied().map(char::from).collect()
    };
    Ok((text, &bytes[end..]))
}

/// A Python literal of the header: the small subset `numpy.save` writes.
#[derive(Clone, Debug, PartialEq)]
enum Literal {
    Str(String),
    Bool(bool),
    Int(usize),
    /// A tuple or a list.
    Seq(Vec<Literal>),
    /// The header dict itself.
    Dict(Vec<(String, Literal)>),
}

/// Reads the header dict and checks its keys.
fn parse_header(text: &str) -> Result<Header, FormatError> {
    let mut parser = Parser {
        chars: text.chars().collect(),
        at: 0,
        depth: 0,
    };
    let literal = parser.value()?;
    parser.skip_space();
    if parser.at < parser.chars.len() {
        return Err(parser.error("unexpected text after the header dict"));
    }
    let Literal::Dict(entries) = literal else {
        return Err(bad("the .npy header is not a dict"));
    };
    let get = |key: &str| {
        entries
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v)
            .ok_or_else(|| bad(format!("the .npy header has no {key:?} key")))
    };
    let (float, big_endian) = match get("descr")? {
        Literal::Str(descr) => dtype(descr)?,
        Literal::Seq(_) => {
            return Err(bad(
                "unsupported dtype: the .npy file holds a structured (record) array; save a \
                 plain float32 or float64 matrix",
            ))
        }
        other => return Err(bad(format!("the .npy header's descr is {other:?}"))),
    };
    let fortran_order = match get("fortran_order")? {
        Literal::Bool(b) => *b,
        other => {
            return Err(bad(format!(
                "the .npy header's fortran_order is {other:?}, not True or False"
            )))
        }
    };
    let shape = match get("shape")? {
        Literal::Seq(items) => items
            .iter()
            .map(|item| match item {
                Literal::Int(n) => Ok(*n),
                other => Err(bad(format!(
                    "the .npy header's shape holds {other:?}, not a size"
                ))),
            })
            .collect::<Result<Vec<_>, _>>()?,
        other => return Err(bad(format!("the .npy header's shape is {other:?}"))),
    };
    Ok(Header {
        float,
        big_endian,
        fortran_order,
        shape,
    })
}

/// The float type and byte order of a dtype string such as `<f8`.
fn dtype(descr: &str) -> Result<(Float, bool), FormatError> {
    let mut chars = descr.chars();
    let order = chars.next().map(String::from).unwrap_or_default();
    let kind = chars.as_str();
    let float = match kind {
        "f4" => Some(Float::F32),
        "f8" => Some(Float::F64),
        _ => None,
    };
    match (order.as_str(), float) {
        ("<" | "=", Some(float)) => Ok((float, false)),
        (">", Some(float)) => Ok((float, true)),
        _ => Err(bad(format!(
            "unsupported dtype {descr:?} ({}): vectors must be float32 or float64 \
             ('<f4', '<f8', '>f4', '>f8'); convert with .astype('float32') before saving",
            dtype_words(kind)
        ))),
    }
}

/// What a dtype code means, for the error message.
fn dtype_words(kind: &str) -> &'static str {
    match kind.chars().next() {
        Some('f') => "a float of another size",
        Some('i') => "signed integers",
        Some('u') => "unsigned integers",
        Some('b') => "booleans",
        Some('c') => "complex numbers",
        Some('U' | 'S') => "strings",
        Some('O') => "Python objects",
        _ => "not a number type",
    }
}

/// A recursive-descent reader of the header literal, at most
/// [`MAX_HEADER_NESTING`] levels deep.
struct Parser {
    chars: Vec<char>,
    at: usize,
    /// Open brackets, braces and parentheses around the current position.
    depth: usize,
}

impl Parser {
    fn error(&self, message: &str) -> FormatError {
        bad(format!(
            "the .npy header does not parse at character {}: {message}",
            self.at + 1
        ))
    }

    fn skip_space(&mut self) {
        while self.chars.get(self.at).is_some_and(|c| c.is_whitespace()) {
            self.at += 1;
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_space();
        self.chars.get(self.at).copied()
    }

    fn expect(&mut self, wanted: char) -> Result<(), FormatError> {
        if self.peek() == Some(wanted) {
            self.at += 1;
            Ok(())
        } else {
            Err(self.error(&format!("expected {wanted:?}")))
        }
    }

    fn value(&mut self) -> Result<Literal, FormatError> {
        match self.peek() {
            Some('{') => self.dict(),
            Some('(') => self.seq(')'),
            Some('[') => self.seq(']'),
            Some(q @ ('\'' | '"')) => self.string(q).map(Literal::Str),
            Some(c) if c.is_ascii_digit() => self.int(),
            Some(c) if c.is_alphabetic() => {
                let start = self.at;
                while self.chars.get(self.at).is_some_and(|c| c.is_alphanumeric()) {
                    self.at += 1;
                }
                let word: String = self.chars[start..self.at].iter().collect();
                match word.as_str() {
                    "True" => Ok(Literal::Bool(true)),
                    "False" => Ok(Literal::Bool(false)),
                    _ => {
                        self.at = start;
                        Err(self.error(&format!("unexpected {word:?}")))
                    }
                }
            }
            _ => Err(self.error("expected a value")),
        }
    }

    /// Items up to `close`, a trailing comma allowed (`(20,)`, `{... , }`).
    fn items<T>(
        &mut self,
        close: char,
        mut item: impl FnMut(&mut Self) -> Result<T, FormatError>,
    ) -> Result<Vec<T>, FormatError> {
        if self.depth >= MAX_HEADER_NESTING {
            return Err(bad(format!(
                "the .npy header nests deeper than {MAX_HEADER_NESTING} levels of brackets at \
                 character {} (a float matrix's header nests 2)",
                self.at + 1
            )));
        }
        self.depth += 1;
        self.at += 1;
        let mut out = Vec::new();
        loop {
            if self.peek() == Some(close) {
                self.at += 1;
                self.depth -= 1;
                return Ok(out);
            }
            out.push(item(self)?);
            match self.peek() {
                Some(',') => self.at += 1,
                Some(c) if c == close => {}
                _ => return Err(self.error(&format!("expected ',' or {close:?}"))),
            }
        }
    }

    fn dict(&mut self) -> Result<Literal, FormatError> {
        self.items('}', |p| {
            let key = match p.peek() {
                Some(q @ ('\'' | '"')) => p.string(q)?,
                _ => return Err(p.error("expected a quoted key")),
            };
            p.expect(':')?;
            Ok((key, p.value()?))
        })
        .map(Literal::Dict)
    }

    fn seq(&mut self, close: char) -> Result<Literal, FormatError> {
        self.items(close, Self::value).map(Literal::Seq)
    }

    fn string(&mut self, quote: char) -> Result<String, FormatError> {
        self.at += 1;
        let start = self.at;
        while let Some(&c) = self.chars.get(self.at) {
            if c == quote {
                let text = self.chars[start..self.at].iter().collect();
                self.at += 1;
                return Ok(text);
            }
            self.at += 1;
        }
        Err(self.error("a string is never closed"))
    }

    fn int(&mut self) -> Result<Literal, FormatError> {
        let start = self.at;
        while self.chars.get(self.at).is_some_and(char::is_ascii_digit) {
            self.at += 1;
        }
        // numpy 1.x wrote sizes as Python 2 longs (`20L`).
        if self.chars.get(self.at) == Some(&'L') {
            self.at += 1;
        }
        let digits: String = self.chars[start..self.at]
            .iter()
            .filter(|c| c.is_ascii_digit())
            .collect();
        digits
            .parse()
            .map(Literal::Int)
            .map_err(|_| self.error(&format!("size {digits} is too large")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version 1.0 file with `header` and `data`, laid out as numpy does.
    fn file(header: &str, data: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend([1, 0]);
        let padded = format!("{header:<118}\n");
        out.extend(u16::try_from(padded.len()).expect("short").to_le_bytes());
        out.extend(padded.as_bytes());
        out.extend(data);
        out
    }

    fn floats(values: &[f64]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn reads_a_small_matrix_in_both_orders() {
        let c = file(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }",
            &floats(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
        );
        let m = read_npy(&c, &Limits::default()).expect("valid");
        assert_eq!((m.rows, m.cols), (2, 3));
        assert_eq!(m.row(1), [4.0, 5.0, 6.0]);
        // The same matrix stored column by column.
        let f = file(
            "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }",
            &floats(&[1.0, 4.0, 2.0, 5.0, 3.0, 6.0]),
        );
        assert_eq!(read_npy(&f, &Limits::default()).expect("valid"), m);
    }

    #[test]
    fn header_oddities_numpy_has_written() {
        // Double quotes, no trailing comma, Python 2 longs.
        let c = file(
            "{\"descr\": \"<f8\", \"shape\": (1L, 2L), \"fortran_order\": False}",
            &floats(&[1.0, 2.0]),
        );
        assert_eq!(
            read_npy(&c, &Limits::default()).expect("valid").row(0),
            [1.0, 2.0]
        );
    }

    #[test]
    fn malformed_files_say_what_is_wrong() {
        let ok = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }";
        for (bytes, wanted) in [
            (b"id,v1\n".to_vec(), "magic bytes"),
            (MAGIC.to_vec(), "cut short inside its header"),
            (
                {
                    let mut b = file(ok, &[]);
                    b[6] = 4;
                    b
                },
                "unsupported .npy version 4.0",
            ),
            (file(ok, &floats(&[1.0; 5])), "cut short: shape (2, 3)"),
            (file(ok, &floats(&[1.0; 7])), "8 bytes after"),
            (
                file("{'descr': '<f8', 'shape': (2, 3), }", &[]),
                "no \"fortran_order\" key",
            ),
            (
                file("{'descr': '<f8', 'fortran_order': Maybe}", &[]),
                "character 35: unexpected \"Maybe\"",
            ),
            (
                file("{'descr': '<f8, 'shape': (2, 3)}", &[]),
                "does not parse",
            ),
            (
                file(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (0, 3), }",
                    &[],
                ),
                "empty (shape (0, 3))",
            ),
            (
                file(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999, 2), }",
                    &[],
                ),
                "99999999999 rows",
            ),
        ] {
            let error = read_npy(&bytes, &Limits::default())
                .expect_err(wanted)
                .to_string();
            assert!(error.contains(wanted), "{wanted}: {error}");
        }
        // Without limits in the way, a shape whose size overflows is cut short.
        let unlimited = Limits {
            max_nodes: usize::MAX,
            max_dimensions: usize::MAX,
            ..Limits::default()
        };
        let huge = file(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999, 99999999999), }",
            &[],
        );
        let error = read_npy(&huge, &unlimited)
            .expect_err("overflow")
            .to_string();
        assert!(error.contains("cut short"), "{error}");
    }
}
