//! Replay of saved frames: stands in for the camera when re-running
//! experiments from disk. This and [`read_frame`] are the crate's only I/O.
use crate::{Frame, SensorError, TactileSensor};
use std::path::{Path, PathBuf};

/// A sensor that returns saved frames from a list of files, in order.
#[derive(Debug, Clone)]
pub struct ReplaySensor {
    paths: Vec<PathBuf>,
    next: usize,
}

impl ReplaySensor {
    /// Replay `paths` in the order given; files are read at capture time.
    pub fn new(paths: Vec<PathBuf>) -> Self {
        Self { paths, next: 0 }
    }

    /// How many frames are left to capture.
    pub fn remaining(&self) -> usize {
        self.paths.len() - self.next
    }
}

impl TactileSensor for ReplaySensor {
    /// Reads the next file; errors after the last one.
    fn capture(&mut self) -> Result<Frame, SensorError> {
        let path = self
            .paths
            .get(self.next)
            .ok_or(SensorError::ReplayExhausted {
                count: self.paths.len(),
            })?;
        let frame = read_frame(path)?;
        self.next += 1;
        Ok(frame)
    }
}

/// The largest frame file read, bytes (a 4096 x 4096 16-bit RGBA PNG
/// stored uncompressed is 128 MiB).
pub const MAX_FRAME_BYTES: u64 = 256 << 20;

/// Read one frame from an image file, converting colour to 8-bit grey by
/// [`tactrace_vision::preprocess::grey_of`] (the conversion `import` and
/// the preprocessing stage use).
///
/// Errors name the file and say whether it is missing, unreadable, not an
/// image or corrupt. Only a regular file of at most `MAX_FRAME_BYTES` (256 MiB)
/// is read: a FIFO named like a frame would block the reader for ever.
pub fn read_frame(path: &Path) -> Result<Frame, SensorError> {
    Ok(tactrace_vision::preprocess::grey_of(&read_image(path)?))
}

/// A camera image file decoded as it is (grey or colour), with the checks
/// of [`read_frame`]; for preprocessing stages that read colour.
pub fn read_image(path: &Path) -> Result<image::DynamicImage, SensorError> {
    if !path.exists() {
        return Err(SensorError::FrameMissing {
            path: path.to_path_buf(),
        });
    }
    let unreadable = |reason: String| SensorError::FrameUnreadable {
        path: path.to_path_buf(),
        reason,
    };
    let meta = std::fs::metadata(path).map_err(|e| unreadable(e.to_string()))?;
    if !meta.is_file() {
        return Err(unreadable(
            "not a regular file (a folder, FIFO or device)".into(),
        ));
    }
    if meta.len() > MAX_FRAME_BYTES {
        return Err(unreadable(format!(
            "{} bytes, more than the {MAX_FRAME_BYTES} bytes a frame file may have",
            meta.len()
        )));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| {
            use std::io::Read;
            f.take(MAX_FRAME_BYTES).read_to_end(&mut bytes)
        })
        .map_err(|e| unreadable(e.to_string()))?;
    let format = image::guess_format(&bytes).map_err(|_| SensorError::NotAnImage {
        path: path.to_path_buf(),
        reason: "contents match no supported image format".into(),
    })?;
    let image = image::load_from_memory_with_format(&bytes, format)
        .map_err(|e| classify_decode_error(path, e))?;
    Ok(image)
}

fn classify_decode_error(path: &Path, err: image::ImageError) -> SensorError {
    let path = path.to_path_buf();
    match err {
        image::ImageError::Unsupported(e) => SensorError::NotAnImage {
            path,
            reason: e.to_string(),
        },
        image::ImageError::IoError(e) => SensorError::FrameUnreadable {
            path,
            reason: e.to_string(),
        },
        other => SensorError::CorruptFrame {
            path,
            reason: plain_chunk_names(&other.to_string()),
        },
    }
}

/// The PNG decoder names chunks by their debug form (`ChunkType { type:
/// IDAT, critical: true, .. }`); keep only the chunk's name (`IDAT`).
fn plain_chunk_names(msg: &str) -> String {
    const OPEN: &str = "ChunkType { type: ";
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    while let Some(at) = rest.find(OPEN) {
        out.push_str(&rest[..at]);
        let tail = &rest[at + OPEN.len()..];
        let name_end = tail.find([',', ' ', '}']).unwrap_or(tail.len());
        out.push_str(&tail[..name_end]);
        rest = tail.find('}').map_or("", |close| &tail[close + 1..]);
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A colour frame file is made grey by the one conversion `import`
    /// and the preprocessing stage use (`grey_of`, OpenCV's weights), not
    /// by the image crate's own (which differs on this frame).
    #[test]
    fn a_colour_frame_is_read_grey_as_import_reads_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("colour.png");
        let image = image::RgbImage::from_fn(7, 5, |x, y| {
            image::Rgb([
                (40 * x) as u8,
                (50 * y + 3) as u8,
                (17 * (x + y) + 90) as u8,
            ])
        });
        image.save(&path).unwrap();
        let frame = read_frame(&path).unwrap();
        let decoded = read_image(&path).unwrap();
        assert_eq!(frame, tactrace_vision::preprocess::grey_of(&decoded));
        assert_ne!(frame, decoded.to_luma8(), "the two conversions differ here");
        let p = image.get_pixel(6, 4).0.map(u32::from);
        let expected = (p[0] * 9798 + p[1] * 19235 + p[2] * 3735 + (1 << 14)) >> 15;
        assert_eq!(u32::from(frame.get_pixel(6, 4)[0]), expected);
    }
}
