//! The leaf labels fitted last (`cache/<name>.labels.bin`, issue 32 item 2:
//! a one-shot `build` reuses what the state folder allows): each label the
//! last render fitted, by the digest of everything that decides it
//! (`render::Parts`: its text and value line, its size range and its cell
//! as drawn). A later process starts its label memo from them, so a build
//! after an edit fits only the labels of the cells that moved (6,000 of
//! them took 110 ms of a 6,000-header rebuild).
//!
//! A small binary file: `NPTL`, version, the renderers' version (the digest
//! of their sources: another version's fitting is never trusted), an entry
//! count, then per entry the digest (u128), 0 for a leaf without a label or
//! 1 and the label: its line count, per line the text (length and UTF-8),
//! centre, baseline and size (f64 bits), then its box (four f64) and angle,
//! little-endian. Local only. A file that does not match (another version,
//! truncated, counts past its end) is ignored.

use crate::config::DatasetConfig;
use crate::render::labels::{Line, Placed, Rect};
use super::binary::{self, renderers, Bytes};

const MAGIC: &[u8; 4] = b"NPTL";
const VERSION: u32 = 1;

/// A label by its digest; `None` for a leaf whose label does not fit.
pub type Entry = (u128, Option<Placed>);

/// The labels kept for `d` (none when there is no file or it is not one of
/// this version's).
pub fn read(d: &DatasetConfig) -> Vec<Entry> {
    binary::read(d, super::labels_path(d), decode)
}

/// Writes `entries` (and the cache folder's `.gitignore`).
pub fn write(d: &DatasetConfig, entries: &[Entry]) -> std::io::Result<()> {
    binary::write(super::labels_path(d), &encode(entries))
}

fn encode(entries: &[Entry]) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + 24 * entries.len());
    let f = |out: &mut Vec<u8>, v: f64| out.extend_from_slice(&v.to_bits().to_le_bytes());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&renderers().to_le_bytes());
    out.extend_from_slice(&(entries.len() as u64).to_le_bytes());
    for (digest, placed) in entries {
        out.extend_from_slice(&digest.to_le_bytes());
        let Some(p) = placed else {
            out.push(0);
            continue;
        };
        out.push(1);
        out.extend_from_slice(&(p.lines.len() as u64).to_le_bytes());
        for line in &p.lines {
            out.extend_from_slice(&(line.text.len() as u64).to_le_bytes());
            out.extend_from_slice(line.text.as_bytes());
            for v in [line.x, line.baseline, line.size] {
                f(&mut out, v);
            }
        }
        for v in [p.rect.x0, p.rect.y0, p.rect.x1, p.rect.y1, p.angle] {
            f(&mut out, v);
        }
    }
    out
}

fn decode(bytes: &[u8]) -> Option<Vec<Entry>> {
    let mut r = Bytes(bytes);
    if r.take(4)? != MAGIC || r.take(4)? != VERSION.to_le_bytes() || r.u128()? != renderers() {
        return None;
    }
    // The smallest entry: a digest and no label.
    let count = r.count(16 + 1)?;
    let mut entries = Vec::with_capacity(count);
    for _ in 0..count {
        let digest = r.u128()?;
        let placed = match r.take(1)?[0] {
            0 => None,
            1 => {
                // The smallest line: an empty text and three numbers.
                let n = r.count(8 + 24)?;
                let mut lines = Vec::with_capacity(n);
                for _ in 0..n {
                    let len = r.count(1)?;
                    let text = std::str::from_utf8(r.take(len)?).ok()?.to_owned();
                    let (x, baseline, size) = (r.f64()?, r.f64()?, r.f64()?);
                    lines.push(Line {
                        text,
                        x,
                        baseline,
                        size,
                    });
                }
                let rect = Rect {
                    x0: r.f64()?,
                    y0: r.f64()?,
                    x1: r.f64()?,
                    y1: r.f64()?,
                };
                Some(Placed {
                    node: 0,
                    lines,
                    rect,
                    angle: r.f64()?,
                })
            }
            _ => return None,
        };
        entries.push((digest, placed));
    }
    r.is_done().then_some(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_round_trip_and_anything_else_is_refused() {
        let label = Placed {
            node: 0,
            lines: vec![
                Line {
                    text: "Zürich".to_string(),
                    x: 10.5,
                    baseline: 20.25,
                    size: 12.0,
                },
                Line {
                    text: String::new(),
                    x: -1.0,
                    baseline: 0.0,
                    size: 9.0,
                },
            ],
            rect: Rect {
                x0: 1.0,
                y0: 2.0,
                x1: 3.0,
                y1: 4.0,
            },
            angle: 0.0,
        };
        let entries = vec![(7, Some(label)), (u128::MAX, None)];
        let bytes = encode(&entries);
        assert_eq!(decode(&bytes), Some(entries));
        for end in 0..bytes.len() {
            assert_eq!(decode(&bytes[..end]), None, "cut at {end}");
        }
        let mut other = bytes.clone();
        other[8] ^= 1;
        assert_eq!(decode(&other), None, "another renderers' version");
        let mut flag = bytes.clone();
        flag[32 + 16] = 2;
        assert_eq!(decode(&flag), None, "an unknown flag");
        let mut huge = bytes[..24].to_vec();
        huge.extend_from_slice(&u64::MAX.to_le_bytes());
        assert_eq!(decode(&huge), None, "a count past the end allocates nothing");
    }
}
