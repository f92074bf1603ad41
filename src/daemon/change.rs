//! What a batch of changed paths means for the builds (issue 6 item 1):
//! which datasets must be laid out again, which only re-rendered from their
//! stored layout, which appeared in or left the config. PURE: paths and
//! configs in, a [`ChangeSet`] out; no files, no watcher (zola's
//! `fs_utils` classification, tested on its own).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::config::{Config, DatasetConfig};

/// Why a dataset is rebuilt; shown in its status line.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Reason {
    /// The daemon started.
    Start,
    /// Input files changed (their names, for the status line).
    Data(Vec<String>),
    /// The config changed the dataset's inputs, fields, similarity or the
    /// layout settings.
    Layout,
    /// The config changed only how it is drawn or where it goes.
    Render,
    /// The dataset is new in the config.
    Added,
    /// SIGHUP: everything read again (a dataset whose inputs did not change
    /// is not rebuilt).
    Reload,
    /// Outputs that could not be written are written again (issue 21 item 9).
    Retry,
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reason::Start => f.write_str("start"),
            Reason::Data(files) => write!(f, "data: {}", files.join(", ")),
            Reason::Layout => f.write_str("config: layout"),
            Reason::Render => f.write_str("config: render"),
            Reason::Added => f.write_str("config: new dataset"),
            Reason::Reload => f.write_str("reload"),
            Reason::Retry => f.write_str("retry of failed writes"),
        }
    }
}

/// The work a batch asks for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ChangeSet {
    /// Datasets to read, lay out and render again, with why.
    pub relayout: BTreeMap<String, Reason>,
    /// Datasets whose stored layout only needs rendering again.
    pub rerender: BTreeSet<String>,
    /// Datasets no longer in the config (their outputs are kept).
    pub removed: BTreeSet<String>,
}

impl ChangeSet {
    /// Whether there is nothing to do.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.relayout.is_empty() && self.rerender.is_empty() && self.removed.is_empty()
    }
}

/// Every path the daemon reacts to: the config file and each dataset's inputs.
pub fn inputs_of(config: &Config, config_path: &Path) -> BTreeSet<PathBuf> {
    let mut paths: BTreeSet<PathBuf> = config
        .datasets
        .iter()
        .flat_map(|d| d.files.values().cloned())
        .collect();
    paths.insert(config_path.to_path_buf());
    paths
}

/// The directories to watch for those paths (their parents, so atomic saves
/// by rename are seen).
pub fn dirs_of(paths: &BTreeSet<PathBuf>) -> BTreeSet<PathBuf> {
    paths
        .iter()
        .filter_map(|p| p.parent().map(Path::to_path_buf))
        .map(|d| {
            if d.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                d
            }
        })
        .collect()
}

/// The datasets reading any of `paths`, with the changed file names.
pub fn touched(config: &Config, paths: &BTreeSet<PathBuf>) -> ChangeSet {
    let mut set = ChangeSet::default();
    for d in &config.datasets {
        let files: Vec<String> = d
            .files
            .values()
            .filter(|p| paths.contains(*p))
            .map(|p| {
                p.file_name().map_or_else(
                    || p.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                )
            })
            .collect();
        if !files.is_empty() {
            set.relayout.insert(d.name.clone(), Reason::Data(files));
        }
    }
    set
}

