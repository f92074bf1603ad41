//! Outputs that cannot destroy anything (issue 11, items 1, 2, 8 and 11): an
//! output over an input, the config, another output or a special file is
//! refused before anything is written; temp files are created exclusively
//! (a planted link is never followed); stale temp files of killed runs are
//! removed; state files of differently named datasets never collide.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support;

const NODES: &str = "id,weight,group\na,3,x\nb,2,x\nc,4,y\nd,1,y\n";
const PAIRS: &str = "a,b\nb,c\n";

/// A folder with `nodes.csv`, `pairs.csv` and a config whose one dataset
/// writes `outputs` (YAML flow entries such as `{path: out/a.svg}`).
fn folder(tag: &str, outputs: &[&str]) -> PathBuf {
    let dir = support::temp_dir(&format!("safety_{tag}"));
    std::fs::write(dir.join("nodes.csv"), NODES).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), PAIRS).expect("pairs");
    let config = format!(
        "datasets:\n  - name: d\n    format: border-list\n    files: {{nodes: nodes.csv, pairs: pairs.csv}}\n    fields: {{groups: [group]}}\n    outputs: [{}]\n",
        outputs.join(", ")
    );
    std::fs::write(dir.join("nptreemap.yaml"), config).expect("config");
    dir
}

fn build(dir: &Path) -> Output {
    support::output_within(
        support::bin().arg("build").arg(dir.join("nptreemap.yaml")),
        120,
    )
}

