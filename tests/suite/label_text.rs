//! What labels say (`render.labels.text`, issue 33 item 1), by the real
//! binary on tables taken from this machine (tests/fixtures/labels: modules
//! of Python's standard library with dotted ids, the modules of the hyper
//! crate with `::` paths, the files of src/render with slash paths): the
//! page's data and the SVG's texts come from the one choice, the default
//! drops a group's name in front of a path-like id, each explicit choice
//! gives what it says, and a template naming a column the data lacks, or an
//! unknown choice, is an error naming the config line.

use std::collections::HashMap;
use std::path::Path;

use crate::support;

fn fixture(dir: &Path, name: &str) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/labels");
    std::fs::copy(src.join(name), dir.join(name)).expect("copy fixture");
}

/// A config of one dataset `t` read from `nodes` with the field mapping
/// `fields`, written as SVG and HTML, with `text` as `render.labels.text`.
fn setup(tag: &str, nodes: &str, fields: &str, text: Option<&str>) -> std::path::PathBuf {
    let dir = support::temp_dir(&format!("label-text-{tag}"));
    fixture(&dir, nodes);
    std::fs::write(dir.join("pairs.csv"), "a,b\n").expect("pairs");
    let render = text.map_or(String::new(), |t| {
        format!("render:\n  labels:\n    text: {t}\n")
    });
    let config = format!(
        "{render}datasets:\n  - name: t\n    format: border-list\n\
         \x20   files: {{nodes: {nodes}, pairs: pairs.csv}}\n\
         \x20   fields: {fields}\n\
         \x20   outputs: [out/t.svg, out/t.html]\n"
    );
    std::fs::write(dir.join("nptreemap.yaml"), config).expect("config");
    dir
}

/// Each node of the page's data: id -> (shown label, parent index), and the
/// nodes in order.
struct Page {
    nodes: Vec<(String, String, Option<usize>)>,
}

impl Page {
    fn read(html: &Path) -> Page {
        let text = std::fs::read_to_string(html).expect("read page");
        let start = text.find("class=\"np-data\"").expect("data block");
        let start = start + text[start..].find('>').expect("tag end") + 1;
        let end = start + text[start..].find("</script>").expect("block end");
        let data: serde_json::Value = serde_json::from_str(&text[start..end]).expect("JSON");
        let nodes = data["nodes"]
            .as_array()
            .expect("nodes")
            .iter()
            .map(|n| {
                let id = n["id"].as_str().expect("id").to_string();
                let label = n["label"].as_str().map_or(id.clone(), str::to_string);
                let parent = n["parent"].as_u64().map(|p| p as usize);
                (id, label, parent)
            })
            .collect();
        Page { nodes }
    }

    /// Leaf id -> shown label.
    fn leaves(&self) -> HashMap<&str, &str> {
        let parents: Vec<usize> = self.nodes.iter().filter_map(|n| n.2).collect();
        self.nodes
            .iter()
            .enumerate()
            .filter(|(i, _)| !parents.contains(i))
            .map(|(_, n)| (n.0.as_str(), n.1.as_str()))
            .collect()
    }

    /// The labels from the top-level group down to node `i`, as the
    /// tooltip's path shows them.
    fn path(&self, mut i: usize) -> Vec<&str> {
        let mut out = Vec::new();
        while let Some(p) = self.nodes[i].2 {
            out.insert(0, self.nodes[i].1.as_str());
            i = p;
        }
        out
    }
}

/// The texts of the SVG's label elements.
fn svg_texts(svg: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(svg).expect("read svg");
    text.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..t.find("</text>")?];
            Some(
                body.replace("<tspan", "\n<")
                    .split('>')
                    .filter_map(|s| s.split('<').next())
                    .collect::<String>(),
            )
        })
        .collect()
}

