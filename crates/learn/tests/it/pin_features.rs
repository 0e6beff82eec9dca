//! The pins' displacement gradients as net inputs (`pin_features =
//! "with_gradients"`) against theory: a rigid shift has none, an affine
//! field `d = A p + b` gives `A` at every pin; and a pose model with them
//! fits, records them in its file, predicts the same after a save and
//! load, and is refused without the reference pins it needs.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_learn::{
    Dataset, FeatureMap, LearnError, ModelConfig, ModelKind, ModelTarget, PinFeatures, PoseModel,
    Preset, Unit,
};

/// A hexagonal patch of pins (px), spacing 10, slightly jittered.
fn hex_pins(rings: i32, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pins = Vec::new();
    for q in -rings..=rings {
        for r in -rings..=rings {
            if (q + r).abs() <= rings {
                let x = 10.0 * (q as f64 + 0.5 * r as f64) + rng.random_range(-0.5..0.5);
                let y = 10.0 * 0.75f64.sqrt() * r as f64 + rng.random_range(-0.5..0.5);
                pins.push([x, y]);
            }
        }
    }
    pins
}

/// The displacements (x then y) of the affine field `d = A p + b`.
fn affine(pins: &[[f64; 2]], a: [[f64; 2]; 2], b: [f64; 2]) -> Vec<f32> {
    let dx = pins.iter().map(|p| a[0][0] * p[0] + a[0][1] * p[1] + b[0]);
    let dy = pins.iter().map(|p| a[1][0] * p[0] + a[1][1] * p[1] + b[1]);
    dx.chain(dy).map(|v| v as f32).collect()
}

#[test]
fn gradients_of_an_affine_field_are_its_matrix_and_of_a_shift_zero() {
    let pins = hex_pins(4, 1);
    let p = pins.len();
    let map = FeatureMap::new(PinFeatures::WithGradients, &pins).unwrap();
    assert_eq!((map.input_dim(), map.output_dim()), (2 * p, 6 * p));
    let a = [[0.02, -0.05], [0.07, -0.01]];
    for (m, b) in [([[0.0; 2]; 2], [3.0, -2.0]), (a, [1.5, 0.5])] {
        let d = affine(&pins, m, b);
        let mut f = Vec::new();
        map.extend(&d, &mut f);
        assert_eq!(&f[..2 * p], &d[..], "the displacements come first");
        for (c, want) in [m[0][0], m[0][1], m[1][0], m[1][1]].into_iter().enumerate() {
            for i in 0..p {
                let got = f[2 * p + c * p + i] as f64;
                assert!((got - want).abs() < 1e-6, "pin {i} G[{c}]: {got} vs {want}");
            }
        }
    }
}

#[test]
fn the_displacements_option_passes_them_through() {
    let pins = hex_pins(2, 2);
    let map = FeatureMap::new(PinFeatures::Displacements, &pins).unwrap();
    let d = affine(&pins, [[0.1, 0.2], [0.3, 0.4]], [1.0, 2.0]);
    assert_eq!(map.rows(&d), d);
}

#[test]
fn too_few_or_collinear_pins_are_refused() {
    let few = hex_pins(0, 3);
    assert!(FeatureMap::new(PinFeatures::WithGradients, &few).is_err());
    let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
    let err = FeatureMap::new(PinFeatures::WithGradients, &line).unwrap_err();
    assert!(err.to_string().contains("collinear"), "{err}");
}

/// Taps of an edge at position `r` (mm) and angle `t` (deg): a shear
/// proportional to `r` and a local strain that turns with the angle.
fn taps(pins: &[[f64; 2]], n: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let r: f64 = rng.random_range(-3.0..3.0);
        let t: f64 = rng.random_range(-180.0..180.0);
        let (s, c) = t.to_radians().sin_cos();
        let a = [[0.03 * c, 0.03 * s], [-0.03 * s, 0.03 * c]];
        x.extend(affine(pins, a, [r, 0.5 * r]));
        y.extend([r as f32, t as f32]);
    }
    Dataset::new(x, y, n, 2 * pins.len(), 2).unwrap()
}

fn outputs() -> [ModelTarget; 2] {
    let mut angle = ModelTarget::new("pose_6", Unit::Deg);
    angle.circular = true;
    [ModelTarget::new("pose_2", Unit::Mm), angle]
}

fn small_config() -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    cfg.set_epochs(5);
    cfg.pin_features = PinFeatures::WithGradients;
    let net = cfg.pose.as_mut().unwrap();
    net.hidden = vec![16];
    net.n_components = Some(8);
    cfg
}

#[test]
fn a_model_with_gradients_records_them_and_predicts_the_same_after_loading() {
    let pins = hex_pins(3, 4);
    let (train, val) = (taps(&pins, 120, 5), taps(&pins, 10, 6));
    let cfg = small_config();
    let (model, _) =
        PoseModel::fit_targets_on_pins(&cfg, &outputs(), &train, None, Some(&pins), &mut |_| {})
            .unwrap();
    assert_eq!(model.input_dim(), 2 * pins.len());
    assert_eq!(model.pin_features(), PinFeatures::WithGradients);
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("\"pin_features\": \"with_gradients\""));
    let again = PoseModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(again.pin_features(), PinFeatures::WithGradients);
    for i in 0..val.n {
        let (a, b) = (
            model.predict_targets(val.x_row(i)).unwrap(),
            again.predict_targets(val.x_row(i)).unwrap(),
        );
        assert_eq!(a, b, "row {i}");
    }
    // A row of another length is refused, not read as features.
    let err = model.predict_targets(&vec![0.0; 6 * pins.len()]);
    assert!(matches!(err, Err(LearnError::DimensionMismatch { .. })));
}

#[test]
fn gradients_without_reference_pins_are_refused() {
    let pins = hex_pins(2, 7);
    let train = taps(&pins, 60, 8);
    let cfg = small_config();
    let err = PoseModel::fit_targets(&cfg, &outputs(), &train, None, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("pin_features"), "{err}");
    let wrong = &pins[..pins.len() - 1];
    let err =
        PoseModel::fit_targets_on_pins(&cfg, &outputs(), &train, None, Some(wrong), &mut |_| {});
    assert!(matches!(err, Err(LearnError::DimensionMismatch { .. })));
}

#[test]
fn the_default_writes_no_features() {
    let pins = hex_pins(2, 9);
    let train = taps(&pins, 80, 10);
    let mut cfg = small_config();
    cfg.pin_features = PinFeatures::Displacements;
    let (model, _) =
        PoseModel::fit_targets_on_pins(&cfg, &outputs(), &train, None, Some(&pins), &mut |_| {})
            .unwrap();
    let (json, _) = model.to_bytes().unwrap();
    assert!(!json.contains("pin_features") && !json.contains("\"features\""));
}
