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

use std::collections::BTreeSet;
use std::io::Read;
use std::os::fd::AsRawFd;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How much of the command's stderr an error message quotes (its end, where
/// a traceback says what went wrong).
const STDERR_QUOTED: usize = 2000;

/// How much of stderr is kept to quote from: the quoted characters at up to
/// four bytes each.
const STDERR_KEPT: usize = 4 * STDERR_QUOTED;

/// How many bytes one read takes from a pipe (the slack over the cap).
const CHUNK: usize = 64 * 1024;

/// How often the adapter is looked at while its pipes are quiet: how late
/// its exit is noticed when a child of it holds the pipes open.
const TICK: Duration = Duration::from_millis(50);

/// An adapter command that did not produce a dataset.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExecError {
    /// The command could not be started (not found, not executable).
    #[error("`{command}`: cannot run: {source}")]
    Spawn {
        /// The command line, with its file arguments.
        command: String,
        /// Why.
        source: std::io::Error,
    },
    /// The command exited with a failure.
    #[error("`{command}` failed ({status}){}", quoted(.stderr))]
    Failed {
        /// The command line, with its file arguments.
        command: String,
        /// Its exit status.
        status: String,
        /// The end of what it printed on stderr.
        stderr: String,
    },
    /// The command ran longer than its timeout; its process group was killed.
    #[error(
        "`{command}` did not finish within {seconds} s and was stopped, with every process \
         it started (`timeout:` sets the limit){}",
        quoted(.stderr)
    )]
    Timeout {
        /// The command line, with its file arguments.
        command: String,
        /// The limit.
        seconds: f64,
        /// The end of what it printed on stderr.
        stderr: String,
    },
    /// The command exited, but a process it started outside its process group
    /// kept its output open until the timeout.
    #[error(
        "`{command}` exited, but a process it started outside its process group still held \
         its output after {seconds} s (`timeout:` sets the limit){}",
        quoted(.stderr)
    )]
    Held {
        /// The command line, with its file arguments.
        command: String,
        /// The limit.
        seconds: f64,
        /// The end of what it printed on stderr.
        stderr: String,
    },
    /// The command printed more than its cap; its process group was killed.
    #[error(
        "`{command}` printed more than {mb} MiB on {stream} and was stopped, with every \
         process it started (`limits.max_adapter_mb` raises the limit; it defaults to \
         `limits.max_file_mb`)"
    )]
    TooLarge {
        /// The command line, with its file arguments.
        command: String,
        /// `stdout` or `stderr`.
        stream: &'static str,
        /// The cap, in MiB.
        mb: u64,
    },
    /// Its output could not be read.
    #[error("`{command}`: cannot read its output: {source}")]
    Read {
        /// The command line, with its file arguments.
        command: String,
        /// Why.
        source: std::io::Error,
    },
    /// The process is stopping (a stop signal): the command was killed, or
    /// not started.
    #[error("`{command}` was stopped: nptreemap is stopping")]
    Stopped {
        /// The command line, with its file arguments.
        command: String,
    },
}

fn quoted(stderr: &str) -> String {
    if stderr.is_empty() {
        String::new()
    } else {
        format!("; its stderr:\n{stderr}")
    }
}

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

/// The process groups of the adapters running now, and whether the process
/// is stopping. Spawning happens under its lock, so that a stop never misses
/// an adapter being started; a group leaves it (under the lock) before its
/// leader is reaped, so that its id is never reused while it is listed.
struct Registry {
    stopping: bool,
    groups: BTreeSet<libc::pid_t>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    stopping: false,
    groups: BTreeSet::new(),
});

