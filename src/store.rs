//! The one writer of files: every output (and every stored layout) goes to a
//! temporary file in its own directory and is renamed into place, so readers
//! never see a partly written file and a failed run leaves existing outputs
//! untouched. Owns the temp files' naming (short enough for any valid output
//! name), their safe creation (O_EXCL and a random name, through the
//! `tempfile` crate, so a link planted at a predictable name is never
//! followed), the refusal to rename over what is not a regular file, fsync of
//! file and directory (at once, or for the watch daemon after the rebuild is
//! reported: [`sync_later`]), and the removal of temp files a killed run
//! left behind. Reading is [`crate::workspace`]'s.

use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Every temp file's name ends so: `.STEM.PID.RANDOM.tmp` (and, from before
/// the random part, `.STEM.PID.tmp`), where STEM is the output's name, or
/// for a long name its start and a hash ([`temp_stem`]).
const TEMP_SUFFIX: &str = ".tmp";

/// The longest output name a temp name repeats whole. A name is at most 255
/// bytes; the temp name adds up to 22 (`.`, `.PID`, `.RANDOM`, `.tmp`), so a
/// longer output name is cut to this many bytes and a hash (17 more).
const STEM_KEEP: usize = 200;

/// Held while a set of outputs is being written ([`writing`]), so that a
/// forced exit (the daemon's answer to SIGTERM during a long rebuild) can wait
/// for the set to be complete instead of leaving a dataset's SVG new and its
/// PNG old.
static WRITING: Mutex<()> = Mutex::new(());

/// Whether writes leave their fsyncs to [`sync_pending`] ([`sync_later`]).
static SYNC_LATER: AtomicBool = AtomicBool::new(false);

/// The files renamed into place since the last [`sync_pending`], when the
/// syncs wait. Drained by every rebuild's sync, so it holds one rebuild's
/// files at most.
static UNSYNCED: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

/// From now on, this process's writes are renamed into place at once and
/// made durable by the next [`sync_pending`]. For the watch daemon, whose
/// latency is to the files being in place: at 6,000 leaves a rebuild's
/// fsyncs and the renames they slow took 50 of its commit's 72 ms, one
/// output after another. A file is as atomic either way (readers see the
/// old bytes or the new); what waits is only its surviving a power cut,
/// which costs nothing a reader trusts: every file a build reads back is
/// checked first (outputs against the manifest's digests, the stored
/// layout and the caches by their own checks), and one that a crash left
/// short is made again.
pub fn sync_later() {
    SYNC_LATER.store(true, Ordering::Relaxed);
}

/// fsyncs every file renamed into place since the last call, then their
/// folders (the renames); the first error, after trying them all. A file
/// gone since (replaced or removed) needs nothing.
pub fn sync_pending() -> std::io::Result<()> {
    let files = std::mem::take(&mut *UNSYNCED.lock().unwrap_or_else(|e| e.into_inner()));
    let mut first = None;
    let mut note = |result: std::io::Result<()>| match result {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            first.get_or_insert(e);
        }
        _ => {}
    };
    let dirs: BTreeSet<PathBuf> = files.iter().map(|f| dir_of(f)).collect();
    for file in &files {
        note(std::fs::File::open(file).and_then(|f| f.sync_all()));
    }
    for dir in &dirs {
        note(sync_dir(dir));
    }
    first.map_or(Ok(()), Err)
}

/// The write lock, held.
pub type Writing = MutexGuard<'static, ()>;

/// Takes the write lock (see `WRITING`): hold it while writing outputs that
/// belong together, or before exiting the process while writes may be going on.
pub fn writing() -> Writing {
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

/// The part of an output's temp names that names the output: the name
/// itself up to [`STEM_KEEP`] bytes (so a stray temp file says whose it
/// is), else its first bytes up to that many (at a character boundary), `~`
/// and a 64-bit FNV-1a hash of the whole name, so that the temp name stays
/// within the 255 bytes of a valid name (a 250-byte output name failed
/// with `File name too long`) and two long names sharing their start still
/// have different temp names.
fn temp_stem(name: &str) -> String {
    if name.len() <= STEM_KEEP {
        return name.to_string();
    }
    let mut cut = STEM_KEEP;
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{}~{hash:016x}", &name[..cut])
}

/// Refuses to replace what is at `path` when it is not a regular file (a
/// FIFO, a device or a link to one, a directory): the rename would put a
/// regular file in its place. `build` refuses such outputs before it starts
/// (`pipeline::check_outputs`); this catches one that appeared since, such
/// as an output replaced while `watch` runs.
fn refuse_special(path: &Path) -> std::io::Result<()> {
    let Some(kind) = std::fs::metadata(path)
        .ok()
        .and_then(|m| crate::workspace::special_kind(m.file_type()))
    else {
        return Ok(());
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::AlreadyExists,
        format!("it exists and is not a regular file ({kind}); refusing to replace it"),
    ))
}

