//! Atomic outputs: an interrupted run never leaves a half-written result that
//! looks complete.
//!
//! Directories are built in a hidden staging folder beside the target and
//! renamed into place at the end; single files are written to a temporary
//! sibling and renamed.
use crate::error::{io_err, LabError, Result};
use std::fs;
use std::path::{Path, PathBuf};

/// Refuse a non-empty existing `target` unless `force`: the check
/// [`StagedDir::new`] makes, available before a long run (a collection on
/// the real rig) starts rather than after it.
pub fn check_output_dir(target: &Path, force: bool) -> Result<()> {
    if dir_has_entries(target) && !force {
        return Err(LabError::OutputExists {
            path: target.to_path_buf(),
        });
    }
    Ok(())
}

/// A directory being written; becomes `target` only on [`StagedDir::commit`].
pub struct StagedDir {
    staging: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl StagedDir {
    /// Start writing `target`. Refuses a non-empty existing target unless
    /// `force`, in which case the old one is replaced only at commit time.
    pub fn new(target: &Path, force: bool) -> Result<Self> {
        check_output_dir(target, force)?;
        let parent = parent_of(target);
        fs::create_dir_all(&parent).map_err(io_err(&parent))?;
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(io_err(&staging))?;
        }
        fs::create_dir_all(&staging).map_err(io_err(&staging))?;
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            committed: false,
        })
    }

    /// Where to write files now.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Move the finished directory into place.
    pub fn commit(mut self) -> Result<PathBuf> {
        if self.target.exists() {
            let old = self.staging.with_extension("old");
            fs::rename(&self.target, &old).map_err(io_err(&self.target))?;
            fs::rename(&self.staging, &self.target).map_err(io_err(&self.target))?;
            fs::remove_dir_all(&old).map_err(io_err(&old))?;
        } else {
            fs::rename(&self.staging, &self.target).map_err(io_err(&self.target))?;
        }
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// Write `bytes` to `path` atomically (temporary sibling, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let parent = parent_of(path);
    fs::create_dir_all(&parent).map_err(io_err(&parent))?;
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    fs::write(&tmp, bytes).map_err(io_err(&tmp))?;
    fs::rename(&tmp, path).map_err(io_err(path))
}

/// Read a whole text file, naming it on error.
pub fn read_text(path: &Path) -> Result<String> {
    fs::read_to_string(path).map_err(io_err(path))
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn dir_has_entries(path: &Path) -> bool {
    fs::read_dir(path)
        .map(|mut d| d.next().is_some())
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncommitted_stage_leaves_nothing() {
        let root = std::env::temp_dir().join(format!("tactrace-fsutil-{}", std::process::id()));
        let target = root.join("ds");
        {
            let stage = StagedDir::new(&target, false).unwrap();
            fs::write(stage.path().join("a.txt"), "x").unwrap();
        }
        assert!(!target.exists());
        let stage = StagedDir::new(&target, false).unwrap();
        fs::write(stage.path().join("a.txt"), "x").unwrap();
        stage.commit().unwrap();
        assert!(target.join("a.txt").exists());
        assert!(matches!(
            StagedDir::new(&target, false),
            Err(LabError::OutputExists { .. })
        ));
        fs::remove_dir_all(&root).unwrap();
    }
}
