//! The simulated camera and the blob detector agree: every pin of a
//! rendered frame is found once, close to the centre it was drawn at, on
//! the grey anti-aliased frame and on the binarised one the default camera
//! gives (as the real frames are).
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_sensor::TacTipModel;
use tactrace_servo::{pose_at_edge, RigConfig};
use tactrace_vision::detect_blobs;

/// Largest distance from a rendered pin centre to its nearest keypoint, px,
/// after checking that there is exactly one keypoint per pin.
fn worst_detection_error(binarise: Option<u8>, r_mm: f64, theta_deg: f64) -> f64 {
    let mut rig = RigConfig::default();
    rig.sensor.camera.binarise_above = binarise;
    let model = TacTipModel::new(rig.sensor.clone()).unwrap();
    let disk = builtin_shape(BuiltinShape::Disk);
    let (edge, normal) = disk.at_arc_length(0.0);
    let depth = rig.tap.nominal_indentation_mm();
    let pins = model.pins(
        &disk,
        pose_at_edge(edge, normal, r_mm, theta_deg, -depth),
        None,
    );
    let keypoints = detect_blobs(&model.render(&pins, None), &rig.blob);
    assert_eq!(keypoints.len(), pins.len(), "one keypoint per pin");
    pins.iter()
        .map(|p| {
            keypoints
                .iter()
                .map(|k| (k.x - p[0]).hypot(k.y - p[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

#[test]
fn grey_frames_give_every_pin_within_0_3_px() {
    for (r, theta) in [(0.0, 0.0), (2.0, 10.0), (-3.0, -30.0), (4.0, 40.0)] {
        let worst = worst_detection_error(None, r, theta);
        assert!(worst < 0.3, "r {r} theta {theta}: {worst} px");
    }
}

#[test]
fn binarised_frames_give_every_pin_within_0_4_px() {
    // Thresholding a disc of 2-4 px radius quantises its centre.
    for (r, theta) in [(0.0, 0.0), (2.0, 10.0), (-3.0, -30.0), (4.0, 40.0)] {
        let worst = worst_detection_error(Some(127), r, theta);
        assert!(worst < 0.4, "r {r} theta {theta}: {worst} px");
    }
}
