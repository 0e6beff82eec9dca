//! The real rig's camera read through a sensor file (`sensor =
//! "sensor.toml"` in the rig file): the same preprocessing stage as
//! `import` and `predict --image`, on the folder camera the hardware
//! tests use; one way to read the camera (a sensor file and the rig's own
//! `[preprocess]` / `[blob]` tables together are refused); a sensor file
//! naming the small-pin detector runs its taps on the fake UR5.
use image::{Rgb, RgbImage};
use std::path::Path;
use tactrace_hw::{FakeUrController, FakeUrOptions, StateInterface};
use tactrace_lab::collect::CollectConfig;
use tactrace_lab::hardware::{collect_hardware, HardwareConfig, StopFlag};
use tactrace_lab::LabError;
use tactrace_sensor::{EdgeTap, Frame, PinLayout, TacTipConfig, TacTipModel};
use tactrace_servo::pose_at_edge;
use tactrace_store::{SensorSummary, SightFile};
use tactrace_vision::{
    detect_blobs, BlobParams, DetectorParams, LayoutKind, MaskCircle, PinExtractor,
    PreprocessParams, Threshold,
};

/// The crop of the synthetic camera image: the dome's square.
const CROP: [u32; 4] = [30, 20, 190, 180];
/// The dome in the cropped frame: centre and radius, px.
const DOME: ([f64; 2], f64) = ([80.0, 80.0], 62.0);

/// Pin centres in the cropped frame: a hexagonal lattice (pitch 12 px)
/// inside 52 px of the dome's centre.
fn pins() -> Vec<[f64; 2]> {
    let ([cx, cy], pitch) = (DOME.0, 12.0);
    let mut out = Vec::new();
    for row in -5i32..=5 {
        for col in -6i32..=6 {
            let x = cx + pitch * (f64::from(col) + 0.5 * f64::from(row.rem_euclid(2)));
            let y = cy + pitch * 0.866 * f64::from(row);
            if (x - cx).hypot(y - cy) <= 52.0 {
                out.push([x, y]);
            }
        }
    }
    out
}

/// A raw 220 x 200 colour camera image: bright round pins (radius 3 px) on
/// an unevenly lit skin, a bright rim round the dome (radius 64-68 px,
/// outside the mask) and specks in the corners, the dome at the crop.
fn camera_image() -> RgbImage {
    let pins = pins();
    let ([cx, cy], (x0, y0)) = (DOME.0, (f64::from(CROP[0]), f64::from(CROP[1])));
    RgbImage::from_fn(220, 200, |x, y| {
        let (fx, fy) = (f64::from(x) - x0, f64::from(y) - y0);
        let base = 40.0 + 30.0 * f64::from(x) / 220.0;
        let r = (fx - cx).hypot(fy - cy);
        let pin = pins.iter().any(|p| (fx - p[0]).hypot(fy - p[1]) <= 3.0);
        let rim = (64.0..=68.0).contains(&r);
        let speck = (fx - 8.0).hypot(fy - 8.0) <= 3.0;
        let v = if pin || rim || speck {
            base + 100.0
        } else {
            base
        } as u8;
        Rgb([v.saturating_add(6), v, v.saturating_sub(6)])
    })
}

/// The sensor file for these images: crop, dome mask, the Bristol
/// adaptive threshold, the blob detector of the real 127-pin frames.
fn sensor_file(pins: usize) -> SightFile {
    SightFile {
        sensor: SensorSummary {
            pins,
            layout: LayoutKind::Hexagonal,
            spacing_px: 12.0,
            pin_pixels: 29.0,
            frame_size: [220, 200],
        },
        preprocess: PreprocessParams {
            crop: Some(CROP),
            mask: Some(MaskCircle {
                centre: DOME.0,
                radius: DOME.1,
            }),
            threshold: Some(Threshold::AdaptiveGaussian { block: 21, c: -5.0 }),
            ..PreprocessParams::default()
        },
        detect: DetectorParams::Blobs(BlobParams::preset("real256").unwrap()),
    }
}

/// A rig file replaying the folder `frames`, with `extra` lines.
fn rig_text(frames: &Path, extra: &str) -> String {
    format!(
        "{extra}\n[arm]\nhost = \"127.0.0.1\"\n\n[camera.folder]\npath = {:?}\nlooping = true\n\n\
         [workspace]\nmin = [-50.0, -50.0, -20.0]\nmax = [50.0, 50.0, 20.0]\n\n\
         [start]\nx_mm = 0.0\ny_mm = 0.0\n",
        frames.display().to_string()
    )
}

