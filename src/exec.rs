//! The runtime format plugin (`format: exec`): runs a dataset's adapter
//! command with its declared files' paths and returns what it printed.
//!
//! An edge, like `workspace`: it starts a process and reads its output; the
//! caller parses the bytes (hierarchy JSON) as it parses a file's. The timeout
//! is `wait-timeout`'s; the pipes are drained on threads so that a command
//! printing more than a pipe buffer cannot block before it exits.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use wait_timeout::ChildExt;

/// How much of the command's stderr an error message quotes (its end, where
/// a traceback says what went wrong).
const STDERR_QUOTED: usize = 2000;

/// An adapter command that did not produce a dataset.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExecError {
    /// The command could not be started (not found, not executable).
    #[error("`{command}`: cannot run: {source}")]
    Spawn {
        /// The command line, as configured.
        command: String,
        /// Why.
        source: std::io::Error,
    },
    /// The command exited with a failure.
    #[error("`{command}` failed ({status}){}", quoted(.stderr))]
    Failed {
        /// The command line, as configured.
        command: String,
        /// Its exit status.
        status: String,
        /// The end of what it printed on stderr.
        stderr: String,
    },
    /// The command ran longer than its timeout and was stopped.
    #[error("`{command}` did not finish within {seconds} s and was stopped (`timeout:` sets the limit){}", quoted(.stderr))]
    Timeout {
        /// The command line, as configured.
        command: String,
        /// The limit.
        seconds: f64,
        /// The end of what it printed on stderr.
        stderr: String,
    },
}

fn quoted(stderr: &str) -> String {
    if stderr.is_empty() {
        String::new()
    } else {
        format!("; its stderr:\n{stderr}")
    }
}

/// The command line as people read it (`python3 adapters/mine.py`).
pub fn display(command: &[String]) -> String {
    command.join(" ")
}

/// Runs `command` (program and arguments) in `dir` with `files` appended as
/// arguments, and returns its stdout. Fails when it cannot start, exits with
/// a failure or runs longer than `timeout`; the error names the command and
/// quotes the end of its stderr.
pub fn run(
    command: &[String],
    files: &[PathBuf],
    dir: &Path,
    timeout: Duration,
) -> Result<Vec<u8>, ExecError> {
    let shown = display(command);
    let Some((program, args)) = command.split_first() else {
        return Err(ExecError::Spawn {
            command: shown,
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "empty command"),
        });
    };
    let mut child = Command::new(program)
        .args(args)
        .args(files)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|source| ExecError::Spawn {
            command: shown.clone(),
            source,
        })?;
    let stdout = drain(child.stdout.take());
    let stderr = drain(child.stderr.take());
    let status = child
        .wait_timeout(timeout)
        .map_err(|source| ExecError::Spawn {
            command: shown.clone(),
            source,
        })?;
    let Some(status) = status else {
        // Stop it. Its own children may keep the pipes open; their readers
        // are left to finish on their own.
        let _ = child.kill();
        let _ = child.wait();
        return Err(ExecError::Timeout {
            command: shown,
            seconds: timeout.as_secs_f64(),
            stderr: tail(&stderr.so_far()),
        });
    };
    let (stdout, stderr) = (stdout.join(), stderr.join());
    if !status.success() {
        return Err(ExecError::Failed {
            command: shown,
            status: status.to_string(),
            stderr: tail(&stderr),
        });
    }
    Ok(stdout)
}

/// A pipe being read on its own thread into a shared buffer, so that what
/// came so far can be taken without waiting for the pipe to close (after a
/// timeout, a grandchild of the command may still hold it open).
struct Reader {
    bytes: Arc<Mutex<Vec<u8>>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

fn drain(pipe: Option<impl Read + Send + 'static>) -> Reader {
    let bytes = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&bytes);
    let thread = pipe.map(|mut pipe| {
        std::thread::spawn(move || {
            let mut chunk = [0u8; 8192];
            // A read error ends the output; what came before is kept.
            while let Ok(n @ 1..) = pipe.read(&mut chunk) {
                sink.lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner())
                    .extend_from_slice(&chunk[..n]);
            }
        })
    });
    Reader { bytes, thread }
}

impl Reader {
    /// Everything, once the pipe has closed.
    fn join(mut self) -> Vec<u8> {
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        self.so_far()
    }

    /// What was read until now.
    fn so_far(&self) -> Vec<u8> {
        std::mem::take(
            &mut *self
                .bytes
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner()),
        )
    }
}

/// The last [`STDERR_QUOTED`] bytes of `stderr` as trimmed text.
fn tail(stderr: &[u8]) -> String {
    let text = String::from_utf8_lossy(stderr);
    let text = text.trim();
    let mut start = text.len().saturating_sub(STDERR_QUOTED);
    while !text.is_char_boundary(start) {
        start += 1;
    }
    text[start..].to_string()
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn sh(script: &str) -> Vec<String> {
        vec!["sh".into(), "-c".into(), script.into(), "adapter".into()]
    }

    const SECOND: Duration = Duration::from_secs(1);

    #[test]
    fn stdout_is_returned_and_files_are_the_arguments() {
        let out = run(
            &sh("printf '%s|' \"$@\"; pwd"),
            &[PathBuf::from("a.csv"), PathBuf::from("b c.csv")],
            Path::new("/"),
            10 * SECOND,
        )
        .expect("runs");
        assert_eq!(String::from_utf8_lossy(&out), "a.csv|b c.csv|/\n");
    }

    #[test]
    fn a_failure_names_the_command_its_status_and_its_stderr() {
        let e = run(
            &sh("echo 'bad row 3' >&2; exit 3"),
            &[],
            Path::new("/"),
            10 * SECOND,
        )
        .expect_err("fails");
        assert_eq!(
            e.to_string(),
            "`sh -c echo 'bad row 3' >&2; exit 3 adapter` failed (exit status: 3); its stderr:\nbad row 3"
        );
    }

    #[test]
    fn a_slow_command_is_stopped_at_its_timeout() {
        let started = std::time::Instant::now();
        let e = run(
            &sh("echo starting >&2; sleep 30"),
            &[],
            Path::new("/"),
            SECOND,
        )
        .expect_err("times out");
        assert!(started.elapsed() < 20 * SECOND, "{:?}", started.elapsed());
        assert!(matches!(e, ExecError::Timeout { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains("did not finish within 1 s"), "{text}");
        assert!(text.ends_with("its stderr:\nstarting"), "{text}");
    }

    #[test]
    fn a_missing_program_is_a_spawn_error_naming_it() {
        let e = run(
            &["/nonexistent/adapter".to_string()],
            &[],
            Path::new("/"),
            SECOND,
        )
        .expect_err("no such program");
        assert!(
            e.to_string()
                .starts_with("`/nonexistent/adapter`: cannot run:"),
            "{e}"
        );
    }

    #[test]
    fn a_large_output_does_not_block() {
        let out = run(
            &sh("head -c 1000000 /dev/zero"),
            &[],
            Path::new("/"),
            20 * SECOND,
        )
        .expect("runs");
        assert_eq!(out.len(), 1_000_000);
    }
}
