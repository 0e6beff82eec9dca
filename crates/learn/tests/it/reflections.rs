//! Mirror copies of the training taps (`reflections`): on a hexagonal
//! lattice every lattice axis through the centre pin carries each pin onto
//! its mirror image; the copy of a tilted surface's field is the field of
//! the surface mirrored, at the negated angle when the mirror line crosses
//! the tilt and the same angle when it runs along it, and a model fitted
//! without the copies tells the two apart; averaging a tap with its copy
//! makes the prediction exactly mirror-symmetric.
use tactrace_learn::{
    mirror_pins, mirrored_copies, mirrored_inputs, Dataset, LearnError, ModelConfig, ModelKind,
    ModelTarget, PoseModel, Preset, Reflections, Unit,
};

const SPACING: f64 = 11.0;
const CENTRE: [f64; 2] = [128.0, 127.0];

/// A hexagonal lattice of `rings` rings about `CENTRE`, rows along the
/// image's x axis (127 pins for 6, as the 127-pin TacTip).
fn hex_layout(rings: i32) -> Vec<[f64; 2]> {
    tactrace_testdata::layouts::hex_lattice(CENTRE, SPACING, rings)
}

/// The point `p` mirrored across the line at `axis_deg` through `CENTRE`.
fn mirrored(p: [f64; 2], axis_deg: f64) -> [f64; 2] {
    let (s, c) = (2.0 * axis_deg).to_radians().sin_cos();
    let (x, y) = (p[0] - CENTRE[0], p[1] - CENTRE[1]);
    [CENTRE[0] + c * x + s * y, CENTRE[1] + s * x - c * y]
}

/// A flat surface pressed `depth` px into the dome, tilted by `angle`
/// deg about the image's y axis: the press at pin `p` is `depth + tan(angle)
/// (x - x_c) / 4`, and a pin pressed moves outward from the centre by a
/// tenth of its press.
fn surface_field(pins: &[[f64; 2]], depth: f64, angle: f64) -> Vec<f32> {
    let slope = angle.to_radians().tan() / 4.0;
    let n = pins.len();
    let mut d = vec![0.0f32; 2 * n];
    for (i, p) in pins.iter().enumerate() {
        let (x, y) = (p[0] - CENTRE[0], p[1] - CENTRE[1]);
        let press = (depth + slope * x).max(0.0);
        let r = x.hypot(y).max(1.0);
        d[i] = (0.1 * press * x / r) as f32;
        d[n + i] = (0.1 * press * y / r) as f32;
    }
    d
}

fn surfaces(pins: &[[f64; 2]], poses: &[(f64, f64)]) -> Dataset {
    let x: Vec<f32> = poses
        .iter()
        .flat_map(|&(h, a)| surface_field(pins, h, a))
        .collect();
    let y: Vec<f32> = poses
        .iter()
        .flat_map(|&(h, a)| [h as f32, a as f32])
        .collect();
    Dataset::new(x, y, poses.len(), 2 * pins.len(), 2).unwrap()
}

fn surface_targets() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("depth", Unit::Mm),
        ModelTarget::new("angle", Unit::Deg),
    ]
}

fn mirror(axis_deg: f64, negate: &[&str]) -> Reflections {
    Reflections {
        axis_deg,
        negate: negate.iter().map(|s| s.to_string()).collect(),
        at_prediction: false,
    }
}

/// The largest difference of two fields.
fn worst(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f32::max)
}

#[test]
fn every_lattice_axis_maps_each_pin_to_its_mirror_image() {
    let pins = hex_layout(6);
    assert_eq!(pins.len(), 127);
    for axis in [0.0, 30.0, 60.0, 90.0, 120.0, 150.0] {
        let lands = mirror_pins(&pins, axis).unwrap();
        for (i, &j) in lands.iter().enumerate() {
            let to = mirrored(pins[i], axis);
            let off = (to[0] - pins[j][0]).hypot(to[1] - pins[j][1]);
            assert!(off < 1e-9, "axis {axis}: pin {i} lands {off} px off");
            assert_eq!(lands[j], i, "axis {axis}: a mirror is its own inverse");
        }
    }
}

#[test]
fn an_axis_off_the_lattice_is_refused_by_name() {
    let pins = hex_layout(6);
    for axis in [15.0, 45.0, 100.0] {
        let err = mirror_pins(&pins, axis).unwrap_err();
        assert!(
            matches!(
                err,
                LearnError::Config {
                    field: "reflections",
                    ..
                }
            ),
            "{err}"
        );
        assert!(err.to_string().contains("not symmetric"), "{err}");
    }
}

