//! The preview mirrors the outputs (issue 33 item 6): each output is served
//! at its path relative to the config's folder, the URLs every output had
//! before (`/<dataset>/<file>`) redirect there for good, the index links
//! the outputs by their paths, and `--open` hands the first page to the
//! system's opener, or says in a line that there is none and serves on.

use std::path::Path;
use std::time::{Duration, Instant};

use super::{get, setup, Served};

#[test]
fn outputs_are_served_at_their_paths_and_old_urls_redirect() {
    let (_dir, config) = setup("serve_mirror");
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    let addr = served.addr;
    assert_eq!(get(addr, "/out/grid.html").status, 200);
    assert_eq!(get(addr, "/out/grid.svg").status, 200);
    for (old, now) in [
        ("/grid/grid.html", "/out/grid.html"),
        ("/grid/grid.svg?x=1", "/out/grid.svg"),
    ] {
        let reply = get(addr, old);
        assert_eq!(reply.status, 308, "{old}");
        assert_eq!(reply.header("location"), Some(now), "{old}");
    }
    // Only outputs move: anything else is still not found.
    assert_eq!(get(addr, "/grid/nptreemap.yaml").status, 404);
    assert_eq!(get(addr, "/out/nptreemap.yaml").status, 404);
    let index = get(addr, "/").text();
    for path in ["out/grid.html", "out/grid.svg"] {
        assert!(
            index.contains(&format!("href=\"/{path}\">{path}</a>")),
            "{index}"
        );
    }
    served.terminate();
}

/// A folder with a fake `xdg-open` that writes the URL it was given to
/// `opened.txt` beside it.
fn fake_opener(dir: &Path) {
    use std::os::unix::fs::PermissionsExt;
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).expect("bin");
    let script = bin.join("xdg-open");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\nprintf '%s' \"$1\" > '{}'\n",
            dir.join("opened.txt").display()
        ),
    )
    .expect("script");
    std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

#[test]
#[cfg(target_os = "linux")]
fn open_hands_the_first_page_to_the_opener() {
    let (dir, config) = setup("serve_open");
    fake_opener(&dir);
    let mut served = Served::start_with(&config, None, |cmd| {
        cmd.arg("--open").env("PATH", dir.join("bin"));
    });
    let opened = dir.join("opened.txt");
    let start = Instant::now();
    while !opened.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(50));
    }
    let url = std::fs::read_to_string(&opened).expect("the opener ran");
    assert_eq!(url, format!("http://{}/out/grid.html", served.addr));
    served.expect(&["grid", "wrote"]);
    served.terminate();
}

#[test]
#[cfg(target_os = "linux")]
fn open_without_an_opener_is_a_line_not_a_failure() {
    let (dir, config) = setup("serve_open_none");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).expect("empty");
    let mut served = Served::start_with(&config, None, |cmd| {
        cmd.arg("--open").env("PATH", &empty);
    });
    served.expect(&["grid", "wrote"]);
    assert_eq!(get(served.addr, "/out/grid.html").status, 200);
    served.terminate();
    let log = std::fs::read_to_string(config.with_extension("log")).expect("log");
    assert!(
        log.contains("cannot open a browser (xdg-open") && log.contains("/out/grid.html yourself"),
        "{log}"
    );
}