/// A folder of one camera image, the sensor file beside the rig file.
fn rig_folder(dir: &Path) -> std::path::PathBuf {
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    camera_image().save(frames.join("cam_0.png")).unwrap();
    std::fs::write(dir.join("sensor.toml"), sensor_file(pins().len()).to_toml()).unwrap();
    frames
}

#[test]
fn the_rig_camera_reads_a_raw_colour_frame_through_a_sensor_file() {
    let dir = tempfile::tempdir().unwrap();
    let frames = rig_folder(dir.path());
    let rig = dir.path().join("rig.toml");
    std::fs::write(&rig, rig_text(&frames, "sensor = \"sensor.toml\"")).unwrap();
    // From another working directory: the sensor file is found beside the rig file.
    let cfg = HardwareConfig::read(&rig).unwrap();
    assert!(cfg.sensor.as_ref().unwrap().is_absolute());
    cfg.validate().unwrap();
    let sight = cfg.sight().unwrap();
    assert_eq!(sight.frame_size, Some([220, 200]));
    let settings = cfg.servo_settings().unwrap();
    let blob = BlobParams::preset("real256").unwrap();
    assert_eq!(*settings.detect(), DetectorParams::Blobs(blob.clone()));

    let frame = cfg.camera().unwrap().capture().unwrap();
    assert_eq!(frame.dimensions(), (160, 160), "cropped");
    // A run folder's copy of the rig (config.toml) reads back as it is.
    let copy = toml::to_string(&cfg).unwrap();
    let again = HardwareConfig::from_toml(&copy, "config.toml").unwrap();
    assert_eq!(again.sensor, cfg.sensor);
    again.validate().unwrap();
    let found: Vec<[f64; 2]> = detect_blobs(&frame, &blob)
        .iter()
        .map(|k| [k.x, k.y])
        .collect();
    let expected = pins();
    assert_eq!(found.len(), expected.len(), "every pin, no rim, no speck");
    for p in &expected {
        let nearest = found
            .iter()
            .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 0.5,
            "pin at {p:?}: nearest detection {nearest} px"
        );
    }
    // The same image through the stage import uses gives the same frame.
    let stage = sensor_file(expected.len()).sight().check(220, 200).unwrap();
    let direct = stage
        .preprocess(&image::DynamicImage::ImageRgb8(camera_image()))
        .unwrap();
    assert_eq!(frame, direct);
}

#[test]
fn a_camera_image_of_another_size_than_the_sensor_files_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = rig_folder(dir.path());
    std::fs::remove_file(frames.join("cam_0.png")).unwrap();
    RgbImage::new(240, 200)
        .save(frames.join("cam_0.png"))
        .unwrap();
    let rig = dir.path().join("rig.toml");
    std::fs::write(&rig, rig_text(&frames, "sensor = \"sensor.toml\"")).unwrap();
    let cfg = HardwareConfig::read(&rig).unwrap();
    let err = cfg.camera().unwrap().capture().unwrap_err().to_string();
    assert!(err.contains("220") && err.contains("240"), "{err}");
}

#[test]
fn a_sensor_file_and_the_rigs_own_tables_together_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = rig_folder(dir.path());
    for table in ["[preprocess]\nmedian_blur = 3", "[blob]\nmin_area = 4.0"] {
        let text = rig_text(&frames, "sensor = \"sensor.toml\"") + "\n" + table + "\n";
        let err = HardwareConfig::from_toml(&text, "rig.toml").unwrap_err();
        assert!(err.is_bad_input(), "{err}");
        assert!(err.to_string().contains("keep one way"), "{err}");
    }
    // Built in code: a sensor file with tables moved off their defaults.
    let rig = dir.path().join("rig.toml");
    std::fs::write(&rig, rig_text(&frames, "sensor = \"sensor.toml\"")).unwrap();
    let mut cfg = HardwareConfig::read(&rig).unwrap();
    cfg.preprocess.median_blur = Some(3);
    let err = cfg.validate().unwrap_err();
    assert!(matches!(err, LabError::Config(_)), "{err}");
    // Without a sensor file the old tables still read the camera.
    let old =
        rig_text(&frames, "") + "[preprocess]\ncrop = [30, 20, 190, 180]\nsize = [160, 160]\n";
    let cfg = HardwareConfig::from_toml(&old, "rig.toml").unwrap();
    let frame = cfg.camera().unwrap().capture().unwrap();
    assert_eq!(frame.dimensions(), (160, 160));
}

