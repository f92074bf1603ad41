//! What `init` reads of each file it is given, and no more: the kind (a `.npy`
//! matrix by its magic bytes, else CSV/TSV text), a bounded sample of a
//! table's first rows, parsed by the formats' own reader so init sees the
//! table as the build will, and, for a table larger than its sample, one
//! streaming pass with fixed buffers that counts its rows and collects its id
//! column. Every file is first checked as the build checks it: a regular file
//! (a FIFO is never opened for a blocking read) within `limits.max_file_mb`.

use std::collections::HashSet;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

use nptreemap_formats::table::{detect_delimiter, read_table, Table};
use nptreemap_formats::{npy, FormatError, Limits};

use crate::pipeline::BuildError;
use crate::workspace::{self, FileError};

/// Most bytes of a table init reads to sniff it: room for thousands of rows,
/// and for a header of 100,000 column names.
pub(super) const SAMPLE_BYTES: usize = 1 << 20;

/// Most rows (the header included) of a table init parses to sniff it.
pub(super) const SAMPLE_ROWS: usize = 10_000;

/// Longest id the streaming pass collects (longer ones are not kept, so a
/// pathological field costs no memory; the build reports what is wrong).
const MAX_ID_BYTES: usize = 4096;

/// One file given to `init`.
pub(super) struct Input {
    /// As named on the command line.
    pub(super) path: PathBuf,
    /// What it holds.
    pub(super) content: Content,
}

/// What an input holds.
pub(super) enum Content {
    /// A CSV/TSV table (its first rows).
    Table(Sampled),
    /// A `.npy` matrix: its rows and columns.
    Npy { rows: usize, cols: usize },
}

/// The first rows of a table, and whether they are all of it.
pub(super) struct Sampled {
    /// The header and the first rows, as the formats read them.
    pub(super) table: Table,
    /// True when `table` holds every row of the file.
    pub(super) whole: bool,
    /// The field delimiter (detected from the header, as the build does).
    pub(super) delimiter: u8,
}

/// A whole table's row count and, when asked for, the values of one column
/// (the id column), from one streaming pass.
pub(super) struct Scan {
    /// Data rows (the header not counted; blank lines skipped).
    pub(super) rows: usize,
    /// The column's values, trimmed; at most `limits.max_nodes + 1` of them
    /// are kept (a table with more is refused anyway).
    pub(super) ids: HashSet<String>,
}

fn file_error(e: FileError) -> anyhow::Error {
    BuildError::File(e).into()
}

fn parse_error(path: &Path, e: FormatError) -> anyhow::Error {
    file_error(FileError::Parse {
        path: path.to_path_buf(),
        source: Box::new(e),
    })
}

impl Input {
    /// Reads what `init` needs of `path` within `limits`.
    pub(super) fn read(path: &Path, limits: &Limits) -> anyhow::Result<Input> {
        let (file, _) = workspace::open_input(path, limits).map_err(file_error)?;
        // One byte past the sample tells whether the sample is the whole file.
        let mut head = Vec::new();
        file.take(SAMPLE_BYTES as u64 + 1)
            .read_to_end(&mut head)
            .map_err(|source| {
                file_error(FileError::Read {
                    path: path.to_path_buf(),
                    source,
                })
            })?;
        let content = if npy::is_npy(&head) {
            // The reader takes the whole file; the size limit is checked first.
            let bytes = workspace::read_input(path, limits).map_err(file_error)?;
            let matrix = npy::read_npy(&bytes, limits).map_err(|e| parse_error(path, e))?;
            Content::Npy {
                rows: matrix.rows,
                cols: matrix.cols,
            }
        } else {
            let whole_file = head.len() <= SAMPLE_BYTES;
            let end = sample_end(&head, SAMPLE_ROWS, whole_file);
            if end == 0 {
                return Err(parse_error(
                    path,
                    FormatError::Structure {
                        line: Some(1),
                        column: None,
                        message: format!(
                            "no line end in the first {} MiB: init sniffs a table by its first \
                             rows (write the config by hand: `nptreemap config --defaults` lists \
                             every key)",
                            SAMPLE_BYTES >> 20
                        ),
                    },
                ));
            }
            let sample = &head[..end];
            let table = read_table(sample, None).map_err(|e| parse_error(path, e))?;
            Content::Table(Sampled {
                table,
                whole: whole_file && end == head.len(),
                delimiter: detect_delimiter(sample, None),
            })
        };
        Ok(Input {
            path: path.to_path_buf(),
            content,
        })
    }
}

