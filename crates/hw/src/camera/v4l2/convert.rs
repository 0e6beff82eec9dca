//! Camera buffers to grey images, and the choice of pixel format: pure
//! functions, tested on buffers made in the tests.
//!
//! Formats (V4L2 fourcc): `GREY` one byte a pixel; `YUYV` packed 4:2:2,
//! bytes `Y0 U Y1 V` for two pixels, so the grey image is every other byte
//! (the luma plane, what OpenCV's grey conversion gives up to rounding);
//! `MJPG` one JPEG image a buffer, decoded and converted to grey. Rows
//! may be padded: `bytes_per_line` is the stride.
use image::GrayImage;
use serde::{Deserialize, Serialize};

use crate::HwError;

/// A pixel format tactrace can turn into a grey frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CameraFormat {
    /// 8-bit grey (`GREY`).
    Grey,
    /// Packed YUV 4:2:2 (`YUYV`); its Y plane is used.
    Yuyv,
    /// Motion JPEG (`MJPG`), decoded.
    Mjpeg,
}

impl CameraFormat {
    /// The V4L2 fourcc.
    pub fn fourcc(self) -> [u8; 4] {
        match self {
            Self::Grey => *b"GREY",
            Self::Yuyv => *b"YUYV",
            Self::Mjpeg => *b"MJPG",
        }
    }

    /// The format of a fourcc, if usable.
    pub fn from_fourcc(fourcc: [u8; 4]) -> Option<Self> {
        [Self::Grey, Self::Yuyv, Self::Mjpeg]
            .into_iter()
            .find(|f| f.fourcc() == fourcc)
    }
}

/// The negotiated layout of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamFormat {
    /// Pixel format.
    pub format: CameraFormat,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Bytes from one row to the next (uncompressed formats).
    pub bytes_per_line: u32,
}

/// The format to ask for among the `offered` fourccs: `wanted` if given
/// and offered, else the first of grey, YUYV, MJPEG offered. The error
/// lists what the camera offers.
pub fn choose_format(
    device: &str,
    offered: &[[u8; 4]],
    wanted: Option<CameraFormat>,
) -> Result<CameraFormat, HwError> {
    let usable: Vec<CameraFormat> = offered
        .iter()
        .filter_map(|f| CameraFormat::from_fourcc(*f))
        .collect();
    let pick = match wanted {
        Some(w) => usable.contains(&w).then_some(w),
        None => [CameraFormat::Grey, CameraFormat::Yuyv, CameraFormat::Mjpeg]
            .into_iter()
            .find(|f| usable.contains(f)),
    };
    pick.ok_or_else(|| HwError::CameraFormat {
        device: device.to_string(),
        offered: if offered.is_empty() {
            "nothing".to_string()
        } else {
            offered
                .iter()
                .map(|f| String::from_utf8_lossy(f).into_owned())
                .collect::<Vec<_>>()
                .join(", ")
        },
    })
}

/// The grey image in one buffer of `format`.
pub fn to_gray(format: &StreamFormat, bytes: &[u8]) -> Result<GrayImage, HwError> {
    let (w, h) = (format.width as usize, format.height as usize);
    let bytes_per_pixel = match format.format {
        CameraFormat::Grey => 1,
        CameraFormat::Yuyv => 2,
        CameraFormat::Mjpeg => return decode_jpeg(format, bytes),
    };
    let stride = (format.bytes_per_line as usize).max(w * bytes_per_pixel);
    let needed = stride * (h.max(1) - 1) + w * bytes_per_pixel;
    if w == 0 || h == 0 || bytes.len() < needed {
        return Err(bad(format!(
            "{} bytes for a {w} x {h} {} frame (stride {stride}), need {needed}",
            bytes.len(),
            String::from_utf8_lossy(&format.format.fourcc())
        )));
    }
    let mut gray = Vec::with_capacity(w * h);
    for row in bytes.chunks(stride).take(h) {
        let row = &row[..w * bytes_per_pixel];
        gray.extend(row.iter().step_by(bytes_per_pixel));
    }
    GrayImage::from_raw(w as u32, h as u32, gray).ok_or_else(|| bad("frame size".into()))
}

