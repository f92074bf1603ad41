//! The bundler of the page's ES modules: `src/render/page/*.js` (and the live
//! preview's `src/serve/live.js`) become one classic script each page embeds,
//! with no network and no JavaScript toolchain at build time.
//!
//! Hand-written because no maintained crate bundles ES modules without a
//! JavaScript engine, and swc's bundler is a very large dependency for a
//! dozen files of our own. It bundles the subset those files keep to, and
//! refuses the rest with the file, the line and what to write instead:
//!
//! - `import { a, b as c } from "./x.js";` (a relative path to one of our
//!   modules) becomes `const { a, b: c } = $x;` — a copy, not an ES live
//!   binding. So a module exports only what never changes after it has run:
//!   `export function f` and `export const x` (mutable shared state lives in
//!   an exported object, `export const view = { node: 0 }`, or behind a
//!   function). `export let`/`var`, default exports, export lists,
//!   re-exports, `import *`, default and bare imports, dynamic `import()`
//!   are refused; so is a module that assigns to, or declares again, a name
//!   it imports (an ES module would throw on the one and confuse on the
//!   other), and any identifier starting with `$` (the bundle's own names).
//! - Modules run in ES order: depth first along the imports in source
//!   order, each after everything it imports, the entries in the order
//!   given; an import cycle is refused (naming it).
//! - The script: one function scope (`(function () { "use strict"; … })()`,
//!   one per map, so several maps share a document: each finds its own
//!   container through `document.currentScript`, which a synchronous
//!   function scope keeps and a real module would not), inside it each
//!   module a function scope of its own returning its exports
//!   (`const $x = (function () { … return { a, b }; })();`). Bytes depend
//!   on the sources only.
//!
//! Not part of the library: `build.rs` runs it once per build (a refused
//! module is a build error, not a panic at the first page; the bundles are
//! `&'static str`s) and `tests/suite/page_scripts.rs` checks the modules
//! with it. Its lexer knows JavaScript's tokens (strings, templates,
//! comments, regular expressions by the usual previous-token rule), not
//! its grammar: the browser tests run what it emits.

use std::collections::BTreeMap;
use std::fmt;

// A sibling file, not a child module: `build.rs` and the suite include this
// file by path, and the path keeps the lexer beside it for both.
#[path = "lexer.rs"]
mod lexer;

pub(crate) use self::lexer::{tokens, Kind, Token};

/// The scripts the crate embeds (file name in `OUT_DIR`) and their entry
/// modules (paths from the crate's root), run in this order.
pub(crate) const BUNDLES: &[(&str, &[&str])] = &[
    ("page.js", &["src/render/page/main.js"]),
    (
        "page-history.js",
        &["src/render/page/main.js", "src/render/page/past.js"],
    ),
    ("live.js", &["src/serve/live.js"]),
];

/// Why a module cannot be bundled: the file, the line (1-based; 0 for the
/// file as a whole) and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct BundleError {
    pub(crate) path: String,
    pub(crate) line: usize,
    pub(crate) message: String,
}

impl fmt::Display for BundleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.path, self.line, self.message)
    }
}

/// One `import { … } from "…"` of a module.
#[derive(Debug, Clone)]
pub(crate) struct Import {
    /// The imported module, as a path from the crate's root.
    pub(crate) from: String,
    /// (name exported there, name bound here), in order.
    pub(crate) names: Vec<(String, String)>,
    pub(crate) line: usize,
}

/// A parsed module: what it imports and exports, and its text as bundled.
#[derive(Debug, Clone)]
pub(crate) struct Module {
    pub(crate) path: String,
    pub(crate) imports: Vec<Import>,
    /// Exported names, in order of declaration.
    pub(crate) exports: Vec<String>,
    /// The text with its imports turned into constants and `export ` gone.
    body: String,
}

/// A bundle: the script, and its modules in the order they run.
#[derive(Debug, Clone)]
pub(crate) struct Bundle {
    pub(crate) script: String,
    pub(crate) modules: Vec<Module>,
}

