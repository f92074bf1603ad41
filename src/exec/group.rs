//! The box's process group: an adapter started in a group of its own and
//! registered, so that its group can be killed when it exits, times out or
//! overflows, and by the stop paths ([`terminate_all`], [`shut_down`]).

use std::collections::BTreeSet;
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Mutex, MutexGuard};

use super::error::ExecError;

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
pub(super) struct Adapter {
    pub(super) child: Child,
    group: libc::pid_t,
    /// Whether its group was killed and unlisted by us.
    ended: bool,
}

impl Adapter {
    /// Starts `command` (its program, arguments and folder set) as the
    /// leader of a process group of its own, with its stdout and stderr
    /// piped and no stdin, and registers the group; refused when the process
    /// is stopping. `shown` is the command line for the errors.
    pub(super) fn start(mut command: Command, shown: &str) -> Result<Adapter, ExecError> {
        let mut registry = registry();
        if registry.stopping {
            return Err(ExecError::Stopped {
                command: shown.to_owned(),
            });
        }
        let child = command
            .process_group(0)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| ExecError::Spawn {
                command: shown.to_owned(),
                source,
            })?;
        let group = child.id() as libc::pid_t;
        registry.groups.insert(group);
        Ok(Adapter {
            child,
            group,
            ended: false,
        })
    }

    /// Kills what is left of the group and unlists it; false when
    /// [`terminate_all`] had already done so (the process is stopping).
    pub(super) fn end_group(&mut self) -> bool {
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
    pub(super) fn exited(&self) -> bool {
        // SAFETY: waitid writes only into `info`, a zeroed siginfo_t.
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        let flags = libc::WEXITED | libc::WNOHANG | libc::WNOWAIT;
        let id = self.group as libc::id_t;
        let done = unsafe { libc::waitid(libc::P_PID, id, &mut info, flags) };
        // An error (ECHILD: already reaped) counts as exited.
        done != 0 || si_pid(&info) != 0
    }

    /// Ends the group and reaps the leader.
    pub(super) fn finish(mut self) -> (bool, std::io::Result<ExitStatus>) {
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
