//! The one reader of files: input data, previous layouts, the layouts stored
//! beside the outputs and the config's text. Attaches the path to every
//! error, so messages read `file: line L, column C: problem`. Refuses what
//! is not a regular file (a FIFO would block the read forever, a device
//! never ends) and files over the size limit, both before reading, and
//! answers what a path really names ([`resolve`], [`special_kind`]) for the
//! pipeline's output checks. Parsing is the formats' (see
//! [`crate::pipeline::parse_inputs`]); writing is [`crate::store`]'s.

use std::io::Read;
use std::path::{Component, Path, PathBuf};

use nptreemap_formats::{Limit, LimitError, Limits};

use nptreemap_formats::FormatError;

/// An input file could not be read, or its content is not valid.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The path names something that is not a regular file.
    #[error("{path}: not a regular file ({kind}); inputs must be regular files")]
    NotRegular {
        /// The path.
        path: PathBuf,
        /// What it is instead ("a FIFO", "a directory", ...).
        kind: &'static str,
    },
    /// The file is larger than `limits.max_file_mb`.
    #[error("{path}: {source}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit and its key.
        source: LimitError,
    },
    /// The file was read but its content is not valid.
    #[error("{path}: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong and where (boxed: it is large and errors are rare).
        source: Box<FormatError>,
    },
    /// The file is not UTF-8 text where text is expected.
    #[error("{path}: not UTF-8 text: {source}")]
    Text {
        /// The file.
        path: PathBuf,
        /// Where the first bad byte is.
        source: std::string::FromUtf8Error,
    },
}

impl FileError {
    /// The file it is about.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Read { path, .. }
            | FileError::NotRegular { path, .. }
            | FileError::TooLarge { path, .. }
            | FileError::Parse { path, .. }
            | FileError::Text { path, .. } => path,
        }
    }
}

/// What a file type is when it is not a regular file, in words; `None` for a
/// regular file.
pub fn special_kind(file_type: std::fs::FileType) -> Option<&'static str> {
    if file_type.is_file() {
        return None;
    }
    if file_type.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return Some("a FIFO");
        }
        if file_type.is_char_device() {
            return Some("a character device");
        }
        if file_type.is_block_device() {
            return Some("a block device");
        }
        if file_type.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a file")
}

/// Opens `path` for reading without blocking: a FIFO opened for reading
/// waits for a writer, unless opened non-blocking. (The caller checks the
/// file type of the opened handle; reads of regular files ignore the flag.)
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    options.open(path)
}

/// Opens a regular file of at most `max` bytes (and says which limit it is)
/// without blocking, returning the handle and the file's length.
fn open_guarded(
    path: &Path,
    max: Option<(u64, &Limits)>,
) -> Result<(std::fs::File, u64), FileError> {
    let read_error = |source| FileError::Read {
        path: path.to_path_buf(),
        source,
    };
    let check = |meta: &std::fs::Metadata| -> Result<(), FileError> {
        if let Some(kind) = special_kind(meta.file_type()) {
            return Err(FileError::NotRegular {
                path: path.to_path_buf(),
                kind,
            });
        }
        if let Some((max, limits)) = max {
            if meta.len() > max {
                return Err(too_large(path, meta.len(), limits));
            }
        }
        Ok(())
    };
    // The type first, from the path (which never blocks), then again from the
    // opened handle, in case the path was swapped in between.
    check(&std::fs::metadata(path).map_err(read_error)?)?;
    let file = open_nonblocking(path).map_err(read_error)?;
    let meta = file.metadata().map_err(read_error)?;
    check(&meta)?;
    Ok((file, meta.len()))
}

/// Reads a regular file of at most `max_bytes` (and says which limit it is).
fn read_guarded(path: &Path, max: Option<(u64, &Limits)>) -> Result<Vec<u8>, FileError> {
    let (file, len) = open_guarded(path, max)?;
    let cap = max.map_or(u64::MAX, |(m, _)| m);
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    file.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
    if let Some((max, limits)) = max {
        // The file grew while it was read.
        if bytes.len() as u64 > max {
            return Err(too_large(path, bytes.len() as u64, limits));
        }
    }
    Ok(bytes)
}

