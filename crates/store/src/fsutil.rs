//! Atomic outputs: an interrupted run never leaves a half-written result that
//! looks complete, and one output has one writer.
//!
//! Directories are built in a staging folder beside the target and renamed
//! into place at the end; single files are written to a uniquely named
//! temporary sibling, synced to disk and renamed. A folder being written is
//! locked for the run's whole life ([`crate::lock`]), and its commit never
//! replaces an existing output without `force`.
use crate::error::{write_err, Result, StoreError};
use crate::lock::OutputLock;
use std::fs;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

/// Lock the output folder `target` ([`OutputLock`]) and refuse it when it
/// exists and is not empty, unless `force`: the check [`StagedDir::new`]
/// makes, available before a long run (a collection on the real rig)
/// starts rather than after it. Keep the lock for the run's whole life.
pub fn check_output_dir(target: &Path, force: bool) -> Result<OutputLock> {
    let lock = OutputLock::acquire(target)?;
    check_existing(target, force)?;
    Ok(lock)
}

/// Refuse a non-empty existing `target` unless `force`, and anything but a
/// folder.
fn check_existing(target: &Path, force: bool) -> Result<()> {
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
/// It holds the target's lock ([`OutputLock`]) until dropped.
pub struct StagedDir {
    staging: PathBuf,
    target: PathBuf,
    /// Keep the staging folder when dropped uncommitted (a run's partial
    /// results), rather than removing it.
    keep_partial: bool,
    /// Replace an existing target at commit time.
    force: bool,
    committed: bool,
    /// The target's lock (and, for `<target>.partial`, that folder's):
    /// dropped after the staging folder is cleaned up.
    _locks: Vec<OutputLock>,
}

impl StagedDir {
    /// Start writing `target` in a hidden, uniquely named staging folder
    /// that is removed if the write is abandoned. Refuses a target another
    /// run is writing, and a non-empty existing target unless `force`, in
    /// which case the old one is replaced only at commit time.
    pub fn new(target: &Path, force: bool) -> Result<Self> {
        let lock = check_output_dir(target, force)?;
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
            force,
            committed: false,
            _locks: vec![lock],
        })
    }

    /// Start writing `target` in `<target>.partial`, which stays (with what
    /// was written so far) if the run stops before [`StagedDir::commit`]:
    /// for runs whose partial results are worth keeping (a follow run's
    /// trajectory). A leftover `<target>.partial` (a run that stopped
    /// early or was killed) is clearly partial and is replaced, with or
    /// without `force`: re-running the same command after a crash must
    /// work. A `<target>.partial` that a live run is writing is never
    /// touched: that run holds `target`'s lock, and this one is refused.
    pub fn new_keeping_partial(target: &Path, force: bool) -> Result<Self> {
        let lock = check_output_dir(target, force)?;
        let staging = partial_path(target);
        // A run writing `<target>.partial` as its own output.
        let partial_lock = check_output_dir(&staging, true)?;
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(write_err(&staging))?;
        }
        fs::create_dir_all(&staging).map_err(write_err(&staging))?;
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            keep_partial: true,
            force,
            committed: false,
            _locks: vec![lock, partial_lock],
        })
    }

    /// As [`StagedDir::new_keeping_partial`], but a leftover
    /// `<target>.partial` is kept with its files (created when absent): a
    /// run resuming what a stopped run wrote there (a search's trials).
    pub fn resume_partial(target: &Path, force: bool) -> Result<Self> {
        let lock = check_output_dir(target, force)?;
        let staging = partial_path(target);
        let partial_lock = check_output_dir(&staging, true)?;
        fs::create_dir_all(&staging).map_err(write_err(&staging))?;
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            keep_partial: true,
            force,
            committed: false,
            _locks: vec![lock, partial_lock],
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

    /// Move the finished directory into place. Without `force` an output
    /// that appeared meanwhile (written by something that does not take
    /// the lock) is never replaced: the rename itself refuses a non-empty
    /// folder, atomically.
    pub fn commit(mut self) -> Result<PathBuf> {
        if self.force && self.target.exists() {
            let old = parent_of(&self.target).join(format!(
                ".{}.old-{}",
                file_name(&self.target),
                std::process::id()
            ));
            fs::rename(&self.target, &old).map_err(write_err(&self.target))?;
            fs::rename(&self.staging, &self.target).map_err(write_err(&self.target))?;
            fs::remove_dir_all(&old).map_err(write_err(&old))?;
        } else {
            // rename(2) replaces only an empty folder, as
            // `check_output_dir` allows; a non-empty one or a file fails.
            fs::rename(&self.staging, &self.target).map_err(|e| match e.kind() {
                ErrorKind::DirectoryNotEmpty | ErrorKind::AlreadyExists => {
                    StoreError::OutputExists {
                        path: self.target.clone(),
                    }
                }
                ErrorKind::NotADirectory => StoreError::Format {
                    path: self.target.clone(),
                    reason: "exists and is not a folder".into(),
                },
                _ => write_err(&self.target)(e),
            })?;
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
    write_file(path, bytes, true)
}

/// Refuse an existing single output file `path` (named by the option
/// `flag`; anything there, a folder too) unless `force`: before the work
/// that makes it. With `force`, what cannot be replaced fails the write.
pub fn check_output_file(path: &Path, force: bool, flag: &'static str) -> Result<()> {
    if !force && fs::symlink_metadata(path).is_ok() {
        return Err(StoreError::OutputFileExists {
            path: path.to_path_buf(),
            flag,
        });
    }
    Ok(())
}

/// Write a single output file (named by the option `flag`) atomically, as
/// [`write_atomic`]; without `force` an existing file is never replaced,
/// even one that appeared since [`check_output_file`] (the final link is
/// made without replacing).
pub fn write_output_file(path: &Path, bytes: &[u8], force: bool, flag: &'static str) -> Result<()> {
    check_output_file(path, force, flag)?;
    write_file(path, bytes, force).map_err(|e| match e {
        StoreError::Write { source, .. } if source.kind() == ErrorKind::AlreadyExists => {
            StoreError::OutputFileExists {
                path: path.to_path_buf(),
                flag,
            }
        }
        other => other,
    })
}

/// Write `path` through a synced temporary sibling, replacing an existing
/// file only when `replace`.
fn write_file(path: &Path, bytes: &[u8], replace: bool) -> Result<()> {
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
    let persisted = if replace {
        tmp.persist(path).map(drop)
    } else {
        tmp.persist_noclobber(path).map(drop)
    };
    persisted.map_err(|e| StoreError::Write {
        path: path.to_path_buf(),
        source: e.error,
    })
}

/// Read a whole text file (a regular file of at most
/// [`crate::input_file::MAX_TEXT_BYTES`]), naming it on error.
pub fn read_text(path: &Path) -> Result<String> {
    let bytes =
        crate::input_file::read_bounded(path, crate::input_file::MAX_TEXT_BYTES, "text file")?;
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

    /// Issue 20: `commit` renamed an existing target away without
    /// `--force`, so a second run (or another program) that made the
    /// output meanwhile lost it.
    #[test]
    fn commit_never_replaces_an_output_that_appeared_without_force() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("ds");
        let stage = StagedDir::new(&target, false).unwrap();
        fs::write(stage.path().join("mine.txt"), "new").unwrap();
        fs::create_dir(&target).unwrap();
        fs::write(target.join("theirs.txt"), "old").unwrap();
        assert!(matches!(
            stage.commit(),
            Err(StoreError::OutputExists { .. })
        ));
        assert_eq!(
            fs::read_to_string(target.join("theirs.txt")).unwrap(),
            "old"
        );
        assert!(!target.join("mine.txt").exists());
        // An empty folder is no output: it is replaced, as the start allows.
        let other = root.path().join("empty");
        let stage = StagedDir::new(&other, false).unwrap();
        fs::write(stage.path().join("mine.txt"), "new").unwrap();
        fs::create_dir(&other).unwrap();
        stage.commit().unwrap();
        assert!(other.join("mine.txt").exists());
        // With force the existing output is replaced.
        let stage = StagedDir::new(&target, true).unwrap();
        fs::write(stage.path().join("mine.txt"), "new").unwrap();
        stage.commit().unwrap();
        assert!(target.join("mine.txt").exists() && !target.join("theirs.txt").exists());
    }

    /// Issue 20: `new_keeping_partial` deleted the `OUT.partial` of a run
    /// still writing it.
    #[test]
    fn a_live_partial_run_is_never_deleted() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("run");
        let partial = partial_path(&target);
        fs::create_dir(&partial).unwrap();
        fs::write(partial.join("trajectory.csv"), "step\n0\n").unwrap();
        // Another process writing `run`: its lock, taken as it would be.
        let lock = root.path().join(".run.lock");
        let other = fs::File::create(&lock).unwrap();
        other.try_lock().unwrap();
        for force in [false, true] {
            assert!(matches!(
                StagedDir::new_keeping_partial(&target, force),
                Err(StoreError::OutputBusy { .. })
            ));
        }
        assert!(partial.join("trajectory.csv").exists());
        // A run writing `run.partial` as its own output blocks it too.
        drop(other);
        let other = fs::File::create(root.path().join(".run.partial.lock")).unwrap();
        other.try_lock().unwrap();
        assert!(matches!(
            StagedDir::new_keeping_partial(&target, false),
            Err(StoreError::OutputBusy { .. })
        ));
        assert!(partial.join("trajectory.csv").exists());
        // Once that run is gone, its leftover is replaced.
        drop(other);
        let stage = StagedDir::new_keeping_partial(&target, false).unwrap();
        assert!(!stage.path().join("trajectory.csv").exists());
    }

    /// Issue 20: single output files were replaced without `--force`.
    #[test]
    fn an_output_file_is_replaced_only_with_force() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("tap.png");
        write_output_file(&p, b"1", false, "--out").unwrap();
        let err = write_output_file(&p, b"2", false, "--out").unwrap_err();
        assert!(matches!(err, StoreError::OutputFileExists { .. }));
        assert!(err.to_string().contains("pass --force"), "{err}");
        assert_eq!(fs::read(&p).unwrap(), b"1");
        write_output_file(&p, b"3", true, "--out").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"3");
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
        // The file appearing after the check is not replaced either.
        let q = root.path().join("late.png");
        check_output_file(&q, false, "--out").unwrap();
        fs::write(&q, b"theirs").unwrap();
        assert!(write_file(&q, b"mine", false).is_err());
        assert_eq!(fs::read(&q).unwrap(), b"theirs");
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
