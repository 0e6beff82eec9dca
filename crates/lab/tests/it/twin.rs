//! The simulated twin of a labelled data set: labels kept, pin order and
//! rest layout of the reference frame, reproducible, clear errors; on the
//! real Bristol set (when present) the twin's fields agree with the real ones.
use std::path::{Path, PathBuf};
use tactrace_lab::import::import;
use tactrace_lab::twin::simulate_twin;
use tactrace_sensor::{TacTipConfig, TacTipModel};
use tactrace_store::collection::{RowSelection, TapColumns};
use tactrace_store::LabelledCollection;
use tactrace_vision::BlobParams;

fn temp_dir(tag: &str) -> PathBuf {
    tempfile::Builder::new()
        .prefix(&format!("tactrace-twin-{tag}-"))
        .tempdir()
        .unwrap()
        .keep()
}

/// A rendered rest frame and a labels CSV (r, theta, dz, shear x, y, rz).
fn synthetic_set(dir: &Path, rows: &[[f32; 6]]) -> LabelledCollection {
    let model = TacTipModel::new(TacTipConfig::default()).unwrap();
    let rest = model.render(model.rest_pins(), None);
    let reference = dir.join("init_0.png");
    std::fs::write(
        &reference,
        tactrace_store::frame_file::png_bytes(&rest, "rest").unwrap(),
    )
    .unwrap();
    let mut csv = String::from("image_name,pose_2,pose_6,pose_3,move_1,move_2,move_6\n");
    for (k, v) in rows.iter().enumerate() {
        let cells: Vec<String> = v.iter().map(|x| x.to_string()).collect();
        csv.push_str(&format!("frame_{k}.png,{}\n", cells.join(",")));
    }
    let targets = dir.join("targets.csv");
    std::fs::write(&targets, csv).unwrap();
    LabelledCollection::new(dir.to_path_buf(), targets, reference)
        .with_blob(BlobParams::preset("sim").unwrap())
        .unwrap()
}

const ROWS: [[f32; 6]; 3] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.0, 20.0, 0.5, 0.5, -0.3, 2.0],
    [-3.0, -30.0, -0.5, 0.0, 0.4, -1.0],
];

#[test]
fn the_twin_keeps_labels_and_order_and_is_reproducible() {
    let dir = temp_dir("synthetic");
    let cfg = synthetic_set(&dir, &ROWS);
    // Pin jitter on (the fitted default is 0), so that seeds differ below.
    let mut sensor = TacTipConfig::default();
    sensor.nuisance.pin_jitter_px = 0.2;
    let a = simulate_twin(&cfg, &sensor, 3, &|| {}).unwrap();
    let b = simulate_twin(&cfg, &sensor, 3, &|| {}).unwrap();
    assert_eq!(a.data.len(), 3);
    assert_eq!(a.data.meta.pins, 127);
    assert_eq!(a.frames_with_missing_pins, 0);
    let labels: Vec<f32> = ROWS.iter().flat_map(|r| [r[0], r[1]]).collect();
    assert_eq!(a.data.targets, labels);
    assert_eq!(a.data.inputs, b.data.inputs, "same seed, same frames");
    // Different taps give clearly different fields (mean |difference| > 1 px).
    let row = |k: usize| &a.data.inputs[k * 254..(k + 1) * 254];
    let diff: f32 = row(1).iter().zip(row(2)).map(|(x, y)| (x - y).abs()).sum();
    assert!(diff / 254.0 > 1.0, "mean difference {}", diff / 254.0);
    // Another seed draws other pin jitter.
    let c = simulate_twin(&cfg, &sensor, 4, &|| {}).unwrap();
    assert_ne!(a.data.inputs, c.data.inputs);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_label_column_is_named_in_the_error() {
    let dir = temp_dir("column");
    let set = synthetic_set(&dir, &ROWS);
    let cfg = set.clone().with_tap(TapColumns {
        depth: Some("depth_mm".into()),
        ..set.tap().clone()
    });
    let err = simulate_twin(&cfg, &TacTipConfig::default(), 3, &|| {})
        .err()
        .expect("no such column");
    assert!(err.to_string().contains("depth_mm"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

fn real_dir() -> Option<PathBuf> {
    tactrace_testdata::real_edge_set()
}

/// Cosine of two displacement vectors.
fn cosine(a: &[f32], b: &[f32]) -> f64 {
    let dot: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64) * (*y as f64))
        .sum();
    let norm = |v: &[f32]| v.iter().map(|x| (*x as f64).powi(2)).sum::<f64>().sqrt();
    dot / (norm(a) * norm(b))
}

#[test]
fn the_twin_of_real_frames_shares_their_pin_order_and_agrees_with_them() {
    let Some(dir) = real_dir() else { return };
    let collection = LabelledCollection::bristol(&dir).with_rows(RowSelection {
        limit: Some(80),
        keep: None,
    });
    let twin = simulate_twin(&collection, &TacTipConfig::default(), 1, &|| {}).unwrap();
    let real = import(&collection, &|| {}).unwrap();
    assert_eq!(twin.data.len(), real.data.len());
    assert_eq!(twin.data.targets, real.data.targets);
    assert_eq!(twin.data.meta.reference_pins, real.data.meta.reference_pins);
    let mut cosines: Vec<f64> = (0..twin.data.len())
        .map(|k| {
            let r = k * 254..(k + 1) * 254;
            cosine(&twin.data.inputs[r.clone()], &real.data.inputs[r])
        })
        .collect();
    cosines.sort_by(f64::total_cmp);
    let median = cosines[cosines.len() / 2];
    eprintln!("twin vs real, 80 frames: median cosine {median:.3}");
    assert!(median > 0.9, "median cosine {median}");
}