/// Where a sample of `bytes` ends: just after the `records`-th line end that
/// is outside quotes, else (when the bytes are not the whole file) after the
/// last such line end, so no record is cut; a whole file ends at its end.
/// RFC 4180 quoting makes "inside quotes" the parity of the quotes seen.
fn sample_end(bytes: &[u8], records: usize, whole_file: bool) -> usize {
    let (mut quoted, mut seen, mut last) = (false, 0, 0);
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => quoted = !quoted,
            b'\n' if !quoted => {
                seen += 1;
                last = i + 1;
                if seen == records {
                    return last;
                }
            }
            _ => {}
        }
    }
    if whole_file {
        bytes.len()
    } else {
        last
    }
}

/// Counts the data rows of the table at `path` and collects the trimmed
/// values of column `id` (0-based), streaming it through csv's state machine
/// with fixed buffers: memory does not grow with the file or with any one
/// record (a row of a hundred million commas costs nothing).
pub(super) fn scan(
    path: &Path,
    limits: &Limits,
    delimiter: u8,
    id: Option<usize>,
) -> anyhow::Result<Scan> {
    let read_error = |source| {
        file_error(FileError::Read {
            path: path.to_path_buf(),
            source,
        })
    };
    let (file, _) = workspace::open_input(path, limits).map_err(file_error)?;
    // Bounded even if the file grows while it is read.
    let file = file.take(limits.max_file_bytes());
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let mut csv = csv_core::ReaderBuilder::new().delimiter(delimiter).build();
    let mut field = vec![0u8; MAX_ID_BYTES];
    let (mut len, mut overflow) = (0, false);
    // Position in the current record, and whether it is blank so far.
    let (mut index, mut blank) = (0, true);
    let mut records = 0usize;
    let mut ids = HashSet::new();
    let mut id_value: Option<String> = None;
    let keep = limits.max_nodes.saturating_add(1);
    let mut start = true;
    loop {
        let buf = input.fill_buf().map_err(read_error)?;
        // A byte order mark is not part of the header's first name.
        let bom = if start && buf.starts_with(b"\xEF\xBB\xBF") {
            3
        } else {
            0
        };
        start = false;
        let at_end = buf.is_empty();
        let (result, read, written) = csv.read_field(&buf[bom..], &mut field[len..]);
        input.consume(bom + read);
        len += written;
        match result {
            csv_core::ReadFieldResult::InputEmpty if at_end => break,
            csv_core::ReadFieldResult::InputEmpty => {}
            csv_core::ReadFieldResult::OutputFull => {
                // Longer than any id kept: drop its bytes, remember it was not blank.
                overflow = true;
                len = 0;
            }
            csv_core::ReadFieldResult::Field { record_end } => {
                let text = &field[..len];
                blank &= !overflow && text.iter().all(u8::is_ascii_whitespace);
                if Some(index) == id && !overflow {
                    id_value = std::str::from_utf8(text).ok().map(|v| v.trim().to_owned());
                }
                index += 1;
                (len, overflow) = (0, false);
                if record_end {
                    // The formats skip a line of only whitespace; the first
                    // record counted is the header.
                    if !(index == 1 && blank) {
                        if records > 0 && ids.len() < keep {
                            ids.extend(id_value.take());
                        }
                        records += 1;
                    }
                    (index, blank, id_value) = (0, true, None);
                }
            }
            csv_core::ReadFieldResult::End => break,
        }
    }
    Ok(Scan {
        rows: records.saturating_sub(1),
        ids,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_never_ends_inside_a_record() {
        let text = b"id,note\na,\"two\nlines\"\nb,x\nc,\"open";
        // Not the whole file: the last complete record ends the sample.
        assert_eq!(sample_end(text, 100, false), 26);
        assert_eq!(&text[..26], b"id,note\na,\"two\nlines\"\nb,x\n");
        // At most `records` line ends; the quoted one does not count.
        assert_eq!(sample_end(text, 2, false), 22);
        assert_eq!(sample_end(text, 100, true), text.len());
        assert_eq!(sample_end(b"no line end", 10, false), 0);
    }

    #[test]
    fn a_scan_counts_rows_and_collects_ids_with_fixed_buffers() {
        let dir = std::env::temp_dir().join(format!("nptreemap-scan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.csv");
        let long = "x".repeat(3 * MAX_ID_BYTES);
        std::fs::write(
            &path,
            format!(
                "\u{feff}id,size\r\n a ,1\n\n   \n\"b\nc\",2\n{long},3\nd,{}\n",
                ",".repeat(100_000)
            ),
        )
        .expect("write");
        let scan = scan(&path, &Limits::default(), b',', Some(0)).expect("scan");
        assert_eq!(scan.rows, 4);
        let mut ids: Vec<_> = scan.ids.into_iter().collect();
        ids.sort();
        assert_eq!(ids, ["a", "b\nc", "d"]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