/// Opens an input within `limits.max_file_mb` for a reader that reads only
/// part of it or streams it (`init`'s sampling): the same checks as
/// [`read_input`] (a regular file, not too large, opened without blocking),
/// returning the handle and the file's length.
pub fn open_input(path: &Path, limits: &Limits) -> Result<(std::fs::File, u64), FileError> {
    open_guarded(path, Some((limits.max_file_bytes(), limits)))
}

fn too_large(path: &Path, size: u64, limits: &Limits) -> FileError {
    let mib = size as f64 / f64::from(1u32 << 20);
    FileError::TooLarge {
        path: path.to_path_buf(),
        source: limits.exceeded(Limit::FileSize, format_args!("a file of {mib:.1} MiB")),
    }
}

/// Reads an input file's bytes within `limits.max_file_mb`, naming it in the error.
pub fn read_input(path: &Path, limits: &Limits) -> Result<Vec<u8>, FileError> {
    read_guarded(path, Some((limits.max_file_bytes(), limits)))
}

/// Reads a file's bytes, naming it in the error (a regular file only; no size limit).
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FileError> {
    read_guarded(path, None)
}

/// Reads a UTF-8 text file, naming it in the error.
pub fn read_text(path: &Path) -> Result<String, FileError> {
    utf8(path, read_bytes(path)?)
}

/// Reads a UTF-8 text file within `limits.max_file_mb`, naming it in the error.
pub fn read_text_within(path: &Path, limits: &Limits) -> Result<String, FileError> {
    utf8(path, read_input(path, limits)?)
}

fn utf8(path: &Path, bytes: Vec<u8>) -> Result<String, FileError> {
    String::from_utf8(bytes).map_err(|source| FileError::Text {
        path: path.to_path_buf(),
        source,
    })
}

