//! Direct camera capture over V4L2: the device stays open for the whole
//! run, as the Bristol stack keeps its camera open, so no frame is taken
//! inside the camera's start-up transient and no tap pays the open.
//!
//! [`V4l2Source`] is a [`FrameSource`] over any [`CaptureDevice`]: the
//! real one (`LinuxDevice`, feature `v4l2` on Linux, through the pure-Rust
//! `linuxvideo` crate) or [`FakeDevice`], which replays buffers a test
//! made, so the conversion, the stale-buffer dropping and the faults are
//! tested without a camera. Before each frame, every buffer the driver
//! filled before the request is dropped (taken while the arm was still
//! moving); the frame returned is the first one filled after it.

mod convert;
mod fake;
#[cfg(all(feature = "v4l2", target_os = "linux"))]
mod linux;

use std::time::{Duration, Instant};

use image::DynamicImage;
use serde::{Deserialize, Serialize};

pub use convert::{choose_format, to_gray, CameraFormat, StreamFormat};
pub use fake::FakeDevice;
#[cfg(all(feature = "v4l2", target_os = "linux"))]
pub use linux::{list_cameras, open_error, LinuxDevice};

use super::FrameSource;
use crate::HwError;

/// A V4L2 capture device, streaming.
pub trait CaptureDevice {
    /// The device path, for messages.
    fn name(&self) -> &str;
    /// The negotiated format.
    fn format(&self) -> StreamFormat;
    /// Whether a filled buffer is waiting; does not block.
    fn ready(&mut self) -> Result<bool, HwError>;
    /// The next filled buffer's bytes; call after `ready` said true.
    fn dequeue(&mut self) -> Result<Vec<u8>, HwError>;
}

/// A capture device found by `list_cameras`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CameraInfo {
    /// `/dev/videoN`.
    pub path: String,
    /// The driver's name for the card.
    pub card: String,
    /// Pixel formats offered (fourcc text).
    pub formats: Vec<String>,
}

/// The video capture devices of this machine: none where V4L2 capture
/// is not built in.
#[cfg(not(all(feature = "v4l2", target_os = "linux")))]
pub fn list_cameras() -> Result<Vec<CameraInfo>, HwError> {
    Ok(Vec::new())
}

/// The `[camera.v4l2]` table of a rig file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct V4l2Config {
    /// The device, e.g. `/dev/video0`.
    pub device: String,
    /// Requested width, px (the driver may pick the nearest it has).
    #[serde(default = "default_width")]
    pub width: u32,
    /// Requested height, px.
    #[serde(default = "default_height")]
    pub height: u32,
    /// Pixel format; default: grey, else YUYV, else MJPEG.
    #[serde(default)]
    pub format: Option<CameraFormat>,
    /// Fixed exposure in the driver's units (`exposure_time_absolute`,
    /// 100 us for UVC cameras); auto exposure is switched off. Default:
    /// leave the camera's setting.
    #[serde(default)]
    pub exposure: Option<i32>,
    /// Frames dropped once after opening (auto exposure, white balance
    /// settling).
    #[serde(default = "default_warmup")]
    pub warmup_frames: u32,
    /// Longest wait for one frame, s.
    #[serde(default = "default_frame_timeout")]
    pub timeout_s: f64,
}

fn default_width() -> u32 {
    640
}
fn default_height() -> u32 {
    480
}
fn default_warmup() -> u32 {
    10
}
fn default_frame_timeout() -> f64 {
    2.0
}

impl V4l2Config {
    /// Defaults for everything but the device.
    pub fn new(device: impl Into<String>) -> Self {
        Self {
            device: device.into(),
            width: default_width(),
            height: default_height(),
            format: None,
            exposure: None,
            warmup_frames: default_warmup(),
            timeout_s: default_frame_timeout(),
        }
    }

    /// Checks ranges: a device, a size, a timeout in (0, 60] s.
    pub fn validate(&self) -> Result<(), HwError> {
        let fail = |field, reason: String| Err(HwError::Config { field, reason });
        if self.device.trim().is_empty() {
            return fail("device", "empty".into());
        }
        if !(1..=8192).contains(&self.width) || !(1..=8192).contains(&self.height) {
            return fail(
                "width",
                format!("{} x {} is not a camera size", self.width, self.height),
            );
        }
        if !(self.timeout_s > 0.0 && self.timeout_s <= 60.0) {
            return fail("timeout_s", format!("{} is not in (0, 60]", self.timeout_s));
        }
        Ok(())
    }
}

/// How often a waiting source asks the device for a buffer.
const POLL: Duration = Duration::from_millis(2);
/// At most this many stale buffers are dropped before a frame (a driver
/// rarely holds more than a handful).
const MAX_STALE: usize = 64;

/// Frames from a V4L2 device kept open.
pub struct V4l2Source<D: CaptureDevice> {
    device: D,
    timeout: Duration,
    dropped: usize,
}

impl<D: CaptureDevice> V4l2Source<D> {
    /// A source over an open, streaming `device`; drops `warmup_frames`
    /// frames first (each waited for up to `timeout`).
    pub fn new(device: D, warmup_frames: u32, timeout: Duration) -> Result<Self, HwError> {
        let mut source = Self {
            device,
            timeout,
            dropped: 0,
        };
        for _ in 0..warmup_frames {
            source.next_fresh()?;
        }
        Ok(source)
    }

    /// Stale buffers dropped so far (warm-up not counted).
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// The device.
    pub fn device(&self) -> &D {
        &self.device
    }

    /// Drops every buffer already filled, then waits for the next one.
    fn next_fresh(&mut self) -> Result<Vec<u8>, HwError> {
        let mut stale = 0;
        while stale < MAX_STALE && self.device.ready()? {
            self.device.dequeue()?;
            stale += 1;
        }
        let start = Instant::now();
        loop {
            if self.device.ready()? {
                let bytes = self.device.dequeue()?;
                self.dropped += stale;
                return Ok(bytes);
            }
            if start.elapsed() >= self.timeout {
                return Err(HwError::CameraTimeout {
                    device: self.device.name().to_string(),
                    seconds: self.timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(POLL);
        }
    }
}

impl<D: CaptureDevice> FrameSource for V4l2Source<D> {
    /// The first frame the camera filled after this call, in grey; blocks
    /// up to the timeout. Errors: timeout, unplugged, bad buffer.
    fn grab(&mut self) -> Result<DynamicImage, HwError> {
        let bytes = self.next_fresh()?;
        let gray = to_gray(&self.device.format(), &bytes)?;
        Ok(DynamicImage::ImageLuma8(gray))
    }
}

/// Opens the camera of `config` and starts streaming (feature `v4l2` on
/// Linux; elsewhere an error saying so).
pub fn open_v4l2(config: &V4l2Config) -> Result<Box<dyn FrameSource>, HwError> {
    config.validate()?;
    #[cfg(all(feature = "v4l2", target_os = "linux"))]
    {
        let device = LinuxDevice::open(config)?;
        let timeout = Duration::from_secs_f64(config.timeout_s);
        Ok(Box::new(V4l2Source::new(
            device,
            config.warmup_frames,
            timeout,
        )?))
    }
    #[cfg(not(all(feature = "v4l2", target_os = "linux")))]
    {
        Err(HwError::Config {
            field: "v4l2",
            reason: "this tactrace was built without V4L2 capture (Linux, feature `v4l2`); \
                     use [camera.command] instead"
                .into(),
        })
    }
}
