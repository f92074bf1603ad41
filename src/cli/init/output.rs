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

/// Refuses `output` when it names one of `inputs`, something other than a
/// regular file, a dangling link, or (without `force`) an existing file.
/// Reads only metadata: nothing at `output` is opened.
pub(super) fn check(output: &Path, inputs: &[PathBuf], force: bool) -> Result<(), UsageError> {
    let shown = output.display();
    let meta = match workspace::target(output) {
        Ok(workspace::Target::Missing) => return Ok(()),
        Ok(workspace::Target::Present(meta)) => meta,
        Ok(workspace::Target::Dangling(target)) => {
            return Err(UsageError(format!(
                "{shown}: a symbolic link to {}, which does not exist; init writes no \
                 config through a dangling link (remove the link or pick another -o)",
                target.display()
            )))
        }
        Err(e) => return Err(UsageError(format!("{shown}: cannot check it: {e}"))),
    };
    if let Some(kind) = workspace::special_kind(meta.file_type()) {
        return Err(UsageError(format!(
            "{shown}: not a regular file ({kind}); the config must be a regular file (pick \
             another -o)"
        )));
    }
    if let Some(input) = inputs
        .iter()
        .find(|i| workspace::same_file(&meta, output, i))
    {
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