fn registry() -> MutexGuard<'static, Registry> {
    // The lock guards plain data that every holder leaves consistent.
    REGISTRY
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Kills the process group of every adapter running now (its runner then
/// returns [`ExecError::Stopped`]). For the daemon's shutdown.
pub fn terminate_all() {
    let mut registry = registry();
    for &group in &registry.groups {
        kill_group(group);
    }
    registry.groups.clear();
}

/// The process is stopping (SIGINT, SIGTERM): kills every running adapter's
/// process group, as [`terminate_all`], and refuses to start another.
/// An adapter runs in a process group of its own, which the terminal's
/// Ctrl-C does not reach, so every stop path must call this.
pub fn shut_down() {
    registry().stopping = true;
    terminate_all();
}

fn kill_group(group: libc::pid_t) {
    // SAFETY: killpg has no memory effects; `group` is a listed adapter's
    // group, whose leader is not reaped yet, so the id is still its own.
    unsafe { libc::killpg(group, libc::SIGKILL) };
}

/// A running adapter: its leader and its registered group.
struct Adapter {
    child: Child,
    group: libc::pid_t,
    /// Whether its group was killed and unlisted by us.
    ended: bool,
}

impl Adapter {
    /// Kills what is left of the group and unlists it; false when
    /// [`terminate_all`] had already done so (the process is stopping).
    fn end_group(&mut self) -> bool {
        if self.ended {
            return true;
        }
        self.ended = true;
        let mut registry = registry();
        let listed = registry.groups.remove(&self.group);
        if listed {
            kill_group(self.group);
        }
        listed
    }

    /// Whether the leader has exited, without reaping it (its pid, the
    /// group's id, stays reserved until [`Adapter::end_group`]).
    fn exited(&self) -> bool {
        // SAFETY: waitid writes only into `info`, a zeroed siginfo_t.
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        let flags = libc::WEXITED | libc::WNOHANG | libc::WNOWAIT;
        let id = self.group as libc::id_t;
        let done = unsafe { libc::waitid(libc::P_PID, id, &mut info, flags) };
        // An error (ECHILD: already reaped) counts as exited.
        done != 0 || si_pid(&info) != 0
    }

    /// Ends the group and reaps the leader.
    fn finish(mut self) -> (bool, std::io::Result<ExitStatus>) {
        let ours = self.end_group();
        let status = self.child.wait();
        (ours, status)
    }
}

impl Drop for Adapter {
    /// On every way out (an early return, a panic): nothing is left running,
    /// and the leader is reaped (no zombie piles up in a long `watch`; a
    /// second wait returns the status already taken).
    fn drop(&mut self) {
        self.end_group();
        let _ = self.child.wait();
    }
}

#[cfg(any(target_os = "linux", target_os = "android"))]
fn si_pid(info: &libc::siginfo_t) -> libc::pid_t {
    // SAFETY: waitid filled it for a child's state change (or left it zeroed).
    unsafe { info.si_pid() }
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn si_pid(info: &libc::siginfo_t) -> libc::pid_t {
    info.si_pid
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
    let started = Instant::now();
    let deadline = started.checked_add(bounds.timeout);
    let mut adapter = {
        let mut registry = registry();
        if registry.stopping {
            return Err(ExecError::Stopped { command: shown });
        }
        let child = Command::new(program)
            .args(args)
            .args(files)
            .current_dir(dir)
            .process_group(0)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| ExecError::Spawn {
                command: shown.clone(),
                source,
            })?;
        let group = child.id() as libc::pid_t;
        registry.groups.insert(group);
        Adapter {
            child,
            group,
            ended: false,
        }
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
                return Err(ExecError::Stopped { command: shown });
            }
        }
        if leader_done && stdout.is_none() && stderr.is_none() {
            break;
        }
        let left = match deadline {
            Some(deadline) => deadline.saturating_duration_since(Instant::now()),
            None => Duration::MAX,
        };
        if left.is_zero() {
            let (ours, _) = adapter.finish();
            let seconds = bounds.timeout.as_secs_f64();
            let stderr = out.stderr_tail();
            return Err(match (ours, leader_done) {
                (false, _) => ExecError::Stopped { command: shown },
                (true, false) => ExecError::Timeout {
                    command: shown,
                    seconds,
                    stderr,
                },
                (true, true) => ExecError::Held {
                    command: shown,
                    seconds,
                    stderr,
                },
            });
        }
        // Once the leader is gone, only the pipes matter: wait for them
        // until the deadline; before, look at the leader every tick.
        let wait = if leader_done { left } else { left.min(TICK) };
        let step = out
            .read_some(&mut stdout, &mut stderr, wait)
            .map_err(|source| ExecError::Read {
                command: shown.clone(),
                source,
            });
        match step {
            Ok(None) => {}
            Ok(Some(stream)) => {
                let ours = adapter.end_group();
                if !ours {
                    return Err(ExecError::Stopped { command: shown });
                }
                return Err(ExecError::TooLarge {
                    command: shown,
                    stream,
                    mb: bounds.max_mb,
                });
            }
            Err(e) => return Err(e),
        }
    }
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

/// What the adapter printed so far: stdout up to the cap, the end of stderr.
struct Output {
    stdout: Vec<u8>,
    stderr: Vec<u8>,
    stderr_total: usize,
    max: usize,
    chunk: Box<[u8]>,
}

impl Output {
    fn new(max: usize) -> Output {
        Output {
            stdout: Vec::new(),
            stderr: Vec::new(),
            stderr_total: 0,
            max,
            chunk: vec![0; CHUNK].into_boxed_slice(),
        }
    }

