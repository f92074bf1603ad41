//! What an adapter prints, read within the box: stdout up to its cap, the
//! end of stderr kept to quote, both pipes read by one thread with `poll(2)`.

use std::io::Read;
use std::os::fd::AsRawFd;
use std::time::Duration;

/// How much of the command's stderr an error message quotes (its end, where
/// a traceback says what went wrong).
pub(super) const STDERR_QUOTED: usize = 2000;

/// How much of stderr is kept to quote from: the quoted characters at up to
/// four bytes each.
const STDERR_KEPT: usize = 4 * STDERR_QUOTED;

/// How many bytes one read takes from a pipe (the slack over the cap).
const CHUNK: usize = 64 * 1024;

/// What the adapter printed so far: stdout up to the cap, the end of stderr.
pub(super) struct Output {
    pub(super) stdout: Vec<u8>,
    stderr: Vec<u8>,
    stderr_total: usize,
    max: usize,
    chunk: Box<[u8]>,
}

impl Output {
    pub(super) fn new(max: usize) -> Output {
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
    pub(super) fn read_some<O: Read + AsRawFd, E: Read + AsRawFd>(
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

    pub(super) fn stderr_tail(&self) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

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
