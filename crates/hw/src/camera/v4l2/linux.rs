//! The real V4L2 device through the `linuxvideo` crate (pure Rust, libc
//! only): open, pick the format, set size and exposure, stream with mmap
//! buffers. Opening failures are mapped to typed errors by [`open_error`].
use std::io;

use linuxvideo::controls::Cid;
use linuxvideo::format::{PixFormat, PixelFormat};
use linuxvideo::stream::ReadStream;
use linuxvideo::{BufType, CapabilityFlags, Device};

use super::{choose_format, CameraFormat, CameraInfo, CaptureDevice, StreamFormat, V4l2Config};
use crate::HwError;

/// V4L2's `V4L2_EXPOSURE_MANUAL` value of the `exposure_auto` menu.
const EXPOSURE_MANUAL: i32 = 1;
/// Linux `ENODEV`: the device went away.
const ENODEV: i32 = 19;
/// Linux `ENOTTY` and `EINVAL`: an ioctl the opened file does not know.
const ENOTTY: i32 = 25;
const EINVAL: i32 = 22;

/// Refuses, before opening it, a path that cannot be a camera (a regular
/// file, a folder): V4L2 devices are character devices.
fn check_device_file(device: &str) -> Result<(), HwError> {
    use std::os::unix::fs::FileTypeExt;
    let kind = std::fs::metadata(device)
        .map_err(|e| open_error(device, e))?
        .file_type();
    if kind.is_char_device() {
        return Ok(());
    }
    let what = if kind.is_dir() {
        "a folder"
    } else if kind.is_file() {
        "a regular file"
    } else {
        "no device file"
    };
    Err(HwError::NotACamera {
        device: device.to_string(),
        reason: format!("it is {what}, not a video device"),
    })
}

/// The typed error of a failed `Device::open` (which asks the device for
/// its V4L2 capabilities): a device that does not know the request is no
/// camera.
fn device_open_error(device: &str, err: io::Error) -> HwError {
    if matches!(err.raw_os_error(), Some(ENOTTY | EINVAL)) {
        return HwError::NotACamera {
            device: device.to_string(),
            reason: "it does not answer as a V4L2 video device".into(),
        };
    }
    open_error(device, err)
}

/// A streaming V4L2 capture device.
pub struct LinuxDevice {
    name: String,
    format: StreamFormat,
    stream: ReadStream,
}

/// The typed error of a failed open or ioctl on `device`.
pub fn open_error(device: &str, err: io::Error) -> HwError {
    let device = device.to_string();
    match err.kind() {
        io::ErrorKind::NotFound => HwError::CameraMissing { device },
        io::ErrorKind::ResourceBusy => HwError::CameraBusy { device },
        _ if err.raw_os_error() == Some(ENODEV) => HwError::CameraUnplugged { device },
        _ => HwError::CameraIo {
            device,
            source: err,
        },
    }
}

impl LinuxDevice {
    /// Opens `config.device`, sets the exposure, negotiates the format and
    /// size and starts streaming.
    pub fn open(config: &V4l2Config) -> Result<Self, HwError> {
        let name = config.device.clone();
        let err = |e| open_error(&name, e);
        check_device_file(&name)?;
        let mut device = Device::open(&config.device).map_err(|e| device_open_error(&name, e))?;
        let offered: Vec<[u8; 4]> = device
            .formats(BufType::VIDEO_CAPTURE)
            .filter_map(|f| f.ok().map(|f| f.pixel_format().as_fourcc()))
            .collect();
        let format = choose_format(&name, &offered, config.format)?;
        if let Some(exposure) = config.exposure {
            device
                .write_control_raw(Cid::EXPOSURE_AUTO, EXPOSURE_MANUAL)
                .map_err(err)?;
            device
                .write_control_raw(Cid::EXPOSURE_ABSOLUTE, exposure)
                .map_err(err)?;
        }
        let wanted = PixFormat::new(
            config.width,
            config.height,
            PixelFormat::from_fourcc(format.fourcc()),
        );
        let capture = device.video_capture(wanted).map_err(err)?;
        let got = capture.format();
        let got_format =
            CameraFormat::from_fourcc(got.pixel_format().as_fourcc()).ok_or_else(|| {
                HwError::CameraFormat {
                    device: name.clone(),
                    offered: format!("{} after negotiation", got.pixel_format()),
                }
            })?;
        let format = StreamFormat {
            format: got_format,
            width: got.width(),
            height: got.height(),
            bytes_per_line: got.bytes_per_line(),
        };
        let stream = capture.into_stream().map_err(err)?;
        Ok(Self {
            name,
            format,
            stream,
        })
    }
}

