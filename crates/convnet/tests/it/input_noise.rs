//! Input noise (`input_noise`, issue 22's accuracy work): Gaussian noise
//! added to the standardised training pixels, a seeded draw per frame and
//! epoch. A noisy fit reproduces bit for bit whatever the thread count,
//! differs from the noiseless one, never touches prediction, is refused
//! out of range, and a model saved before the setting existed still loads
//! (no noise).
use crate::common;

use common::{moving_pair_frames, tiny_config, SIDE};
use tactrace_convnet::{ConvConfig, ConvError, ConvModel, Frames, ModelKind, Targets};

fn config(kind: ModelKind, noise: f64) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.input_noise = noise;
    c
}

fn fit(config: &ConvConfig, threads: usize) -> ConvModel {
    let (pixels, targets) = moving_pair_frames(40);
    let f = Frames::new(&pixels, 40, SIDE, SIDE).unwrap();
    let t = Targets::new(&targets, 40, 2).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| ConvModel::fit(&f, &t, config, 9).unwrap().0)
}

#[test]
fn input_noise_is_seeded_and_only_in_training() {
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        let noisy = fit(&config(kind, 0.5), 1);
        let again = fit(&config(kind, 0.5), 3);
        assert_eq!(noisy.to_bytes().unwrap(), again.to_bytes().unwrap());
        let plain = fit(&config(kind, 0.0), 1);
        assert_ne!(noisy.network().parameters(), plain.network().parameters());
        // Prediction draws no noise: the same frame, the same numbers.
        let (pixels, _) = moving_pair_frames(1);
        assert_eq!(
            noisy.predict(&pixels).unwrap(),
            noisy.predict(&pixels).unwrap()
        );
    }
}

#[test]
fn input_noise_out_of_range_is_refused_and_old_models_load() {
    for bad in [-0.1, f64::NAN, 11.0] {
        let err = config(ModelKind::ConvMlp, bad).validate().unwrap_err();
        assert!(matches!(err, ConvError::Config { .. }), "{err}");
        assert!(err.to_string().contains("input_noise"), "{err}");
    }
    let model = fit(&config(ModelKind::ConvMlp, 0.0), 1);
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("\"input_noise\""), "{json}");
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(drop_key(&mut value, "input_noise"));
    let old = value.to_string();
    let back = ConvModel::from_bytes(&old, &weights).unwrap();
    assert_eq!(back.config().input_noise, 0.0);
    assert_eq!(back, model);
}

/// Remove `key` wherever it is in `v`; whether it was found.
fn drop_key(v: &mut serde_json::Value, key: &str) -> bool {
    let mut found = false;
    match v {
        serde_json::Value::Object(map) => {
            found = map.remove(key).is_some();
            for x in map.values_mut() {
                found |= drop_key(x, key);
            }
        }
        serde_json::Value::Array(items) => {
            for x in items {
                found |= drop_key(x, key);
            }
        }
        _ => {}
    }
    found
}
