//! Issue 34 item 5: the number of threads (`-j N`, `NPTREEMAP_THREADS`)
//! changes the time only: every output is the same bytes with one thread as
//! with two, for the neighbourhood method and for the plain treemap (whose
//! diagrams of a level run in parallel and, with skewed weights, settle).

use std::path::Path;

use crate::support;

/// Every output kind of `nptreemap layout` on `input`, with `threads` set by
/// `-j` (`Some`) or by `NPTREEMAP_THREADS`.
fn outputs(input: &Path, tag: &str, threads: &str, by_flag: bool, extra: &[&str]) -> Vec<Vec<u8>> {
    let dir = input.parent().expect("a folder");
    let names =
        ["json", "svg", "html", "png"].map(|ext| dir.join(format!("{tag}-{threads}.{ext}")));
    let mut cmd = support::bin();
    cmd.arg("layout").arg(input).args(extra);
    for n in &names {
        cmd.arg("--out").arg(n);
    }
    if by_flag {
        cmd.args(["-j", threads]);
    } else {
        cmd.env("NPTREEMAP_THREADS", threads);
    }
    let out = cmd.output().expect("run nptreemap");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    names
        .iter()
        .map(|n| std::fs::read(n).expect("output"))
        .collect()
}

#[test]
fn one_thread_and_two_give_the_same_bytes() {
    let dir = support::temp_dir("threads");
    let similar = support::generate(&dir, 600, 2, 11);
    let one = outputs(&similar, "neighbor", "1", true, &[]);
    let two = outputs(&similar, "neighbor", "2", false, &[]);
    for (kind, (a, b)) in ["json", "svg", "html", "png"]
        .iter()
        .zip(one.iter().zip(&two))
    {
        assert!(a == b, "{kind} differs between 1 and 2 threads");
    }
    let one = outputs(&similar, "plain", "1", false, &["--method", "plain"]);
    let two = outputs(&similar, "plain", "2", true, &["--method", "plain"]);
    for (kind, (a, b)) in ["json", "svg", "html", "png"]
        .iter()
        .zip(one.iter().zip(&two))
    {
        assert!(a == b, "plain {kind} differs between 1 and 2 threads");
    }
}

#[test]
fn a_bad_thread_count_is_an_error_naming_it() {
    let out = support::bin()
        .args(["config", "--defaults"])
        .env("NPTREEMAP_THREADS", "many")
        .output()
        .expect("run nptreemap");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("NPTREEMAP_THREADS") && err.contains("many"),
        "{err}"
    );
}