/// The text of a stored layout (see [`crate::state::layout_path`]):
/// `Ok(None)` when there is none (a cold start), the error when one is there
/// but cannot be read (the caller warns: the picture will jump).
pub fn read_state(path: &Path, limits: &Limits) -> Result<Option<String>, FileError> {
    match read_text_within(path, limits) {
        Ok(text) => Ok(Some(text)),
        Err(FileError::Read { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// The file `path` names: absolute, with `.`, `..` and symbolic links
/// resolved as far as the path exists (the rest, which has no links yet, is
/// taken as written). Two paths naming the same file resolve to the same path.
pub fn resolve(path: &Path) -> PathBuf {
    let Ok(absolute) = std::path::absolute(path) else {
        return path.to_path_buf();
    };
    let mut resolved = PathBuf::new();
    // Whether `resolved` exists (and is therefore canonical).
    let mut exists = true;
    for component in absolute.components() {
        match component {
            Component::Prefix(_) | Component::RootDir => resolved.push(component),
            Component::CurDir => {}
            Component::ParentDir => {
                // `resolved` is canonical, or canonical followed by names that
                // do not exist (so are no links): its parent is the real
                // parent, and canonical again once back inside what exists.
                resolved.pop();
                exists = exists || resolved.exists();
            }
            Component::Normal(name) => {
                let next = resolved.join(name);
                if exists {
                    match std::fs::canonicalize(&next) {
                        Ok(real) => {
                            resolved = real;
                            continue;
                        }
                        Err(_) => exists = false,
                    }
                }
                resolved = next;
            }
        }
    }
    resolved
}

/// What is at `path` when it exists and is not a regular file (following
/// links): an output there must not be replaced.
pub fn special_at(path: &Path) -> Option<&'static str> {
    std::fs::metadata(path)
        .ok()
        .and_then(|m| special_kind(m.file_type()))
}

/// Whether `path` is a regular file (following links).
pub fn is_file(path: &Path) -> bool {
    path.is_file()
}

/// Whether something is at `path` (following links).
pub fn exists(path: &Path) -> bool {
    path.exists()
}

/// Where the symbolic link at `path` points, if it is one.
pub fn link_target(path: &Path) -> Option<PathBuf> {
    std::fs::read_link(path).ok()
}

/// `path` with every link and `..` resolved, if it exists.
pub fn canonical(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok()
}

/// When the file at `path` was last modified, if that can be told.
pub fn modified(path: &Path) -> Option<std::time::SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// A folder's identity (device and inode on Unix; elsewhere all folders
/// look alike), to tell a folder made again under the same name from the
/// one that was there; `None` when `dir` is not a folder.
pub fn dir_identity(dir: &Path) -> Option<(u64, u64)> {
    let meta = std::fs::metadata(dir).ok().filter(std::fs::Metadata::is_dir)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((meta.dev(), meta.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        Some((0, 0))
    }
}

/// A file [`open_capped`] opened.
pub type Opened = std::fs::File;

/// An output file opened for serving, with its length capped at `cap`
/// bytes (what [`read_opened`] will read of it).
pub fn open_capped(path: &Path, cap: u64) -> Option<(Opened, u64)> {
    let f = std::fs::File::open(path).ok()?;
    let len = f.metadata().ok()?.len().min(cap);
    Some((f, len))
}

/// At most `cap` bytes of a file [`open_capped`] opened.
pub fn read_opened(file: Opened, cap: u64) -> Option<Vec<u8>> {
    let mut bytes = Vec::new();
    file.take(cap).read_to_end(&mut bytes).ok()?;
    Some(bytes)
}

/// What is at a path a writer is about to replace, looked at without
/// opening it (nothing there blocks, a FIFO included).
#[derive(Debug)]
pub enum Target {
    /// Nothing.
    Missing,
    /// A symbolic link to nothing, with where it points (`?` if unreadable).
    Dangling(PathBuf),
    /// Something (links followed).
    Present(std::fs::Metadata),
}

/// What is at `path` (see [`Target`]).
pub fn target(path: &Path) -> std::io::Result<Target> {
    let link = match std::fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Target::Missing),
        Err(e) => return Err(e),
    };
    if !link.file_type().is_symlink() {
        return Ok(Target::Present(link));
    }
    match std::fs::metadata(path) {
        Ok(meta) => Ok(Target::Present(meta)),
        Err(_) => Ok(Target::Dangling(
            std::fs::read_link(path).unwrap_or_else(|_| PathBuf::from("?")),
        )),
    }
}

/// True when `meta` (of the file at `path`) and the file at `other` are one
/// file: the same device and inode on Unix (hard links included), else the
/// same resolved path.
pub fn same_file(meta: &std::fs::Metadata, path: &Path, other: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let _ = path;
        std::fs::metadata(other).is_ok_and(|m| m.dev() == meta.dev() && m.ino() == meta.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        resolve(path) == resolve(other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_removes_dots_and_follows_links() {
        let dir = std::env::temp_dir().join(format!("nptreemap-resolve-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("a")).expect("dir");
        std::fs::write(dir.join("a/f.txt"), "x").expect("file");
        #[cfg(unix)]
        std::os::unix::fs::symlink(dir.join("a"), dir.join("link")).expect("link");
        let real = resolve(&dir.join("a/f.txt"));
        assert_eq!(resolve(&dir.join("a/./../a/f.txt")), real);
        #[cfg(unix)]
        assert_eq!(resolve(&dir.join("link/f.txt")), real);
        // Paths that do not exist yet resolve through what does.
        assert_eq!(resolve(&dir.join("new/../a/f.txt")), real);
        assert_eq!(
            resolve(&dir.join("a/new/x.svg")),
            resolve(&dir.join("a")).join("new/x.svg")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
