//! The learning crate's shared test data (`tests/support`) is the data the
//! tests made each for themselves before: seeded, shaped and valued as
//! they were.
use crate::support;

/// The same seed gives the same rows, another seed others; `n` rows of
/// `dim` values and two targets in their ranges, the values a smooth
/// function of the targets plus at most 0.2 of noise.
#[test]
fn correlated_rows_are_seeded_and_follow_their_targets() {
    let (x, y) = support::correlated_rows(50, 7, 3);
    assert_eq!((x.len(), y.len()), (350, 100));
    assert_eq!((x.clone(), y.clone()), support::correlated_rows(50, 7, 3));
    assert_ne!(y, support::correlated_rows(50, 7, 4).1);
    for (row, t) in x.chunks_exact(7).zip(y.chunks_exact(2)) {
        let (a, b) = (t[0], t[1]);
        assert!(
            (-5.0..5.0).contains(&a) && (-45.0..45.0).contains(&b),
            "{t:?}"
        );
        for (j, v) in row.iter().enumerate() {
            let phase = j as f32 * 0.37;
            let smooth = a * phase.sin() + 0.1 * b * phase.cos();
            assert!((v - smooth).abs() <= 0.2 + 1e-5, "{v} vs {smooth}");
        }
    }
}

/// A model's two files in `tests/fixtures`: its JSON and its weights.
fn fixture(name: &str) -> (String, Vec<u8>) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let json = std::fs::read_to_string(dir.join(format!("{name}.json"))).expect("fixture json");
    let weights = std::fs::read(dir.join(format!("{name}.safetensors"))).expect("fixture weights");
    (json, weights)
}

/// The pin and image models' files share one safetensors writer and
/// reader: files written before it (a PCA-DenNN of two nets; a conv-mlp
/// of two networks with its mean frame) load, and save again to the
/// same bytes.
#[test]
fn model_files_written_before_load_and_save_to_the_same_bytes() {
    let (json, weights) = fixture("pin_model");
    let pin = tactrace_learn::PoseModel::from_bytes(&json, &weights).expect("pin model");
    assert_eq!(pin.to_bytes().expect("save"), (json, weights));
    let (json, weights) = fixture("conv_model");
    let conv = tactrace_convnet::ConvModel::from_bytes(&json, &weights).expect("image model");
    assert_eq!(conv.to_bytes().expect("save"), (json, weights));
}

/// A weights file whose tensor has another shape, or is not safetensors,
/// is a corrupt model naming the tensor, as before.
#[test]
fn a_tensor_of_another_shape_is_named() {
    let (json, _) = fixture("pin_model");
    let err = tactrace_learn::PoseModel::from_bytes(&json, b"not safetensors").expect_err("bad");
    assert!(err.to_string().contains("weights: "), "{err}");
    let (json, weights) = fixture("conv_model");
    let wider = json.replace("\"outputs\": 2", "\"outputs\": 3");
    assert_ne!(wider, json);
    let err = tactrace_convnet::ConvModel::from_bytes(&wider, &weights).expect_err("bad shape");
    let text = err.to_string();
    assert!(
        text.contains("tensor ") && text.contains("expected F"),
        "{text}"
    );
}
