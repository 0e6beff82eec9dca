//! Frame files: PNG encoding with errors that name the frame.
use crate::error::{Result, StoreError};
use image::{GrayImage, ImageFormat};
use std::io::Cursor;
use std::path::Path;

/// Encode a grayscale frame as PNG bytes (`name` for the error).
pub fn png_bytes(frame: &GrayImage, name: &str) -> Result<Vec<u8>> {
    let mut out = Cursor::new(Vec::new());
    frame
        .write_to(&mut out, ImageFormat::Png)
        .map_err(|e| StoreError::Write {
            path: Path::new(name).to_path_buf(),
            source: std::io::Error::other(e),
        })?;
    Ok(out.into_inner())
}