/// Operators that change the name on their left.
const ASSIGN: &[&str] = &[
    "=", "+=", "-=", "*=", "/=", "%=", "**=", "<<=", ">>=", ">>>=", "&=", "|=", "^=", "&&=", "||=",
    "??=", "++", "--",
];

/// The bundle's name for the module at `path`: `$` and its file stem.
fn module_var(path: &str) -> String {
    let name = path.rsplit('/').next().unwrap_or(path);
    let stem = name.strip_suffix(".js").unwrap_or(name);
    let clean: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("${clean}")
}

/// `spec` (`./x.js`, `../y/z.js`) from the module at `path`, as a path from
/// the crate's root; `None` for anything else.
fn resolve(path: &str, spec: &str) -> Option<String> {
    if !(spec.starts_with("./") || spec.starts_with("../")) || !spec.ends_with(".js") {
        return None;
    }
    let mut parts: Vec<&str> = path.split('/').collect();
    parts.pop();
    for part in spec.split('/') {
        match part {
            "." => {}
            ".." => {
                parts.pop()?;
            }
            "" => return None,
            p => parts.push(p),
        }
    }
    Some(parts.join("/"))
}

/// A module's tokens with the text they come from.
struct Source<'a> {
    path: &'a str,
    text: &'a str,
    toks: Vec<Token>,
}

impl Source<'_> {
    fn text(&self, k: usize) -> &str {
        self.toks.get(k).map_or("", |t| &self.text[t.start..t.end])
    }
    fn is(&self, k: usize, s: &str) -> bool {
        self.toks
            .get(k)
            .is_some_and(|t| t.kind != Kind::Str && self.text(k) == s)
    }
    fn line(&self, k: usize) -> usize {
        self.toks.get(k).or(self.toks.last()).map_or(0, |t| t.line)
    }
    fn err(&self, k: usize, message: impl Into<String>) -> BundleError {
        BundleError {
            path: self.path.to_string(),
            line: self.line(k),
            message: message.into(),
        }
    }
    fn ident(&self, k: usize) -> Option<&str> {
        self.toks
            .get(k)
            .filter(|t| t.kind == Kind::Ident)
            .map(|t| &self.text[t.start..t.end])
    }
    /// Whether token k is a name, not a property (`a.k`, `a?.k`).
    fn free(&self, k: usize) -> bool {
        self.toks[k].kind == Kind::Ident
            && !(k > 0 && (self.is(k - 1, ".") || self.is(k - 1, "?.")))
    }
}

/// Text replacements, by byte range of the module's text.
type Edits = Vec<(usize, usize, String)>;

/// Parses the module at `path` (a path from the crate's root): its imports
/// and exports, refusing what the bundle cannot keep correct.
pub(crate) fn parse(path: &str, text: &str) -> Result<Module, BundleError> {
    let whole = |line: usize, message: String| BundleError {
        path: path.to_string(),
        line,
        message,
    };
    let lower = text.to_ascii_lowercase();
    for bad in ["</script", "<!--"] {
        if let Some(at) = lower.find(bad) {
            let line = text[..at].matches('\n').count() + 1;
            return Err(whole(
                line,
                format!("`{bad}` would end or break the page's <script> element"),
            ));
        }
    }
    let toks = tokens(text).map_err(|(line, m)| whole(line, m))?;
    let src = Source { path, text, toks };
    let (mut imports, mut exports, mut edits) = (Vec::new(), Vec::new(), Edits::new());
    let mut depth = 0i64;
    let mut k = 0;
    while k < src.toks.len() {
        let t = src.text(k);
        if src.toks[k].kind == Kind::Punct {
            match t {
                "(" | "[" | "{" => depth += 1,
                ")" | "]" | "}" => depth -= 1,
                _ => {}
            }
        }
        if src.toks[k].kind == Kind::Ident && t.starts_with('$') {
            return Err(src.err(
                k,
                format!("`{t}`: names starting with `$` are the bundle's own"),
            ));
        }
        if src.free(k) && t == "import" {
            if depth != 0 || src.is(k + 1, "(") || src.is(k + 1, ".") {
                return Err(src.err(
                    k,
                    "dynamic `import()` or `import.meta`: import at the top, `import { a } from \"./x.js\";`",
                ));
            }
            let (import, next) = parse_import(&src, k, &mut edits)?;
            imports.push(import);
            k = next;
            continue;
        }
        if src.free(k) && t == "export" {
            if depth != 0 {
                return Err(src.err(k, "`export` inside a block"));
            }
            k = parse_export(&src, k, &mut exports, &mut edits)?;
            continue;
        }
        k += 1;
    }
    check_exports(&src, &exports)?;
    check_imported_names(&src, &imports)?;
    edits.sort_by_key(|e| e.0);
    let mut body = String::with_capacity(text.len());
    let mut at = 0;
    for (start, end, with) in &edits {
        body.push_str(&text[at..*start]);
        body.push_str(with);
        at = *end;
    }
    body.push_str(&text[at..]);
    if !body.ends_with('\n') {
        body.push('\n');
    }
    Ok(Module {
        path: path.to_string(),
        imports,
        exports: exports.into_iter().map(|(name, _)| name).collect(),
        body,
    })
}

