//! `watch --serve --open`: the default browser opened on the preview's first
//! page, through the system's own opener (`xdg-open`, `open`, `start`). A
//! machine without one, or an opener that fails, is a line on stderr, never
//! a failure of `watch`.

use std::process::{Command, Stdio};

/// The command that opens `url` in the default browser on this system.
fn opener(url: &str) -> Command {
    if cfg!(target_os = "macos") {
        let mut c = Command::new("open");
        c.arg(url);
        c
    } else if cfg!(windows) {
        // `start` is a shell built-in; its first quoted argument is a title.
        let mut c = Command::new("cmd");
        c.args(["/C", "start", "", url]);
        c
    } else {
        let mut c = Command::new("xdg-open");
        c.arg(url);
        c
    }
}

/// Opens `url` in the default browser without waiting for it: the opener
/// is reaped on a thread of its own, which reports a failure as a warning.
pub(crate) fn open(url: &str) {
    let mut command = opener(url);
    let program = command.get_program().to_string_lossy().into_owned();
    let spawned = command
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn();
    let mut child = match spawned {
        Ok(child) => child,
        Err(e) => {
            super::warn(format_args!(
                "cannot open a browser ({program}: {e}); open {url} yourself"
            ));
            return;
        }
    };
    let url = url.to_string();
    let reaped = std::thread::Builder::new()
        .name("np-open".to_string())
        .spawn(move || match child.wait() {
            Ok(status) if status.success() => {}
            Ok(status) => super::warn(format_args!(
                "cannot open a browser ({program} {status}); open {url} yourself"
            )),
            Err(e) => super::warn(format_args!(
                "cannot open a browser ({program}: {e}); open {url} yourself"
            )),
        });
    // Without a thread the opener is left unreaped until `watch` ends.
    drop(reaped);
}
