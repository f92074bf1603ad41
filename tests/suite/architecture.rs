//! The architecture of ARCHITECTURE.md, checked from the source text: the pure
//! modules (geometry, power diagrams, layout, neighbourhoods, rendering,
//! measurement, layout JSON) never touch files, standard output or the clock;
//! the import graph between top-level modules (read from `crate::…` paths in
//! non-test code) has no cycle, keeps the pure core away from the edges, and is
//! exactly the graph ARCHITECTURE.md draws; every file opens with a `//!` line.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const PURE: &[&str] = &[
    "src/geom",
    "src/power",
    "src/layout",
    "src/layout_json",
    "src/measure",
    "src/neighborhood",
    "src/render",
    "src/rng.rs",
];
const FORBIDDEN: &[&str] = &[
    "std::fs",
    "std::io::stdout",
    "println!",
    "print!(",
    "eprintln!",
    "Instant::now",
    "SystemTime",
    "std::env",
    "notify::",
    "serde_yaml",
];

/// The core modules, which may not reach the edges.
const CORE: &[&str] = &[
    "geom",
    "power",
    "layout",
    "layout_json",
    "neighborhood",
    "render",
    "measure",
];
/// The edges: files, config, the daemon and the orchestration.
const EDGE: &[&str] = &["pipeline", "daemon", "config", "store", "workspace", "exec"];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        let mut entries: Vec<_> = std::fs::read_dir(path)
            .expect("read dir")
            .map(|e| e.expect("entry").path())
            .collect();
        entries.sort();
        for e in entries {
            rust_files(&e, out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_path_buf());
    }
}