/// The import statement at token k; returns it and the token after it.
fn parse_import(src: &Source, k: usize, edits: &mut Edits) -> Result<(Import, usize), BundleError> {
    let named = "name what it imports: `import { a, b } from \"./x.js\";`";
    if src.is(k + 1, "*") {
        return Err(src.err(k, format!("`import *`: {named}")));
    }
    if src.ident(k + 1).is_some() {
        return Err(src.err(k, format!("default import: {named}")));
    }
    if src.toks.get(k + 1).is_some_and(|t| t.kind == Kind::Str) {
        return Err(src.err(k, format!("import for its effects only: {named}")));
    }
    if !src.is(k + 1, "{") {
        return Err(src.err(k, format!("unexpected import: {named}")));
    }
    let mut names = Vec::new();
    let mut j = k + 2;
    loop {
        if src.is(j, "}") {
            break;
        }
        let Some(name) = src.ident(j) else {
            return Err(src.err(
                j,
                format!("unexpected `{}` in an import: {named}", src.text(j)),
            ));
        };
        let mut local = name;
        j += 1;
        if src.is(j, "as") {
            local = src
                .ident(j + 1)
                .ok_or_else(|| src.err(j, "a name after `as`"))?;
            j += 2;
        }
        names.push((name.to_string(), local.to_string()));
        if src.is(j, ",") {
            j += 1;
        } else if !src.is(j, "}") {
            return Err(src.err(
                j,
                format!("unexpected `{}` in an import: {named}", src.text(j)),
            ));
        }
    }
    if !src.is(j + 1, "from") || src.toks.get(j + 2).map(|t| t.kind) != Some(Kind::Str) {
        return Err(src.err(j, format!("expected `from \"./x.js\"`: {named}")));
    }
    let spec = src.text(j + 2);
    let spec = &spec[1..spec.len() - 1];
    let from = resolve(src.path, spec).ok_or_else(|| {
        src.err(
            j + 2,
            format!("`{spec}`: only relative paths to the project's own modules (`./x.js`, `../y/z.js`): no packages, no network"),
        )
    })?;
    let mut end = j + 3;
    if src.is(end, ";") {
        end += 1;
    }
    if names.is_empty() {
        return Err(src.err(k, format!("an import of nothing: {named}")));
    }
    let binds: Vec<String> = names
        .iter()
        .map(|(name, local)| {
            if name == local {
                name.clone()
            } else {
                format!("{name}: {local}")
            }
        })
        .collect();
    edits.push((
        src.toks[k].start,
        src.toks[end - 1].end,
        format!("const {{ {} }} = {};", binds.join(", "), module_var(&from)),
    ));
    let import = Import {
        from,
        names,
        line: src.line(k),
    };
    Ok((import, end))
}

