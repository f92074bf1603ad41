//! The pure modules (geometry, power diagrams, layout, neighbourhoods, rendering,
//! metrics) never touch files, standard output or the clock (ARCHITECTURE.md).
//! A grep keeps it so.

use std::path::Path;

const PURE: &[&str] = &[
    "src/geom",
    "src/power",
    "src/layout",
    "src/neighborhood",
    "src/render",
    "src/metrics.rs",
    "src/previous.rs",
    "src/rng.rs",
    "src/stability.rs",
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

fn rust_files(path: &Path, out: &mut Vec<std::path::PathBuf>) {
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

#[test]
fn pure_modules_do_no_io() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for p in PURE {
        rust_files(&root.join(p), &mut files);
    }
    assert!(
        files.len() >= 10,
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
fn every_source_file_opens_with_a_module_doc() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    rust_files(&root.join("formats/src"), &mut files);
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
