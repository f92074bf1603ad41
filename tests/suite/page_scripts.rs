//! The page's scripts as ES modules (issue 31 item 7), checked from their
//! files: the bundler (`src/render/page/bundle.rs`, the one `build.rs` runs)
//! reaches every module and resolves every import, the bundles run each
//! module after what it imports, no module uses a name it neither declares,
//! imports nor gets from the browser, none imports a name it does not use;
//! `node --check` on each module and each bundle when node is installed
//! (required with `NPTREEMAP_REQUIRE_NODE=1`, as CI sets it), a bundle that
//! runs in node as the same modules run as real ES modules; and each
//! refusal of the bundler, with its file, line and message.

#[allow(dead_code)]
#[path = "../../src/render/page/bundle.rs"]
mod bundle;

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use bundle::{Bundle, BundleError, Kind, BUNDLES};

use nptreemap::geom::{ConvexPolygon, Point};
use nptreemap::render::labels::place_leaf;
use nptreemap::render::metrics;

use crate::support::temp_dir;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every JavaScript file of the page and of the live preview, as paths
/// from the crate's root.
fn module_files() -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for dir in ["src/render/page", "src/serve"] {
        for entry in std::fs::read_dir(root().join(dir)).expect("read dir") {
            let name = entry
                .expect("entry")
                .file_name()
                .to_string_lossy()
                .into_owned();
            if name.ends_with(".js") {
                out.insert(format!("{dir}/{name}"));
            }
        }
    }
    out
}

fn read(path: &str) -> Result<String, String> {
    std::fs::read_to_string(root().join(path)).map_err(|e| e.to_string())
}

fn real_bundles() -> Vec<(&'static str, Bundle)> {
    BUNDLES
        .iter()
        .map(|(name, entries)| {
            let made = bundle::bundle(entries, read).unwrap_or_else(|e| panic!("{name}: {e}"));
            (*name, made)
        })
        .collect()
}

/// A bundle of modules given as text.
fn bundle_of(files: &[(&str, &str)], entries: &[&str]) -> Result<Bundle, BundleError> {
    let files: BTreeMap<&str, &str> = files.iter().copied().collect();
    bundle::bundle(entries, |p| {
        files
            .get(p)
            .map(|s| s.to_string())
            .ok_or_else(|| "no such file".to_string())
    })
}

#[test]
fn every_module_is_bundled_after_what_it_imports() {
    let bundles = real_bundles();
    let mut reached = BTreeSet::new();
    for (name, made) in &bundles {
        let order: Vec<&str> = made.modules.iter().map(|m| m.path.as_str()).collect();
        let exports: BTreeMap<&str, &Vec<String>> = made
            .modules
            .iter()
            .map(|m| (m.path.as_str(), &m.exports))
            .collect();
        for (at, m) in made.modules.iter().enumerate() {
            reached.insert(m.path.clone());
            for import in &m.imports {
                let there = order.iter().position(|p| *p == import.from);
                assert!(
                    there.is_some_and(|k| k < at),
                    "{name}: {} runs before {}, which it imports",
                    m.path,
                    import.from
                );
                for (n, _) in &import.names {
                    assert!(
                        exports[import.from.as_str()].contains(n),
                        "{name}: {}:{} imports `{n}`, which {} does not export",
                        m.path,
                        import.line,
                        import.from
                    );
                }
            }
            // Each module once, in the script as its own function scope.
            let header = format!("// {}\n", m.path);
            assert_eq!(
                made.script.matches(&header).count(),
                1,
                "{name}: {}",
                m.path
            );
        }
        // Deterministic: the same files, the same bytes.
        let again = bundle::bundle(
            BUNDLES.iter().find(|b| b.0 == *name).expect("listed").1,
            read,
        )
        .expect("bundles");
        assert_eq!(again.script, made.script, "{name}");
    }
    assert_eq!(reached, module_files(), "a module no bundle reaches");
    // A page with history runs the page's modules first, in the same order,
    // so it behaves as the page without history, steps added.
    let page: Vec<&str> = bundles[0]
        .1
        .modules
        .iter()
        .map(|m| m.path.as_str())
        .collect();
    let with: Vec<&str> = bundles[1]
        .1
        .modules
        .iter()
        .map(|m| m.path.as_str())
        .collect();
    assert_eq!(&with[..page.len()], &page[..]);
    assert_eq!(page.last(), Some(&"src/render/page/main.js"));
    assert_eq!(with.last(), Some(&"src/render/page/past.js"));
    // The live preview shares the morph, and nothing else, with the page.
    let live: BTreeSet<&str> = bundles[2]
        .1
        .modules
        .iter()
        .map(|m| m.path.as_str())
        .collect();
    let shared: Vec<&&str> = live.iter().filter(|p| with.contains(p)).collect();
    assert_eq!(shared, [&"src/render/page/history.js"]);
}