#[test]
fn a_mirror_across_the_tilt_negates_the_angle_and_along_it_keeps_it() {
    let pins = hex_layout(6);
    let poses = [(3.0, 20.0), (8.0, -12.5), (5.0, 0.0)];
    let data = surfaces(&pins, &poses);
    // Across the tilt: the line x = x_c (90 deg) swaps the deep and the
    // shallow side, the copy is the surface at -angle.
    let across =
        mirrored_copies(&data, &surface_targets(), &mirror(90.0, &["angle"]), &pins).unwrap();
    assert_eq!(across.n, 2 * poses.len());
    assert_eq!(&across.x[..data.x.len()], &data.x[..], "the taps first");
    for (i, &(h, a)) in poses.iter().enumerate() {
        let row = poses.len() + i;
        assert_eq!(across.y_row(row), &[h as f32, -a as f32]);
        let off = worst(across.x_row(row), &surface_field(&pins, h, -a));
        assert!(
            off < 1e-5,
            "tap {i}: the copy is {off} px off the surface at -angle"
        );
        if a != 0.0 {
            let wrong = worst(across.x_row(row), &surface_field(&pins, h, a));
            assert!(wrong > 0.05, "tap {i}: the copy also fits +angle ({wrong})");
        }
    }
    // Along the tilt: the line y = y_c (0 deg) keeps the angle.
    let along = mirrored_copies(&data, &surface_targets(), &mirror(0.0, &[]), &pins).unwrap();
    for (i, &(h, a)) in poses.iter().enumerate() {
        let row = poses.len() + i;
        assert_eq!(along.y_row(row), &[h as f32, a as f32]);
        let off = worst(along.x_row(row), &surface_field(&pins, h, a));
        assert!(off < 1e-5, "tap {i}: {off} px off the surface as read");
    }
}

/// Seeded toy surfaces: depth in [2, 9] px, angle in [-25, 25] deg.
fn random_surfaces(pins: &[[f64; 2]], count: usize, seed: u64) -> Dataset {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let poses: Vec<(f64, f64)> = (0..count)
        .map(|_| (rng.random_range(2.0..9.0), rng.random_range(-25.0..25.0)))
        .collect();
    surfaces(pins, &poses)
}

/// An MLP of one hidden layer of 32 units a target, 8 principal
/// components, `epochs` epochs, with `reflections`.
fn small_mlp(reflections: Option<Reflections>, epochs: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::Mlp, Preset::Default);
    cfg.reflections = reflections;
    cfg.epochs = epochs;
    for net in [cfg.position.as_mut(), cfg.angle.as_mut()]
        .into_iter()
        .flatten()
    {
        net.hidden = vec![32];
        net.n_components = Some(8);
    }
    cfg
}

fn fit_on_pins(cfg: &ModelConfig, data: &Dataset, pins: &[[f64; 2]]) -> PoseModel {
    PoseModel::fit_targets_on_pins(cfg, &surface_targets(), data, None, Some(pins), &mut |_| {})
        .map(|(model, _)| model)
        .map_err(|e| e.to_string())
        .unwrap()
}

/// Mean absolute error of the angle predicted for `data` against its
/// labels times `sign`.
fn angle_mae(model: &PoseModel, data: &Dataset, sign: f64) -> f64 {
    let predicted = model.predict_targets_batch(data).unwrap();
    let sum: f64 = predicted
        .iter()
        .enumerate()
        .map(|(i, p)| (p[1] - sign * f64::from(data.y_row(i)[1])).abs())
        .sum();
    sum / data.n as f64
}

#[test]
fn a_model_fitted_without_copies_tells_the_sign_of_a_mirror() {
    // The check run on the data before trusting a sign: predict mirrored
    // held-out taps with a model that never saw a copy. Across the tilt
    // its angles follow -angle, along it +angle; the wrong sign fails.
    let pins = hex_layout(6);
    let model = fit_on_pins(&small_mlp(None, 40), &random_surfaces(&pins, 200, 1), &pins);
    let held = random_surfaces(&pins, 100, 2);
    for (axis, sign) in [(90.0, -1.0), (0.0, 1.0)] {
        let flipped = mirrored_inputs(&held, &pins, axis).unwrap();
        let right = angle_mae(&model, &flipped, sign);
        let wrong = angle_mae(&model, &flipped, -sign);
        assert!(
            right < 2.0 && wrong > 5.0 * right,
            "mirror at {axis} deg: sign {sign} {right:.2} deg, the other {wrong:.2}"
        );
    }
}

