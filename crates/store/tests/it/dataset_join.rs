//! Several datasets as one training set: a dataset cut in two and joined
//! again is the same rows, and every difference a model cannot train
//! across is refused by name.
use std::path::Path;
use tactrace_store::dataset_join::{check_alike, check_frames_alike};
use tactrace_store::training_record::dataset_hash;
use tactrace_store::{
    join_datasets, join_frames, DatasetId, DatasetMeta, DatasetMismatch, FramesInfo, ImageFrames,
    StoreError, TapData, TrainingRecord,
};

/// `n` rows over a 3 x 3 grid of pins, targets `x` (mm) and `angle`
/// (deg, circular), each row named by its image; `extra` keys replace
/// the meta's.
fn data(n: usize, extra: serde_json::Value) -> TapData {
    let pins: Vec<[f64; 2]> = (0..9)
        .map(|k| [(k % 3) as f64 * 10.0, (k / 3) as f64 * 10.0])
        .collect();
    let mut meta = serde_json::json!({
        "source": "real", "origin": "a", "seed": null, "samples": n, "pins": 9,
        "targets": ["x (mm)", "angle (deg)"], "target_names": ["x", "angle"],
        "target_units": ["mm", "deg"], "target_circular": [false, true],
        "frames_with_missing_pins": 1, "reference_pins": pins, "settings": {},
        "tactrace_version": "t", "frames_total": n, "frames_fully_tracked": n - 1,
        "images": (0..n).map(|k| format!("frame_{k}.png")).collect::<Vec<_>>(),
    });
    for (k, v) in extra.as_object().expect("an object") {
        meta[k] = v.clone();
    }
    let meta: DatasetMeta = serde_json::from_value(meta).expect("meta");
    TapData {
        inputs: (0..n * 18).map(|v| (v as f32 * 0.37).sin()).collect(),
        targets: (0..n * 2).map(|v| v as f32 * 0.5).collect(),
        meta,
    }
}

fn no_extra() -> serde_json::Value {
    serde_json::json!({})
}

#[test]
fn two_halves_joined_are_the_whole_row_for_row() {
    let whole = data(10, no_extra());
    let first: Vec<usize> = (0..4).collect();
    let second: Vec<usize> = (4..10).collect();
    let (a, b) = (whole.subset(&first), whole.subset(&second));
    let joined = join_datasets(&[(Path::new("a"), &a), (Path::new("b"), &b)]).expect("alike");
    assert_eq!(joined.inputs, whole.inputs);
    assert_eq!(joined.targets, whole.targets);
    assert_eq!(joined.meta.images, whole.meta.images);
    assert_eq!(joined.len(), 10);
    assert_eq!(dataset_hash(&joined), dataset_hash(&whole));
    // The counts are summed, what both share kept.
    assert_eq!(joined.meta.frames_with_missing_pins, 2);
    assert_eq!(joined.meta.origin, "a + a");
    assert_eq!(joined.meta.source, "real");
}

#[test]
fn what_the_parts_disagree_on_is_said_in_the_joined_meta() {
    let a = data(3, no_extra());
    let b = data(
        2,
        serde_json::json!({"source": "simulated", "images": [], "seed": 4}),
    );
    let joined = join_datasets(&[(Path::new("a"), &a), (Path::new("b"), &b)]).expect("alike");
    assert_eq!(joined.meta.source, "mixed");
    assert!(joined.meta.images.is_empty(), "not every row is named");
    assert_eq!(joined.meta.seed, None);
    assert_eq!(joined.meta.tracking.frames_total, 5);
}

/// The mismatch `join_datasets` refuses `b` beside `a` with, naming both.
fn refusal(a: &TapData, b: &TapData) -> DatasetMismatch {
    let err = join_datasets(&[(Path::new("first"), a), (Path::new("second"), b)]).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("first") && text.contains("second"), "{text}");
    assert!(err.is_bad_input());
    match err {
        StoreError::Mismatch { mismatch, .. } => mismatch,
        other => panic!("not a mismatch: {other}"),
    }
}

#[test]
fn another_pin_count_or_order_is_refused_by_name() {
    let a = data(3, no_extra());
    let mut fewer = data(3, serde_json::json!({"pins": 8}));
    fewer.meta.reference_pins.pop();
    fewer.inputs.truncate(3 * 16);
    let why = refusal(&a, &fewer);
    assert!(matches!(
        why,
        DatasetMismatch::PinCount {
            first: 9,
            other: 8,
            ..
        }
    ));
    assert!(why.to_string().contains("pin counts differ"), "{why}");
    let mut swapped = data(3, no_extra());
    swapped.meta.reference_pins.swap(0, 8);
    let why = refusal(&a, &swapped);
    assert!(matches!(why, DatasetMismatch::PinOrder(_)), "{why}");
    assert!(why.to_string().contains("reference pins differ"));
}

