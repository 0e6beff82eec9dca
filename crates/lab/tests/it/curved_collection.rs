//! The 3D collections' curved patches and taps along the edge.
//!
//! - Curved patches (surface_3d): the flat set's labels at the same seed,
//!   other pin fields (a convex patch presses less of the dome than the
//!   floor at the same depth, a concave one more), each label the true
//!   label of its pose on its patch, recorded in the meta, refused for an
//!   edge task and beyond 1/20 per mm.
//! - Along the edge (edge tasks): the same labels, taps spread over the
//!   edge (their poses' edge points far apart), refused for surface_3d.
use tactrace_control::Task;
use tactrace_lab::collect::Collected;
use tactrace_lab::collect3d::{collect_3d, tap_edge_frame, tap_patch, Collect3dConfig};
use tactrace_servo::RigConfig;
use tactrace_shape3d::{pose_of_label, true_label, HeightField, ObjectConfig, Surface};
use tactrace_store::TapData;

fn object(name: &str) -> Surface {
    ObjectConfig::named(name).unwrap().build().unwrap()
}

/// `cfg`'s taps on the built-in object `name`.
fn collect(cfg: &Collect3dConfig, name: &str) -> Collected {
    let rig = RigConfig::default();
    collect_3d(&rig, &object(name), cfg, name, |_| {}).unwrap()
}

fn surface_taps(curvature_per_mm: f64) -> TapData {
    let cfg = Collect3dConfig {
        samples: 24,
        seed: 5,
        curvature_per_mm,
        ..Collect3dConfig::default()
    };
    collect(&cfg, "plane").data
}

/// Mean pin displacement of tap `i`, px.
fn mean_displacement(d: &TapData, i: usize) -> f32 {
    let p = d.meta.pins;
    let r = &d.inputs[i * 2 * p..(i + 1) * 2 * p];
    (0..p).map(|k| f32::hypot(r[k], r[p + k])).sum::<f32>() / p as f32
}

#[test]
fn curved_patches_keep_the_labels_and_press_by_their_curvature() {
    let flat = surface_taps(0.0);
    let curved = surface_taps(0.05);
    assert_eq!(
        flat.targets, curved.targets,
        "the patch is not in the labels"
    );
    let cfg = Collect3dConfig {
        samples: 24,
        seed: 5,
        curvature_per_mm: 0.05,
        ..Collect3dConfig::default()
    };
    let (mut convex, mut concave) = (0, 0);
    for i in 0..24 {
        let patch = tap_patch(&cfg, i).unwrap().expect("a patch");
        // Which way the patch curves: its height 10 mm out, both ways.
        let h = |x: f64, y: f64| {
            patch.column_top(
                tactrace_shape3d::Vec3::new(x, y, -50.0),
                tactrace_shape3d::Vec3::z(),
                100.0,
            ) - 50.0
        };
        let mean = (h(10.0, 0.0) + h(-10.0, 0.0) + h(0.0, 10.0) + h(0.0, -10.0)) / 4.0;
        let (f, c) = (mean_displacement(&flat, i), mean_displacement(&curved, i));
        if mean < -0.5 {
            convex += 1;
            assert!(c < f, "tap {i}: a convex patch presses less ({c} vs {f})");
        } else if mean > 0.5 {
            concave += 1;
            assert!(c > f, "tap {i}: a concave patch presses more ({c} vs {f})");
        }
        // The label is the true label of the pose on the patch.
        let row = &curved.targets[3 * i..3 * i + 3];
        let s = [
            0.0,
            0.0,
            f64::from(row[0]),
            f64::from(row[1]),
            f64::from(row[2]),
            0.0,
        ];
        let pose = pose_of_label(&nalgebra::Isometry3::identity(), s);
        let truth = true_label(patch.as_ref(), pose).unwrap();
        for (k, want) in [(2, s[2]), (3, s[3]), (4, s[4])] {
            assert!(
                (truth[k] - want).abs() < 1e-3,
                "tap {i} component {k}: {truth:?}"
            );
        }
    }
    assert!(
        convex >= 3 && concave >= 3,
        "{convex} convex, {concave} concave"
    );
    let settings = &curved.meta.settings["collect_3d"];
    assert_eq!(settings["curvature_per_mm"], 0.05);
    // Refused: an edge task, a curvature beyond 1/20 per mm.
    let edge = Collect3dConfig {
        task: Task::Edge5d,
        curvature_per_mm: 0.01,
        ..Collect3dConfig::default()
    };
    assert!(edge.validate().is_err());
    let sharp = Collect3dConfig {
        curvature_per_mm: 0.06,
        ..Collect3dConfig::default()
    };
    assert!(sharp.validate().is_err());
    assert!(HeightField::quadric([0.06, 0.0], 0.0).is_err());
}

#[test]
fn taps_along_the_edge_keep_the_labels_and_spread_over_it() {
    let cfg = |along_edge: bool| Collect3dConfig {
        samples: 16,
        seed: 6,
        task: Task::Edge5d,
        at_mm: [0.0, 40.0],
        x_range_mm: 3.0,
        tilt_range_deg: 10.0,
        rz_range_deg: 30.0,
        along_edge,
        ..Collect3dConfig::default()
    };
    let foil = object("foil");
    let taps =
        |along| collect_3d(&RigConfig::default(), &foil, &cfg(along), "foil", |_| {}).unwrap();
    let (one, along) = (taps(false), taps(true));
    assert_eq!(one.data.targets, along.data.targets);
    // The foil's face tilts 0-29 deg along its edge and the angle to its
    // outline wall changes: the same labels and noise elsewhere on it
    // give other pin fields (at one point the set repeats bit for bit).
    let diff: f32 = one
        .data
        .inputs
        .iter()
        .zip(&along.data.inputs)
        .map(|(a, b)| (a - b).abs())
        .sum::<f32>()
        / one.data.inputs.len() as f32;
    assert!(diff > 0.01, "mean field difference {diff} px");
    assert_eq!(one.data.inputs, taps(false).data.inputs);
    assert_eq!(along.data.meta.settings["collect_3d"]["along_edge"], true);
    // The taps' edge points spread round the edge (radius 40 mm).
    let edge = object("foil").edge().unwrap();
    let points: Vec<_> = (0..16)
        .map(|i| tap_edge_frame(&cfg(true), &edge, i).translation.vector)
        .collect();
    let spread = points
        .iter()
        .flat_map(|a| points.iter().map(move |b| (a - b).norm()))
        .fold(0.0, f64::max);
    assert!(
        spread > 60.0,
        "the taps span {spread} mm of a 80 mm wide edge"
    );
    let surface = Collect3dConfig {
        along_edge: true,
        ..Collect3dConfig::default()
    };
    assert!(surface.validate().is_err());
}
