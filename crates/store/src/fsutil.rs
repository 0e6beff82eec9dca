//! Atomic outputs: an interrupted run never leaves a half-written result that
//! looks complete.
//!
//! Directories are built in a staging folder beside the target and renamed
//! into place at the end; single files are written to a uniquely named
//! temporary sibling, synced to disk and renamed.
use crate::error::{read_err, write_err, Result, StoreError};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Refuse a non-empty existing `target` unless `force`: the check
/// [`StagedDir::new`] makes, available before a long run (a collection on
/// the real rig) starts rather than after it.
pub fn check_output_dir(target: &Path, force: bool) -> Result<()> {
    if target.exists() && !target.is_dir() {
        return Err(StoreError::Format {
            path: target.to_path_buf(),
            reason: "exists and is not a folder".into(),
        });
    }
    if dir_has_entries(target) && !force {
        return Err(StoreError::OutputExists {
            path: target.to_path_buf(),
        });
    }
    Ok(())
}

/// A directory being written; becomes `target` only on [`StagedDir::commit`].
pub struct StagedDir {
    staging: PathBuf,
    target: PathBuf,
    /// Keep the staging folder when dropped uncommitted (a run's partial
    /// results), rather than removing it.
    keep_partial: bool,
    committed: bool,
}

impl StagedDir {
    /// Start writing `target` in a hidden, uniquely named staging folder
    /// that is removed if the write is abandoned. Refuses a non-empty
    /// existing target unless `force`, in which case the old one is
    /// replaced only at commit time.
    pub fn new(target: &Path, force: bool) -> Result<Self> {
        check_output_dir(target, force)?;
        let parent = parent_of(target);
        fs::create_dir_all(&parent).map_err(write_err(&parent))?;
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{}.partial-", file_name(target)))
            .tempdir_in(&parent)
            .map_err(write_err(&parent))?
            .keep();
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            keep_partial: false,
            committed: false,
        })
    }

    /// Start writing `target` in `<target>.partial`, which stays (with what
    /// was written so far) if the run stops before [`StagedDir::commit`]:
    /// for runs whose partial results are worth keeping (a follow run's
    /// trajectory). A leftover `<target>.partial` (a run that stopped
    /// early or was killed) is clearly partial and is replaced, with or
    /// without `force`: re-running the same command after a crash must
    /// work. Two runs into the same `target` at once are not supported.
    pub fn new_keeping_partial(target: &Path, force: bool) -> Result<Self> {
        check_output_dir(target, force)?;
        let staging = partial_path(target);
        check_output_dir(&staging, true)?;
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(write_err(&staging))?;
        }
        fs::create_dir_all(&staging).map_err(write_err(&staging))?;
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            keep_partial: true,
            committed: false,
        })
    }

    /// Where to write files now.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Where the finished directory will be.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Move the finished directory into place.
    pub fn commit(mut self) -> Result<PathBuf> {
        if self.target.exists() {
            let old = parent_of(&self.target).join(format!(
                ".{}.old-{}",
                file_name(&self.target),
                std::process::id()
            ));
            fs::rename(&self.target, &old).map_err(write_err(&self.target))?;
            fs::rename(&self.staging, &self.target).map_err(write_err(&self.target))?;
            fs::remove_dir_all(&old).map_err(write_err(&old))?;
        } else {
            fs::rename(&self.staging, &self.target).map_err(write_err(&self.target))?;
        }
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed && !self.keep_partial {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// `<target>.partial`: where a run keeps what it did when it stops early.
pub fn partial_path(target: &Path) -> PathBuf {
    parent_of(target).join(format!("{}.partial", file_name(target)))
}

/// Write `bytes` to `path` atomically: a uniquely named temporary sibling,
/// synced to disk, then renamed over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let parent = parent_of(path);
    fs::create_dir_all(&parent).map_err(write_err(&parent))?;
    let prefix = format!(".{}.", file_name(path));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix);
    // As any file the user writes (0666 less the umask), not tempfile's
    // owner-only 0600: the output is for the lab to read.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(&parent).map_err(write_err(path))?;
    tmp.write_all(bytes).map_err(write_err(path))?;
    tmp.as_file().sync_all().map_err(write_err(path))?;
    tmp.persist(path).map_err(|e| StoreError::Write {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
}

/// Read a whole text file, naming it on error.
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = fs::read(path).map_err(read_err(path))?;
    String::from_utf8(bytes).map_err(|_| StoreError::Format {
        path: path.to_path_buf(),
        reason: "not UTF-8 text".into(),
    })
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into())
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
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("ds");
        {
            let stage = StagedDir::new(&target, false).unwrap();
            fs::write(stage.path().join("a.txt"), "x").unwrap();
        }
        assert!(!target.exists());
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 0);
        let stage = StagedDir::new(&target, false).unwrap();
        fs::write(stage.path().join("a.txt"), "x").unwrap();
        stage.commit().unwrap();
        assert!(target.join("a.txt").exists());
        assert!(matches!(
            StagedDir::new(&target, false),
            Err(StoreError::OutputExists { .. })
        ));
    }

    #[test]
    fn a_partial_run_is_kept_under_a_partial_name() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("run");
        {
            let stage = StagedDir::new_keeping_partial(&target, false).unwrap();
            fs::write(stage.path().join("trajectory.csv"), "step\n").unwrap();
        }
        assert!(!target.exists());
        assert!(partial_path(&target).join("trajectory.csv").exists());
        // A stale partial does not block the next run; it is replaced.
        let stage = StagedDir::new_keeping_partial(&target, false).unwrap();
        assert!(!stage.path().join("trajectory.csv").exists());
        fs::write(stage.path().join("metrics.json"), "{}").unwrap();
        stage.commit().unwrap();
        assert!(target.is_dir() && !partial_path(&target).exists());
        // A complete run is refused without force.
        assert!(StagedDir::new_keeping_partial(&target, false).is_err());
    }

    #[test]
    fn write_atomic_replaces_and_leaves_no_temporary() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("m.json");
        write_atomic(&p, b"1").unwrap();
        write_atomic(&p, b"2").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"2");
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
    }

    /// Files written atomically were left owner-only (0600, tempfile's
    /// default) where any other output of the same run was group- and
    /// world-readable under the usual umask.
    #[cfg(unix)]
    #[test]
    fn write_atomic_gives_the_permissions_of_a_plain_file() {
        use std::os::unix::fs::PermissionsExt;
        let root = tempfile::tempdir().unwrap();
        let (atomic, plain) = (root.path().join("a"), root.path().join("p"));
        write_atomic(&atomic, b"1").unwrap();
        fs::write(&plain, b"1").unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&atomic), mode(&plain));
    }
}