/// The code of a Rust file with comments removed and every string and char
/// literal emptied, so that only real paths remain.
fn code_only(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    while i < b.len() {
        let rest = &src[i..];
        if rest.starts_with("//") {
            i += rest.find('\n').unwrap_or(rest.len());
        } else if rest.starts_with("/*") {
            i += rest.find("*/").map_or(rest.len(), |k| k + 2);
        } else if (rest.starts_with("r\"") || rest.starts_with("r#"))
            && (i == 0 || !ident(b[i - 1]))
        {
            let hashes = rest[1..].bytes().take_while(|&c| c == b'#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let body = 1 + hashes + 1;
            i += body
                + rest[body..]
                    .find(&close)
                    .map_or(rest.len(), |k| k + close.len());
            out.push_str("\"\"");
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            i = j + 1;
            out.push_str("\"\"");
        } else if b[i] == b'\'' {
            // A char literal ('x', '\n', '\'', '\u{..}'), else a lifetime.
            let body = &rest[1..];
            let len = if body.starts_with('\\') {
                body.get(2..).and_then(|t| t.find('\'')).map(|k| k + 4)
            } else {
                body.chars()
                    .next()
                    .filter(|c| body[c.len_utf8()..].starts_with('\''))
                    .map(|c| c.len_utf8() + 2)
            };
            match len {
                Some(len) => {
                    i += len;
                    out.push_str("' '");
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let c = rest.chars().next().expect("non-empty");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// `code` without its `#[cfg(test)]` items (a `mod x;` line or a braced item),
/// and the names of the modules declared test-only.
fn without_tests(mut code: String) -> (String, Vec<String>) {
    let mut test_mods = Vec::new();
    while let Some(k) = code.find("#[cfg(test)]") {
        let after = k + "#[cfg(test)]".len();
        let rest = code[after..].trim_start();
        let skipped = code.len() - after - rest.len();
        let words: Vec<&str> = rest.split_whitespace().take(3).collect();
        let decl = match words.as_slice() {
            ["mod", name, ..] | ["pub(crate)", "mod", name] => Some(*name),
            _ => None,
        };
        if let Some(name) = decl.filter(|n| n.ends_with(';')) {
            test_mods.push(name.trim_end_matches(';').to_string());
            let end = after + skipped + rest.find(';').expect("semicolon") + 1;
            code.replace_range(k..end, "");
            continue;
        }
        let open = after + code[after..].find('{').expect("a braced test item");
        let mut depth = 0;
        let mut end = open;
        for (j, c) in code[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + j + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        code.replace_range(k..end, "");
    }
    (code, test_mods)
}

/// The top-level modules each `crate::…` path names, `use crate::{a, b}` included.
fn crate_paths(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        let before = rest[..k].chars().next_back();
        rest = &rest[k + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // `nptreemap_crate::` or similar
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// The library's import graph: top-level module → the top-level modules its
/// non-test code names (itself left out). The binary (`main.rs`, `cli/`) and
/// test-only files are not part of it.
fn import_graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut test_only: BTreeSet<PathBuf> = BTreeSet::new();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut sources = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("read source");
        let (code, test_mods) = without_tests(code_only(&text));
        let dir = f.parent().expect("a folder");
        for m in test_mods {
            test_only.insert(dir.join(format!("{m}.rs")));
        }
        sources.push((f.clone(), code));
    }
    for (f, code) in sources {
        let rel = f.strip_prefix(&src).expect("under src");
        let first = rel
            .components()
            .next()
            .expect("a component")
            .as_os_str()
            .to_string_lossy()
            .into_owned();
        if first == "main.rs" || first == "cli" || first == "lib.rs" || test_only.contains(&f) {
            continue;
        }
        let module = first.trim_end_matches(".rs").to_string();
        let uses = graph.entry(module.clone()).or_default();
        for target in crate_paths(&code) {
            if target != module {
                uses.insert(target);
            }
        }
    }
    graph
}

#[test]
fn pure_modules_do_no_io() {
    let mut files = Vec::new();
    for p in PURE {
        rust_files(&root().join(p), &mut files);
    }
    assert!(
        files.len() >= 20,
        "expected the pure modules, found {}",
        files.len()
    );
    let mut offences = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("read source");
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for word in FORBIDDEN {
                if code.contains(word) {
                    offences.push(format!("{}:{}: {word}", f.display(), n + 1));
                }
            }
        }
    }
    assert!(
        offences.is_empty(),
        "I/O in pure modules:\n{}",
        offences.join("\n")
    );
}

#[test]
fn the_core_never_reaches_the_edges() {
    let graph = import_graph();
    let mut offences = Vec::new();
    for module in CORE {
        let uses = graph
            .get(*module)
            .unwrap_or_else(|| panic!("module {module} not found"));
        for edge in EDGE {
            if uses.contains(*edge) {
                offences.push(format!("{module} imports {edge}"));
            }
        }
    }
    for module in ["geom", "power"] {
        for upper in ["layout", "neighborhood"] {
            if graph[module].contains(upper) {
                offences.push(format!("{module} imports {upper}"));
            }
        }
    }
    // The renderer draws finished layouts; similarity and constraints are
    // already in them.
    if graph["render"].contains("neighborhood") {
        offences.push("render imports neighborhood".to_string());
    }
    assert!(offences.is_empty(), "{}", offences.join("\n"));
}

#[test]
fn top_level_modules_have_no_cycles() {
    let graph = import_graph();
    // Kahn's algorithm: repeatedly remove modules that use nothing left.
    let mut left: BTreeMap<&str, BTreeSet<&str>> = graph
        .iter()
        .map(|(m, uses)| {
            let uses = uses
                .iter()
                .map(String::as_str)
                .filter(|u| graph.contains_key(*u))
                .collect();
            (m.as_str(), uses)
        })
        .collect();
    loop {
        let free: Vec<&str> = left
            .iter()
            .filter(|(_, uses)| uses.is_empty())
            .map(|(m, _)| *m)
            .collect();
        if free.is_empty() {
            break;
        }
        for m in &free {
            left.remove(m);
        }
        for uses in left.values_mut() {
            for m in &free {
                uses.remove(m);
            }
        }
    }
    assert!(left.is_empty(), "import cycle among {left:?}");
}

/// The dependency list of ARCHITECTURE.md: the lines `module -> a, b` between
/// the `<!-- imports -->` markers.
fn documented_graph() -> BTreeMap<String, BTreeSet<String>> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let start = text.find("<!-- imports -->").expect("imports block start") + 16;
    let end = start + text[start..].find("<!-- /imports -->").expect("block end");
    text[start..end]
        .lines()
        .filter_map(|l| l.split_once("->"))
        .map(|(m, uses)| {
            let uses = uses
                .split(',')
                .map(|u| u.trim().to_string())
                .filter(|u| !u.is_empty())
                .collect();
            (m.trim().to_string(), uses)
        })
        .collect()
}

#[test]
fn architecture_md_draws_the_real_graph() {
    let real = import_graph();
    let documented = documented_graph();
    assert_eq!(
        documented, real,
        "ARCHITECTURE.md's import list differs from the code"
    );
}

#[test]
fn the_formats_crate_imports_nothing_of_the_main_crate() {
    let mut files = Vec::new();
    rust_files(&root().join("formats/src"), &mut files);
    assert!(files.len() >= 10);
    for f in files {
        let code = code_only(&std::fs::read_to_string(&f).expect("read source"));
        assert!(
            !code.contains("nptreemap::"),
            "{} names the main crate",
            f.display()
        );
    }
    let manifest = std::fs::read_to_string(root().join("formats/Cargo.toml")).expect("manifest");
    assert!(
        !manifest
            .lines()
            .any(|l| l.trim_start().starts_with("nptreemap ")
                || l.trim_start().starts_with("nptreemap=")
                || l.trim_start().starts_with("nptreemap.")),
        "formats/Cargo.toml depends on the main crate"
    );
}

#[test]
fn the_import_reader_sees_grouped_and_plain_paths_but_not_comments() {
    let code = code_only(
        "use crate::{geom::Point, layout};\n// crate::daemon\nlet s = \"crate::store\";\n\
         let c = '\"'; crate::render::svg(x);\n#[cfg(test)]\nmod tests { use crate::config; }\n",
    );
    let (code, _) = without_tests(code);
    let names: Vec<String> = crate_paths(&code).into_iter().collect();
    assert_eq!(names, ["geom", "layout", "render"]);
}

#[test]
fn every_source_file_opens_with_a_module_doc() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    rust_files(&root().join("formats/src"), &mut files);
    let missing: Vec<_> = files
        .iter()
        .filter(|f| {
            !std::fs::read_to_string(f)
                .expect("read source")
                .starts_with("//!")
        })
        .collect();
    assert!(
        missing.is_empty(),
        "files without a //! opening line: {missing:?}"
    );
}

/// Issue 23: the files of `neighborhood/` (bins, kernels, rows, stages, …)
/// import one another without a cycle (`constraints.rs` and
/// `filtered_rows.rs` imported each other).
#[test]
fn neighborhood_files_have_no_cycles() {
    let dir = root().join("src/neighborhood");
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let names: BTreeSet<String> = files
        .iter()
        .filter_map(|f| f.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .filter(|n| n != "mod")
        .collect();
    assert!(names.len() >= 8, "files of neighborhood/: {names:?}");
    let mut left: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let name = f
            .file_stem()
            .expect("a name")
            .to_string_lossy()
            .into_owned();
        if !names.contains(&name) {
            continue;
        }
        let text = std::fs::read_to_string(f).expect("read source");
        let (code, _) = without_tests(code_only(&text));
        let uses = names
            .iter()
            .filter(|n| **n != name)
            .filter(|n| {
                code.contains(&format!("super::{n}::")) || code.contains(&format!("super::{n};"))
            })
            .cloned()
            .collect();
        left.insert(name, uses);
    }
    assert!(
        left["constraints"].contains("stages"),
        "the scan sees imports: {left:?}"
    );
    loop {
        let free: Vec<String> = left
            .iter()
            .filter(|(_, uses)| uses.iter().all(|u| !left.contains_key(u)))
            .map(|(m, _)| m.clone())
            .collect();
        if free.is_empty() {
            break;
        }
        for m in &free {
            left.remove(m);
        }
    }
    assert!(left.is_empty(), "import cycle among the files {left:?}");
}
