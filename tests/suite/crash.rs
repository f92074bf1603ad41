//! The crash test (issue 11): `build` on a large dataset is killed with
//! SIGKILL at several points (before its writes, while a temp file of an
//! output is being written, while the stored layout is being written, after
//! the last output); every output must then be the complete old or the
//! complete new file, the next run must leave no temp file behind, and the
//! stored layout must let it start again (to the same pictures as a run that
//! was never interrupted).

use std::path::{Path, PathBuf};
use std::process::Child;
use std::time::{Duration, Instant};

use crate::support;

/// Outputs of the dataset, and the stored layout, relative to the folder.
const FILES: [&str; 4] = [
    "out/big.svg",
    "out/big.png",
    "out/big.json",
    "out/.nptreemap/big.layout.json",
];

const CONFIG: &str = "datasets:
  - name: big
    format: hierarchy-json
    files: {hierarchy: tree.json}
    outputs:
      - path: out/big.svg
      - {path: out/big.png, scale: 2}
      - path: out/big.json
";

/// A three-level hierarchy of 2,400 leaves (laid out without similarity, so
/// the run's time goes to the layout's diagrams and to large outputs).
fn tree(version: u64) -> String {
    let mut groups = Vec::new();
    for g in 0..12 {
        let mut subs = Vec::new();
        for s in 0..10 {
            let leaves: Vec<String> = (0..20)
                .map(|l| {
                    let w = 1 + (g * 31 + s * 7 + l * 13 + version * 5) % 40;
                    format!(r#"{{"id": "g{g}s{s}l{l}", "value": {w}}}"#)
                })
                .collect();
            subs.push(format!(
                r#"{{"id": "g{g}s{s}", "children": [{}]}}"#,
                leaves.join(", ")
            ));
        }
        groups.push(format!(
            r#"{{"id": "g{g}", "children": [{}]}}"#,
            subs.join(", ")
        ));
    }
    format!(r#"{{"id": "root", "children": [{}]}}"#, groups.join(",\n"))
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("type").is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("copy");
        }
    }
}

fn read_all(dir: &Path) -> Vec<Vec<u8>> {
    FILES
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))
        .collect()
}

fn build(dir: &Path) -> Child {
    support::bin()
        .arg("build")
        .arg(dir.join("nptreemap.yaml"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start build")
}

fn build_to_end(dir: &Path) -> Duration {
    let t = Instant::now();
    let status = build(dir).wait().expect("wait");
    assert!(status.success(), "build in {} failed", dir.display());
    t.elapsed()
}

/// Temp files of ours in the output folders.
fn temps(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for sub in ["out", "out/.nptreemap"] {
        if let Ok(entries) = std::fs::read_dir(dir.join(sub)) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with('.') && name.ends_with(".tmp") {
                    found.push(e.path());
                }
            }
        }
    }
    found
}

/// When to kill the build.
#[derive(Clone, Copy, Debug)]
enum Point {
    /// This long after the start (before any write, for small fractions).
    After(Duration),
    /// As soon as a temp file for a name starting so appears.
    Writing(&'static str),
}

#[test]
fn kill_9_at_any_point_leaves_old_or_new_files() {
    let base = support::temp_dir("crash_base");
    std::fs::write(base.join("nptreemap.yaml"), CONFIG).expect("config");
    std::fs::write(base.join("tree.json"), tree(1)).expect("tree");
    build_to_end(&base);
    let old = read_all(&base);

    // The reference: the same change, never interrupted.
    let reference = support::temp_dir("crash_reference");
    copy_dir(&base, &reference);
    std::fs::write(reference.join("tree.json"), tree(2)).expect("tree v2");
    let full = build_to_end(&reference);
    let new = read_all(&reference);
    for (k, f) in FILES.iter().enumerate() {
        assert_ne!(old[k], new[k], "{f}: the change must change every file");
    }

    let points = [
        Point::After(full / 10),
        Point::After(full / 3),
        Point::Writing(".big.svg."),
        Point::Writing(".big.png."),
        Point::Writing(".big.json."),
        Point::Writing(".big.layout.json."),
        Point::After(full * 2),
    ];
    let mut caught_writing = 0;
    for (n, point) in points.iter().enumerate() {
        // A kill meant to land during a write misses it when the write ends
        // before the poll looks (a loaded machine may not look for a while):
        // try again, a few times, each a whole run checked as any other.
        let tries = if matches!(point, Point::Writing(_)) {
            5
        } else {
            1
        };
        for attempt in 0..tries {
            let run = Run {
                base: &base,
                old: &old,
                new: &new,
                full,
            };
            if run.kill_at(&format!("crash_{n}_{attempt}"), *point) {
                caught_writing += 1;
                break;
            }
        }
    }
    assert!(
        caught_writing >= 2,
        "only {caught_writing} kills landed during a write"
    );
}

/// One interrupted run: the base folder, its files before and after the
/// change, and how long an uninterrupted build of the change took.
struct Run<'a> {
    base: &'a Path,
    old: &'a [Vec<u8>],
    new: &'a [Vec<u8>],
    full: Duration,
}

impl Run<'_> {
    /// Copies the base to the temp folder `tag`, changes the tree, kills a
    /// build of it at `point`, and checks what it left and that the next
    /// runs end where an uninterrupted one does. Returns whether the kill
    /// landed while a temp file of the point's name existed.
    fn kill_at(&self, tag: &str, point: Point) -> bool {
        let Run {
            base,
            old,
            new,
            full,
        } = *self;
        let dir = support::temp_dir(tag);
        copy_dir(base, &dir);
        std::fs::write(dir.join("tree.json"), tree(2)).expect("tree v2");
        let mut child = build(&dir);
        let mut caught = false;
        let started = Instant::now();
        match point {
            Point::After(wait) => {
                while started.elapsed() < wait {
                    if child.try_wait().expect("try_wait").is_some() {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
            Point::Writing(prefix) => loop {
                let seen = temps(&dir).iter().any(|p| {
                    p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
                });
                if seen {
                    caught = true;
                    break;
                }
                if child.try_wait().expect("try_wait").is_some() {
                    break;
                }
                assert!(
                    started.elapsed() < (full * 20).max(support::WAIT),
                    "{point:?}: no temp file appeared"
                );
                std::thread::sleep(Duration::from_micros(200));
            },
        }
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();

        // Every file is the complete old or the complete new one.
        let mut states = Vec::new();
        for (k, f) in FILES.iter().enumerate() {
            let bytes =
                std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{point:?}: {f}: {e}"));
            let which = if bytes == old[k] {
                "old"
            } else if bytes == new[k] {
                "new"
            } else {
                panic!(
                    "{point:?}: {f} is neither the old nor the new file ({} bytes)",
                    bytes.len()
                )
            };
            states.push(which);
        }
        // The next run restarts from what is there, removes the temp files
        // of the killed one, and ends at the uninterrupted run's pictures.
        build_to_end(&dir);
        let left = temps(&dir);
        assert!(
            left.is_empty(),
            "{point:?}: temp files survived the next run: {left:?}"
        );
        let after = read_all(&dir);
        for (k, f) in FILES.iter().enumerate().take(3) {
            assert!(
                after[k] == new[k],
                "{point:?} ({states:?}): {f} differs from the uninterrupted run"
            );
        }
        // And it is settled: a further run changes nothing.
        build_to_end(&dir);
        assert!(
            read_all(&dir) == after,
            "{point:?}: a further run changed files"
        );
        caught
    }
}