    /// Waits at most `wait` for either pipe, reads what one has, and drops a
    /// pipe at its end. Returns the stream that went over the cap, if one did.
    fn read_some<O: Read + AsRawFd, E: Read + AsRawFd>(
        &mut self,
        stdout: &mut Option<O>,
        stderr: &mut Option<E>,
        wait: Duration,
    ) -> std::io::Result<Option<&'static str>> {
        let fd = |p: Option<&dyn AsRawFd>| p.map_or(-1, |p| p.as_raw_fd());
        // A negative fd is skipped by poll(2).
        let mut fds = [
            libc::pollfd {
                fd: fd(stdout.as_ref().map(|p| p as &dyn AsRawFd)),
                events: libc::POLLIN,
                revents: 0,
            },
            libc::pollfd {
                fd: fd(stderr.as_ref().map(|p| p as &dyn AsRawFd)),
                events: libc::POLLIN,
                revents: 0,
            },
        ];
        // Rounded up, so that a wait of less than a millisecond still waits.
        let ms = wait.as_micros().div_ceil(1000).min(i32::MAX as u128) as libc::c_int;
        // SAFETY: `fds` is a valid array of two pollfd for the call.
        let ready = unsafe { libc::poll(fds.as_mut_ptr(), 2, ms) };
        if ready < 0 {
            let e = std::io::Error::last_os_error();
            // A signal interrupted the wait: the caller's loop waits again.
            return if e.kind() == std::io::ErrorKind::Interrupted {
                Ok(None)
            } else {
                Err(e)
            };
        }
        let readable = |p: &libc::pollfd| p.revents != 0;
        if readable(&fds[0]) {
            if let Some(pipe) = stdout {
                match read_chunk(pipe, &mut self.chunk)? {
                    None => {}
                    Some(0) => *stdout = None,
                    Some(n) if self.stdout.len() + n > self.max => return Ok(Some("stdout")),
                    Some(n) => push_within(&mut self.stdout, &self.chunk[..n], self.max)?,
                }
            }
        }
        if readable(&fds[1]) {
            if let Some(pipe) = stderr {
                match read_chunk(pipe, &mut self.chunk)? {
                    None => {}
                    Some(0) => *stderr = None,
                    Some(n) => {
                        self.stderr_total += n;
                        if self.stderr_total > self.max {
                            return Ok(Some("stderr"));
                        }
                        keep_tail(&mut self.stderr, &self.chunk[..n], STDERR_KEPT);
                    }
                }
            }
        }
        Ok(None)
    }

    fn stderr_tail(&self) -> String {
        tail(&self.stderr)
    }
}

/// One read of a pipe poll(2) found ready: `Some(0)` at its end, `None`
/// when a signal interrupted it (the caller's loop comes back to it).
fn read_chunk(pipe: &mut impl Read, chunk: &mut [u8]) -> std::io::Result<Option<usize>> {
    match pipe.read(chunk) {
        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(None),
        other => other.map(Some),
    }
}

/// Appends `bytes` to `buf`, growing it at most to `max` (doubling below it),
/// so that the buffer never holds much more than the cap.
fn push_within(buf: &mut Vec<u8>, bytes: &[u8], max: usize) -> std::io::Result<()> {
    let need = buf.len() + bytes.len();
    if need > buf.capacity() {
        let want = need.max(buf.len().saturating_mul(2)).min(max).max(need);
        buf.try_reserve_exact(want - buf.len())
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::OutOfMemory, e))?;
    }
    buf.extend_from_slice(bytes);
    Ok(())
}

/// Appends `bytes` to `buf`, keeping only its last `keep` bytes.
fn keep_tail(buf: &mut Vec<u8>, bytes: &[u8], keep: usize) {
    buf.extend_from_slice(&bytes[bytes.len().saturating_sub(keep)..]);
    if buf.len() > keep {
        buf.drain(..buf.len() - keep);
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

    #[test]
    fn buffers_grow_no_further_than_the_cap() {
        let max = 1000;
        let mut buf = Vec::new();
        for _ in 0..100 {
            push_within(&mut buf, &[7; 10], max).expect("room");
        }
        assert_eq!(buf.len(), max);
        assert!(buf.capacity() <= max, "{}", buf.capacity());
        let mut kept = Vec::new();
        for i in 0..100u8 {
            keep_tail(&mut kept, &[i; 3], 10);
        }
        assert_eq!(kept, [96, 97, 97, 97, 98, 98, 98, 99, 99, 99]);
    }
}