/// Names a module may use without declaring or importing them: the
/// language's and the browser's.
const GLOBALS: &[&str] = &[
    "AbortController",
    "Array",
    "CSS",
    "DOMParser",
    "Error",
    "EventSource",
    "Float64Array",
    "Infinity",
    "Int32Array",
    "JSON",
    "Map",
    "Math",
    "Number",
    "Object",
    "Promise",
    "Set",
    "String",
    "Uint8Array",
    "document",
    "encodeURIComponent",
    "fetch",
    "location",
    "parseFloat",
    "parseInt",
    "performance",
    "requestAnimationFrame",
    "undefined",
    "window",
];

const KEYWORDS: &[&str] = &[
    "as",
    "break",
    "case",
    "catch",
    "class",
    "const",
    "continue",
    "default",
    "delete",
    "do",
    "else",
    "export",
    "false",
    "finally",
    "for",
    "from",
    "function",
    "if",
    "import",
    "in",
    "instanceof",
    "let",
    "new",
    "null",
    "return",
    "switch",
    "this",
    "throw",
    "true",
    "try",
    "typeof",
    "var",
    "void",
    "while",
];

/// The names a module uses but neither declares, imports nor finds among
/// [`GLOBALS`], and the names it imports but never uses. Scopes are not
/// told apart (a name declared anywhere in the module counts), so this
/// finds a name that lost its import, not every misuse.
fn name_faults(path: &str, text: &str) -> (Vec<String>, Vec<String>) {
    let toks = bundle::tokens(text).unwrap_or_else(|(l, m)| panic!("{path}:{l}: {m}"));
    let s = |k: usize| toks.get(k).map_or("", |t| &text[t.start..t.end]);
    let module = bundle::parse(path, text).unwrap_or_else(|e| panic!("{e}"));
    let imported: BTreeSet<&str> = module
        .imports
        .iter()
        .flat_map(|i| i.names.iter().map(|n| n.1.as_str()))
        .collect();
    let mut declared: BTreeSet<&str> = BTreeSet::new();
    let mut params = 0i64;
    for (k, tok) in toks.iter().enumerate() {
        if s(k) == "("
            && k > 0
            && (s(k - 1) == "function" || s(k - 1) == "catch" || (k > 1 && s(k - 2) == "function"))
        {
            params = 1;
            continue;
        }
        if params > 0 {
            match s(k) {
                "(" => params += 1,
                ")" => params -= 1,
                _ => {}
            }
        }
        let after_declare =
            k > 0 && ["var", "let", "const", "function", "class"].contains(&s(k - 1));
        // `var a = 1, b = 2;`: a name after a comma followed by `=` in a
        // declaration is declared too (an assignment to a free name would
        // be found as a use elsewhere; strict mode refuses it anyway).
        let listed = k > 0 && s(k - 1) == "," && s(k + 1) == "=";
        if tok.kind == Kind::Ident && (after_declare || params > 0 || listed) {
            declared.insert(s(k));
        }
    }
    let mut used: BTreeSet<&str> = BTreeSet::new();
    let mut free = BTreeSet::new();
    let mut in_import = false;
    for (k, tok) in toks.iter().enumerate() {
        let t = s(k);
        if tok.kind == Kind::Ident && t == "import" {
            in_import = true;
        }
        if in_import {
            in_import = tok.kind != Kind::Str;
            continue;
        }
        if tok.kind != Kind::Ident || (k > 0 && (s(k - 1) == "." || s(k - 1) == "?.")) {
            continue;
        }
        // An object literal's key.
        if s(k + 1) == ":" && k > 0 && (s(k - 1) == "{" || s(k - 1) == ",") {
            continue;
        }
        used.insert(t);
        if !(declared.contains(t)
            || imported.contains(t)
            || GLOBALS.contains(&t)
            || KEYWORDS.contains(&t))
        {
            free.insert(format!("{t} (line {})", tok.line));
        }
    }
    let unused = imported
        .iter()
        .filter(|n| !used.contains(*n))
        .map(|n| n.to_string())
        .collect();
    (free.into_iter().collect(), unused)
}