#[test]
fn other_target_names_units_or_circularity_are_refused_by_name() {
    let a = data(3, no_extra());
    for (extra, says) in [
        (
            serde_json::json!({"target_names": ["x", "theta"]}),
            "theta (deg",
        ),
        (
            serde_json::json!({"target_units": ["mm", "mm"], "target_circular": [false, false]}),
            "angle (mm)",
        ),
        (
            serde_json::json!({"target_circular": [false, false]}),
            "circular) against x (mm), angle (deg)",
        ),
    ] {
        let why = refusal(&a, &data(3, extra));
        let text = why.to_string();
        assert!(matches!(why, DatasetMismatch::Targets { .. }), "{text}");
        assert!(text.starts_with("their targets differ"), "{text}");
        assert!(text.contains(says), "{text} does not say {says}");
    }
    assert_eq!(check_alike(&a, &data(5, no_extra())), Ok(()));
}

fn frames(side: usize, n: usize) -> ImageFrames {
    ImageFrames {
        info: FramesInfo::new(side, side, [64, 64]),
        pixels: (0..n * side * side).map(|v| v as u8).collect(),
    }
}

#[test]
fn frames_join_in_order_and_another_size_or_preprocessing_is_refused() {
    let (a, b) = (frames(4, 2), frames(4, 3));
    let joined = join_frames(&[(Path::new("a"), &a), (Path::new("b"), &b)]).expect("alike");
    assert_eq!(joined.count(), 5);
    assert_eq!(joined.frame(2), b.frame(0));
    let why = check_frames_alike(&a.info, &frames(8, 1).info).unwrap_err();
    assert_eq!(
        why.to_string(),
        "their frames differ: 4 x 4 px, no preprocessing recorded against 8 x 8 px, \
         no preprocessing recorded"
    );
    let blurred = tactrace_vision::PreprocessParams {
        median_blur: Some(3),
        ..Default::default()
    };
    let pre = a.info.clone().with_preprocess(Some(&blurred));
    let why = check_frames_alike(&a.info, &pre).unwrap_err();
    assert!(
        why.to_string()
            .ends_with("preprocessed by a sensor's settings"),
        "{why}"
    );
    let wider = tactrace_vision::PreprocessParams {
        median_blur: Some(5),
        ..Default::default()
    };
    let other = a.info.clone().with_preprocess(Some(&wider));
    let why = check_frames_alike(&pre, &other).unwrap_err();
    assert!(why.to_string().ends_with("by other settings"), "{why}");
    let err = join_frames(&[(Path::new("a"), &a), (Path::new("c"), &frames(8, 1))]).unwrap_err();
    assert!(
        err.to_string().starts_with("a and c cannot be trained on"),
        "{err}"
    );
}

#[test]
fn a_record_of_joined_datasets_lists_each_and_one_dataset_writes_none() {
    let whole = data(6, no_extra());
    let (a, b) = (whole.subset(&[0, 1]), whole.subset(&[2, 3, 4, 5]));
    let joined = join_datasets(&[(Path::new("a"), &a), (Path::new("b"), &b)]).unwrap();
    let parts = vec![
        DatasetId::of(&a, Some(Path::new("a"))),
        DatasetId::of(&b, Some(Path::new("b"))),
    ];
    let record = TrainingRecord::all_rows(&joined, Some(Path::new("a"))).with_datasets(parts);
    record.check().expect("consistent");
    assert_eq!(record.dataset.path, None);
    assert_eq!(record.datasets[1].rows, 4);
    assert_eq!(record.rows_seen(&b), 4);
    let json = serde_json::to_value(&record).unwrap();
    assert_eq!(json["datasets"][0]["path"], "a");
    let one = TrainingRecord::all_rows(&a, Some(Path::new("a")));
    let one = one.with_datasets(vec![DatasetId::of(&a, Some(Path::new("a")))]);
    let json = serde_json::to_value(&one).unwrap();
    assert!(json.get("datasets").is_none(), "{json}");
    assert_eq!(json["dataset"]["path"], "a");
    let mut bad = record.clone();
    bad.datasets.pop();
    assert!(bad.check().unwrap_err().contains("hold 2 rows"));
}