/// What changed between two valid configs.
///
/// A change to the `layout` section lays every dataset out again; a change to
/// `render` re-renders every one. Per dataset, a change to its format, files,
/// fields or similarity lays it out again; a change to its title or outputs
/// only re-renders it.
pub fn diff(old: &Config, new: &Config) -> ChangeSet {
    let mut set = ChangeSet::default();
    let old_by_name: BTreeMap<&str, &DatasetConfig> =
        old.datasets.iter().map(|d| (d.name.as_str(), d)).collect();
    let layout_changed = old.layout != new.layout;
    let render_changed = old.render != new.render;
    for d in &new.datasets {
        match old_by_name.get(d.name.as_str()) {
            None => {
                set.relayout.insert(d.name.clone(), Reason::Added);
            }
            Some(before) => {
                let inputs_changed = before.format != d.format
                    || before.files != d.files
                    || before.fields != d.fields
                    || before.similarity != d.similarity
                    || before.command != d.command
                    || before.timeout != d.timeout
                    || before.max_adapter_mb != d.max_adapter_mb;
                if layout_changed || inputs_changed {
                    set.relayout.insert(d.name.clone(), Reason::Layout);
                } else if render_changed || before.title != d.title || before.outputs != d.outputs {
                    set.rerender.insert(d.name.clone());
                }
            }
        }
    }
    let names: BTreeSet<&str> = new.datasets.iter().map(|d| d.name.as_str()).collect();
    for d in &old.datasets {
        if !names.contains(d.name.as_str()) {
            set.removed.insert(d.name.clone());
        }
    }
    set
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = "datasets:
  - name: a
    format: border-list
    files: {nodes: data/a.csv, pairs: data/a-pairs.csv}
    outputs: [{path: out/a.svg}]
  - name: b
    format: hierarchy-json
    files: {hierarchy: other/b.json}
    outputs: [{path: out/b.png}]
";

    fn config(text: &str) -> Config {
        Config::from_str(text, Path::new("/w")).expect("valid config")
    }

    #[test]
    fn inputs_and_their_directories() {
        let c = config(BASE);
        let inputs = inputs_of(&c, Path::new("/w/nptreemap.yaml"));
        assert_eq!(inputs.len(), 4);
        let dirs: Vec<PathBuf> = dirs_of(&inputs).into_iter().collect();
        assert_eq!(
            dirs,
            vec![
                PathBuf::from("/w"),
                PathBuf::from("/w/data"),
                PathBuf::from("/w/other")
            ]
        );
    }

    #[test]
    fn a_changed_file_touches_the_datasets_reading_it() {
        let c = config(BASE);
        let set = touched(
            &c,
            &[PathBuf::from("/w/data/a-pairs.csv")].into_iter().collect(),
        );
        assert_eq!(
            set.relayout.get("a"),
            Some(&Reason::Data(vec!["a-pairs.csv".to_string()]))
        );
        assert!(!set.relayout.contains_key("b"));
        // An output or a temp file beside the input touches nothing.
        let none = touched(
            &c,
            &[
                PathBuf::from("/w/out/a.svg"),
                PathBuf::from("/w/data/.a.csv.swp"),
            ]
            .into_iter()
            .collect(),
        );
        assert!(none.is_empty());
    }

    #[test]
    fn config_diff_sorts_layout_render_added_removed() {
        let old = config(BASE);
        assert!(diff(&old, &old).is_empty());

        let render_only = config(&format!("render: {{legend: false}}\n{BASE}"));
        let set = diff(&old, &render_only);
        assert!(set.relayout.is_empty());
        assert_eq!(set.rerender.len(), 2);

        let layout = config(&format!("layout: {{seed: 7}}\n{BASE}"));
        let set = diff(&old, &layout);
        assert_eq!(set.relayout.len(), 2);
        assert!(set.relayout.values().all(|r| *r == Reason::Layout));

        let output_moved = config(&BASE.replace("out/a.svg", "out/a2.svg"));
        let set = diff(&old, &output_moved);
        assert_eq!(set.rerender, ["a".to_string()].into_iter().collect());
        assert!(set.relayout.is_empty());

        let fields = config(&BASE.replace(
            "format: border-list\n",
            "format: border-list\n    fields: {id: iso}\n",
        ));
        assert_eq!(diff(&old, &fields).relayout.get("a"), Some(&Reason::Layout));

        let swapped = config(&BASE.replace("name: b", "name: c"));
        let set = diff(&old, &swapped);
        assert_eq!(set.relayout.get("c"), Some(&Reason::Added));
        assert_eq!(set.removed, ["b".to_string()].into_iter().collect());
    }
}
