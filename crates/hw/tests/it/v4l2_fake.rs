//! The V4L2 frame source over the fake device layer: buffers made here
//! (GREY, YUYV, MJPEG) go through the source and the TacTip
//! preprocessing; stale buffers are dropped before each frame; a timeout
//! and an unplugged camera are typed errors, never panics.
use std::time::{Duration, Instant};

use image::GrayImage;
use tactrace_hw::camera::v4l2::{CameraFormat, FakeDevice, StreamFormat, V4l2Source};
use tactrace_hw::{CameraSensor, FrameSource, HwError, PreprocessConfig};
use tactrace_sensor::TactileSensor;

const TIMEOUT: Duration = Duration::from_millis(200);

fn grey(width: u32, height: u32) -> StreamFormat {
    StreamFormat {
        format: CameraFormat::Grey,
        width,
        height,
        bytes_per_line: width,
    }
}

/// A 4 x 2 grey buffer filled with `level`.
fn flat(level: u8) -> Vec<u8> {
    vec![level; 8]
}

fn level_of(source: &mut V4l2Source<FakeDevice>) -> u8 {
    source.grab().unwrap().to_luma8().get_pixel(0, 0)[0]
}

#[test]
fn stale_buffers_are_dropped_before_each_frame() {
    let device = FakeDevice::new(
        grey(4, 2),
        vec![flat(1), flat(2), flat(3)],
        vec![flat(10), flat(20)],
    );
    let mut source = V4l2Source::new(device, 0, TIMEOUT).unwrap();
    assert_eq!(
        level_of(&mut source),
        10,
        "the first frame after the request"
    );
    assert_eq!(source.dropped(), 3);
    assert_eq!(level_of(&mut source), 20);
    assert_eq!(source.device().dequeued(), 5);
}

#[test]
fn warm_up_frames_are_dropped_once_at_open() {
    let device = FakeDevice::new(grey(4, 2), vec![], vec![flat(1), flat(2), flat(3)]);
    let mut source = V4l2Source::new(device, 2, TIMEOUT).unwrap();
    assert_eq!(level_of(&mut source), 3);
}

#[test]
fn a_yuyv_camera_gives_the_luma_plane_through_the_tactip_preprocessing() {
    let (w, h) = (64u32, 48u32);
    let luma = |x: u32, y: u32| ((x * 3 + y * 5) % 251) as u8;
    let mut buffer = Vec::new();
    for y in 0..h {
        for x in 0..w {
            buffer.push(luma(x, y));
            buffer.push(if x % 2 == 0 { 90 } else { 160 });
        }
    }
    let format = StreamFormat {
        format: CameraFormat::Yuyv,
        width: w,
        height: h,
        bytes_per_line: 2 * w,
    };
    let device = FakeDevice::new(format, vec![], vec![buffer]);
    let source = V4l2Source::new(device, 0, TIMEOUT).unwrap();
    let preprocess = PreprocessConfig::grayscale_only().validate().unwrap();
    let mut sensor = CameraSensor::new(source, preprocess);
    let frame = sensor.capture().unwrap();
    assert_eq!(
        frame,
        GrayImage::from_fn(w, h, |x, y| image::Luma([luma(x, y)]))
    );
}

#[test]
fn an_mjpeg_camera_is_decoded() {
    let original = GrayImage::from_fn(32, 24, |x, _| image::Luma([(x * 8) as u8]));
    let mut jpeg = Vec::new();
    image::DynamicImage::ImageLuma8(original)
        .write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    let format = StreamFormat {
        format: CameraFormat::Mjpeg,
        width: 32,
        height: 24,
        bytes_per_line: 0,
    };
    let mut source =
        V4l2Source::new(FakeDevice::new(format, vec![], vec![jpeg]), 0, TIMEOUT).unwrap();
    let frame = source.grab().unwrap().to_luma8();
    assert_eq!(frame.dimensions(), (32, 24));
    assert!(frame.get_pixel(31, 0)[0] > 230 && frame.get_pixel(0, 0)[0] < 20);
}

#[test]
fn no_frame_in_time_is_a_timeout() {
    let device = FakeDevice::new(grey(4, 2), vec![flat(1)], vec![]);
    let mut source = V4l2Source::new(device, 0, TIMEOUT).unwrap();
    let start = Instant::now();
    let err = source.grab().unwrap_err();
    assert!(matches!(err, HwError::CameraTimeout { .. }), "{err:?}");
    assert!(err.to_string().starts_with("timeout"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(2));
}

#[test]
fn a_camera_unplugged_mid_run_fails_the_capture_cleanly() {
    let device =
        FakeDevice::new(grey(4, 2), vec![], vec![flat(1), flat(2), flat(3)]).unplug_after(2);
    let source = V4l2Source::new(device, 0, TIMEOUT).unwrap();
    let preprocess = PreprocessConfig::grayscale_only().validate().unwrap();
    let mut sensor = CameraSensor::new(source, preprocess);
    sensor.capture().unwrap();
    sensor.capture().unwrap();
    let err = sensor.capture().unwrap_err();
    assert!(err.to_string().contains("unplugged"), "{err}");
    assert!(sensor.capture().is_err(), "stays failed");
}

#[test]
fn a_short_buffer_is_a_frame_error() {
    let device = FakeDevice::new(grey(4, 2), vec![], vec![vec![0; 5]]);
    let mut source = V4l2Source::new(device, 0, TIMEOUT).unwrap();
    assert!(matches!(source.grab(), Err(HwError::FrameData { .. })));
}
