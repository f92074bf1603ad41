//! [`Limits`]: how large an input the readers accept (nodes, depth, dense
//! feature dimensions, distinct set members, file size), and [`LimitError`], the refusal that names the
//! limit and the config key raising it. Readers check them as they go, before
//! any allocation that grows with the quantity limited, so an oversized input
//! costs memory in proportion to the limit, never to the input's claims.
//!
//! The defaults are generous for the tool's use (pictures of a few dozen to a
//! few thousand items; real datasets here reach 3,041 leaves, depth 5): a
//! picture of more than 100,000 cells has cells below a pixel on any screen,
//! but embedding maps of 100,000 documents are a use the method promises
//! (issue 12 measures one), so the node limit sits at 250,000: room for
//! 100,000 leaves and their groups, with memory still in the hundreds of MB.
//! A hierarchy deeper than 32 levels nests cells too thin to see.

use std::fmt;

/// Limits on what readers accept. The config's `limits:` section sets them
/// (`config/default.yaml` documents each key); every field must be >= 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Limits {
    /// Most nodes a dataset may have (rows, groups and the root together).
    /// Default: 250,000.
    pub max_nodes: usize,
    /// Deepest level a node may sit at (the root is depth 0). Default: 32.
    pub max_depth: usize,
    /// Longest dense feature vector: values per embedding row, dates of a time
    /// series. Sets (genres, lists of names) are not dense: see
    /// [`Limits::max_set_members`]. Default: 1,024.
    pub max_dimensions: usize,
    /// Most distinct members the sets of one dataset may draw from: genres of
    /// a genre table, names of a hierarchy JSON's lists of strings (or the
    /// length of its 0/1 vectors under `similarityMeasure: jaccard`). Sets are
    /// stored as member ids, so memory grows with the members nodes have, not
    /// with this count. Default: 1,000,000.
    pub max_set_members: usize,
    /// Largest input file, in MiB (checked before it is read). Default: 256.
    pub max_file_mb: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_nodes: 250_000,
            max_depth: 32,
            max_dimensions: 1_024,
            max_set_members: 1_000_000,
            max_file_mb: 256,
        }
    }
}

/// Which limit an input exceeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// [`Limits::max_nodes`].
    Nodes,
    /// [`Limits::max_depth`].
    Depth,
    /// [`Limits::max_dimensions`].
    Dimensions,
    /// [`Limits::max_set_members`].
    SetMembers,
    /// [`Limits::max_file_mb`].
    FileSize,
}

impl Limit {
    /// The config key that raises this limit (under `limits:`).
    pub fn key(self) -> &'static str {
        match self {
            Limit::Nodes => "max_nodes",
            Limit::Depth => "max_depth",
            Limit::Dimensions => "max_dimensions",
            Limit::SetMembers => "max_set_members",
            Limit::FileSize => "max_file_mb",
        }
    }
}

/// An input larger than a [`Limits`] allows.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what}: over the limit of {allowed} (`limits.{key}` in the config raises it)",
    key = .limit.key()
)]
pub struct LimitError {
    /// The limit exceeded.
    pub limit: Limit,
    /// Its value.
    pub allowed: u64,
    /// What was found, for people ("more than 100000 nodes", "node \"x\" at depth 33").
    pub what: String,
}

impl Limits {
    /// The value of `limit`.
    pub fn get(&self, limit: Limit) -> u64 {
        match limit {
            Limit::Nodes => self.max_nodes as u64,
            Limit::Depth => self.max_depth as u64,
            Limit::Dimensions => self.max_dimensions as u64,
            Limit::SetMembers => self.max_set_members as u64,
            Limit::FileSize => self.max_file_mb,
        }
    }

    /// The largest file accepted, in bytes.
    pub fn max_file_bytes(&self) -> u64 {
        self.max_file_mb.saturating_mul(1 << 20)
    }

    /// The refusal for `limit`, describing what was found.
    pub fn exceeded(&self, limit: Limit, what: impl fmt::Display) -> LimitError {
        LimitError {
            limit,
            allowed: self.get(limit),
            what: what.to_string(),
        }
    }

    /// An error when `count` nodes are more than allowed.
    pub fn check_nodes(&self, count: usize) -> Result<(), LimitError> {
        if count > self.max_nodes {
            return Err(self.exceeded(
                Limit::Nodes,
                format_args!("more than {} nodes", self.max_nodes),
            ));
        }
        Ok(())
    }

    /// An error when a feature vector of `len` values is longer than allowed;
    /// `what` names it ("the vectors", "genres").
    pub fn check_dimensions(&self, len: usize, what: &str) -> Result<(), LimitError> {
        if len > self.max_dimensions {
            return Err(self.exceeded(
                Limit::Dimensions,
                format_args!("{what} have {len} dimensions"),
            ));
        }
        Ok(())
    }

    /// An error when sets draw from `count` distinct members, more than
    /// allowed; `what` names them ("genres", "names in lists").
    pub fn check_set_members(&self, count: usize, what: &str) -> Result<(), LimitError> {
        if count > self.max_set_members {
            return Err(self.exceeded(Limit::SetMembers, format_args!("{count} distinct {what}")));
        }
        Ok(())
    }

    /// The first limit that is 0 (every limit must be at least 1), with its key.
    pub fn zero_limit(&self) -> Option<&'static str> {
        [
            Limit::Nodes,
            Limit::Depth,
            Limit::Dimensions,
            Limit::SetMembers,
            Limit::FileSize,
        ]
        .into_iter()
        .find(|&l| self.get(l) == 0)
        .map(Limit::key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_names_the_limit_and_its_key() {
        let limits = Limits::default();
        let error = limits.check_nodes(250_001).expect_err("too many");
        assert_eq!(
            error.to_string(),
            "more than 250000 nodes: over the limit of 250000 (`limits.max_nodes` in the config raises it)"
        );
        assert!(limits.check_nodes(250_000).is_ok());
        let error = limits
            .check_dimensions(2000, "the vectors")
            .expect_err("too wide");
        assert!(
            error.to_string().contains("`limits.max_dimensions`"),
            "{error}"
        );
        assert_eq!(
            Limits {
                max_depth: 0,
                ..limits
            }
            .zero_limit(),
            Some("max_depth")
        );
        assert_eq!(limits.zero_limit(), None);
        let error = limits
            .check_set_members(1_000_001, "genres")
            .expect_err("too many");
        assert_eq!(
            error.to_string(),
            "1000001 distinct genres: over the limit of 1000000 (`limits.max_set_members` in the config raises it)"
        );
        assert!(limits.check_set_members(1_000_000, "genres").is_ok());
        assert_eq!(limits.max_file_bytes(), 256 << 20);
    }
}