/// The export at token k (recording its names and dropping `export `);
/// returns the token after `export`.
fn parse_export(
    src: &Source,
    k: usize,
    exports: &mut Vec<(String, usize)>,
    edits: &mut Edits,
) -> Result<usize, BundleError> {
    let only = "only `export function f` and `export const x` are bundled";
    let next = src.text(k + 1);
    match next {
        "function" => {
            let name_at = if src.is(k + 2, "*") { k + 3 } else { k + 2 };
            let name = src
                .ident(name_at)
                .ok_or_else(|| src.err(k, "`export function` without a name"))?;
            exports.push((name.to_string(), k));
        }
        "const" => {
            let mut j = k + 2;
            loop {
                let Some(name) = src.ident(j) else {
                    return Err(src.err(
                        j,
                        format!("`export const` of a pattern: {only}, one name each"),
                    ));
                };
                exports.push((name.to_string(), k));
                if !src.is(j + 1, "=") {
                    return Err(src.err(j, "`export const` without a value"));
                }
                // The value runs to the next `,` or `;` outside brackets.
                let mut depth = 0i64;
                j += 2;
                while j < src.toks.len() {
                    match src.text(j) {
                        "(" | "[" | "{" => depth += 1,
                        ")" | "]" | "}" => depth -= 1,
                        "," | ";" if depth == 0 => break,
                        _ => {}
                    }
                    j += 1;
                }
                if src.is(j, ",") {
                    j += 1;
                } else if src.is(j, ";") {
                    break;
                } else {
                    return Err(src.err(k, "`export const` not ended by `;`"));
                }
            }
        }
        "let" | "var" => {
            return Err(src.err(
                k,
                format!(
                    "`export {next}`: imports are copied once, so an export must never change; \
                     export a const object and change its fields (`export const view = {{ … }}`), or a function"
                ),
            ));
        }
        "default" => {
            return Err(src.err(k, format!("default export: {only}, each by its name")));
        }
        "{" | "*" => {
            return Err(src.err(
                k,
                format!("export list or re-export: {only}, where the name is declared; import a name from the module that declares it"),
            ));
        }
        _ => return Err(src.err(k, format!("`export {next}`: {only}"))),
    }
    edits.push((src.toks[k].start, src.toks[k + 1].start, String::new()));
    Ok(k + 1)
}

/// Each export once.
fn check_exports(src: &Source, exports: &[(String, usize)]) -> Result<(), BundleError> {
    let mut seen = BTreeMap::new();
    for (name, k) in exports {
        if seen.insert(name.as_str(), *k).is_some() {
            return Err(src.err(*k, format!("`{name}` is exported twice")));
        }
    }
    Ok(())
}

/// Imported names are bound once, never assigned and never declared again
/// in the module (an ES module throws on the one; the other hides the
/// import from the reader).
fn check_imported_names(src: &Source, imports: &[Import]) -> Result<(), BundleError> {
    let mut bound: BTreeMap<&str, &str> = BTreeMap::new();
    for import in imports {
        for (_, local) in &import.names {
            if bound.insert(local, &import.from).is_some() {
                return Err(BundleError {
                    path: src.path.to_string(),
                    line: import.line,
                    message: format!("`{local}` is imported twice"),
                });
            }
        }
    }
    let declares = ["var", "let", "const", "function", "class"];
    let mut in_import = false;
    let mut params = 0i64;
    for k in 0..src.toks.len() {
        let t = src.text(k);
        // The import statements themselves bind the names.
        if src.free(k) && t == "import" {
            in_import = true;
        }
        if in_import {
            in_import = src.toks[k].kind != Kind::Str;
            continue;
        }
        // A parameter list: after `function [name] (` or `catch (`.
        if t == "("
            && k > 0
            && (src.is(k - 1, "function")
                || src.is(k - 1, "catch")
                || (k > 1 && src.is(k - 2, "function")))
        {
            params = 1;
            continue;
        }
        if params > 0 {
            match t {
                "(" | "[" | "{" => params += 1,
                ")" | "]" | "}" => params -= 1,
                _ => {}
            }
        }
        if !src.free(k) {
            continue;
        }
        let Some(from) = bound.get(t) else { continue };
        let declared = k > 0 && declares.iter().any(|d| src.is(k - 1, d));
        if declared || params > 0 {
            return Err(src.err(
                k,
                format!("declares `{t}` again, which it imports from {from}"),
            ));
        }
        let assigned = ASSIGN.iter().any(|op| src.is(k + 1, op))
            || (k > 0 && (src.is(k - 1, "++") || src.is(k - 1, "--")));
        if assigned {
            return Err(src.err(
                k,
                format!(
                    "assigns to `{t}`, which it imports from {from}: imports are constant; \
                         let {from} export a function that changes it"
                ),
            ));
        }
    }
    Ok(())
}

