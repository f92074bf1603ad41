//! What ships: notify's native watcher on every platform (from `cargo tree`
//! over the lock file, `.ci/platforms`) and the crates' package lists (free of
//! tests, fixtures, examples' data and outputs; licence files in both).

use std::path::Path;
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

/// FSEvents on macOS (aarch64-apple-darwin), ReadDirectoryChangesW on
/// Windows (x86_64-pc-windows-msvc) and inotify on Linux, as resolved by
/// `cargo tree --target` from the lock file.
#[test]
fn notify_has_its_native_backend_on_macos_windows_and_linux() {
    let out = Command::new("bash")
        .arg(root().join(".ci/platforms"))
        .env(
            "CARGO",
            std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()),
        )
        .output()
        .expect("run .ci/platforms");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for line in [
        "ok   aarch64-apple-darwin: notify's FSEvents backend",
        "ok   aarch64-apple-darwin: the FSEvents binding",
        "ok   x86_64-pc-windows-msvc: ReadDirectoryChangesW",
        "ok   x86_64-unknown-linux-gnu: inotify",
    ] {
        assert!(stdout.contains(line), "{line} missing in:\n{stdout}");
    }
}

fn package_list(krate: &str) -> Vec<String> {
    let out = cargo()
        .args([
            "package",
            "--list",
            "--allow-dirty",
            "--offline",
            "-p",
            krate,
        ])
        .current_dir(root())
        .output()
        .expect("run cargo package --list");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn package_lists_hold_sources_docs_and_licences_only() {
    for krate in ["nptreemap", "nptreemap-formats"] {
        let files = package_list(krate);
        for needed in [
            "Cargo.toml",
            "README.md",
            "LICENSE-MIT",
            "LICENSE-APACHE",
            "src/lib.rs",
        ] {
            assert!(files.iter().any(|f| f == needed), "{krate}: no {needed}");
        }
        let allowed = |f: &str| {
            f.starts_with("src/")
                || f == "config/default.yaml"
                || matches!(
                    f,
                    "Cargo.toml"
                        | "build.rs"
                        | "Cargo.toml.orig"
                        | "Cargo.lock"
                        | ".cargo_vcs_info.json"
                        | "README.md"
                        | "LICENSE-MIT"
                        | "LICENSE-APACHE"
                )
        };
        let extra: Vec<&String> = files.iter().filter(|f| !allowed(f)).collect();
        assert!(extra.is_empty(), "{krate} would ship {extra:?}");
    }
    // The built-in font and the documented defaults are all the crate embeds.
    let main = package_list("nptreemap");
    assert!(main.iter().any(|f| f == "src/render/fonts/DejaVuSans.ttf"));
    assert!(main.iter().any(|f| f == "config/default.yaml"));
    // The build script that bundles the page's scripts, and what it reads.
    assert!(main.iter().any(|f| f == "build.rs"));
    assert!(main.iter().any(|f| f == "src/render/page/bundle.rs"));
}
