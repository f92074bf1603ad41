//! The one writer of files: every output (and every stored layout) goes to a
//! temporary file in its own directory and is renamed into place, so readers
//! never see a partly written file and a failed run leaves existing outputs
//! untouched. Owns the temp files' naming, their safe creation (O_EXCL and a
//! random name, through the `tempfile` crate, so a link planted at a
//! predictable name is never followed), fsync of file and directory, and the
//! removal of temp files a killed run left behind. Reading is
//! [`crate::workspace`]'s.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Every temp file's name ends so: `.NAME.PID.RANDOM.tmp` (and, from before
/// the random part, `.NAME.PID.tmp`).
const TEMP_SUFFIX: &str = ".tmp";

/// Held while a set of outputs is being written ([`writing`]), so that a
/// forced exit (the daemon's answer to SIGTERM during a long rebuild) can wait
/// for the set to be complete instead of leaving a dataset's SVG new and its
/// PNG old.
static WRITING: Mutex<()> = Mutex::new(());

/// Takes the write lock (see `WRITING`): hold it while writing outputs that
/// belong together, or before exiting the process while writes may be going on.
pub fn writing() -> MutexGuard<'static, ()> {
    // A panic while writing leaves no invariant behind this lock to protect.
    WRITING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The directory `path` is written in (`.` for a bare file name).
fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn name_of(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_string())
}

/// Writes `bytes` to `path` atomically: a new temp file in the same directory
/// (created exclusively under a random name, never through an existing file
/// or link), written and fsynced, renamed over `path`, then the directory
/// fsynced so the rename survives a power cut. Creates the directory if it is
/// missing. On any failure the temp file is removed and `path` is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = dir_of(path);
    std::fs::create_dir_all(&dir)?;
    let prefix = format!(".{}.{}.", name_of(path), std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(TEMP_SUFFIX);
    // Outputs are for others to read (a web server, a docs build): the
    // umask's default for new files, as `File::create` gave, not tempfile's
    // private 0600.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(&dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    // On failure the returned NamedTempFile is dropped, which deletes it.
    tmp.persist(path).map_err(|e| e.error)?;
    sync_dir(&dir)
}

/// fsyncs a directory (its entries: the rename). Not possible on every
/// platform; where a directory cannot be opened for it, the rename is still
/// atomic, only not yet durable.
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::fs::File::open(dir)?.sync_all()
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        Ok(())
    }
}

/// Writes `bytes` to `path` atomically unless the file already holds exactly
/// these bytes (so unchanged pictures keep their timestamps and watchers of the
/// output folder are not woken). Returns whether it wrote.
pub fn write_if_changed(path: &Path, bytes: &[u8]) -> std::io::Result<bool> {
    // The size first: most changed files change size, and reading a large
    // PNG back only to find that out costs milliseconds per rebuild. Only a
    // regular file is read back (a FIFO there would block; the pipeline
    // refuses such outputs before this point anyway).
    let same_size = std::fs::symlink_metadata(path)
        .is_ok_and(|m| m.file_type().is_file() && m.len() == bytes.len() as u64);
    if same_size && std::fs::read(path).is_ok_and(|old| old == bytes) {
        return Ok(false);
    }
    write_atomic(path, bytes)?;
    Ok(true)
}

/// Whether `file` (a name in `dir`) is a temp file of ours for the output
/// `output_name`, and if so the id of the process that made it.
fn temp_owner(file: &str, output_name: &str) -> Option<u32> {
    let rest = file
        .strip_prefix('.')?
        .strip_prefix(output_name)?
        .strip_prefix('.')?
        .strip_suffix(TEMP_SUFFIX)?;
    // `PID` (the old naming) or `PID.RANDOM` (tempfile's random part).
    let (pid, random) = match rest.split_once('.') {
        Some((pid, random)) => (pid, Some(random)),
        None => (rest, None),
    };
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    if random.is_some_and(|r| r.is_empty() || r.contains('.')) {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` may still be running (and so may still be writing
/// its temp file). On Linux `/proc` says; elsewhere a temp file counts as
/// abandoned only when it is over an hour old.
fn may_be_running(pid: u32, modified: Option<std::time::SystemTime>) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        return proc.join(pid.to_string()).exists();
    }
    let age = modified.and_then(|m| m.elapsed().ok());
    age.is_none_or(|a| a <= std::time::Duration::from_secs(3600))
}

/// Removes the temp files that runs killed mid-write (`kill -9`, a power
/// cut) left beside `outputs`: only names of our own pattern for those
/// outputs (`.NAME.PID[.RANDOM].tmp`), only when process PID is gone. A
/// symlink of that name is removed itself, never followed. Returns the files
/// removed; one that cannot be removed is skipped (the next run tries again).
pub fn remove_stale_temps(outputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut by_dir: std::collections::BTreeMap<PathBuf, Vec<String>> = Default::default();
    for out in outputs {
        by_dir.entry(dir_of(out)).or_default().push(name_of(out));
    }
    let mut removed = Vec::new();
    for (dir, names) in by_dir {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let file = entry.file_name();
            let Some(file) = file.to_str() else { continue };
            let Some(pid) = names.iter().find_map(|n| temp_owner(file, n)) else {
                continue;
            };
            let meta = entry.metadata().ok();
            if meta.as_ref().is_some_and(|m| m.is_dir()) {
                continue;
            }
            if may_be_running(pid, meta.and_then(|m| m.modified().ok())) {
                continue;
            }
            let path = entry.path();
            if std::fs::remove_file(&path).is_ok() {
                removed.push(path);
            }
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names_are_recognised_only_for_their_output() {
        assert_eq!(temp_owner(".a.svg.123.tmp", "a.svg"), Some(123));
        assert_eq!(temp_owner(".a.svg.123.Xy9kQz.tmp", "a.svg"), Some(123));
        for other in [
            "a.svg",
            ".a.svg.tmp",
            ".a.svg..tmp",
            ".a.svg.12x.tmp",
            ".a.svg.123.Xy.z.tmp",
            ".a.svg.123.tmp.bak",
            ".b.svg.123.tmp",
            ".a.svg.123.",
        ] {
            assert_eq!(temp_owner(other, "a.svg"), None, "{other}");
        }
        // A name that only starts like another output's is not that output's.
        assert_eq!(temp_owner(".a.svg.png.1.tmp", "a.svg"), None);
    }
}
