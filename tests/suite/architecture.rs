//! The architecture of ARCHITECTURE.md, checked from the source text: the pure
//! modules (geometry, power diagrams, layout, neighbourhoods, rendering,
//! measurement, layout JSON) never touch files, standard output or the clock;
//! the import graph between top-level modules (read from `crate::…` paths in
//! non-test code) has no cycle, keeps the pure core away from the edges, and is
//! exactly the graph ARCHITECTURE.md draws; no two files import each other
//! (directly or around a loop); every source path ARCHITECTURE.md names
//! exists; every file opens with a `//!` line.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const PURE: &[&str] = &[
    "src/geom",
    "src/power",
    "src/layout",
    "src/layout_json",
    "src/line_memo.rs",
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
    "line_memo",
    "neighborhood",
    "render",
    "measure",
];
/// The edges: files, config, the daemon, the orchestration, the binary.
const EDGE: &[&str] = &[
    "pipeline",
    "graph",
    "state",
    "daemon",
    "config",
    "store",
    "workspace",
    "exec",
    "cli",
];

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
fn without_tests(code: String) -> (String, Vec<String>) {
    // Tests that run on Unix only are tests too.
    let mut code = code.replace("#[cfg(all(test, unix))]", "#[cfg(test)]");
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

/// Every non-test source file under `src/` (relative to it) with its code
/// (comments, literals and `#[cfg(test)]` items removed). Test-only files
/// (declared under `#[cfg(test)]`) are left out.
fn sources() -> Vec<(PathBuf, String)> {
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut test_only: BTreeSet<PathBuf> = BTreeSet::new();
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
    sources
        .into_iter()
        .filter(|(f, _)| !test_only.contains(f))
        .map(|(f, code)| (f.strip_prefix(&src).expect("under src").to_path_buf(), code))
        .collect()
}

/// The library's import graph: top-level module → the top-level modules its
/// non-test code names (itself left out). The binary's code, `cli/`, is a
/// module like the others; `main.rs` and `lib.rs` only declare and call.
fn import_graph() -> BTreeMap<String, BTreeSet<String>> {
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, code) in sources() {
        let first = rel
            .components()
            .next()
            .expect("a component")
            .as_os_str()
            .to_string_lossy()
            .into_owned();
        if first == "main.rs" || first == "lib.rs" {
            continue;
        }
        let module = first.trim_end_matches(".rs").to_string();
        let uses = graph.entry(module.clone()).or_default();
        // Items re-exported at the crate root (`crate::Dataset`) are not modules.
        let src = root().join("src");
        for target in crate_paths(&code) {
            let is_module =
                src.join(format!("{target}.rs")).is_file() || src.join(&target).is_dir();
            if target != module && is_module {
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

/// Issue 22 item 1, issue 31 item 8: the program reaches files only
/// through the one reader (`workspace.rs`) and the one writer (`store.rs`),
/// so that every read is bounded and every write atomic, each in one place.
/// Every other file of the library and the binary (the daemon, the preview
/// server and the CLI included) asks them; a new file that opens a file
/// itself fails here.
#[test]
fn files_are_reached_only_through_the_reader_and_the_writer() {
    const THE_READER_AND_THE_WRITER: &[&str] = &["workspace.rs", "store.rs"];
    const FILE_ACCESS: &[&str] = &[
        "std::fs",
        "fs::",
        "File::",
        ".exists()",
        ".is_file()",
        ".is_dir()",
        ".metadata()",
        "read_dir(",
        "read_link(",
        "canonicalize(",
    ];
    let mut offences = Vec::new();
    let mut seen = 0;
    for (rel, code) in sources() {
        let rel = rel.to_string_lossy().replace('\\', "/");
        if THE_READER_AND_THE_WRITER.contains(&rel.as_str()) {
            continue;
        }
        seen += 1;
        for word in FILE_ACCESS {
            if code.contains(word) {
                offences.push(format!("src/{rel}: {word}"));
            }
        }
    }
    assert!(seen >= 100, "expected every source file, found {seen}");
    assert!(
        offences.is_empty(),
        "file access around workspace.rs and store.rs:\n{}",
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

/// The module path of a source file (`layout/compute.rs` → `layout::compute`,
/// `layout/mod.rs` → `layout`, `lib.rs` → the crate root).
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let file = parts.pop().expect("a file name");
    if file != "mod.rs" && file != "lib.rs" && file != "main.rs" {
        parts.push(file.trim_end_matches(".rs").to_string());
    }
    parts
}

/// The file that defines module `path`, or the nearest enclosing one that
/// exists (an item's path resolves to the file of its module).
fn file_of(path: &[String], files: &BTreeSet<PathBuf>) -> Option<PathBuf> {
    for len in (1..=path.len()).rev() {
        let dir: PathBuf = path[..len].iter().collect();
        for candidate in [dir.with_extension("rs"), dir.join("mod.rs")] {
            if files.contains(&candidate) {
                return Some(candidate);
            }
        }
    }
    None
}

/// Every path a piece of code names from `crate::`, `super::` or `self::`,
/// with `{a, b::{c, d}}` groups expanded, as absolute module paths.
fn named_paths(code: &str, module: &[String]) -> Vec<Vec<String>> {
    fn expand(text: &str, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
        // `text` starts right after `prefix::`.
        if let Some(group) = text.strip_prefix('{') {
            let mut depth = 0;
            let mut start = 0;
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        expand(group[start..i].trim(), prefix, out);
                        return;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(group[start..i].trim(), prefix.clone(), out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            return;
        }
        let name: String = text
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let mut path = prefix;
        if name.is_empty() || name == "self" {
            out.push(path);
            return;
        }
        path.push(name.clone());
        match text[name.len()..].strip_prefix("::") {
            Some(rest) => expand(rest, path, out),
            None => out.push(path),
        }
    }
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    for (k, _) in code.match_indices("::") {
        // The word before `::`, and what comes before it.
        let start = code[..k]
            .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
            .map_or(0, |i| i + 1);
        let word = &code[start..k];
        let before = start.checked_sub(1).map(|i| bytes[i]);
        let continues = matches!(before, Some(b':'));
        if continues {
            continue;
        }
        let mut base: Vec<String> = match word {
            "crate" => Vec::new(),
            "self" => module.to_vec(),
            "super" => {
                let mut m = module.to_vec();
                m.pop();
                m
            }
            _ => continue,
        };
        // `super::super::x`
        let mut rest = &code[k + 2..];
        while word == "super" && rest.starts_with("super::") {
            base.pop();
            rest = &rest["super::".len()..];
        }
        expand(rest, base, &mut out);
    }
    out
}

/// The import graph between files: file → the files whose modules its
/// non-test code names (itself and the crate root left out).
fn file_graph() -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let sources = sources();
    let files: BTreeSet<PathBuf> = sources.iter().map(|(f, _)| f.clone()).collect();
    let mut graph = BTreeMap::new();
    for (rel, code) in &sources {
        let module = module_of(rel);
        // A module's root file (`mod.rs`) naming its own children is
        // containment, as its `mod` and `pub use` lines are: not an import.
        let own_child = |f: &PathBuf| {
            rel.ends_with("mod.rs") && f.parent() == rel.parent()
                || rel.ends_with("mod.rs") && f.parent().and_then(Path::parent) == rel.parent()
        };
        let uses: BTreeSet<PathBuf> = named_paths(code, &module)
            .iter()
            .filter_map(|p| file_of(p, &files))
            .filter(|f| f != rel && !own_child(f))
            .collect();
        graph.insert(rel.clone(), uses);
    }
    graph
}

/// Issue 22: no two files import each other, directly or around a longer
/// loop (module-level acyclicity let `neighborhood/constraints.rs` and
/// `filtered_rows.rs` import each other). Only `crate::`, `super::` and
/// `self::` paths are imports, and a module's `mod.rs` naming its own
/// children is containment (as its `mod` and `pub use` lines are), not an
/// import; a child naming its parent's items is one.
#[test]
fn no_cycle_between_files() {
    let graph = file_graph();
    assert!(graph.len() >= 80, "only {} files read", graph.len());
    assert!(
        graph[Path::new("neighborhood/filtered_rows.rs")]
            .contains(Path::new("neighborhood/similarity.rs")),
        "the reader misses super:: imports"
    );
    // Depth-first search for a back edge; report the loop it closes.
    fn visit(
        f: &Path,
        graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>,
        stack: &mut Vec<PathBuf>,
        done: &mut BTreeSet<PathBuf>,
        cycles: &mut Vec<String>,
    ) {
        if done.contains(f) {
            return;
        }
        if let Some(at) = stack.iter().position(|s| s == f) {
            let cycle: Vec<String> = stack[at..]
                .iter()
                .chain(std::iter::once(&f.to_path_buf()))
                .map(|p| p.display().to_string())
                .collect();
            cycles.push(cycle.join(" -> "));
            return;
        }
        stack.push(f.to_path_buf());
        for next in graph.get(f).into_iter().flatten() {
            visit(next, graph, stack, done, cycles);
        }
        stack.pop();
        done.insert(f.to_path_buf());
    }
    let mut cycles = Vec::new();
    let mut done = BTreeSet::new();
    for f in graph.keys() {
        visit(f, &graph, &mut Vec::new(), &mut done, &mut cycles);
    }
    assert!(
        cycles.is_empty(),
        "import cycles between files:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn the_file_reader_sees_super_groups_and_nested_paths() {
    let module: Vec<String> = vec!["neighborhood".into(), "constraints".into()];
    let code = "use super::{bins::{a, b}, similarity};\nlet x = crate::rng::Rng::new(1);\n\
                use self::inner::X; pub(super) fn f() {}";
    let paths: Vec<String> = named_paths(code, &module)
        .into_iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        paths,
        [
            "neighborhood::bins::a",
            "neighborhood::bins::b",
            "neighborhood::similarity",
            "rng::Rng::new",
            "neighborhood::constraints::inner::X",
        ]
    );
}

/// Issue 22: every source path ARCHITECTURE.md names is there (`src/…`,
/// `layout/similar/`, a file name such as `treemap.rs`), so the document
/// cannot keep naming a file that was moved or split.
#[test]
fn architecture_md_names_only_paths_that_exist() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let src = root().join("src");
    let mut all = Vec::new();
    rust_files(&src, &mut all);
    rust_files(&root().join("formats/src"), &mut all);
    let names: BTreeSet<String> = all
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let mut missing = Vec::new();
    let mut checked = 0;
    for token in text.split(|c: char| !(c.is_alphanumeric() || "_./-".contains(c))) {
        let token = token.trim_end_matches('.');
        let is_rs = token.ends_with(".rs");
        let is_src = token.starts_with("src/");
        if !(is_rs || is_src) {
            continue;
        }
        checked += 1;
        let exists = if is_src {
            root().join(token).exists()
        } else if token.contains('/') {
            src.join(token).exists() || root().join(token).exists()
        } else {
            names.contains(token)
        };
        if !exists {
            missing.push(token.to_string());
        }
    }
    assert!(checked >= 20, "only {checked} paths found");
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names paths that do not exist: {missing:?}"
    );
}
