//! The PNG outputs' picture records (`cache/<name>.pictures.bin`, issue 32
//! item 2: a one-shot `build` reuses what the state folder allows): for
//! each PNG output, the digest of the file's bytes, the scale, the digest
//! of the SVG text it was painted from and its bands' digests
//! (`render::png`). A later build that finds the file still holding those
//! bytes reads its pixels back and repaints only the bands whose digest
//! changed; `render::png::read_back` refuses a picture whose encoding lost
//! anything (a pixel neither opaque nor fully transparent).
//!
//! A small binary file: `NPTP`, version, the renderers' version (the
//! digest of their sources, so another version's bands are never trusted),
//! a record count, then per record the output's path (as the manifest
//! names it: length and UTF-8), the scale (f64 bits), the two digests
//! (u128) and the bands (count, then u128 each), little-endian. Local
//! only, like the constraint cache. A file that does not match (another
//! version, truncated, counts past its end) is ignored.

use crate::config::DatasetConfig;
use super::binary::{self, renderers, Bytes};

const MAGIC: &[u8; 4] = b"NPTP";
const VERSION: u32 = 1;

/// What one PNG output was painted from.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// The output's path relative to the config's folder (as the manifest
    /// names it).
    pub path: String,
    /// Pixels per SVG unit.
    pub scale: f64,
    /// xxh3-128 of the PNG file's bytes.
    pub png: u128,
    /// xxh3-128 of the SVG text it was painted from.
    pub svg: u128,
    /// The bands' digests, top to bottom.
    pub bands: Vec<u128>,
}

/// The records of `d`'s PNG outputs (none when there is no file or it is
/// not one of this version's).
pub fn read(d: &DatasetConfig) -> Vec<Record> {
    binary::read(d, super::pictures_path(d), decode)
}

/// Writes `records` (and the cache folder's `.gitignore`).
pub fn write(d: &DatasetConfig, records: &[Record]) -> std::io::Result<()> {
    binary::write(super::pictures_path(d), &encode(records))
}

fn encode(records: &[Record]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&renderers().to_le_bytes());
    out.extend_from_slice(&(records.len() as u64).to_le_bytes());
    for r in records {
        out.extend_from_slice(&(r.path.len() as u64).to_le_bytes());
        out.extend_from_slice(r.path.as_bytes());
        out.extend_from_slice(&r.scale.to_bits().to_le_bytes());
        out.extend_from_slice(&r.png.to_le_bytes());
        out.extend_from_slice(&r.svg.to_le_bytes());
        out.extend_from_slice(&(r.bands.len() as u64).to_le_bytes());
        for b in &r.bands {
            out.extend_from_slice(&b.to_le_bytes());
        }
    }
    out
}

fn decode(bytes: &[u8]) -> Option<Vec<Record>> {
    let mut r = Bytes(bytes);
    if r.take(4)? != MAGIC || r.take(4)? != VERSION.to_le_bytes() || r.u128()? != renderers() {
        return None;
    }
    // The smallest record: an empty path and no bands.
    let count = r.count(8 + 8 + 16 + 16 + 8)?;
    let mut records = Vec::with_capacity(count);
    for _ in 0..count {
        let len = r.count(1)?;
        let path = std::str::from_utf8(r.take(len)?).ok()?.to_owned();
        let scale = f64::from_bits(r.u64()?);
        let (png, svg) = (r.u128()?, r.u128()?);
        let n = r.count(16)?;
        let bands = (0..n).map(|_| r.u128()).collect::<Option<Vec<_>>>()?;
        records.push(Record {
            path,
            scale,
            png,
            svg,
            bands,
        });
    }
    r.is_done().then_some(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip_and_anything_else_is_refused() {
        let records = vec![
            Record {
                path: "out/a.png".to_string(),
                scale: 2.0,
                png: 7,
                svg: u128::MAX,
                bands: vec![1, 2, 3],
            },
            Record {
                path: "ü/b.png".to_string(),
                scale: 0.5,
                png: 0,
                svg: 9,
                bands: Vec::new(),
            },
        ];
        let bytes = encode(&records);
        assert_eq!(decode(&bytes), Some(records));
        // Every truncation, a byte more, another renderers' version.
        for end in 0..bytes.len() {
            assert_eq!(decode(&bytes[..end]), None, "cut at {end}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(decode(&longer), None);
        let mut other = bytes.clone();
        other[8] ^= 1;
        assert_eq!(decode(&other), None);
        // A count that claims more than the file holds allocates nothing.
        let mut huge = bytes[..24].to_vec();
        huge.extend_from_slice(&u64::MAX.to_le_bytes());
        assert_eq!(decode(&huge), None);
    }
}
