//! Bundles the page's ES modules into the scripts the crate embeds
//! (`src/render/page/bundle.rs` says how, and why here rather than once per
//! process: a module the bundler refuses fails the build with its file and
//! line, and the pages carry `&'static str`s built before any page is).
//! Writes `page.js`, `page-history.js` and `live.js` into `OUT_DIR`.

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
