//! Where `init` may write its config (`-o`): never over one of its own input
//! tables (by path, through a symbolic link, or a hard link to the same
//! file), never into a FIFO, device or folder (none is ever opened, so nothing
//! blocks), never through a dangling symbolic link; an existing config only
//! with `--force`. The config is then written atomically (temp file and
//! rename, as every output is), so even a path swapped after the checks is
//! replaced, not written through.

use std::path::{Path, PathBuf};

use super::super::UsageError;
use crate::workspace;

/// True when `meta` (of the output) and the file at `input` are one file:
/// the same device and inode on Unix (hard links included), else the same
/// resolved path.
fn same_file(meta: &std::fs::Metadata, output: &Path, input: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let _ = output;
        std::fs::metadata(input).is_ok_and(|m| m.dev() == meta.dev() && m.ino() == meta.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        workspace::resolve(output) == workspace::resolve(input)
    }
}

/// Refuses `output` when it names one of `inputs`, something other than a
/// regular file, a dangling link, or (without `force`) an existing file.
/// Reads only metadata: nothing at `output` is opened.
pub(super) fn check(output: &Path, inputs: &[PathBuf], force: bool) -> Result<(), UsageError> {
    let shown = output.display();
    let link = match std::fs::symlink_metadata(output) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(UsageError(format!("{shown}: cannot check it: {e}"))),
    };
    let meta = if link.file_type().is_symlink() {
        std::fs::metadata(output).map_err(|_| {
            let target = std::fs::read_link(output)
                .map(|t| t.display().to_string())
                .unwrap_or_else(|_| "?".to_owned());
            UsageError(format!(
                "{shown}: a symbolic link to {target}, which does not exist; init writes no \
                 config through a dangling link (remove the link or pick another -o)"
            ))
        })?
    } else {
        link
    };
    if let Some(kind) = workspace::special_kind(meta.file_type()) {
        return Err(UsageError(format!(
            "{shown}: not a regular file ({kind}); the config must be a regular file (pick \
             another -o)"
        )));
    }
    if let Some(input) = inputs.iter().find(|i| same_file(&meta, output, i)) {
        return Err(UsageError(format!(
            "{shown}: is the input table {} (the same file); init never writes over its \
             inputs (pick another -o)",
            input.display()
        )));
    }
    if !force {
        return Err(UsageError(format!(
            "{shown}: exists; give --force to replace it"
        )));
    }
    Ok(())
}

/// Writes the config atomically.
pub(super) fn write(output: &Path, text: &str) -> anyhow::Result<()> {
    crate::store::write_atomic(output, text.as_bytes())
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", output.display()))
}
