//! The constraint cache (`cache/<name>.constraints.bin`): the constraints of
//! a dataset's last similarity inputs, keyed by their fingerprint
//! (`graph::keys::similarity`: ids, hierarchy, vectors, sets and relations,
//! and the measure; not the weights, which no constraint depends on). A
//! weight edit then recomputes none; any other edit replaces the file.
//!
//! A small binary file, 18 bytes per constraint (141,718 constraints: 2.5 MB)
//! after a 48-byte header: `NPTC`, version, the key, the prepared dataset's
//! node count and the constraint count, then per constraint `a` and `b`
//! (u32), score and strength (u8) and the similarity (f64), little-endian.
//! Local only (the folder has its own `.gitignore`). A file that does not
//! match (another key, truncated, a node out of range) is ignored.

use std::path::Path;

use nptreemap_formats::Dataset;

use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::neighborhood::Constraint;
use crate::{store, workspace};

const MAGIC: &[u8; 4] = b"NPTC";
/// 2: levels of 30,000 nodes and more whose exact search does not pay are
/// binned by the approximate one (`neighborhood::knn_rows`), so a cache of
/// version 1 may hold other constraints for them than a cold build makes.
const VERSION: u32 = 2;
const HEADER: usize = 4 + 4 + 16 + 8 + 8;
const RECORD: usize = 4 + 4 + 1 + 1 + 8;

/// The constraints cached for `key`, if the cache holds them and they fit
/// `prepared` (every node in range, both ends at one depth, `a < b`).
pub fn read(d: &DatasetConfig, key: Fingerprint, prepared: &Dataset) -> Option<Vec<Constraint>> {
    let path = super::constraints_path(d)?;
    let bytes = match workspace::read_input(&path, &d.fields.limits) {
        Ok(bytes) => bytes,
        Err(e) => {
            tracing::debug!(error = %e, "no constraint cache");
            return None;
        }
    };
    decode(&bytes, key, prepared)
}

fn decode(bytes: &[u8], key: Fingerprint, prepared: &Dataset) -> Option<Vec<Constraint>> {
    let (header, body) = bytes.split_at_checked(HEADER)?;
    let u64_at = |at: usize| header[at..at + 8].try_into().ok().map(u64::from_le_bytes);
    if &header[..4] != MAGIC || header[4..8] != VERSION.to_le_bytes() {
        return None;
    }
    let stored_key = Fingerprint::from_bytes(header[8..24].try_into().ok()?);
    let nodes = u64_at(24)?;
    let count = usize::try_from(u64_at(32)?).ok()?;
    if stored_key != key
        || nodes != prepared.len() as u64
        || Some(body.len()) != count.checked_mul(RECORD)
    {
        return None;
    }
    let mut out = Vec::with_capacity(count);
    for r in body.chunks_exact(RECORD) {
        let a = u32::from_le_bytes(r[0..4].try_into().ok()?) as usize;
        let b = u32::from_le_bytes(r[4..8].try_into().ok()?) as usize;
        let (score, strength) = (r[8], r[9]);
        let similarity = f64::from_le_bytes(r[10..18].try_into().ok()?);
        let valid = a < b
            && b < prepared.len()
            && prepared.node(a).depth == prepared.node(b).depth
            && (1..=3).contains(&strength)
            && similarity.is_finite();
        if !valid {
            return None;
        }
        out.push(Constraint {
            a,
            b,
            score,
            similarity,
            strength,
        });
    }
    Some(out)
}

fn encode(key: Fingerprint, nodes: usize, constraints: &[Constraint]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + RECORD * constraints.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&key.to_bytes());
    out.extend_from_slice(&(nodes as u64).to_le_bytes());
    out.extend_from_slice(&(constraints.len() as u64).to_le_bytes());
    for c in constraints {
        // Node indices of a dataset within `limits.max_nodes` fit a u32.
        out.extend_from_slice(&(c.a as u32).to_le_bytes());
        out.extend_from_slice(&(c.b as u32).to_le_bytes());
        out.push(c.score);
        out.push(c.strength);
        out.extend_from_slice(&c.similarity.to_le_bytes());
    }
    out
}

/// Writes the cache for `key` (and the cache folder's `.gitignore`).
pub fn write(
    d: &DatasetConfig,
    key: Fingerprint,
    prepared: &Dataset,
    constraints: &[Constraint],
) -> std::io::Result<()> {
    let Some(path) = super::constraints_path(d) else {
        return Ok(());
    };
    if constraints
        .iter()
        .any(|c| u32::try_from(c.b).is_err() || u32::try_from(c.a).is_err())
    {
        return Ok(());
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    store::write_if_changed(&dir.join(".gitignore"), super::CACHE_GITIGNORE.as_bytes())?;
    store::write_if_changed(&path, &encode(key, prepared.len(), constraints)).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    #[test]
    fn the_cache_round_trips_and_refuses_what_does_not_fit() {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for id in ["a", "b", "c"] {
            b.add(NodeSpec::new(id).parent("r").weight(1.0));
        }
        let data = b.build().expect("valid");
        let key = Fingerprint::of_bytes(b"k");
        let cs = vec![Constraint {
            a: 1,
            b: 3,
            score: 40,
            similarity: 0.4,
            strength: 2,
        }];
        let bytes = encode(key, data.len(), &cs);
        assert_eq!(bytes.len(), HEADER + RECORD);
        assert_eq!(decode(&bytes, key, &data), Some(cs.clone()));
        assert_eq!(decode(&bytes, Fingerprint::of_bytes(b"other"), &data), None);
        assert_eq!(decode(&bytes[..bytes.len() - 1], key, &data), None);
        let mut bad = cs.clone();
        bad[0].a = 0; // the root is at another depth
        assert_eq!(decode(&encode(key, data.len(), &bad), key, &data), None);
    }
}
