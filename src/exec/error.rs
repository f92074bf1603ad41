//! The messages of an adapter command that did not produce a dataset
//! ([`ExecError`]): each names the whole command line and, where it failed,
//! quotes the end of its stderr.

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
