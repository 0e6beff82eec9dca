//! One writer per output: an advisory lock beside every output, held for
//! the run's whole life.
//!
//! A run writing `OUT` (a folder or a plots folder) holds an exclusive
//! advisory lock ([`std::fs::File::try_lock`]) on `.OUT.lock` in OUT's
//! parent folder, with its process id written in it. A second run into
//! the same `OUT` finds the lock taken and is refused
//! ([`StoreError::OutputBusy`], naming that pid), with or without
//! `--force`. Advisory locks belong to the open file and end with the
//! process: a run killed with -9 leaves at most an unlocked `.OUT.lock`,
//! which the next run takes over.
//!
//! The lock file is removed by the run holding it, while it still holds
//! it. A run that locked a file which was removed (or replaced) meanwhile
//! opens the path again, so two runs never both hold the lock of one
//! output.
//!
//! Within one process the lock is shared: acquiring it again for an
//! output this process holds gives another handle (a command takes it when
//! it starts, its staging folder again when it writes), and the lock ends
//! with the last handle. On a file system without advisory locks the run
//! goes on unlocked (the commit still never replaces an output without
//! `--force`).
use crate::error::{write_err, Result, StoreError};
use std::collections::HashMap;
use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock, PoisonError};

/// The locks this process holds: lock file -> (the open, locked file, how
/// many handles share it).
fn held() -> &'static Mutex<HashMap<PathBuf, (File, usize)>> {
    static HELD: OnceLock<Mutex<HashMap<PathBuf, (File, usize)>>> = OnceLock::new();
    HELD.get_or_init(Default::default)
}

/// How often to reopen a lock file that was removed under us before
/// giving up (each retry means another run finished meanwhile).
const RETRIES: usize = 32;

/// A held lock on one output; the lock ends when the last handle for the
/// output in this process is dropped.
#[must_use = "the output is locked only while the OutputLock lives"]
#[derive(Debug)]
pub struct OutputLock {
    /// The lock file, canonical (the key among this process's locks).
    file: PathBuf,
}

impl OutputLock {
    /// Lock the output `target` (creating its parent folder if needed):
    /// refused with [`StoreError::OutputBusy`] while another process holds
    /// it.
    pub fn acquire(target: &Path) -> Result<Self> {
        let file = lock_path(target)?;
        let mut map = held().lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((_, users)) = map.get_mut(&file) {
            *users += 1;
            return Ok(Self { file });
        }
        let locked = lock_file(&file, target)?;
        map.insert(file.clone(), (locked, 1));
        Ok(Self { file })
    }

    /// The lock file (`.OUT.lock` beside the output).
    pub fn path(&self) -> &Path {
        &self.file
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let mut map = held().lock().unwrap_or_else(PoisonError::into_inner);
        let last = match map.get_mut(&self.file) {
            Some((_, users)) => {
                *users -= 1;
                *users == 0
            }
            None => false,
        };
        if last {
            // Remove the file while it is still locked, then close it: a
            // run that opened it meanwhile sees it gone and starts over.
            let _ = fs::remove_file(&self.file);
            map.remove(&self.file);
        }
    }
}

/// `.OUT.lock` in OUT's parent folder (created if needed), canonical: one
/// file for every spelling of the output (`out`, `./out`, `.` for the
/// current folder, a path through a symbolic link).
fn lock_path(target: &Path) -> Result<PathBuf> {
    let target = match fs::canonicalize(target) {
        Ok(real) => real,
        Err(_) => {
            let parent = match target.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                _ => PathBuf::from("."),
            };
            fs::create_dir_all(&parent).map_err(write_err(&parent))?;
            let parent = fs::canonicalize(&parent).map_err(write_err(&parent))?;
            match target.file_name() {
                Some(name) => parent.join(name),
                None => parent,
            }
        }
    };
    let parent = target.parent().unwrap_or(&target);
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "root".into());
    Ok(parent.join(format!(".{name}.lock")))
}