/// Bundles the modules reached from `entries` (paths from the crate's root),
/// reading each once through `load`.
pub(crate) fn bundle(
    entries: &[&str],
    mut load: impl FnMut(&str) -> Result<String, String>,
) -> Result<Bundle, BundleError> {
    let mut walk = Walk {
        done: BTreeMap::new(),
        order: Vec::new(),
        stack: Vec::new(),
        load: &mut load,
    };
    for entry in entries {
        walk.visit(entry, None)?;
    }
    let Walk {
        mut done, order, ..
    } = walk;
    let modules: Vec<Module> = order.iter().filter_map(|p| done.remove(p)).collect();
    let mut vars: BTreeMap<String, &str> = BTreeMap::new();
    for m in &modules {
        if let Some(other) = vars.insert(module_var(&m.path), &m.path) {
            return Err(BundleError {
                path: m.path.clone(),
                line: 0,
                message: format!(
                    "two modules named alike: {other} and {}; rename one",
                    m.path
                ),
            });
        }
    }
    let mut script = String::from("(function () {\n\"use strict\";\n");
    for m in &modules {
        script.push_str(&format!("// {}\n", m.path));
        if m.exports.is_empty() {
            script.push_str("(function () {\n");
        } else {
            script.push_str(&format!(
                "const {} = (function () {{\n",
                module_var(&m.path)
            ));
        }
        script.push_str(&m.body);
        if !m.exports.is_empty() {
            script.push_str(&format!("return {{ {} }};\n", m.exports.join(", ")));
        }
        script.push_str("})();\n");
    }
    script.push_str("})();\n");
    Ok(Bundle { script, modules })
}

/// The depth-first walk along the imports.
struct Walk<'a, L: FnMut(&str) -> Result<String, String>> {
    done: BTreeMap<String, Module>,
    order: Vec<String>,
    stack: Vec<String>,
    load: &'a mut L,
}

impl<L: FnMut(&str) -> Result<String, String>> Walk<'_, L> {
    /// Visits `path`, imported at `by` (the importing file and line).
    fn visit(&mut self, path: &str, by: Option<(&str, usize)>) -> Result<(), BundleError> {
        let at = |message: String| BundleError {
            path: by.map_or(path, |b| b.0).to_string(),
            line: by.map_or(0, |b| b.1),
            message,
        };
        if self.done.contains_key(path) {
            return Ok(());
        }
        if let Some(from) = self.stack.iter().position(|p| p == path) {
            let mut cycle = self.stack[from..].to_vec();
            cycle.push(path.to_string());
            return Err(at(format!("an import cycle: {}", cycle.join(" imports "))));
        }
        let text = (self.load)(path).map_err(|e| at(format!("cannot read {path}: {e}")))?;
        let module = parse(path, &text)?;
        self.stack.push(path.to_string());
        for import in &module.imports {
            self.visit(&import.from, Some((path, import.line)))?;
            let there = &self.done[&import.from];
            for (name, _) in &import.names {
                if !there.exports.contains(name) {
                    return Err(BundleError {
                        path: path.to_string(),
                        line: import.line,
                        message: format!("`{name}` is not exported by {}", import.from),
                    });
                }
            }
        }
        self.stack.pop();
        self.order.push(path.to_string());
        self.done.insert(path.to_string(), module);
        Ok(())
    }
}