fn decode_jpeg(format: &StreamFormat, bytes: &[u8]) -> Result<GrayImage, HwError> {
    let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Jpeg)
        .map_err(|e| bad(format!("MJPEG frame does not decode: {e}")))?
        .to_luma8();
    if (image.width(), image.height()) != (format.width, format.height) {
        return Err(bad(format!(
            "MJPEG frame is {} x {}, the stream {} x {}",
            image.width(),
            image.height(),
            format.width,
            format.height
        )));
    }
    Ok(image)
}

fn bad(reason: String) -> HwError {
    HwError::FrameData { reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stream(format: CameraFormat, width: u32, height: u32, stride: u32) -> StreamFormat {
        StreamFormat {
            format,
            width,
            height,
            bytes_per_line: stride,
        }
    }

    #[test]
    fn yuyv_gives_its_luma_plane() {
        // 4 x 2 pixels: Y0 U Y1 V per pair; luma 10, 20, ... 80.
        let mut buffer = Vec::new();
        for pair in 0..4u8 {
            buffer.extend([20 * pair + 10, 128, 20 * pair + 20, 130]);
        }
        let gray = to_gray(&stream(CameraFormat::Yuyv, 4, 2, 8), &buffer).unwrap();
        assert_eq!(gray.into_raw(), [10, 20, 30, 40, 50, 60, 70, 80]);
    }

    #[test]
    fn grey_rows_skip_their_padding() {
        let buffer = [1, 2, 3, 0, 0, 4, 5, 6, 0, 0];
        let gray = to_gray(&stream(CameraFormat::Grey, 3, 2, 5), &buffer).unwrap();
        assert_eq!(gray.into_raw(), [1, 2, 3, 4, 5, 6]);
        let short = to_gray(&stream(CameraFormat::Grey, 3, 3, 5), &buffer);
        assert!(matches!(short, Err(HwError::FrameData { .. })));
    }

    #[test]
    fn mjpeg_decodes_to_the_image_it_holds() {
        let original = GrayImage::from_fn(32, 16, |x, y| image::Luma([(x * 6 + y * 3) as u8]));
        let mut jpeg = Vec::new();
        image::DynamicImage::ImageLuma8(original.clone())
            .write_to(
                &mut std::io::Cursor::new(&mut jpeg),
                image::ImageFormat::Jpeg,
            )
            .unwrap();
        let gray = to_gray(&stream(CameraFormat::Mjpeg, 32, 16, 0), &jpeg).unwrap();
        let worst = gray
            .pixels()
            .zip(original.pixels())
            .map(|(a, b)| a[0].abs_diff(b[0]))
            .max()
            .unwrap();
        assert!(worst <= 8, "JPEG error {worst}");
        let wrong_size = to_gray(&stream(CameraFormat::Mjpeg, 64, 16, 0), &jpeg);
        assert!(matches!(wrong_size, Err(HwError::FrameData { .. })));
        let garbage = to_gray(&stream(CameraFormat::Mjpeg, 32, 16, 0), &[0xff, 0xd8, 1, 2]);
        assert!(matches!(garbage, Err(HwError::FrameData { .. })));
    }

    #[test]
    fn format_choice_prefers_grey_then_yuyv_then_mjpeg() {
        let offered = [*b"MJPG", *b"YUYV"];
        assert_eq!(
            choose_format("d", &offered, None).unwrap(),
            CameraFormat::Yuyv
        );
        let wanted = choose_format("d", &offered, Some(CameraFormat::Mjpeg));
        assert_eq!(wanted.unwrap(), CameraFormat::Mjpeg);
        let err = choose_format("/dev/video0", &[*b"RGB3", *b"H264"], None).unwrap_err();
        assert!(err.to_string().contains("it offers RGB3, H264"), "{err}");
        assert!(choose_format("d", &offered, Some(CameraFormat::Grey)).is_err());
    }
}
