//! Turned copies of the training taps (`rotations`): on a hexagonal layout
//! a turn by 60 deg carries every pin onto a pin, the copy of an edge's
//! displacement field is the field of the edge turned, and six turns give
//! the tap back; layouts without the symmetry and bad settings are refused.
use tactrace_learn::{
    turned_copies, Dataset, LearnError, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset,
    Rotations, Unit,
};

use crate::support;
use support::{edge_field, hex_layout, SPACING};

fn edges(pins: &[[f64; 2]], poses: &[(f64, f64)]) -> Dataset {
    let (x, y) = support::edge_rows(pins, poses);
    Dataset::new(x, y, poses.len(), 2 * pins.len(), 2).unwrap()
}

fn circular_edge() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget {
            circular: true,
            ..ModelTarget::new("pose_6", Unit::Deg)
        },
    ]
}

const SIX: Rotations = Rotations {
    order: 6,
    angle_sign: -1,
    at_prediction: false,
};

#[test]
fn a_turned_edge_is_the_edge_turned_and_keeps_its_distance() {
    let pins = hex_layout(10);
    assert_eq!(pins.len(), 331);
    let poses = [(3.0, 170.0), (-7.5, -20.0), (0.0, 95.0)];
    let data = edges(&pins, &poses);
    let out = turned_copies(&data, &circular_edge(), &SIX, &pins).unwrap();
    assert_eq!(out.n, 6 * poses.len());
    assert_eq!(
        &out.x[..data.x.len()],
        &data.x[..],
        "the taps come first, as read"
    );
    for k in 1..6 {
        for (i, &(r, theta)) in poses.iter().enumerate() {
            let row = k * poses.len() + i;
            let want = tactrace_learn::wrap_deg(theta - 60.0 * k as f64);
            let y = out.y_row(row);
            assert_eq!(f64::from(y[0]), r, "a turn keeps the signed distance");
            assert!(
                (f64::from(y[1]) - want).abs() < 1e-3,
                "turn {k}: {} vs {want}",
                y[1]
            );
            let expect = edge_field(&pins, r, want);
            let worst = out
                .x_row(row)
                .iter()
                .zip(&expect)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-4, "turn {k}, tap {i}: field off by {worst}");
        }
    }
}

#[test]
fn the_angle_moves_the_other_way_with_the_other_sign() {
    let pins = hex_layout(4);
    let data = edges(&pins, &[(1.0, 179.0)]);
    let plus = Rotations {
        angle_sign: 1,
        ..SIX
    };
    let out = turned_copies(&data, &circular_edge(), &plus, &pins).unwrap();
    let angles: Vec<f32> = (0..6).map(|k| out.y_row(k)[1]).collect();
    let want = [179.0, -121.0, -61.0, -1.0, 59.0, 119.0];
    for (a, w) in angles.iter().zip(want) {
        assert!((a - w).abs() < 1e-3, "{angles:?}");
    }
}

#[test]
fn a_pure_shift_turns_as_a_vector_at_every_pin() {
    let pins = hex_layout(3);
    let n = pins.len();
    let mut x = vec![1.0f32; n];
    x.extend(vec![0.0f32; n]);
    let data = Dataset::new(x, vec![0.0, 10.0], 1, 2 * n, 2).unwrap();
    let out = turned_copies(&data, &circular_edge(), &SIX, &pins).unwrap();
    let row = out.x_row(1);
    let (s, c) = 60f64.to_radians().sin_cos();
    for i in 0..n {
        assert!((f64::from(row[i]) - c).abs() < 1e-6 && (f64::from(row[n + i]) - s).abs() < 1e-6);
    }
}

