//! Tests of the camera path: preprocessing a synthetic TacTip camera image,
//! the folder and command sources, and the sensor round trip.
use std::path::{Path, PathBuf};

use image::{DynamicImage, GrayImage, Rgb, RgbImage};
use tactrace_sensor::{SensorError, TactileSensor};

use super::*;

/// Pin centres (camera pixels) on a hex lattice inside the default crop.
fn pin_centres() -> Vec<(f64, f64)> {
    let (cx, cy, pitch) = (318.0, 260.0, 18.0);
    let mut pins = Vec::new();
    for row in -6i32..=6 {
        for col in -7i32..=7 {
            let x = cx + pitch * (col as f64 + 0.5 * (row.rem_euclid(2)) as f64);
            let y = cy + pitch * 0.866 * row as f64;
            if (x - cx).hypot(y - cy) < 110.0 {
                pins.push((x, y));
            }
        }
    }
    pins
}

/// `image` through the rig's default (Bristol) preprocessing.
fn bristol(image: &DynamicImage) -> Result<GrayImage, HwError> {
    apply(&PreprocessConfig::default(), image)
}

/// `image` through `config`, laid out for its size.
fn apply(config: &PreprocessConfig, image: &DynamicImage) -> Result<GrayImage, HwError> {
    let stage = config
        .validate()?
        .stage(image.width(), image.height())
        .map_err(|source| HwError::Preprocess { source })?;
    stage
        .apply(image)
        .map_err(|source| HwError::Preprocess { source })
}

/// A 640x480 colour "camera" image: bright round pins (radius 4 px) on a
/// dark skin lit unevenly (a left-to-right ramp of 40 grey levels).
fn synthetic_camera_image() -> RgbImage {
    let pins = pin_centres();
    RgbImage::from_fn(640, 480, |x, y| {
        let base = 40.0 + 40.0 * x as f64 / 640.0;
        let lit = pins
            .iter()
            .any(|&(px, py)| (x as f64 - px).hypot(y as f64 - py) <= 4.0);
        let v = if lit { base + 90.0 } else { base } as u8;
        Rgb([v, v.saturating_add(3), v.saturating_sub(3)])
    })
}

#[test]
fn default_preprocessing_gives_white_pins_on_black() {
    let image = DynamicImage::ImageRgb8(synthetic_camera_image());
    let frame = bristol(&image).unwrap();
    assert_eq!(frame.dimensions(), (256, 256));
    let pins = pin_centres();
    for &(px, py) in &pins {
        // Camera -> frame coordinates: subtract the crop origin (190, 132).
        let (fx, fy) = ((px - 190.0).round() as u32, (py - 132.0).round() as u32);
        assert_eq!(frame.get_pixel(fx, fy)[0], 255, "pin at ({fx}, {fy})");
    }
    let white = frame.pixels().filter(|p| p[0] == 255).count() as f64;
    // Each pin is a disc of radius 4 (about 49 px); the median blur and the
    // threshold may shave a few edge pixels but add no background.
    let disc = pins.len() as f64 * 49.0;
    assert!(
        white > 0.8 * disc && white < 1.1 * disc,
        "{white} white px vs {disc}"
    );
    assert_eq!(frame.get_pixel(2, 2)[0], 0, "corner background");
}