impl CaptureDevice for LinuxDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn format(&self) -> StreamFormat {
        self.format
    }

    fn ready(&mut self) -> Result<bool, HwError> {
        self.stream
            .will_block()
            .map(|blocks| !blocks)
            .map_err(|e| open_error(&self.name, e))
    }

    fn dequeue(&mut self) -> Result<Vec<u8>, HwError> {
        self.stream
            .dequeue(|view| {
                if view.is_error() {
                    Err(io::Error::other("the driver flagged the buffer corrupt"))
                } else {
                    Ok(view.to_vec())
                }
            })
            .map_err(|e| open_error(&self.name, e))
    }
}

/// The video capture devices of this machine (`/dev/video*` that can
/// capture); an empty list when there are none.
pub fn list_cameras() -> Result<Vec<CameraInfo>, HwError> {
    let devices = linuxvideo::list().map_err(|e| HwError::Io {
        what: "listing /dev".into(),
        source: e,
    })?;
    let mut found = Vec::new();
    for device in devices.flatten() {
        let Ok(caps) = device.capabilities() else {
            continue;
        };
        if !caps
            .device_capabilities()
            .contains(CapabilityFlags::VIDEO_CAPTURE)
        {
            continue;
        }
        let path = device
            .path()
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        let formats = device
            .formats(BufType::VIDEO_CAPTURE)
            .filter_map(|f| f.ok().map(|f| f.pixel_format().to_string()))
            .collect();
        found.push(CameraInfo {
            path,
            card: caps.card().to_string(),
            formats,
        });
    }
    found.sort_by(|a, b| super::super::natural_cmp(&a.path, &b.path));
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_failures_become_typed_errors() {
        let missing = open_error("/dev/video9", io::Error::from(io::ErrorKind::NotFound));
        assert!(matches!(missing, HwError::CameraMissing { .. }));
        assert!(missing.to_string().contains("tactrace camera list"));
        let busy = open_error("/dev/video0", io::Error::from_raw_os_error(16));
        assert!(matches!(busy, HwError::CameraBusy { .. }), "{busy:?}");
        let gone = open_error("/dev/video0", io::Error::from_raw_os_error(ENODEV));
        assert!(matches!(gone, HwError::CameraUnplugged { .. }), "{gone:?}");
        let other = open_error("/dev/video0", io::Error::from_raw_os_error(13));
        assert!(matches!(other, HwError::CameraIo { .. }), "{other:?}");
    }

    #[test]
    fn a_file_a_folder_or_dev_null_is_not_a_camera() {
        let dir = std::env::temp_dir();
        let file = dir.join(format!("tactrace-not-a-camera-{}", std::process::id()));
        std::fs::write(&file, b"png").unwrap();
        for path in [file.to_str().unwrap(), dir.to_str().unwrap(), "/dev/null"] {
            let err = LinuxDevice::open(&V4l2Config::new(path)).err().unwrap();
            assert!(matches!(err, HwError::NotACamera { .. }), "{path}: {err}");
            assert!(err.to_string().contains("is not a camera"), "{err}");
        }
        assert_eq!(
            std::fs::read(&file).unwrap(),
            b"png",
            "the file is untouched"
        );
        std::fs::remove_file(&file).unwrap();
    }

    #[test]
    fn a_missing_device_is_a_typed_error_on_open() {
        let err = LinuxDevice::open(&V4l2Config::new("/dev/video-tactrace-none"))
            .err()
            .unwrap();
        assert!(matches!(err, HwError::CameraMissing { .. }), "{err:?}");
    }
}