#[test]
fn a_layout_without_the_symmetry_is_refused_by_name() {
    let square: Vec<[f64; 2]> = (0..25)
        .map(|i| [f64::from(i % 5) * SPACING, f64::from(i / 5) * SPACING])
        .collect();
    let data = Dataset::new(vec![0.0; 50], vec![0.0, 0.0], 1, 50, 2).unwrap();
    let err = turned_copies(&data, &circular_edge(), &SIX, &square).unwrap_err();
    assert!(
        matches!(
            err,
            LearnError::Config {
                field: "rotations",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("not symmetric"), "{err}");
    let four = Rotations { order: 4, ..SIX };
    assert_eq!(
        turned_copies(&data, &circular_edge(), &four, &square)
            .unwrap()
            .n,
        4
    );
}

#[test]
fn bad_settings_are_refused_and_the_default_writes_nothing() {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    assert!(cfg.rotations.is_none());
    let plain = toml::to_string(&cfg).unwrap();
    assert!(!plain.contains("rotations"));
    for bad in [(1, -1), (13, 1), (6, 0), (6, 2)] {
        cfg.rotations = Some(Rotations {
            order: bad.0,
            angle_sign: bad.1,
            ..SIX
        });
        let err = cfg.validate().unwrap_err();
        assert!(err.to_string().contains("rotations"), "{bad:?}: {err}");
    }
    cfg.rotations = Some(SIX);
    let text = toml::to_string(&cfg).unwrap();
    let back: ModelConfig = toml::from_str(&text).unwrap();
    assert_eq!(back.rotations, Some(SIX));
}

/// `cfg` fitted on `data`, a circular edge over the layout `pins`.
fn fit_on_pins(
    cfg: &ModelConfig,
    data: &Dataset,
    pins: &[[f64; 2]],
) -> Result<PoseModel, LearnError> {
    PoseModel::fit_targets_on_pins(cfg, &circular_edge(), data, None, Some(pins), &mut |_| {})
        .map(|(model, _)| model)
}

/// A PCADenNN of one hidden layer of `hidden` units on `components`
/// principal components, `epochs` epochs.
fn small_pcadennn(
    rotations: Option<Rotations>,
    epochs: usize,
    hidden: usize,
    components: usize,
) -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    cfg.rotations = rotations;
    cfg.epochs = epochs;
    if let Some(net) = cfg.pose.as_mut() {
        net.hidden = vec![hidden];
        net.n_components = Some(components);
    }
    cfg
}

#[test]
fn a_fit_with_rotations_needs_the_reference_pins() {
    let pins = hex_layout(2);
    let poses: Vec<(f64, f64)> = (0..12)
        .map(|i| (0.5 * f64::from(i % 3), 30.0 * f64::from(i)))
        .collect();
    let data = edges(&pins, &poses);
    let cfg = small_pcadennn(Some(SIX), 2, 8, 4);
    let err = PoseModel::fit_targets(&cfg, &circular_edge(), &data, None, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("reference pins"), "{err}");
    let fitted = fit_on_pins(&cfg, &data, &pins);
    assert!(fitted.is_ok(), "{:?}", fitted.err().map(|e| e.to_string()));
}

/// Toy edges at `count` seeded poses (r in [-6, 6] px, theta over the
/// circle), every displacement with seeded noise of `noise` px (sd).
fn noisy_edges(pins: &[[f64; 2]], count: usize, noise: f64, seed: u64) -> Dataset {
    use rand::{Rng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let poses: Vec<(f64, f64)> = (0..count)
        .map(|_| (rng.random_range(-6.0..6.0), rng.random_range(-180.0..180.0)))
        .collect();
    let mut data = edges(pins, &poses);
    let normal = Normal::new(0.0, noise).unwrap();
    for v in &mut data.x {
        *v += normal.sample(&mut rng) as f32;
    }
    data
}

/// Mean wrapped angle error (deg) of `model` over `data`.
fn angle_mae(model: &PoseModel, data: &Dataset) -> f64 {
    let predicted = model.predict_targets_batch(data).unwrap();
    let sum: f64 = predicted
        .iter()
        .enumerate()
        .map(|(i, p)| tactrace_learn::wrap_deg(p[1] - f64::from(data.y_row(i)[1])).abs())
        .sum();
    sum / data.n as f64
}

#[test]
fn a_net_fitted_on_turned_copies_gains_from_averaging_its_turned_views() {
    let pins = hex_layout(3);
    let train = noisy_edges(&pins, 60, 0.1, 1);
    let held = noisy_edges(&pins, 200, 0.1, 2);
    let cfg = small_pcadennn(Some(SIX), 30, 32, 8);
    let mut model = fit_on_pins(&cfg, &train, &pins).unwrap();
    assert!(!model.averages_turned_views(), "off unless asked for");
    let plain = angle_mae(&model, &held);
    model.set_turned_views(true).unwrap();
    let averaged = angle_mae(&model, &held);
    assert!(
        averaged < 0.9 * plain,
        "six views {averaged:.3} deg against the tap alone {plain:.3}"
    );
    // The switch is kept in the file, with the layout it needs.
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("at_prediction") && json.contains("rotation_pins"));
    let back = PoseModel::from_bytes(&json, &weights).unwrap();
    assert!(back.averages_turned_views());
    assert_eq!(
        back.predict_targets(held.x_row(3)).unwrap(),
        model.predict_targets(held.x_row(3)).unwrap()
    );
    let off = json.replace("\"at_prediction\": true", "\"at_prediction\": false");
    let off = PoseModel::from_bytes(&off, &weights).unwrap();
    assert!((angle_mae(&off, &held) - plain).abs() < 1e-12);
}

#[test]
fn averaging_is_refused_without_rotations_or_their_recorded_layout() {
    let pins = hex_layout(2);
    let data = noisy_edges(&pins, 12, 0.05, 3);
    let mut cfg = small_pcadennn(None, 2, 8, 4);
    let (mut plain, _) =
        PoseModel::fit_targets(&cfg, &circular_edge(), &data, None, &mut |_| {}).unwrap();
    let err = plain.set_turned_views(true).unwrap_err();
    assert!(err.to_string().contains("rotations"), "{err}");
    cfg.rotations = Some(Rotations {
        at_prediction: true,
        ..SIX
    });
    let turned = fit_on_pins(&cfg, &data, &pins).unwrap();
    assert!(
        turned.averages_turned_views(),
        "asked for in the configuration"
    );
    // A file that sets the switch but lost its layout is refused, by name.
    let (json, weights) = turned.to_bytes().unwrap();
    let start = json.find("\"rotation_pins\"").unwrap();
    let cut = format!("{}}}", json[..start].trim_end().trim_end_matches(','));
    let err = PoseModel::from_bytes(&cut, &weights).unwrap_err();
    assert!(err.to_string().contains("rotation_pins"), "{err}");
}