/// Open and lock `path` for the output `target`, retrying when the file
/// was removed or replaced between opening and locking it.
fn lock_file(path: &Path, target: &Path) -> Result<File> {
    for _ in 0..RETRIES {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(write_err(path))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                return Err(StoreError::OutputBusy {
                    path: target.to_path_buf(),
                    pid: holder_pid(path),
                })
            }
            // No advisory locks here: go on unlocked.
            Err(TryLockError::Error(e)) if e.kind() == ErrorKind::Unsupported => return Ok(file),
            Err(TryLockError::Error(e)) => return Err(write_err(path)(e)),
        }
        if still_at(&file, path) {
            write_pid(&file).map_err(write_err(path))?;
            return Ok(file);
        }
    }
    Err(write_err(path)(std::io::Error::other(
        "the lock file kept being removed while it was being taken",
    )))
}

/// Whether `path` still names the open `file` (not removed or replaced).
fn still_at(file: &File, path: &Path) -> bool {
    let (Ok(open), Ok(named)) = (file.metadata(), fs::metadata(path)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        (open.dev(), open.ino()) == (named.dev(), named.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = (open, named);
        true
    }
}

/// Write this process's id into the lock file (for the message another
/// run gives).
fn write_pid(mut file: &File) -> std::io::Result<()> {
    file.set_len(0)?;
    file.write_all(format!("{}\n", std::process::id()).as_bytes())?;
    file.flush()
}

/// The process id written in a lock file, if it can be read yet.
fn holder_pid(path: &Path) -> Option<u32> {
    let mut text = String::new();
    File::open(path)
        .ok()?
        .take(32)
        .read_to_string(&mut text)
        .ok()?;
    text.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Another process's lock, as the test can make one: a separate open
    /// file locked with flock semantics.
    fn foreign_lock(target: &Path, pid: &str) -> File {
        let path = lock_path(target).unwrap();
        let mut f = File::create(&path).unwrap();
        f.try_lock().unwrap();
        f.write_all(pid.as_bytes()).unwrap();
        f
    }

    #[test]
    fn a_held_output_is_refused_naming_the_holder() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("out");
        let other = foreign_lock(&target, "4242\n");
        match OutputLock::acquire(&target) {
            Err(StoreError::OutputBusy { pid, path }) => {
                assert_eq!(pid, Some(4242));
                assert_eq!(path, target);
            }
            other => panic!("expected OutputBusy, got {other:?}"),
        }
        let msg = OutputLock::acquire(&target).unwrap_err().to_string();
        assert!(msg.contains("another tactrace run (pid 4242)"), "{msg}");
        // The holder ends (killed -9 or not): its lock dies with its file.
        drop(other);
        let lock = OutputLock::acquire(&target).unwrap();
        assert!(lock.path().exists());
        let pid = fs::read_to_string(lock.path()).unwrap();
        assert_eq!(pid.trim(), std::process::id().to_string());
        drop(lock);
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 0);
    }

    #[test]
    fn one_process_shares_its_lock_and_the_last_handle_removes_it() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("sub/out");
        let a = OutputLock::acquire(&target).unwrap();
        // Other spellings of the same output, before and after it exists.
        let b = OutputLock::acquire(&root.path().join("sub/./out")).unwrap();
        assert_eq!(a.path(), b.path());
        fs::create_dir(&target).unwrap();
        let c = OutputLock::acquire(&target.join(".")).unwrap();
        assert_eq!(a.path(), c.path());
        drop(c);
        drop(a);
        assert!(b.path().exists(), "still held by the second handle");
        let path = b.path().to_path_buf();
        drop(b);
        assert!(!path.exists());
        // Free again: another process could take it now.
        drop(foreign_lock(&target, "1"));
    }

    #[test]
    fn a_stale_unlocked_lock_file_does_not_block() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("out");
        fs::write(root.path().join(".out.lock"), "999999\n").unwrap();
        let lock = OutputLock::acquire(&target).unwrap();
        drop(lock);
        assert!(!root.path().join(".out.lock").exists());
    }
}