/// Writes `bytes` to `path` atomically: a new temp file in the same directory
/// (created exclusively under a random name, never through an existing file
/// or link), written and fsynced, renamed over `path`, then the directory
/// fsynced so the rename survives a power cut (both fsyncs left to
/// [`sync_pending`] after [`sync_later`]). Creates the directory if it is
/// missing. On any failure the temp file is removed and `path` is untouched;
/// so is a `path` that holds something other than a regular file (see
/// `refuse_special`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    refuse_special(path)?;
    write_via_temp(path, bytes).map_err(without_temp_path)
}

/// The error without the temp file's name, which `tempfile` adds to errors
/// of its own calls (`No space left on device (os error 28) at path
/// "/out/.a.svg.123.XyZ.tmp"`): the caller names the output, and a name
/// that is random each time would make the same failure (a full disk,
/// retried) read as a new one.
fn without_temp_path(e: std::io::Error) -> std::io::Error {
    let text = e.to_string();
    match text.find(" at path ") {
        Some(cut) => std::io::Error::new(e.kind(), text[..cut].to_string()),
        None => e,
    }
}

fn write_via_temp(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = dir_of(path);
    std::fs::create_dir_all(&dir)?;
    let prefix = format!(".{}.{}.", temp_stem(&name_of(path)), std::process::id());
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
    tmp.as_file_mut().write_all(bytes)?;
    let later = SYNC_LATER.load(Ordering::Relaxed);
    if !later {
        tmp.as_file().sync_all()?;
    }
    // On failure the returned NamedTempFile is dropped, which deletes it.
    tmp.persist(path).map_err(|e| e.error)?;
    if later {
        let mut unsynced = UNSYNCED.lock().unwrap_or_else(|e| e.into_inner());
        unsynced.insert(path.to_path_buf());
        return Ok(());
    }
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
/// whose [`temp_stem`] is `stem`, and if so the id of the process that made it.
fn temp_owner(file: &str, stem: &str) -> Option<u32> {
    let rest = file
        .strip_prefix('.')?
        .strip_prefix(stem)?
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
/// outputs (`.STEM.PID[.RANDOM].tmp`), only when process PID is gone. A
/// symlink of that name is removed itself, never followed. Returns the files
/// removed; one that cannot be removed is skipped (the next run tries again).
pub fn remove_stale_temps(outputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut by_dir: std::collections::BTreeMap<PathBuf, Vec<String>> = Default::default();
    for out in outputs {
        by_dir
            .entry(dir_of(out))
            .or_default()
            .push(temp_stem(&name_of(out)));
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

    /// The watch daemon's writes: in place at once (the new bytes, no temp
    /// file left), fsynced by the next `sync_pending`, which forgets them;
    /// a file removed before its sync is no error. (Turns this test
    /// process's syncs to later: nothing else here depends on when.)
    #[test]
    fn writes_after_sync_later_are_in_place_at_once_and_synced_by_the_next_sync() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (a, b) = (dir.path().join("a.svg"), dir.path().join("sub/b.png"));
        sync_later();
        write_atomic(&a, b"old").expect("write");
        write_atomic(&a, b"new").expect("write again");
        write_atomic(&b, b"png").expect("write b");
        assert_eq!(std::fs::read(&a).expect("a"), b"new");
        assert_eq!(std::fs::read(&b).expect("b"), b"png");
        let names = |d: &Path| std::fs::read_dir(d).expect("dir").count();
        assert_eq!((names(dir.path()), names(&dir.path().join("sub"))), (2, 1));
        let waiting = |p: &Path| UNSYNCED.lock().expect("unsynced").contains(p);
        assert!(waiting(&a) && waiting(&b), "both wait for their sync");
        std::fs::remove_file(&b).expect("rm b");
        sync_pending().expect("synced; a file gone since is no error");
        assert!(!waiting(&a) && !waiting(&b), "synced once");
    }

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

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("nptreemap-store-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    }

    /// Issue 21 item 9: a temp name fits in a name's 255 bytes whatever the
    /// output's name, long names that share their start get different temp
    /// names, and the stale temp files of a long name are still recognised
    /// (a temp file of this naming, made by a process that is gone).
    #[test]
    fn long_output_names_have_short_temp_names() {
        let long = |c: char| format!("{}{c}.svg", "é".repeat(124));
        let (a, b) = (long('a'), long('b'));
        assert!(a.len() == 253 && b.len() == 253);
        let (sa, sb) = (temp_stem(&a), temp_stem(&b));
        assert_ne!(sa, sb);
        // The longest temp name: `.`, the stem, `.`, a 10-digit pid, `.`,
        // tempfile's 6 random characters, `.tmp`.
        assert!(1 + sa.len() + 1 + 10 + 1 + 6 + 4 <= 255, "{}", sa.len());
        assert_eq!(temp_stem("a.svg"), "a.svg");

        let dir = scratch("long");
        let out = dir.join(&a);
        write_atomic(&out, b"new").expect("a 253-byte name is written");
        assert_eq!(std::fs::read(&out).expect("read"), b"new");
        // What a killed run would have left (pid 4999999 belongs to no
        // process), and one of a live process (ours), and another output's.
        let stale = dir.join(format!(".{sa}.4999999.Ab12Cd.tmp"));
        let live = dir.join(format!(".{sa}.{}.Ab12Cd.tmp", std::process::id()));
        let other = dir.join(format!(".{sb}.4999999.Ab12Cd.tmp"));
        for f in [&stale, &live, &other] {
            std::fs::write(f, "x").expect("temp");
        }
        assert_eq!(remove_stale_temps(&[out]), vec![stale.clone()]);
        assert!(!stale.exists() && live.exists() && other.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A failed write names no temp file (whose random name would make the
    /// same failure, retried, read as a new one each time), but keeps the
    /// system's reason: here tempfile's own error for a folder that is gone.
    #[test]
    fn write_errors_do_not_name_the_temp_file() {
        let dir = scratch("gone");
        let _ = std::fs::remove_dir_all(&dir);
        let raw = tempfile::Builder::new()
            .prefix(".x.1.")
            .tempfile_in(&dir)
            .expect_err("no folder");
        assert!(raw.to_string().contains(".x.1."), "{raw}");
        let plain = without_temp_path(raw);
        assert_eq!(
            plain.to_string(),
            std::io::Error::from_raw_os_error(libc::ENOENT).to_string()
        );
        assert_eq!(plain.kind(), std::io::ErrorKind::NotFound);
        // What names no temp file is left as it is.
        assert_eq!(without_temp_path(std::io::Error::other("x")).to_string(), "x");
    }

    /// Issue 21 item 9: what is not a regular file (a FIFO, a link to a
    /// device, a directory) is never replaced by a write; a regular file,
    /// a link to one (the link is replaced, as ever) and nothing are written.
    #[cfg(unix)]
    #[test]
    fn special_files_are_not_replaced() {
        let dir = scratch("special");
        let fifo = dir.join("fifo.svg");
        let name = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).expect("path");
        // SAFETY: mkfifo(3) with a NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o644) }, 0, "mkfifo");
        std::os::unix::fs::symlink("/dev/null", dir.join("null.png")).expect("link");
        std::fs::create_dir_all(dir.join("dir.json")).expect("dir");
        for (file, kind) in [
            ("fifo.svg", "a FIFO"),
            ("null.png", "a character device"),
            ("dir.json", "a directory"),
        ] {
            let e = write_if_changed(&dir.join(file), b"x").expect_err(file);
            assert!(e.to_string().contains(kind), "{file}: {e}");
        }
        use std::os::unix::fs::FileTypeExt;
        let meta = |f: &str| std::fs::symlink_metadata(dir.join(f)).expect(f).file_type();
        assert!(meta("fifo.svg").is_fifo());
        assert!(meta("null.png").is_symlink());
        assert!(meta("dir.json").is_dir());
        std::fs::write(dir.join("real.svg"), "old").expect("real");
        std::os::unix::fs::symlink(dir.join("real.svg"), dir.join("link.svg")).expect("link");
        for file in ["plain.svg", "link.svg"] {
            assert!(write_if_changed(&dir.join(file), b"new").expect(file));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
