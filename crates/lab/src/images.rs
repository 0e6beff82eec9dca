//! Frame files: PNG encoding and decoding with errors that name the file.
use crate::error::{LabError, Result};
use image::{GrayImage, ImageFormat};
use std::io::Cursor;

/// Encode a grayscale frame as PNG bytes.
pub fn png_bytes(frame: &GrayImage) -> Result<Vec<u8>> {
    let mut out = Cursor::new(Vec::new());
    frame
        .write_to(&mut out, ImageFormat::Png)
        .map_err(|e| LabError::Config(format!("PNG encoding failed: {e}")))?;
    Ok(out.into_inner())
}
