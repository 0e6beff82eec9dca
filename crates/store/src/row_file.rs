//! Files written row by row with whole rows only: each CSV row is
//! formatted in memory and written in one piece, and when a write fails
//! part way (a full disk) the file is cut back to its last whole row, so
//! a reader never meets a torn last row.
use crate::error::{Result, StoreError};
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// A writer that can be cut back to a length (a file, or a test double).
pub trait Truncate: Write {
    /// Cut the written data to its first `len` bytes and write on from
    /// there.
    fn truncate_to(&mut self, len: u64) -> std::io::Result<()>;
}

impl Truncate for File {
    fn truncate_to(&mut self, len: u64) -> std::io::Result<()> {
        self.set_len(len)?;
        self.seek(SeekFrom::Start(len)).map(drop)
    }
}

/// A CSV file written a whole row at a time, each row flushed.
pub struct RowFile<W: Truncate> {
    out: W,
    /// Bytes of whole rows written so far.
    len: u64,
    /// The file's name, for errors.
    path: PathBuf,
}

impl RowFile<File> {
    /// Create (or empty) the file `path`.
    pub fn create(path: &Path) -> Result<Self> {
        let file = File::create(path).map_err(crate::write_err(path))?;
        Ok(Self::new(file, path))
    }
}

impl<W: Truncate> RowFile<W> {
    /// Rows go to `out` (empty), named `path` in errors.
    pub fn new(out: W, path: &Path) -> Self {
        Self {
            out,
            len: 0,
            path: path.to_path_buf(),
        }
    }

    /// Append one row (CSV-quoted as needed) and flush it; on failure the
    /// file is cut back to the rows before it.
    pub fn write_row<I, F>(&mut self, fields: I) -> Result<()>
    where
        I: IntoIterator<Item = F>,
        F: AsRef<[u8]>,
    {
        let mut row = csv::Writer::from_writer(Vec::new());
        row.write_record(fields).map_err(|e| self.error(e.into()))?;
        let bytes = row.into_inner().map_err(|e| self.error(e.into_error()))?;
        match self.out.write_all(&bytes).and_then(|()| self.out.flush()) {
            Ok(()) => {
                self.len += bytes.len() as u64;
                Ok(())
            }
            Err(e) => {
                // Best effort: if even this fails the disk is beyond us.
                let _ = self.out.truncate_to(self.len);
                Err(self.error(e))
            }
        }
    }

    /// Bytes of whole rows written so far.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True when no row was written.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn error(&self, source: std::io::Error) -> StoreError {
        StoreError::Write {
            path: self.path.clone(),
            source,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A test double for a disk that fills: it takes `room` bytes, then every
    /// write fails after taking what still fits.
    struct FillingDisk {
        /// What was written (and not cut back).
        data: Vec<u8>,
        /// Bytes it still takes.
        room: usize,
    }

    impl Write for FillingDisk {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::from_raw_os_error(28)); // ENOSPC
            }
            let n = buf.len().min(self.room);
            self.data.extend_from_slice(&buf[..n]);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Truncate for FillingDisk {
        fn truncate_to(&mut self, len: u64) -> std::io::Result<()> {
            self.data.truncate(len as usize);
            Ok(())
        }
    }

    #[test]
    fn a_write_failing_mid_row_leaves_only_whole_rows() {
        let disk = FillingDisk {
            data: Vec::new(),
            room: 30,
        };
        let mut rows = RowFile::new(disk, Path::new("run.partial/trajectory.csv"));
        rows.write_row(["step", "x_mm"]).unwrap();
        rows.write_row(["0", "1.2500"]).unwrap();
        let whole = rows.len();
        assert_eq!(whole, 19);
        // 11 bytes left: the next row (13 bytes) is cut off part way.
        let err = rows.write_row(["1", "100.2500", "x"]).unwrap_err();
        let msg = format!("{err}: {}", std::error::Error::source(&err).unwrap());
        assert!(
            msg.starts_with("cannot write run.partial/trajectory.csv: No space left"),
            "{msg}"
        );
        assert_eq!(rows.out.data, b"step,x_mm\n0,1.2500\n");
        assert_eq!(rows.len(), whole);
    }

    #[test]
    fn rows_reach_a_real_file_whole_and_quoted() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("t.csv");
        let mut rows = RowFile::create(&p).unwrap();
        rows.write_row(["a", "b,c"]).unwrap();
        rows.out.truncate_to(0).unwrap();
        rows.len = 0;
        rows.write_row(["1", "2"]).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "1,2\n");
    }
}