#[test]
fn modules_declare_or_import_every_name_they_use() {
    let mut faults = Vec::new();
    for path in module_files() {
        let text = read(&path).expect("module");
        // Every module says what it owns, and no user text becomes markup.
        assert!(text.starts_with("// "), "{path} opens without a comment");
        for markup in [
            "innerHTML",
            "outerHTML",
            "insertAdjacentHTML",
            "document.write",
        ] {
            assert!(!text.contains(markup), "{path}: {markup}");
        }
        let (free, unused) = name_faults(&path, &text);
        if !free.is_empty() {
            faults.push(format!(
                "{path} uses names it neither declares nor imports: {free:?}"
            ));
        }
        if !unused.is_empty() {
            faults.push(format!("{path} imports names it never uses: {unused:?}"));
        }
    }
    assert!(faults.is_empty(), "{}", faults.join("\n"));
}

#[test]
fn the_name_check_finds_a_lost_import_and_an_unused_one() {
    let text =
        "// x\nimport { a, b } from \"./m.js\";\nfunction f(p) { var q = p; return a + q + c; }\n";
    let (free, unused) = name_faults("src/x.js", text);
    assert_eq!(free, ["c (line 3)"]);
    assert_eq!(unused, ["b"]);
}

/// node, or None after reporting the check skipped (a failure when
/// `NPTREEMAP_REQUIRE_NODE=1`).
fn node_or_skip() -> Option<PathBuf> {
    let found = ["node", "nodejs"]
        .into_iter()
        .find(|name| {
            Command::new(name)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(PathBuf::from);
    if found.is_none() {
        assert!(
            std::env::var("NPTREEMAP_REQUIRE_NODE").as_deref() != Ok("1"),
            "NPTREEMAP_REQUIRE_NODE=1 but no node installed"
        );
        let _ = writeln!(
            std::io::stderr(),
            "skipped: node not installed (no `node --check`)"
        );
    }
    found
}

/// node's verdict on `text` read from standard input.
fn node_check(node: &Path, module: bool, text: &str) -> Result<(), String> {
    let kind = if module {
        "--input-type=module"
    } else {
        "--input-type=commonjs"
    };
    let mut child = Command::new(node)
        .args([kind, "--check"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run node");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(text.as_bytes())
        .expect("write to node");
    let out = child.wait_with_output().expect("node finishes");
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

#[test]
fn node_checks_every_module_and_bundle() {
    let Some(node) = node_or_skip() else { return };
    for path in module_files() {
        let text = read(&path).expect("module");
        if let Err(e) = node_check(&node, true, &text) {
            panic!("{path} as a module:\n{e}");
        }
    }
    for (name, made) in real_bundles() {
        if let Err(e) = node_check(&node, false, &made.script) {
            panic!("the bundle {name}:\n{e}");
        }
    }
    // The check itself refuses what is not JavaScript.
    assert!(node_check(&node, true, "export const x = ;\n").is_err());
}

/// Modules with side effects in their order, exports of both kinds, a
/// renamed import and shared state in an exported object.
const ORDERED: &[(&str, &str)] = &[
    (
        "m/main.js",
        "import { a } from \"./a.js\";\nimport { b, twice as double } from \"./b.js\";\nimport { state, bump } from \"./s.js\";\n\
         bump(); bump();\nconsole.log(\"main\", a, b, double(a), state.count);\n",
    ),
    ("m/a.js", "import { log } from \"./s.js\";\nlog(\"a\");\nexport const a = 2;\n"),
    (
        "m/b.js",
        "import { a } from \"./a.js\";\nimport { log } from \"./s.js\";\nlog(\"b\");\nexport const b = a + 1, c = [1, 2];\n\
         export function twice(x) { return 2 * x + c.length - 2; }\n",
    ),
    (
        "m/s.js",
        "console.log(\"s\");\nexport const state = { count: 0 };\nexport function bump() { state.count += 1; }\n\
         export function log(what) { console.log(what); }\n",
    ),
];

#[test]
fn a_bundle_runs_as_its_modules_run_in_node() {
    let made = bundle_of(ORDERED, &["m/main.js"]).expect("bundles");
    let order: Vec<&str> = made.modules.iter().map(|m| m.path.as_str()).collect();
    assert_eq!(order, ["m/s.js", "m/a.js", "m/b.js", "m/main.js"]);
    assert!(made.script.contains("const { b, twice: double } = $b;"));
    let Some(node) = node_or_skip() else { return };
    let dir = temp_dir("page_scripts_es_order");
    std::fs::create_dir_all(dir.join("m")).expect("dir");
    std::fs::write(dir.join("package.json"), "{\"type\": \"module\"}\n").expect("write");
    for (path, text) in ORDERED {
        std::fs::write(dir.join(path), text).expect("write");
    }
    std::fs::write(dir.join("bundle.cjs"), &made.script).expect("write");
    let run = |file: &str| {
        let out = Command::new(&node)
            .arg(dir.join(file))
            .output()
            .expect("node runs");
        assert!(
            out.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let real = run("m/main.js");
    assert_eq!(real, "s\na\nb\nmain 2 3 4 2\n", "node's own ES modules");
    assert_eq!(run("bundle.cjs"), real, "the bundle as the modules");
}

/// The bundler's refusal of `text` as the entry module `m/x.js`, beside a
/// module `m/y.js` that exports `y`.
fn refusal(text: &str) -> BundleError {
    let files = [("m/x.js", text), ("m/y.js", "export const y = 1;\n")];
    match bundle_of(&files, &["m/x.js"]) {
        Ok(_) => panic!("bundled:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn the_bundler_refuses_what_it_cannot_keep_correct() {
    let cases: &[(&str, usize, &str)] = &[
        (
            "// x\nexport let x = 1;\n",
            2,
            "`export let`: imports are copied once",
        ),
        ("// x\n\nexport var x = 1;\n", 3, "`export var`"),
        ("export default function () {}\n", 1, "default export"),
        (
            "const x = 1;\nexport { x };\n",
            2,
            "export list or re-export",
        ),
        (
            "export { y } from \"./y.js\";\n",
            1,
            "export list or re-export",
        ),
        ("export * from \"./y.js\";\n", 1, "export list or re-export"),
        ("import * as m from \"./y.js\";\n", 1, "`import *`"),
        ("import y from \"./y.js\";\n", 1, "default import"),
        ("import \"./y.js\";\n", 1, "import for its effects only"),
        (
            "import { y } from \"lodash\";\n",
            1,
            "`lodash`: only relative paths",
        ),
        (
            "import { y } from \"https://x.org/y.js\";\n",
            1,
            "no packages, no network",
        ),
        (
            "function f() {\n  return import(\"./y.js\");\n}\n",
            2,
            "dynamic `import()`",
        ),
        ("export class C {}\n", 1, "`export class`"),
        (
            "export const { a } = {};\n",
            1,
            "`export const` of a pattern",
        ),
        (
            "import { y } from \"./y.js\";\ny = 2;\n",
            2,
            "assigns to `y`, which it imports from m/y.js",
        ),
        (
            "import { y } from \"./y.js\";\nfunction f() { y++; }\n",
            2,
            "assigns to `y`",
        ),
        (
            "import { y } from \"./y.js\";\nfunction f() { var y = 3; }\n",
            2,
            "declares `y` again",
        ),
        (
            "import { y } from \"./y.js\";\nfunction f(a, y) {}\n",
            2,
            "declares `y` again",
        ),
        (
            "import { z } from \"./y.js\";\n",
            1,
            "`z` is not exported by m/y.js",
        ),
        (
            "import { y } from \"./none.js\";\n",
            1,
            "cannot read m/none.js",
        ),
        ("var $y = 1;\n", 1, "names starting with `$`"),
        ("var s = \"</script>\";\n", 1, "`</script`"),
        (
            "export function f() {}\nexport const f = 1;\n",
            2,
            "`f` is exported twice",
        ),
    ];
    for (text, line, message) in cases {
        let e = refusal(text);
        assert_eq!((e.path.as_str(), e.line), ("m/x.js", *line), "{text}: {e}");
        assert!(e.message.contains(message), "{text}: {e}");
        // The message says what to write instead, where there is a way.
        assert!(!e.message.is_empty());
    }
}

#[test]
fn the_bundler_refuses_a_cycle_naming_it() {
    let files = [
        (
            "m/a.js",
            "import { b } from \"./b.js\";\nexport const a = 1;\n",
        ),
        (
            "m/b.js",
            "// b\nimport { c } from \"./c.js\";\nexport const b = 2;\n",
        ),
        (
            "m/c.js",
            "import { a } from \"./a.js\";\nexport const c = 3;\n",
        ),
    ];
    let e = bundle_of(&files, &["m/a.js"]).expect_err("a cycle");
    assert_eq!((e.path.as_str(), e.line), ("m/c.js", 1), "{e}");
    assert!(
        e.message
            .contains("an import cycle: m/a.js imports m/b.js imports m/c.js imports m/a.js"),
        "{e}"
    );
}

#[test]
fn the_lexer_tells_regular_expressions_from_division() {
    // A regular expression holding `"`, `//` and `/` in a class, beside
    // divisions; a string holding `import`: none of it is read as code.
    let text = "export function f(a, b) { return (a / 2) / b + \"import x\".length + /\"[/]\\/\\/\"/g.source.length; }\n\
                export const g = /^(https?:\\/\\/)/i, h = 1e-12;\n";
    let module = bundle::parse("m/x.js", text).expect("parses");
    assert_eq!(module.exports, ["f", "g", "h"]);
    assert!(module.imports.is_empty());
}

/// The strings the fitter of `text` may measure: the text, its words and
/// the halves of every break, and every prefix cut with an ellipsis (a
/// superset: a string missing from the table fails the run in node).
fn measured(text: &str) -> Vec<String> {
    let mut out = vec![text.to_owned()];
    let chars: Vec<char> = text.chars().collect();
    for k in 0..=chars.len() {
        let (a, b) = (
            chars[..k].iter().collect::<String>(),
            chars[k..].iter().collect::<String>(),
        );
        out.extend([a.trim().to_owned(), b.trim().to_owned()]);
    }
    for k in 0..chars.len() {
        out.push(chars[..k].iter().collect::<String>().trim_end().to_owned() + "…");
    }
    out
}

/// Convex cells of every shape the fitter meets: points on an ellipse
/// (3 to 12 corners, stretched up to 8:1, turned), from a seeded LCG.
fn random_cells(count: usize) -> Vec<ConvexPolygon> {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            let n = 3 + (next() * 10.0) as usize;
            let (rx, ry) = (
                5.0 + 200.0 * next(),
                (5.0 + 200.0 * next()) / (1.0 + 7.0 * next()),
            );
            let (turn, (cx, cy)) = (
                next() * std::f64::consts::TAU,
                (1000.0 * next(), 1000.0 * next()),
            );
            let mut angles: Vec<f64> = (0..n).map(|_| next() * std::f64::consts::TAU).collect();
            angles.sort_by(f64::total_cmp);
            let points = angles
                .iter()
                .map(|a| {
                    let (x, y) = (rx * a.cos(), ry * a.sin());
                    Point::new(
                        cx + x * turn.cos() - y * turn.sin(),
                        cy + x * turn.sin() + y * turn.cos(),
                    )
                })
                .collect();
            ConvexPolygon::new(points).expect("points on an ellipse are convex")
        })
        .collect()
}

/// The page's fitter (`page/fit.js`, run in node) places every label as
/// the picture's `place_leaf` does, given the same cells, sizes and text widths:
/// the same lines, the same size and anchor (one algorithm in two
/// languages, issue 31 item 5).
#[test]
fn the_page_fits_labels_as_the_picture_does() {
    let Some(node) = node_or_skip() else { return };
    let texts = [
        "Congo",
        "Bosnia and Herzegovina",
        "xml.etree.ElementTree",
        "os",
        "libreoffice-calc",
        "configuration_manager_with_a_long_name",
        "src/render/labels.rs",
        "naïve café au lait",
        "日本語のテキスト",
        "a b",
        "Saint Vincent and the Grenadines",
        "x",
        "python3-distutils-extra",
        "The Lord of the Rings: The Return of the King",
    ];
    let cells = random_cells(600);
    let mut widths = std::collections::BTreeMap::new();
    let mut cases = Vec::new();
    for (k, cell) in cells.iter().enumerate() {
        let text = texts[k % texts.len()];
        let min = 4.0 + (k % 9) as f64;
        let max = min * (1.2 + (k % 5) as f64);
        for m in measured(text) {
            let w = metrics::width_em(&m);
            widths.insert(m, w);
        }
        let points: Vec<f64> = cell.points().iter().flat_map(|p| [p.x, p.y]).collect();
        cases.push(serde_json::json!({"text": text, "p": points, "min": min, "max": max}));
    }
    let dir = temp_dir("page-fit-twin");
    let fit = include_str!("../../src/render/page/fit.js");
    std::fs::write(dir.join("fit.mjs"), fit).expect("write");
    let input = serde_json::json!({
        "widths": widths, "cases": cases, "line": metrics::line_step_em(), "ascent": metrics::ascent_em(),
    });
    std::fs::write(dir.join("in.json"), input.to_string()).expect("write");
    let driver = r#"
        import { placeLeaf } from "./fit.mjs";
        import { readFileSync } from "node:fs";
        const input = JSON.parse(readFileSync(new URL("./in.json", import.meta.url)));
        const width = (s) => {
          if (!(s in input.widths)) { throw new Error("no width for " + JSON.stringify(s)); }
          return input.widths[s];
        };
        const out = input.cases.map((c) =>
          placeLeaf(c.text, c.p, c.min, c.max, width, input.line, input.ascent));
        process.stdout.write(JSON.stringify(out));
    "#;
    std::fs::write(dir.join("driver.mjs"), driver).expect("write");
    let run = Command::new(node)
        .arg(dir.join("driver.mjs"))
        .output()
        .expect("node runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let page: Vec<serde_json::Value> = serde_json::from_slice(&run.stdout).expect("JSON");
    let mut outcomes = [0usize; 4];
    for (k, (cell, got)) in cells.iter().zip(&page).enumerate() {
        let case = &cases[k];
        let text = case["text"].as_str().expect("text");
        let (min, max) = (
            case["min"].as_f64().expect("min"),
            case["max"].as_f64().expect("max"),
        );
        let want = place_leaf(k, text, None, cell, min, max);
        let Some(want) = want else {
            assert!(got.is_null(), "case {k} {text:?}: the page placed {got}");
            outcomes[3] += 1;
            continue;
        };
        let lines = got["lines"]
            .as_array()
            .unwrap_or_else(|| panic!("case {k} {text:?}: placed"));
        assert_eq!(lines.len(), want.lines.len(), "case {k} {text:?}");
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs());
        let size = got["size"].as_f64().expect("size");
        assert!(
            close(size, want.lines[0].size),
            "case {k}: {size} vs {}",
            want.lines[0].size
        );
        for (g, w) in lines.iter().zip(&want.lines) {
            assert_eq!(g["text"].as_str(), Some(w.text.as_str()), "case {k}");
            assert!(close(g["x"].as_f64().expect("x"), w.x), "case {k}: x");
            assert!(
                close(g["baseline"].as_f64().expect("y"), w.baseline),
                "case {k}: y"
            );
        }
        let outcome = match (want.lines.len(), want.lines[0].text.ends_with('…')) {
            (2, _) => 1,
            (_, true) => 2,
            _ => 0,
        };
        outcomes[outcome] += 1;
    }
    // Every rule was met: one line, two lines, cut, left out.
    assert!(outcomes.iter().all(|&n| n >= 10), "outcomes {outcomes:?}");
}
