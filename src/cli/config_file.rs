//! Which config file a command reads: the one named (`CONFIG` or `--config`),
//! else the first `nptreemap.yaml` found from the working directory upward, as
//! cargo finds `Cargo.toml`.

use std::path::{Path, PathBuf};

use clap::Args;

use super::UsageError;

/// The config file name searched for.
pub(crate) const CONFIG_NAME: &str = "nptreemap.yaml";

/// The config a command reads.
#[derive(Debug, Clone, Args)]
pub(crate) struct ConfigArg {
    /// The config file [default: the first nptreemap.yaml in the working
    /// directory or a parent of it].
    #[arg(value_name = "CONFIG", conflicts_with = "config")]
    positional: Option<PathBuf>,
    /// The config file (the same as CONFIG).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

impl ConfigArg {
    /// The config file: the one named, else the nearest `nptreemap.yaml` from
    /// the working directory upward.
    pub(crate) fn path(&self) -> Result<PathBuf, UsageError> {
        if let Some(p) = self.positional.as_ref().or(self.config.as_ref()) {
            return Ok(p.clone());
        }
        let cwd = std::env::current_dir()
            .map_err(|e| UsageError(format!("cannot read the working directory: {e}")))?;
        // Found in the working directory, it is named as `nptreemap.yaml`, so
        // messages stay short.
        let found =
            find_upward(&cwd).map(|p| p.strip_prefix(&cwd).map(Path::to_path_buf).unwrap_or(p));
        found.ok_or_else(|| {
            UsageError(format!(
                "no {CONFIG_NAME} in {} or any folder above it; name one (nptreemap build FILE) \
                 or write one with `nptreemap init`",
                cwd.display()
            ))
        })
    }
}

/// The first `nptreemap.yaml` in `dir` or one of its ancestors.
pub(crate) fn find_upward(dir: &Path) -> Option<PathBuf> {
    dir.ancestors()
        .map(|d| d.join(CONFIG_NAME))
        .find(|p| crate::workspace::is_file(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_config_upward_wins() {
        let root = std::env::temp_dir().join(format!("nptreemap-find-{}", std::process::id()));
        let deep = root.join("docs/a/b");
        std::fs::create_dir_all(&deep).expect("dirs");
        assert_eq!(find_upward(&deep).filter(|p| p.starts_with(&root)), None);
        std::fs::write(root.join(CONFIG_NAME), "").expect("write");
        assert_eq!(find_upward(&deep), Some(root.join(CONFIG_NAME)));
        std::fs::write(root.join("docs").join(CONFIG_NAME), "").expect("write");
        assert_eq!(
            find_upward(&deep),
            Some(root.join("docs").join(CONFIG_NAME))
        );
        std::fs::write(deep.join(CONFIG_NAME), "").expect("write");
        assert_eq!(find_upward(&deep), Some(deep.join(CONFIG_NAME)));
        std::fs::remove_dir_all(&root).expect("clean");
    }
}
