//! The runtime format plugin (`format: exec`): runs a dataset's adapter
//! command with its declared files' paths and returns what it printed, in a
//! box of time and size.
//!
//! An edge, like `workspace`: it starts a process and reads its output; the
//! caller parses the bytes (hierarchy JSON) as it parses a file's. The box:
//! - the adapter runs in a process group of its own, and its timeout covers
//!   the whole group and the reading of its output: a child it leaves behind
//!   holding the pipe (`sleep 30 &`) can neither hold the build past the
//!   timeout nor outlive it;
//! - when the adapter exits, what is left of its group is killed (so nothing
//!   is orphaned) and the output is read to its end without waiting for them;
//!   on a timeout, or when the output passes its cap, the whole group is;
//! - stdout is read up to a cap, so memory stays at the cap plus a chunk;
//!   stderr keeps only its end, which the error messages quote;
//! - the live groups are registered, so that a stop signal or the daemon's
//!   shutdown kills them ([`terminate_all`], [`shut_down`]).
//!
//! One thread does it all with `poll(2)`: no reader thread can outlive a run.
//! A process that leaves the group (`setsid`) is out of reach of the kills;
//! if it holds the output, the timeout still ends the reading.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// The messages of a command that did not produce a dataset.
mod error;
/// The adapter's process group, registered for the stop paths.
mod group;
/// Its stdout and stderr, read within the caps.
mod output;

pub use error::ExecError;
pub use group::{shut_down, terminate_all};

use group::Adapter;
use output::Output;

/// How often the adapter is looked at while its pipes are quiet: how late
/// its exit is noticed when a child of it holds the pipes open.
const TICK: Duration = Duration::from_millis(50);

/// The box an adapter runs in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// How long it and its output may take, from its start to the end of its
    /// output.
    pub timeout: Duration,
    /// The most it may print on stdout (and on stderr), in MiB.
    pub max_mb: u64,
}

impl Bounds {
    fn max_bytes(&self) -> usize {
        usize::try_from(self.max_mb.saturating_mul(1 << 20)).unwrap_or(usize::MAX)
    }
}

