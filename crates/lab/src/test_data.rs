//! Small datasets made in memory for the unit tests of lab's modules.
use tactrace_store::{DatasetMeta, TapData};

/// An edge dataset (targets r and theta) of the given rows, two
/// `targets` and `2 x reference_pins` `inputs` a row, with nothing else
/// recorded.
pub(crate) fn edge_data(
    inputs: Vec<f32>,
    targets: Vec<f32>,
    reference_pins: &[[f64; 2]],
) -> TapData {
    let samples = targets.len() / 2;
    assert_eq!(inputs.len(), samples * 2 * reference_pins.len(), "inputs");
    let meta: DatasetMeta = serde_json::from_value(serde_json::json!({
        "source": "test", "origin": "", "seed": null, "samples": samples,
        "pins": reference_pins.len(), "targets": ["r", "theta"],
        "frames_with_missing_pins": 0, "reference_pins": reference_pins,
        "settings": null, "tactrace_version": ""
    }))
    .expect("an edge dataset's meta");
    TapData {
        inputs,
        targets,
        meta,
    }
}
