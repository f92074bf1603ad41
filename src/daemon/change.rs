//! What a batch of changed paths means for the builds (issue 6 item 1):
//! which datasets must be laid out again, which only re-rendered from their
//! stored layout, which appeared in or left the config. PURE: paths and
//! configs in, a [`ChangeSet`] out; no files, no watcher (zola's
//! `fs_utils` classification, tested on its own).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::config::{
    Config, DatasetConfig, LayoutConfig, OutputConfig, PageConfig, RenderConfig,
};
use crate::neighborhood::SimilarityKind;
use nptreemap_formats::FormatOptions;

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

/// What a batch means, the one pure decision of the watch loop: the work
/// the config's change calls for (`new`: the config as read again, when it
/// changed and is usable; it then replaces `old`), the datasets whose inputs
/// are among `paths`, and with `reload` (SIGHUP) every dataset read again.
pub fn classify(
    paths: &BTreeSet<PathBuf>,
    old: &Config,
    new: Option<&Config>,
    reload: bool,
) -> ChangeSet {
    let mut set = new.map_or_else(ChangeSet::default, |new| diff(old, new));
    let config = new.unwrap_or(old);
    for (name, reason) in touched(config, paths).relayout {
        set.relayout.entry(name).or_insert(reason);
    }
    if reload {
        for d in &config.datasets {
            set.relayout.entry(d.name.clone()).or_insert(Reason::Reload);
        }
    }
    set
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

/// What a config says about one dataset, sorted by what a change to it
/// calls for (issue 30 item 7). Every key of the config reaches a dataset
/// through exactly one of these classes, and the comparison is the derived
/// `PartialEq` of the typed values, whole sections at a time: a key added to
/// a section is compared with its section, and a field added to [`Config`]
/// or [`DatasetConfig`] does not compile until [`facets`] places it (the
/// test `every_config_key_is_classified` checks the placing key by key).
#[derive(PartialEq)]
struct Facets<'a> {
    /// How the data is read (format, files, field mapping with the columns
    /// the pictures carry and the limits, the adapter): read and lay out
    /// again.
    read: Read<'a>,
    /// The layout settings and the similarity: lay out again.
    layout: (&'a LayoutConfig, &'a Option<SimilarityKind>),
    /// How it is drawn and what is written: render again.
    render: Render<'a>,
    /// Where its state lives: render again (the commit writes the state to
    /// its new place).
    state: (&'a Option<PathBuf>, &'a Option<String>),
}

/// [`Facets::read`].
type Read<'a> = (
    &'a str,
    &'a BTreeMap<String, PathBuf>,
    &'a FormatOptions,
    &'a [String],
    &'a Option<f64>,
    u64,
    &'a Path,
);

/// [`Facets::render`].
type Render<'a> = (
    &'a RenderConfig,
    &'a Option<String>,
    &'a PageConfig,
    &'a [OutputConfig],
    usize,
);

/// The facets of dataset `d` of `config`.
fn facets<'a>(config: &'a Config, d: &'a DatasetConfig) -> Facets<'a> {
    let Config {
        layout,
        render,
        // Copied into every dataset's `fields.limits` and `max_adapter_mb`
        // when the config is read: compared there.
        limits: _,
        // Copied into every dataset's `state_dir`: compared there.
        state_dir: _,
        history,
        // Compared one by one, by name ([`diff`]).
        datasets: _,
    } = config;
    let DatasetConfig {
        // The identity: a renamed dataset is removed and added.
        name: _,
        format,
        files,
        fields,
        similarity,
        title,
        page,
        outputs,
        command,
        timeout,
        max_adapter_mb,
        base,
        state_dir,
        config_stem,
    } = d;
    Facets {
        read: (format, files, fields, command, timeout, *max_adapter_mb, base),
        layout: (layout, similarity),
        render: (render, title, page, outputs, *history),
        state: (state_dir, config_stem),
    }
}