#[test]
fn dotted_ids_show_their_own_segment_by_default() {
    let dir = setup(
        "dotted",
        "stdlib.csv",
        "{weight: size, path: package, path_separator: \".\"}",
        None,
    );
    support::build(&dir.join("nptreemap.yaml"));
    let page = Page::read(&dir.join("out/t.html"));
    let leaves = page.leaves();
    assert!(leaves.len() > 90, "{} leaves", leaves.len());
    for (id, label) in &leaves {
        let last = id.rsplit('.').next().expect("segment");
        assert_eq!(label, &last, "{id}");
    }
    assert_eq!(leaves["xml.etree.ElementTree"], "ElementTree");
    // The tooltip's path still spells the whole module name.
    for (i, n) in page.nodes.iter().enumerate() {
        if leaves.contains_key(n.0.as_str()) && n.0.contains('.') {
            let mut path = page.path(i);
            // A package's own module (`xml/dom/__init__.py`) sits in its package.
            if path.len() > 1 && path[path.len() - 1] == path[path.len() - 2] {
                path.pop();
            }
            assert_eq!(path.join("."), n.0, "path of {}", n.0);
        }
    }
    // The picture says the same: no label repeats its package.
    let texts = svg_texts(&dir.join("out/t.svg"));
    assert!(texts.iter().any(|t| t == "ElementTree"), "{texts:?}");
    assert!(
        !texts.iter().any(|t| t.contains("xml.etree")),
        "a label repeats its group: {texts:?}"
    );
}

#[test]
fn rust_paths_lose_their_module_and_each_choice_says_what_it_is() {
    let fields = "{weight: size, groups: [module]}";
    let dir = setup("colons", "hyper.csv", fields, None);
    support::build(&dir.join("nptreemap.yaml"));
    let page = Page::read(&dir.join("out/t.html"));
    let leaves = page.leaves();
    assert_eq!(leaves["hyper::proto::h1::role"], "role");
    for (id, label) in &leaves {
        let (module, own) = id.rsplit_once("::").unwrap_or(("", id));
        let expected = if module.is_empty() { *id } else { own };
        assert_eq!(label, &expected, "{id}");
    }
    let texts = svg_texts(&dir.join("out/t.svg"));
    assert!(
        !texts.iter().any(|t| t.starts_with("hyper::proto::h1::")),
        "{texts:?}"
    );

    for (text, expect) in [
        ("id", "hyper::proto::h1::role"),
        ("label", "hyper::proto::h1::role"),
        ("segment", "role"),
        ("relative", "role"),
        ("'{id} ({size} B)'", "hyper::proto::h1::role ("),
    ] {
        let dir = setup("colons-choice", "hyper.csv", fields, Some(text));
        support::build(&dir.join("nptreemap.yaml"));
        let page = Page::read(&dir.join("out/t.html"));
        let shown = page.leaves()["hyper::proto::h1::role"].to_string();
        assert!(shown.starts_with(expect), "{text}: {shown}");
    }
}

#[test]
fn slash_paths_by_segment() {
    let dir = setup(
        "slash",
        "files.csv",
        "{id: path, weight: size, groups: [folder]}",
        Some("segment"),
    );
    support::build(&dir.join("nptreemap.yaml"));
    let page = Page::read(&dir.join("out/t.html"));
    let leaves = page.leaves();
    assert!(leaves.len() > 20);
    for (id, label) in &leaves {
        assert_eq!(Some(*label), id.rsplit('/').next(), "{id}");
        assert!(!label.contains('/'));
    }
    assert_eq!(leaves["src/render/fonts/DejaVuSans.ttf"], "DejaVuSans.ttf");
}

#[test]
fn a_template_column_the_data_lacks_is_an_error_at_its_line() {
    let dir = setup(
        "template-missing",
        "hyper.csv",
        "{weight: size, groups: [module]}",
        Some("'{id} {version}'"),
    );
    let out = support::bin()
        .arg("build")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("version"), "{err}");
    assert!(err.contains("render.labels.text, config line 3"), "{err}");
    assert!(!dir.join("out/t.svg").exists(), "no output written");
}

#[test]
fn an_unknown_choice_or_a_broken_template_is_a_config_error() {
    for (text, needle) in [
        ("segmnet", "did you mean \"segment\""),
        ("'{name'", "without its"),
    ] {
        let dir = setup("unknown", "hyper.csv", "{weight: size}", Some(text));
        let out = support::bin()
            .arg("build")
            .arg(dir.join("nptreemap.yaml"))
            .output()
            .expect("run");
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("nptreemap.yaml"), "{err}");
        assert!(err.contains("line 3"), "{err}");
        assert!(err.contains("labels.text"), "{err}");
        assert!(err.contains(needle), "{err}");
    }
}