/// Asserts a refusal: exit 2, every one of `names` in the message, no panic.
fn assert_refused(out: &Output, names: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    for name in names {
        assert!(stderr.contains(name), "{name:?} not in: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn an_output_over_an_input_or_the_config_is_refused() {
    for (tag, output, victim) in [
        ("over_input", "{path: nodes.csv, kind: json}", "nodes.csv"),
        (
            "over_input_dotdot",
            "{path: out/../pairs.csv, kind: svg}",
            "pairs.csv",
        ),
        (
            "over_config",
            "{path: nptreemap.yaml, kind: json}",
            "nptreemap.yaml",
        ),
    ] {
        let dir = folder(tag, &["{path: out/first.svg}", output]);
        let before = std::fs::read(dir.join(victim)).expect("victim");
        let out = build(&dir);
        let stderr = assert_refused(&out, &[victim]);
        // Both paths are named: the output and what it would overwrite.
        assert!(
            stderr.matches(victim).count() >= 2 || stderr.contains("output"),
            "{tag}: {stderr}"
        );
        assert_eq!(
            std::fs::read(dir.join(victim)).expect("victim"),
            before,
            "{tag}"
        );
        // Nothing at all was written, not even the harmless first output.
        assert!(
            !dir.join("out/first.svg").exists(),
            "{tag}: wrote out/first.svg"
        );
    }
}

#[test]
fn an_output_through_a_symlink_onto_an_input_is_refused() {
    let dir = folder("symlink_input", &["{path: out/link.json}"]);
    std::fs::create_dir_all(dir.join("out")).expect("out");
    std::os::unix::fs::symlink(dir.join("nodes.csv"), dir.join("out/link.json")).expect("link");
    let out = build(&dir);
    assert_refused(&out, &["link.json", "nodes.csv"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("nodes.csv")).expect("nodes"),
        NODES
    );
}

#[test]
fn two_outputs_with_one_path_are_refused() {
    let dir = folder("twice", &["{path: out/a.svg}", "{path: out/./a.svg}"]);
    let out = build(&dir);
    let stderr = assert_refused(&out, &["a.svg", "outputs[0]", "outputs[1]"]);
    assert!(!dir.join("out/a.svg").exists(), "{stderr}");
    // Across datasets too.
    let dir = folder("twice_across", &["{path: out/a.svg}"]);
    let config = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("config");
    let second = config["datasets:\n".len()..].replace("name: d", "name: e");
    std::fs::write(dir.join("nptreemap.yaml"), format!("{config}{second}")).expect("config");
    let out = build(&dir);
    assert_refused(&out, &["a.svg", "datasets[0]", "datasets[1]"]);
}

#[test]
fn special_files_are_never_replaced() {
    // A FIFO, and a link to a character device (/dev/null itself is never
    // touched: before the fix the link, not the device, would be replaced).
    let dir = folder("special", &["{path: out/pipe.svg}", "{path: out/null.png}"]);
    std::fs::create_dir_all(dir.join("out")).expect("out");
    support::mkfifo(&dir.join("out/pipe.svg"));
    std::os::unix::fs::symlink("/dev/null", dir.join("out/null.png")).expect("link");
    let out = build(&dir);
    let stderr = assert_refused(&out, &["pipe.svg", "not a regular file"]);
    use std::os::unix::fs::FileTypeExt;
    let kind = std::fs::symlink_metadata(dir.join("out/pipe.svg"))
        .expect("fifo")
        .file_type();
    assert!(kind.is_fifo(), "the FIFO was replaced: {stderr}");
    let link = std::fs::symlink_metadata(dir.join("out/null.png")).expect("link");
    assert!(
        link.file_type().is_symlink(),
        "the link was replaced: {stderr}"
    );
    // The FIFO alone: the link to /dev/null is refused as well.
    std::fs::remove_file(dir.join("out/pipe.svg")).expect("rm fifo");
    let out = build(&dir);
    assert_refused(&out, &["null.png", "not a regular file"]);
    // A directory where a file should go.
    let dir = folder("special_dir", &["{path: out/dir.svg}"]);
    std::fs::create_dir_all(dir.join("out/dir.svg")).expect("dir");
    assert_refused(&build(&dir), &["dir.svg", "not a regular file"]);
}

#[test]
fn layout_refuses_to_write_over_its_input() {
    let dir = support::temp_dir("safety_layout_input");
    let input = dir.join("in.json");
    let text =
        r#"{"name": "r", "children": [{"name": "a", "value": 1}, {"name": "b", "value": 2}]}"#;
    std::fs::write(&input, text).expect("input");
    let out = support::output_within(
        support::bin()
            .arg("layout")
            .arg(&input)
            .arg("--out")
            .arg(&input),
        60,
    );
    assert_refused(&out, &["in.json"]);
    assert_eq!(std::fs::read_to_string(&input).expect("input"), text);
    // The same for --previous, and for two --out of one path.
    let first = dir.join("first.json");
    support::layout(&input, &[&first], &[]);
    let before = std::fs::read(&first).expect("first");
    let out = support::output_within(
        support::bin()
            .arg("layout")
            .arg(&input)
            .arg("--previous")
            .arg(&first)
            .arg("--out")
            .arg(&first),
        60,
    );
    assert_refused(&out, &["first.json"]);
    assert_eq!(std::fs::read(&first).expect("first"), before);
    let out = support::output_within(
        support::bin()
            .arg("layout")
            .arg(&input)
            .args(["--out"])
            .arg(dir.join("x.svg"))
            .args(["--out"])
            .arg(dir.join("sub/../x.svg")),
        60,
    );
    assert_refused(&out, &["x.svg"]);
}

#[test]
fn a_link_planted_at_the_temp_name_is_not_followed() {
    // The old writer's temp name was `.NAME.PID.tmp`: predictable from the
    // PID. The shell plants the link for its own PID, then execs the build
    // in the same process.
    let dir = folder("planted", &["{path: out.svg}"]);
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious").expect("victim");
    let script = format!(
        "ln -s {victim} {dir}/.out.svg.$$.tmp && exec {bin} build {dir}/nptreemap.yaml",
        victim = victim.display(),
        dir = dir.display(),
        bin = env!("CARGO_BIN_EXE_nptreemap"),
    );
    let out = support::output_within(std::process::Command::new("sh").args(["-c", &script]), 120);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(&victim).expect("victim"),
        "precious"
    );
    let meta = std::fs::symlink_metadata(dir.join("out.svg")).expect("out.svg");
    assert!(meta.file_type().is_file(), "out.svg is not a regular file");
    let svg = std::fs::read_to_string(dir.join("out.svg")).expect("svg");
    assert!(svg.ends_with("</svg>\n"), "out.svg is the picture");
}

#[test]
fn outputs_are_readable_by_others_as_new_files_are() {
    let dir = folder("mode", &["{path: out/a.svg}"]);
    assert!(build(&dir).status.success());
    use std::os::unix::fs::PermissionsExt;
    let mode = std::fs::metadata(dir.join("out/a.svg"))
        .expect("a.svg")
        .permissions()
        .mode();
    // The umask decides the rest; a temp file's private 0600 would lack these.
    std::fs::write(dir.join("probe"), "x").expect("probe");
    let plain = std::fs::metadata(dir.join("probe"))
        .expect("probe")
        .permissions()
        .mode();
    assert_eq!(
        mode & 0o777,
        plain & 0o777,
        "output mode {mode:o} vs new file {plain:o}"
    );
}

#[test]
fn stale_temp_files_of_dead_runs_are_removed() {
    let dir = folder("stale", &["{path: out/a.svg}"]);
    let out_dir = dir.join("out");
    std::fs::create_dir_all(out_dir.join(".nptreemap")).expect("dirs");
    // PIDs above the kernel's maximum (4,194,304) belong to no process.
    let stale = [
        "out/.a.svg.4999999.tmp",
        "out/.a.svg.4999998.Ab12Cd.tmp",
        "out/.nptreemap/.d.layout.json.4999997.tmp",
    ];
    for name in stale {
        std::fs::write(dir.join(name), vec![b'x'; 1000]).expect("stale");
    }
    // Kept: a live process's temp file (this test's own), and other files.
    let live = format!("out/.a.svg.{}.Zz9Yy8.tmp", std::process::id());
    let kept = [live.as_str(), "out/.other.svg.4999999.tmp", "out/notes.tmp"];
    for name in kept {
        std::fs::write(dir.join(name), "x").expect("kept");
    }
    let out = build(&dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in stale {
        assert!(
            !dir.join(name).exists(),
            "{name} survived: {:?}",
            files_in(&out_dir)
        );
    }
    for name in kept {
        assert!(dir.join(name).exists(), "{name} was removed");
    }
}

#[test]
fn datasets_with_non_ascii_names_keep_separate_state() {
    let dir = support::temp_dir("safety_state_names");
    std::fs::write(dir.join("nodes.csv"), NODES).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), PAIRS).expect("pairs");
    let other = NODES.replace("a,3", "a,9");
    std::fs::write(dir.join("other.csv"), other).expect("other");
    let mut config = String::from("datasets:\n");
    for (name, nodes, out) in [
        ("日本", "nodes.csv", "jp"),
        ("中国", "other.csv", "cn"),
        ("a b", "nodes.csv", "ab"),
        ("a_b", "other.csv", "a_b"),
    ] {
        config.push_str(&format!(
            "  - name: \"{name}\"\n    format: border-list\n    files: {{nodes: {nodes}, pairs: pairs.csv}}\n    fields: {{groups: [group]}}\n    outputs: [{{path: out/{out}.json}}]\n"
        ));
    }
    std::fs::write(dir.join("nptreemap.yaml"), config).expect("config");
    let first = build(&dir);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let states: Vec<String> = files_in(&dir.join("out/.nptreemap"))
        .into_iter()
        .filter(|f| f.ends_with(".layout.json"))
        .collect();
    assert_eq!(states.len(), 4, "one stored layout per dataset: {states:?}");
    // A second build with no input change starts warm from each dataset's
    // own state and rewrites nothing.
    let second = build(&dir);
    let stdout = String::from_utf8_lossy(&second.stdout);
    assert!(second.status.success());
    assert!(
        !stdout.contains("wrote"),
        "a rebuild without changes wrote:\n{stdout}"
    );
}

/// Issue 21 item 9: output names of 240 to 255 bytes are valid names and
/// are written (the temp file's name used to add to them: `File name too
/// long`), in `build` and again unchanged, leaving no temp file behind.
/// (That stale temp files of such names are recognised is a unit test of
/// `store.rs`.)
#[test]
fn outputs_with_the_longest_names_are_written() {
    for len in [240, 250, 255] {
        let name = format!("{}.svg", "n".repeat(len - 4));
        let dir = folder(
            &format!("long_name_{len}"),
            &[&format!("{{path: out/{name}}}")],
        );
        let out = build(&dir);
        assert!(
            out.status.success(),
            "{len}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let svg = std::fs::read_to_string(dir.join("out").join(&name)).expect("svg");
        assert!(svg.ends_with("</svg>\n"), "{len}");
        // Again, with nothing to change; and no temp file is left over.
        assert!(build(&dir).status.success(), "{len}: second build");
        let left: Vec<String> = files_in(&dir.join("out"))
            .into_iter()
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{len}: {left:?}");
    }
}