/// The command line as a shell would take it, each word quoted where it
/// needs to be (`python3 du_tree.py 'my sizes.du'`), so that it can be pasted
/// into a shell in the adapter's folder.
pub fn display(command: &[String], files: &[PathBuf]) -> String {
    let words = command
        .iter()
        .map(|w| w.to_string())
        .chain(files.iter().map(|f| f.to_string_lossy().into_owned()));
    words
        .map(|w| match shlex::try_quote(&w) {
            Ok(quoted) => quoted.into_owned(),
            // A NUL byte, which no argument can carry anyway.
            Err(_) => format!("{w:?}"),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Runs `command` (program and arguments) in `dir` with `files` appended as
/// arguments, and returns its stdout. Fails when it cannot start, exits with
/// a failure, runs past `bounds.timeout` or prints more than
/// `bounds.max_mb`; the error names the command line and quotes the end of
/// its stderr. Whatever happens, no process of its group is left running.
pub fn run(
    command: &[String],
    files: &[PathBuf],
    dir: &Path,
    bounds: Bounds,
) -> Result<Vec<u8>, ExecError> {
    let shown = display(command, files);
    let Some((program, args)) = command.split_first() else {
        return Err(ExecError::Spawn {
            command: shown,
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "empty command"),
        });
    };
    let deadline = Instant::now().checked_add(bounds.timeout);
    let mut line = Command::new(program);
    line.args(args).args(files).current_dir(dir);
    let adapter = Adapter::start(line, &shown)?;
    let (adapter, out) = read_output(adapter, deadline, bounds, &shown)?;
    let (ours, status) = adapter.finish();
    if !ours {
        return Err(ExecError::Stopped { command: shown });
    }
    let status = status.map_err(|source| ExecError::Read {
        command: shown.clone(),
        source,
    })?;
    if !status.success() {
        return Err(ExecError::Failed {
            command: shown,
            status: status.to_string(),
            stderr: out.stderr_tail(),
        });
    }
    Ok(out.stdout)
}

/// Reads what the adapter prints until both pipes end after its leader
/// exited (what is left of its group is killed then), or fails at the
/// `deadline`, past the caps of `bounds`, or when the process is stopping.
/// `shown` is the command line for the errors.
fn read_output(
    mut adapter: Adapter,
    deadline: Option<Instant>,
    bounds: Bounds,
    shown: &str,
) -> Result<(Adapter, Output), ExecError> {
    let stopped = || ExecError::Stopped {
        command: shown.to_owned(),
    };
    let mut out = Output::new(bounds.max_bytes());
    let mut stdout = adapter.child.stdout.take();
    let mut stderr = adapter.child.stderr.take();
    let mut leader_done = false;
    loop {
        if !leader_done && adapter.exited() {
            leader_done = true;
            // What is left of the group (children holding the pipes) goes
            // now, so the pipes close and nothing is orphaned.
            if !adapter.end_group() {
                return Err(stopped());
            }
        }
        if leader_done && stdout.is_none() && stderr.is_none() {
            return Ok((adapter, out));
        }
        let left = match deadline {
            Some(deadline) => deadline.saturating_duration_since(Instant::now()),
            None => Duration::MAX,
        };
        if left.is_zero() {
            let (ours, _) = adapter.finish();
            let (command, seconds) = (shown.to_owned(), bounds.timeout.as_secs_f64());
            let stderr = out.stderr_tail();
            return Err(match (ours, leader_done) {
                (false, _) => stopped(),
                (true, false) => ExecError::Timeout {
                    command,
                    seconds,
                    stderr,
                },
                (true, true) => ExecError::Held {
                    command,
                    seconds,
                    stderr,
                },
            });
        }
        // Once the leader is gone, only the pipes matter: wait for them
        // until the deadline; before, look at the leader every tick.
        let wait = if leader_done { left } else { left.min(TICK) };
        let over = out
            .read_some(&mut stdout, &mut stderr, wait)
            .map_err(|source| ExecError::Read {
                command: shown.to_owned(),
                source,
            })?;
        if let Some(stream) = over {
            if !adapter.end_group() {
                return Err(stopped());
            }
            return Err(ExecError::TooLarge {
                command: shown.to_owned(),
                stream,
                mb: bounds.max_mb,
            });
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::output::STDERR_QUOTED;
    use super::*;

    fn sh(script: &str) -> Vec<String> {
        vec!["sh".into(), "-c".into(), script.into(), "adapter".into()]
    }

    const SECOND: Duration = Duration::from_secs(1);

    fn bounds(seconds: u64) -> Bounds {
        Bounds {
            timeout: Duration::from_secs(seconds),
            max_mb: 16,
        }
    }

    /// A fresh file path for a script to write a pid to.
    fn pid_file(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("nptreemap-exec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join(name);
        let _ = std::fs::remove_file(&path);
        path
    }

    fn pid_in(file: &Path) -> libc::pid_t {
        std::fs::read_to_string(file)
            .expect("pid file")
            .trim()
            .parse()
            .expect("a pid")
    }

    /// Whether `pid` runs (a zombie does not); waits up to 10 s for the
    /// kernel to finish a kill.
    fn still_running_after_a_while(pid: libc::pid_t) -> bool {
        let running = || {
            std::fs::read_to_string(format!("/proc/{pid}/stat"))
                .is_ok_and(|s| !s.rsplit(')').next().unwrap_or("").trim_start().starts_with('Z'))
        };
        let deadline = Instant::now() + 10 * SECOND;
        while running() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
        }
        let alive = running();
        if alive {
            // SAFETY: a plain kill of the test's own leftover.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        alive
    }

    #[test]
    fn stdout_is_returned_and_files_are_the_arguments() {
        let out = run(
            &sh("printf '%s|' \"$@\"; pwd"),
            &[PathBuf::from("a.csv"), PathBuf::from("b c.csv")],
            Path::new("/"),
            bounds(10),
        )
        .expect("runs");
        assert_eq!(String::from_utf8_lossy(&out), "a.csv|b c.csv|/\n");
    }

    #[test]
    fn the_command_line_is_shown_as_a_shell_would_read_it() {
        let command = sh("echo 'it''s' \"$1\" >&2; exit 3");
        let files = [PathBuf::from("my data.csv"), PathBuf::from("plain.csv")];
        let shown = display(&command, &files);
        let words: Vec<String> = command
            .iter()
            .cloned()
            .chain(files.iter().map(|f| f.display().to_string()))
            .collect();
        assert_eq!(shlex::split(&shown), Some(words), "{shown}");
        assert!(shown.ends_with(" adapter 'my data.csv' plain.csv"), "{shown}");
    }

    #[test]
    fn a_failure_names_the_command_its_status_and_its_stderr() {
        let e = run(
            &sh("echo 'bad row 3' >&2; exit 3"),
            &[PathBuf::from("in.csv")],
            Path::new("/"),
            bounds(10),
        )
        .expect_err("fails");
        let text = e.to_string();
        assert!(text.starts_with("`sh -c "), "{text}");
        assert!(
            text.ends_with(" adapter in.csv` failed (exit status: 3); its stderr:\nbad row 3"),
            "{text}"
        );
    }

    #[test]
    fn a_slow_command_is_stopped_at_its_timeout() {
        let e = run(&sh("echo starting >&2; sleep 30"), &[], Path::new("/"), bounds(1))
            .expect_err("times out");
        assert!(matches!(e, ExecError::Timeout { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains("did not finish within 1 s"), "{text}");
        assert!(text.ends_with("its stderr:\nstarting"), "{text}");
    }

    #[test]
    fn a_child_left_holding_stdout_is_killed_when_the_adapter_exits() {
        let pids = pid_file("left.pid");
        let out = run(
            &sh("sleep 60 & echo $! > \"$1\"; echo done"),
            std::slice::from_ref(&pids),
            Path::new("/"),
            bounds(50),
        )
        .expect("the adapter's own output");
        assert_eq!(out, b"done\n");
        assert!(!still_running_after_a_while(pid_in(&pids)), "orphan left");
    }

    #[test]
    fn a_timeout_kills_the_whole_group() {
        let pids = pid_file("group.pid");
        let e = run(
            &sh("sleep 60 & echo $! > \"$1\"; sleep 60"),
            std::slice::from_ref(&pids),
            Path::new("/"),
            bounds(2),
        )
        .expect_err("times out");
        assert!(matches!(e, ExecError::Timeout { .. }), "{e}");
        assert!(!still_running_after_a_while(pid_in(&pids)), "orphan left");
    }

    #[test]
    fn output_held_outside_the_group_ends_at_the_timeout() {
        // A process of its own session holds stdout for 60 s; the group
        // kill cannot reach it, the timeout still ends the reading.
        let pids = pid_file("escaped.pid");
        let e = run(
            &sh("python3 -c 'import os, sys; os.setsid(); open(sys.argv[1], \"w\").write(str(os.getpid())); os.execvp(\"sleep\", [\"sleep\", \"60\"])' \"$1\" &
                 while [ ! -s \"$1\" ]; do sleep 0.05; done; echo done"),
            std::slice::from_ref(&pids),
            Path::new("/"),
            bounds(5),
        )
        .expect_err("held");
        assert!(matches!(e, ExecError::Held { .. }), "{e}");
        assert!(e.to_string().contains("still held its output after 5 s"), "{e}");
        // Out of the group's reach: the test ends it itself.
        if let Ok(pid) = std::fs::read_to_string(&pids) {
            if let Ok(pid) = pid.trim().parse::<libc::pid_t>() {
                // SAFETY: a plain kill of the test's own leftover.
                unsafe { libc::kill(pid, libc::SIGKILL) };
            }
        }
    }

    #[test]
    fn a_missing_program_is_a_spawn_error_naming_it() {
        let e = run(
            &["/nonexistent/adapter".to_string()],
            &[],
            Path::new("/"),
            bounds(1),
        )
        .expect_err("no such program");
        assert!(
            e.to_string()
                .starts_with("`/nonexistent/adapter`: cannot run:"),
            "{e}"
        );
    }

    #[test]
    fn output_up_to_the_cap_is_read_whole_and_beyond_it_refused() {
        let mib = 1 << 20;
        let one = Bounds {
            timeout: 20 * SECOND,
            max_mb: 1,
        };
        let out = run(&sh(&format!("head -c {mib} /dev/zero")), &[], Path::new("/"), one)
            .expect("exactly the cap");
        assert_eq!(out.len(), mib);
        for (script, stream) in [
            (format!("head -c {} /dev/zero", mib + 1), "stdout"),
            ("yes".to_string(), "stdout"),
            (format!("head -c {} /dev/zero >&2", 3 * mib), "stderr"),
        ] {
            let e = run(&sh(&script), &[], Path::new("/"), one).expect_err(&script);
            assert!(
                matches!(e, ExecError::TooLarge { stream: s, mb: 1, .. } if s == stream),
                "{script}: {e}"
            );
            assert!(
                e.to_string().contains("more than 1 MiB on "),
                "{script}: {e}"
            );
        }
    }

    #[test]
    fn an_adapter_stopped_at_the_cap_is_reaped() {
        let pids = pid_file("reaped.pid");
        let one = Bounds {
            timeout: 20 * SECOND,
            max_mb: 1,
        };
        let e = run(
            &sh("echo $$ > \"$1\"; exec yes"),
            std::slice::from_ref(&pids),
            Path::new("/"),
            one,
        )
        .expect_err("over the cap");
        assert!(matches!(e, ExecError::TooLarge { .. }), "{e}");
        // Reaped: not even a zombie is left (a long `watch` would pile them up).
        let pid = pid_in(&pids);
        assert!(
            !Path::new(&format!("/proc/{pid}")).exists(),
            "the adapter {pid} was not reaped"
        );
    }

    #[test]
    fn a_large_output_does_not_block() {
        let out = run(
            &sh("head -c 1000000 /dev/zero; head -c 1000000 /dev/zero >&2"),
            &[],
            Path::new("/"),
            bounds(20),
        )
        .expect("runs");
        assert_eq!(out.len(), 1_000_000);
    }

    #[test]
    fn only_the_end_of_a_long_stderr_is_kept_and_quoted() {
        let e = run(
            &sh("head -c 100000 /dev/zero | tr '\\0' x >&2; echo ' the cause' >&2; exit 1"),
            &[],
            Path::new("/"),
            bounds(20),
        )
        .expect_err("fails");
        let ExecError::Failed { stderr, .. } = &e else {
            panic!("{e}")
        };
        assert!(stderr.ends_with("x the cause"), "{stderr}");
        assert!(stderr.len() <= STDERR_QUOTED, "{}", stderr.len());
    }
}