#[test]
fn averaging_with_the_mirror_copy_is_exactly_mirror_symmetric_and_saved() {
    // y(d) = (f(d) + S f(M d)) / 2 gives y(M d) = S y(d) for any f.
    let pins = hex_layout(4);
    let refl = Reflections {
        at_prediction: true,
        ..mirror(90.0, &["angle"])
    };
    let model = fit_on_pins(
        &small_mlp(Some(refl), 5),
        &random_surfaces(&pins, 40, 3),
        &pins,
    );
    let held = random_surfaces(&pins, 5, 4);
    let flipped = mirrored_inputs(&held, &pins, 90.0).unwrap();
    for i in 0..held.n {
        let a = model.predict_targets(held.x_row(i)).unwrap();
        let b = model.predict_targets(flipped.x_row(i)).unwrap();
        assert!(
            (a[0] - b[0]).abs() < 1e-9 && (a[1] + b[1]).abs() < 1e-9,
            "{a:?} {b:?}"
        );
    }
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("reflection_pins") && json.contains("at_prediction"));
    let back = PoseModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(
        back.predict_targets(held.x_row(1)).unwrap(),
        model.predict_targets(held.x_row(1)).unwrap()
    );
    let start = json.find("\"reflection_pins\"").unwrap();
    let cut = format!("{}}}", json[..start].trim_end().trim_end_matches(','));
    let err = PoseModel::from_bytes(&cut, &weights).unwrap_err();
    assert!(err.to_string().contains("reflection_pins"), "{err}");
}

#[test]
fn bad_settings_are_refused_and_the_default_writes_nothing() {
    let mut cfg = ModelConfig::preset(ModelKind::Mlp, Preset::Default);
    assert!(!toml::to_string(&cfg).unwrap().contains("reflections"));
    for bad in [
        mirror(180.0, &[]),
        mirror(f64::NAN, &[]),
        mirror(0.0, &["a", "a"]),
    ] {
        cfg.reflections = Some(bad);
        let err = cfg.validate().unwrap_err();
        assert!(err.to_string().contains("reflections"), "{err}");
    }
    cfg.reflections = Some(mirror(90.0, &["angle"]));
    cfg.validate().unwrap();
    let back: ModelConfig = toml::from_str(&toml::to_string(&cfg).unwrap()).unwrap();
    assert_eq!(back.reflections, cfg.reflections);
    cfg.rotations = Some(tactrace_learn::Rotations {
        order: 6,
        angle_sign: -1,
        at_prediction: false,
    });
    assert!(cfg
        .validate()
        .unwrap_err()
        .to_string()
        .contains("reflections"));
    // A target the model does not have, or a circular one, is refused.
    let pins = hex_layout(2);
    let data = random_surfaces(&pins, 4, 5);
    for (refl, targets) in [
        (mirror(0.0, &["pose_6"]), surface_targets()),
        (
            mirror(0.0, &[]),
            vec![
                ModelTarget::new("depth", Unit::Mm),
                ModelTarget::circular("angle"),
            ],
        ),
    ] {
        let err = mirrored_copies(&data, &targets, &refl, &pins).unwrap_err();
        assert!(err.to_string().contains("reflections"), "{err}");
    }
}

#[test]
fn the_mirror_view_is_switched_as_turned_views_are() {
    // `--views on|off` reaches a mirror-copies model: off predicts the tap
    // alone (no longer mirror-symmetric), on the mean with its copy.
    let pins = hex_layout(4);
    let refl = Reflections {
        at_prediction: true,
        ..mirror(90.0, &["angle"])
    };
    let mut model = fit_on_pins(
        &small_mlp(Some(refl), 5),
        &random_surfaces(&pins, 40, 3),
        &pins,
    );
    let held = random_surfaces(&pins, 5, 4);
    let flipped = mirrored_inputs(&held, &pins, 90.0).unwrap();
    let asymmetry = |m: &PoseModel| -> f64 {
        (0..held.n)
            .map(|i| {
                let a = m.predict_targets(held.x_row(i)).unwrap();
                let b = m.predict_targets(flipped.x_row(i)).unwrap();
                (a[1] + b[1]).abs()
            })
            .fold(0.0, f64::max)
    };
    let on = model.predict_targets(held.x_row(0)).unwrap();
    assert_eq!(model.views_at_prediction(), Some(true));
    model.set_turned_views(false).unwrap();
    assert_eq!(model.views_at_prediction(), Some(false));
    assert!(asymmetry(&model) > 1e-6, "the tap alone is not symmetric");
    assert_ne!(model.predict_targets(held.x_row(0)).unwrap(), on);
    model.set_turned_views(true).unwrap();
    assert!(asymmetry(&model) < 1e-9);
    assert_eq!(model.predict_targets(held.x_row(0)).unwrap(), on);
    let plain = fit_on_pins(&small_mlp(None, 2), &random_surfaces(&pins, 20, 5), &pins);
    assert_eq!(plain.views_at_prediction(), None);
    let err = plain.clone().set_turned_views(true).unwrap_err();
    assert!(err.to_string().contains("rotations"), "{err}");
}