/// A small-pin TacTip (127 pins about 3 px wide, 7 px apart, on rings in
/// 128 x 128 binarised frames): its rest frame and `n` pressed frames.
fn small_pin_frames(n: usize) -> (Frame, Vec<Frame>) {
    let mut cfg = TacTipConfig::default();
    cfg.geometry.layout = PinLayout::Rings;
    cfg.geometry.pin_radius_mm = 0.7;
    cfg.camera.width = 128;
    cfg.camera.height = 128;
    cfg.camera.centre_px = [63.4, 64.5];
    cfg.camera.focal_px = 39.0;
    let model = TacTipModel::new(cfg).unwrap();
    let rest = model.render(model.rest_pins(), None);
    let taps = (0..n)
        .map(|k| {
            let tap = EdgeTap {
                r_mm: -4.0 + k as f64,
                theta_deg: 10.0 * k as f64 - 20.0,
                ..EdgeTap::default()
            };
            model.render(&model.edge_tap_pins(&tap), None)
        })
        .collect();
    (rest, taps)
}

/// A rig whose sensor file names the small-pin detector runs its taps on
/// the fake UR5: the collection reads every tap's pins with that
/// detector, against the pins it found in the frame taken at the start,
/// exactly as the detector reads the same frames off the rig.
#[test]
fn a_small_pin_sensor_file_on_the_rig_runs_its_taps_on_the_fake_ur5() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let (rest, taps) = small_pin_frames(6);
    // The camera replays the frame taken at the start, then the taps.
    for (k, f) in std::iter::once(&rest).chain(&taps).enumerate() {
        f.save(frames.join(format!("{k:05}.png"))).unwrap();
    }
    let spots = DetectorParams::Spots(tactrace_vision::SpotParams {
        level: 127,
        min_pixels: 1,
        max_pixels: 16,
        max_cluster_pixels: 48,
        connectivity: Default::default(),
    });
    let file = SightFile {
        sensor: SensorSummary {
            pins: 127,
            layout: LayoutKind::Rings,
            spacing_px: 7.0,
            pin_pixels: 7.0,
            frame_size: [128, 128],
        },
        preprocess: PreprocessParams::default(),
        detect: spots.clone(),
    };
    std::fs::write(dir.path().join("sensor.toml"), file.to_toml()).unwrap();
    let rig = dir.path().join("rig.toml");
    std::fs::write(&rig, rig_text(&frames, "sensor = \"sensor.toml\"")).unwrap();
    let mut cfg = HardwareConfig::read(&rig).unwrap();
    let collect = CollectConfig {
        samples: taps.len(),
        theta_range_deg: 5.0,
        r_range_mm: 2.0,
        ..CollectConfig::default()
    };
    let (edge, normal) = tactrace_lab::hardware::collection_edge(&cfg);
    let first = pose_at_edge(edge, normal, 0.0, -5.0, cfg.tap.height_mm);
    let fake = FakeUrController::start(FakeUrOptions {
        start: [
            first.x / 1000.0,
            first.y / 1000.0,
            (first.z + 5.0) / 1000.0,
            0.0,
            0.0,
            first.rz.to_radians(),
        ],
        state: StateInterface::Rtde,
        ..FakeUrOptions::default()
    })
    .unwrap();
    cfg.arm = fake.config();
    cfg.validate().unwrap();
    assert_eq!(cfg.servo_settings().unwrap().detect(), &spots);
    let got = collect_hardware(&cfg, &collect, "rig", &StopFlag::new(), |_| {}).unwrap();
    let extractor = PinExtractor::with_detector(&rest, spots.check().unwrap()).unwrap();
    let pins = extractor.tracker.reference();
    assert_eq!(pins.len(), 127, "every pin found at rest");
    let expected: Vec<f32> = taps
        .iter()
        .flat_map(|f| extractor.extract(f).unwrap().displacement(pins))
        .collect();
    assert_eq!(got.data.inputs, expected);
}
