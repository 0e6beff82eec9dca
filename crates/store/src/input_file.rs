//! Input files read with bounds: only regular files (a FIFO named like a
//! frame would block the reader for ever, `/dev/zero` never ends), and a
//! whole file read into memory only up to a size that suits its kind.
use crate::error::{read_err, Result, StoreError};
use std::fs::{self, File};
use std::io::Read;
use std::path::Path;

/// The largest text file (configuration, JSON, CSV read whole), bytes.
pub const MAX_TEXT_BYTES: u64 = 256 << 20;

/// The largest binary file read whole (model weights, sensor tensors),
/// bytes.
pub const MAX_BINARY_BYTES: u64 = 4 << 30;

/// Open `path` for reading when it is a regular file (symbolic links
/// followed), with its size; a folder, FIFO, socket or device is refused
/// before it is opened (opening a FIFO waits for a writer), and checked
/// again on the open file.
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    let meta = fs::metadata(path).map_err(read_err(path))?;
    not_regular(path, &meta)?;
    let file = File::open(path).map_err(read_err(path))?;
    let meta = file.metadata().map_err(read_err(path))?;
    not_regular(path, &meta)?;
    Ok((file, meta.len()))
}

/// Read the whole regular file `path` (a `what`, for the message) when it
/// is at most `max` bytes.
pub fn read_bounded(path: &Path, max: u64, what: &str) -> Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    if len > max {
        return Err(StoreError::Format {
            path: path.to_path_buf(),
            reason: format!(
                "{len} bytes, more than the {max} bytes a {what} may have: is it the right file?"
            ),
        });
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // `take`: a file that grows while read stays within the bound.
    file.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(read_err(path))?;
    if bytes.len() as u64 > max {
        return Err(StoreError::Format {
            path: path.to_path_buf(),
            reason: format!("grew past the {max} bytes a {what} may have while being read"),
        });
    }
    Ok(bytes)
}

/// Refuse anything but a regular file, naming what it is.
fn not_regular(path: &Path, meta: &fs::Metadata) -> Result<()> {
    if meta.is_file() {
        return Ok(());
    }
    let kind = file_kind(&meta.file_type());
    Err(StoreError::Format {
        path: path.to_path_buf(),
        reason: format!("is {kind}, not a regular file"),
    })
}

/// What a non-regular file is, in words.
fn file_kind(t: &fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a file"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_fifo_or_device_is_refused_without_blocking() {
        let root = tempfile::tempdir().unwrap();
        let fifo = root.path().join("frame_1_0.png");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs");
        assert!(made.success());
        let msg = open_regular(&fifo).unwrap_err().to_string();
        assert!(msg.contains("FIFO"), "{msg}");
        let msg = read_bounded(Path::new("/dev/zero"), 10, "test file")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("a device, not a regular file"), "{msg}");
        let msg = open_regular(root.path()).unwrap_err().to_string();
        assert!(msg.contains("a folder"), "{msg}");
    }

    #[test]
    fn a_file_over_its_bound_is_refused_before_reading() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("big.toml");
        fs::write(&p, vec![b'#'; 100]).unwrap();
        let msg = read_bounded(&p, 99, "configuration file")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("100 bytes, more than the 99 bytes"), "{msg}");
        assert_eq!(
            read_bounded(&p, 100, "configuration file").unwrap().len(),
            100
        );
    }
}