/// What changed between two valid configs: per dataset, a change to how it
/// is read or laid out lays it out again, a change only to how it is drawn,
/// what is written or where its state lives renders it again ([`Facets`]).
pub fn diff(old: &Config, new: &Config) -> ChangeSet {
    let mut set = ChangeSet::default();
    let old_by_name: BTreeMap<&str, &DatasetConfig> =
        old.datasets.iter().map(|d| (d.name.as_str(), d)).collect();
    for d in &new.datasets {
        match old_by_name.get(d.name.as_str()) {
            None => {
                set.relayout.insert(d.name.clone(), Reason::Added);
            }
            Some(before) => {
                let (was, is) = (facets(old, before), facets(new, d));
                if was.read != is.read || was.layout != is.layout {
                    set.relayout.insert(d.name.clone(), Reason::Layout);
                } else if was != is {
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

        // Issue 30 item 7: `page:` and `history:` were never compared.
        let html = BASE.replace("out/a.svg}]", "out/a.svg}, {path: out/a.html}]");
        let old_html = config(&html);
        let target = config(&html.replace(
            "    outputs: [{path: out/a.svg},",
            "    page: {link_target: same-tab}\n    outputs: [{path: out/a.svg},",
        ));
        let set = diff(&old_html, &target);
        assert_eq!(set.rerender, ["a".to_string()].into_iter().collect(), "{set:?}");
        let history = config(&format!("history: 3\n{html}"));
        let set = diff(&history, &old_html);
        assert_eq!(set.rerender.len(), 2, "{set:?}");

        let swapped = config(&BASE.replace("name: b", "name: c"));
        let set = diff(&old, &swapped);
        assert_eq!(set.relayout.get("c"), Some(&Reason::Added));
        assert_eq!(set.removed, ["b".to_string()].into_iter().collect());
    }

    /// A config of two datasets (`a` reads tables and writes an SVG and a
    /// page; `b` runs an adapter) with `key: value` set in `section`.
    fn config_with(section: &str, key: &str, value: &str) -> String {
        let mut sections: BTreeMap<&str, Vec<(String, String)>> = BTreeMap::new();
        let base: [(&str, &str, &str); 7] = [
            ("a", "format", "border-list"),
            ("a", "files", "{nodes: n.csv, pairs: p.csv}"),
            ("b", "format", "exec"),
            ("b", "command", "[cat]"),
            ("b", "files", "{tree: t.json}"),
            ("b", "outputs", "[out/b.json]"),
            ("a.outputs0", "path", "out/a.svg"),
        ];
        for (s, k, v) in base {
            sections.entry(s).or_default().push((k.to_string(), v.to_string()));
        }
        let entries = sections.entry(section).or_default();
        entries.retain(|(k, _)| k != key);
        entries.push((key.to_string(), value.to_string()));
        let block = |name: &str, indent: &str| -> String {
            sections.get(name).map_or(String::new(), |kv| {
                kv.iter().map(|(k, v)| format!("{indent}{k}: {v}\n")).collect()
            })
        };
        let flow = |name: &str| -> String {
            let kv = sections.get(name).cloned().unwrap_or_default();
            let inner: Vec<String> = kv.iter().map(|(k, v)| format!("{k}: {v}")).collect();
            format!("{{{}}}", inner.join(", "))
        };
        format!(
            "{top}layout: {layout}\nrender:\n  labels: {labels}\n{render}limits: {limits}\n\
             datasets:\n  - name: a\n{a}    fields: {fields}\n    page: {page}\n    \
             outputs: [{outputs0}, out/a.html]\n  - name: b\n{b}",
            top = block("", ""),
            layout = flow("layout"),
            labels = flow("render.labels"),
            render = block("render", "  "),
            limits = flow("limits"),
            a = block("a", "    "),
            fields = flow("a.fields"),
            page = flow("a.page"),
            outputs0 = flow("a.outputs0"),
            b = block("b", "    "),
        )
    }

    /// The keys serde knows in `section`, from the error that an unknown one
    /// gets ("unknown field `x`, expected one of `a`, `b`, ...").
    fn keys_of(section: &str) -> Vec<String> {
        let text = config_with(section, "no_such_key", "1");
        let e = Config::from_str(&text, Path::new("/w")).expect_err("an unknown key").to_string();
        let expected = e
            .split_once("expected ")
            .unwrap_or_else(|| panic!("{section}: {e}"))
            .1;
        expected.split('`').skip(1).step_by(2).map(str::to_string).collect()
    }

    /// Issue 30 item 7: every key of every section of the config, as serde
    /// lists them (so a key added later is listed too), is classified below,
    /// and a change to it gives the work its class calls for: a key missing
    /// from the table fails this test until someone decides what it affects.
    #[test]
    fn every_config_key_is_classified() {
        use Class::{Layout, Render};
        #[derive(Clone, Copy, Debug, PartialEq)]
        enum Class {
            /// Lays dataset `a` out again.
            Layout,
            /// Renders dataset `a` again.
            Render,
            /// A section of its own (its keys are listed one by one), or the
            /// list of datasets.
            Section,
        }
        let table: &[(&str, &str, &str, Class)] = &[
            ("", "layout", "", Class::Section),
            ("", "render", "", Class::Section),
            ("", "limits", "", Class::Section),
            ("", "datasets", "", Class::Section),
            ("", "state_dir", "elsewhere", Render),
            ("", "history", "2", Render),
            ("layout", "width", "900", Layout),
            ("layout", "height", "900", Layout),
            ("layout", "outline", "circle", Layout),
            ("layout", "seed", "2", Layout),
            ("layout", "method", "plain", Layout),
            ("layout", "convergence_ratio", "0.02", Layout),
            ("layout", "max_iterations", "100", Layout),
            ("layout", "min_iterations", "4", Layout),
            ("layout", "min_weight_ratio", "0.01", Layout),
            ("layout", "prototype", "true", Layout),
            ("layout", "frames", "2", Layout),
            ("layout", "zero_weights", "floor", Layout),
            ("render", "title", "T", Render),
            ("render", "legend", "false", Render),
            ("render", "legend_order", "data", Render),
            ("render", "palette", "colorblind", Render),
            ("render", "colors", "{x: '#000000'}", Render),
            ("render", "background", "none", Render),
            ("render", "border_color", "'#000000'", Render),
            ("render", "border_width", "2", Render),
            ("render", "stroke", "'#000000'", Render),
            ("render", "stroke_width", "2", Render),
            ("render", "labels", "", Class::Section),
            ("render", "tabs", "false", Render),
            ("render", "unrealized_links", "true", Render),
            ("render", "unlinked_markers", "false", Render),
            ("render", "unlinked_markers_share", "0.1", Render),
            // A column the readers must carry into the model: read again.
            ("render", "color_by", "size", Layout),
            ("render", "color_scale", "diverging", Render),
            ("render", "color_midpoint", "1", Render),
            ("render.labels", "show", "false", Render),
            ("render.labels", "min_size", "5", Render),
            ("render.labels", "max_size", "20", Render),
            ("render.labels", "value", "true", Render),
            ("render.labels", "unit", "kg", Render),
            ("render.labels", "groups", "false", Render),
            ("render.labels", "names", "{x: X}", Render),
            ("render.labels", "text", "segment", Render),
            ("limits", "max_nodes", "100", Layout),
            ("limits", "max_depth", "5", Layout),
            ("limits", "max_dimensions", "5", Layout),
            ("limits", "max_set_members", "5", Layout),
            ("limits", "max_file_mb", "5", Layout),
            ("limits", "max_adapter_mb", "5", Layout),
            ("a", "name", "", Class::Section),
            ("a", "format", "hierarchy-json", Layout),
            ("a", "files", "{nodes: n2.csv, pairs: p.csv}", Layout),
            ("a", "fields", "", Class::Section),
            ("a", "similarity", "jaccard", Layout),
            ("a", "title", "T", Render),
            ("a", "page", "", Class::Section),
            ("a", "outputs", "", Class::Section),
            ("b", "command", "[cat, -u]", Layout),
            ("b", "timeout", "5", Layout),
            ("a.fields", "id", "key", Layout),
            ("a.fields", "label", "x", Layout),
            ("a.fields", "weight", "x", Layout),
            ("a.fields", "color", "x", Layout),
            ("a.fields", "parent", "x", Layout),
            ("a.fields", "path", "x", Layout),
            ("a.fields", "path_separator", "'.'", Layout),
            ("a.fields", "groups", "[x]", Layout),
            ("a.fields", "strength", "x", Layout),
            ("a.fields", "delimiter", "';'", Layout),
            ("a.fields", "root_label", "x", Layout),
            ("a.fields", "genres", "x", Layout),
            ("a.fields", "separator", "'+'", Layout),
            ("a.fields", "genre_columns", "[x]", Layout),
            ("a.fields", "fill_missing", "true", Layout),
            ("a.fields", "on_unknown_id", "error", Layout),
            // Columns the page shows are carried into the model: read again.
            ("a.page", "fields", "[x]", Layout),
            ("a.page", "link", "url", Layout),
            ("a.page", "link_target", "same-tab", Render),
            ("a.outputs0", "path", "out/a2.svg", Render),
            ("a.outputs0", "kind", "png", Render),
            ("a.outputs0", "scale", "2", Render),
        ];
        let base = Config::from_str(&config_with("", "history", "0"), Path::new("/w"))
            .expect("the base config");
        // The exec keys belong to the dataset section `a` is listed under.
        let sections = [
            "",
            "layout",
            "render",
            "render.labels",
            "limits",
            "a",
            "a.fields",
            "a.page",
            "a.outputs0",
        ];
        for section in sections {
            for key in keys_of(section) {
                let in_b = section == "a" && (key == "command" || key == "timeout");
                let listed = if in_b { "b" } else { section };
                let Some(&(_, _, value, class)) =
                    table.iter().find(|(s, k, _, _)| *s == listed && *k == key)
                else {
                    panic!("config key {section}.{key} is not classified: add it to this table (and to `facets` in its class)");
                };
                if class == Class::Section {
                    continue;
                }
                let text = config_with(listed, &key, value);
                let changed = Config::from_str(&text, Path::new("/w"))
                    .unwrap_or_else(|e| panic!("{listed}.{key}: {e}\n{text}"));
                let set = diff(&base, &changed);
                let name = if in_b { "b" } else { "a" };
                let got = if set.relayout.contains_key(name) {
                    Layout
                } else if set.rerender.contains(name) {
                    Render
                } else {
                    panic!("{listed}.{key}: {value} changed nothing: {set:?}");
                };
                assert_eq!(got, class, "{listed}.{key}: {set:?}");
            }
        }
        // Every row of the table is a key that exists.
        for (section, key, _, _) in table {
            let listed = if *section == "b" { "a" } else { section };
            assert!(keys_of(listed).contains(&key.to_string()), "{section}.{key}");
        }
    }
}
