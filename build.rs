//! Bundles the page's ES modules into the scripts the crate embeds
//! (`src/render/page/bundle.rs` says how, and why here rather than once per
//! process: a module the bundler refuses fails the build with its file and
//! line, and the pages carry `&'static str`s built before any page is).
//! Writes `page.js`, `page-history.js` and `live.js` into `OUT_DIR`, and
//! sets `NPTREEMAP_RENDER_SOURCE`, a fingerprint of the renderers' sources
//! (`src/render/`, `src/layout_json/`): a part of every output's render key,
//! so that outputs made by another version of the renderers are made again
//! rather than reported up to date.

use std::path::PathBuf;

#[path = "src/render/page/bundle.rs"]
mod bundle;

fn main() {
    let root = PathBuf::from(
        std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"),
    );
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/render/page/bundle.rs");
    println!("cargo:rerun-if-changed=src/render/page/lexer.rs");
    println!("cargo:rerun-if-changed=src/render");
    println!("cargo:rerun-if-changed=src/layout_json");
    let id = render_source(&root, &["src/render", "src/layout_json"]);
    println!("cargo:rustc-env=NPTREEMAP_RENDER_SOURCE={id:016x}");
    for (name, entries) in bundle::BUNDLES {
        let made = bundle::bundle(entries, |path| {
            std::fs::read_to_string(root.join(path)).map_err(|e| e.to_string())
        });
        let made = match made {
            Ok(made) => made,
            Err(e) => {
                eprintln!("error: the page's scripts: {e}");
                std::process::exit(1);
            }
        };
        for module in &made.modules {
            println!("cargo:rerun-if-changed={}", module.path);
        }
        let file = out.join(name);
        if let Err(e) = std::fs::write(&file, made.script) {
            eprintln!("error: cannot write {}: {e}", file.display());
            std::process::exit(1);
        }
    }
}

/// FNV-1a over every file under `dirs` (paths relative to `root`, sorted,
/// each path and its bytes with their lengths): stable across runs and
/// toolchains, and a build script needs no hash crate for it.
fn render_source(root: &std::path::Path, dirs: &[&str]) -> u64 {
    fn files(dir: &std::path::Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                files(&path, out);
            } else {
                out.push(path);
            }
        }
    }
    let mut all = Vec::new();
    for dir in dirs {
        files(&root.join(dir), &mut all);
    }
    all.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for chunk in [&(bytes.len() as u64).to_le_bytes()[..], bytes] {
            for b in chunk {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
    };
    for path in all {
        let rel = path.strip_prefix(root).unwrap_or(&path);
        feed(rel.to_string_lossy().as_bytes());
        feed(&std::fs::read(&path).unwrap_or_default());
    }
    h
}
