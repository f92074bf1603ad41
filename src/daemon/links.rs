//! Inputs behind symbolic links (issue 21 item 5). An input, or the config,
//! may be a link to a file in another folder (docs folders link shared data
//! so); the daemon watches folders, and the link's folder sees the link
//! change but not the file it names. This follows each watched path's chain
//! of links to the file it names, so that the folders along the chain are
//! watched too and an event on any path of the chain is mapped back to the
//! path the config names. The daemon resolves the chains again before every
//! wait, so a link pointed elsewhere is followed. Reads links; knows
//! nothing of datasets or configs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest chain of links followed (Linux's own limit): a loop of links
/// ends there.
const MAX_HOPS: usize = 40;

/// Every path that stands for a watched path: the path itself, each link on
/// its way to the file it names, and that file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Aliases {
    /// Each such path, with the watched paths it stands for.
    of: BTreeMap<PathBuf, BTreeSet<PathBuf>>,
}

impl Aliases {
    /// Follows the links of every one of `paths` (absolute paths; a path
    /// that is no link stands for itself alone).
    pub fn resolve(paths: &BTreeSet<PathBuf>) -> Self {
        let mut of: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
        for path in paths {
            for alias in chain(path) {
                of.entry(alias).or_default().insert(path.clone());
            }
        }
        Aliases { of }
    }

    /// Whether an event on `path` concerns a watched path.
    pub fn contains(&self, path: &Path) -> bool {
        self.of.contains_key(path)
    }

    /// The watched paths that events on `paths` concern.
    pub fn watched_of(&self, paths: &BTreeSet<PathBuf>) -> BTreeSet<PathBuf> {
        paths
            .iter()
            .filter_map(|p| self.of.get(p))
            .flatten()
            .cloned()
            .collect()
    }

    /// The watched paths with a path of their chain in `dir`.
    pub fn watched_in(&self, dir: &Path) -> BTreeSet<PathBuf> {
        self.of
            .iter()
            .filter(|(alias, _)| alias.parent() == Some(dir))
            .flat_map(|(_, of)| of.iter().cloned())
            .collect()
    }

    /// Every path of every chain (their folders are the ones to watch).
    pub fn paths(&self) -> BTreeSet<PathBuf> {
        self.of.keys().cloned().collect()
    }
}

/// `path`, then each path its links lead to, up to [`MAX_HOPS`]. A link's
/// target is taken relative to the link's folder, and the folder of each
/// path after the first is resolved (links, `..`), as the watcher reports
/// events in it under that name.
fn chain(path: &Path) -> Vec<PathBuf> {
    let mut hops = vec![path.to_path_buf()];
    let mut at = path.to_path_buf();
    while hops.len() <= MAX_HOPS {
        let Some(target) = crate::workspace::link_target(&at) else {
            break;
        };
        let next = match at.parent() {
            Some(dir) if target.is_relative() => dir.join(target),
            _ => target,
        };
        let next = real_folder(&next);
        if hops.contains(&next) {
            break;
        }
        hops.push(next.clone());
        at = next;
    }
    hops
}

/// `path` with its folder resolved, when the folder exists.
fn real_folder(path: &Path) -> PathBuf {
    match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) => crate::workspace::canonical(dir)
            .map(|d| d.join(name))
            .unwrap_or_else(|| path.to_path_buf()),
        _ => path.to_path_buf(),
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    fn scratch() -> PathBuf {
        let dir = std::env::temp_dir().join(format!("nptreemap-links-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        // Resolved, so the expected paths compare equal on systems whose
        // temp folder is itself behind a link.
        std::fs::canonicalize(&dir).expect("real scratch")
    }

    /// A link into another folder, through a second link in a third, stands
    /// for the file it names; events there map back to the configured path;
    /// a loop of links ends.
    #[test]
    fn chains_of_links_lead_to_the_file_and_back() {
        let dir = scratch();
        for d in ["data", "shared", "deep"] {
            std::fs::create_dir_all(dir.join(d)).expect("dir");
        }
        std::fs::write(dir.join("deep/real.csv"), "id\n").expect("file");
        symlink("../deep/real.csv", dir.join("shared/hop.csv")).expect("hop");
        symlink("../shared/hop.csv", dir.join("data/nodes.csv")).expect("link");
        symlink("b", dir.join("data/a")).expect("loop a");
        symlink("a", dir.join("data/b")).expect("loop b");
        let nodes = dir.join("data/nodes.csv");
        let plain = dir.join("data/plain.csv");
        let looped = dir.join("data/a");
        let aliases = Aliases::resolve(&[nodes.clone(), plain.clone(), looped.clone()].into());
        assert_eq!(
            aliases.paths(),
            [
                nodes.clone(),
                dir.join("shared/hop.csv"),
                dir.join("deep/real.csv"),
                plain.clone(),
                looped.clone(),
                dir.join("data/b"),
            ]
            .into()
        );
        assert!(aliases.contains(&dir.join("deep/real.csv")));
        assert!(!aliases.contains(&dir.join("deep/other.csv")));
        let touched: BTreeSet<PathBuf> = [dir.join("deep/real.csv")].into();
        assert_eq!(aliases.watched_of(&touched), [nodes.clone()].into());
        assert_eq!(aliases.watched_in(&dir.join("shared")), [nodes].into());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