#[test]
fn mean_method_agrees_with_gaussian_on_clean_pins() {
    let image = DynamicImage::ImageRgb8(synthetic_camera_image());
    let gaussian = bristol(&image).unwrap();
    let config = PreprocessConfig {
        threshold_method: ThresholdMethod::Mean,
        ..PreprocessConfig::default()
    };
    let mean = apply(&config, &image).unwrap();
    let differ = gaussian
        .pixels()
        .zip(mean.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(differ < 256 * 256 / 100, "{differ} pixels differ");
}

#[test]
fn crop_outside_the_image_is_an_error() {
    let small = DynamicImage::ImageLuma8(GrayImage::new(320, 240));
    let err = bristol(&small).unwrap_err();
    assert!(
        matches!(
            err,
            HwError::Preprocess {
                source: tactrace_vision::VisionError::Crop {
                    width: 320,
                    height: 240,
                    ..
                }
            }
        ),
        "{err}"
    );
}

#[test]
fn invalid_settings_are_rejected() {
    let even_block = PreprocessConfig {
        threshold: Some((60, -5.0)),
        ..PreprocessConfig::default()
    };
    let err = even_block.validate().unwrap_err();
    assert!(
        matches!(err, HwError::Preprocess { .. }) && err.to_string().contains("threshold"),
        "{err}"
    );
    let empty_crop = PreprocessConfig {
        crop: Some([10, 10, 10, 20]),
        ..PreprocessConfig::default()
    };
    assert!(empty_crop.validate().is_err());
    let unknown = serde_json::from_str::<PreprocessConfig>(r#"{"crops": [0, 0, 1, 1]}"#);
    assert!(unknown.is_err());
}

#[test]
fn the_rig_table_reads_into_the_shared_preprocessing() {
    let params = PreprocessConfig::default().to_params();
    assert_eq!(params.crop, Some([190, 132, 446, 388]));
    assert_eq!(params.median_blur, Some(5));
    assert_eq!(
        params.threshold,
        Some(tactrace_vision::Threshold::AdaptiveGaussian { block: 61, c: -5.0 })
    );
    assert_eq!(params.resize.map(|r| r.size), Some([256, 256]));
    assert_eq!(
        PreprocessConfig::grayscale_only().to_params(),
        tactrace_vision::PreprocessParams::default()
    );
}

#[test]
fn collection_meta_reproduces_the_default() {
    let Some(data) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let text = std::fs::read_to_string(data.join("collection_meta.json")).unwrap();
    let config = PreprocessConfig::from_collection_meta(&text).unwrap();
    assert_eq!(config, PreprocessConfig::default());
    assert!(PreprocessConfig::from_collection_meta(r#"{"crop": [1, 2]}"#).is_err());
    assert!(PreprocessConfig::from_collection_meta("not json").is_err());
    let none = PreprocessConfig::from_collection_meta("{}").unwrap();
    assert_eq!((none.crop, none.threshold), (None, None));
}

fn write_gray(dir: &Path, name: &str, value: u8) -> PathBuf {
    let path = dir.join(name);
    GrayImage::from_pixel(8, 6, image::Luma([value]))
        .save(&path)
        .unwrap();
    path
}

#[test]
fn folder_source_uses_natural_order_and_ends() {
    let dir = tempfile::tempdir().unwrap();
    for (name, value) in [
        ("frame_10_0.png", 10),
        ("frame_2_0.png", 2),
        ("frame_1_0.png", 1),
    ] {
        write_gray(dir.path(), name, value);
    }
    std::fs::write(dir.path().join("notes.txt"), "not an image").unwrap();
    let source = FolderSource::new(dir.path()).unwrap();
    let mut sensor = CameraSensor::new(
        source,
        PreprocessConfig::grayscale_only().validate().unwrap(),
    );
    let values: Vec<u8> = (0..3)
        .map(|_| sensor.capture().unwrap().get_pixel(0, 0)[0])
        .collect();
    assert_eq!(values, [1, 2, 10]);
    assert!(matches!(
        sensor.capture(),
        Err(SensorError::ReplayExhausted { count: 3 })
    ));
    assert_eq!(sensor.captured(), 3);
}

#[test]
fn folder_source_loops_on_request_and_rejects_empty_folders() {
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        FolderSource::new(dir.path()),
        Err(HwError::EmptyFolder { .. })
    ));
    write_gray(dir.path(), "a.png", 5);
    let mut source = FolderSource::new(dir.path()).unwrap().looping(true);
    for _ in 0..3 {
        assert_eq!(source.grab().unwrap().to_luma8().get_pixel(0, 0)[0], 5);
    }
}

#[test]
fn camera_sensor_round_trip_through_a_folder() {
    let dir = tempfile::tempdir().unwrap();
    synthetic_camera_image()
        .save(dir.path().join("cam_0.png"))
        .unwrap();
    let direct = bristol(&DynamicImage::ImageRgb8(synthetic_camera_image())).unwrap();
    let preprocess = PreprocessConfig::default().validate().unwrap();
    let mut sensor = CameraSensor::new(FolderSource::new(dir.path()).unwrap(), preprocess);
    let frame = sensor.capture().unwrap();
    assert_eq!(frame, direct);
}

#[test]
fn natural_order_compares_numbers_by_value() {
    use std::cmp::Ordering::*;
    assert_eq!(natural_cmp("frame_2_0.png", "frame_10_0.png"), Less);
    assert_eq!(natural_cmp("a10", "a9"), Greater);
    assert_eq!(natural_cmp("a007", "a7"), Greater);
    assert_eq!(natural_cmp("init_0.png", "init_0.png"), Equal);
}

#[cfg(unix)]
#[test]
fn command_source_runs_a_program_and_reads_its_output() {
    let dir = tempfile::tempdir().unwrap();
    let original = write_gray(dir.path(), "original.png", 77);
    let output = dir.path().join("out.png");
    let args = vec![
        original.to_string_lossy().into_owned(),
        OUTPUT_PLACEHOLDER.to_string(),
    ];
    let mut source = CommandSource::new("cp", args, &output);
    assert_eq!(source.grab().unwrap().to_luma8().get_pixel(3, 3)[0], 77);
    assert!(output.exists());
}

#[cfg(unix)]
#[test]
fn command_source_reports_failures_and_timeouts() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.png");
    let mut failing = CommandSource::new(
        "sh",
        vec!["-c".into(), "echo no camera >&2; exit 3".into()],
        &output,
    );
    let err = failing.grab().unwrap_err();
    assert!(
        matches!(&err, HwError::Command { reason, .. } if reason.contains("no camera")),
        "{err}"
    );
    let mut silent = CommandSource::new("true", vec![], &output);
    assert!(matches!(silent.grab(), Err(HwError::Command { .. })));
    let mut slow = CommandSource::new("sleep", vec!["5".into()], &output)
        .with_timeout(std::time::Duration::from_millis(200));
    let start = std::time::Instant::now();
    let err = slow.grab().unwrap_err();
    assert!(start.elapsed().as_secs_f64() < 2.0, "{err}");
    let mut missing = CommandSource::new("/nonexistent/capture-tool", vec![], &output);
    assert!(matches!(missing.grab(), Err(HwError::Command { .. })));
}

/// A camera image made from a real binarised TacTip frame: blurred (optics),
/// dimmed to 55-135 grey levels, lit unevenly, with seeded noise, and
/// placed at the crop origin of a 640x480 image.
fn camera_image_from_frame(frame: &GrayImage, seed: u64) -> GrayImage {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let soft = image::imageops::blur(frame, 1.2);
    GrayImage::from_fn(640, 480, |x, y| {
        let light = 55.0 + 30.0 * x as f64 / 640.0 + rng.random_range(-4.0..4.0);
        let inside = (190..446).contains(&x) && (132..388).contains(&y);
        let pin = if inside {
            soft.get_pixel(x - 190, y - 132)[0] as f64
        } else {
            0.0
        };
        image::Luma([(light + 80.0 * pin / 255.0).round().clamp(0.0, 255.0) as u8])
    })
}

#[test]
fn real_frame_survives_the_camera_round_trip() {
    let Some(data) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let original = image::open(data.join("frames/init_0.png")).unwrap();
    let original = original.to_luma8();
    let camera = DynamicImage::ImageLuma8(camera_image_from_frame(&original, 11));
    let start = std::time::Instant::now();
    let frame = bristol(&camera).unwrap();
    eprintln!("preprocessing one 640x480 frame: {:?}", start.elapsed());
    let white = |p: &image::Luma<u8>| p[0] > 127;
    let both = original
        .pixels()
        .zip(frame.pixels())
        .filter(|(a, b)| white(a) && white(b))
        .count();
    let either = original
        .pixels()
        .zip(frame.pixels())
        .filter(|(a, b)| white(a) || white(b))
        .count();
    let iou = both as f64 / either.max(1) as f64;
    let agree = original
        .pixels()
        .zip(frame.pixels())
        .filter(|(a, b)| white(a) == white(b))
        .count();
    let agreement = agree as f64 / (256.0 * 256.0);
    eprintln!("init_0 round trip: IoU {iou:.3}, pixel agreement {agreement:.4}");
    assert!(iou > 0.7, "IoU {iou}");
    assert!(agreement > 0.95, "agreement {agreement}");
}
