//! The two pin layouts against theory (docs/sensor-model.md, eqs. S1 and
//! S1r): counts, spacing, symmetry and the centre pin of concentric
//! rings; a rings sensor's configuration, rendering and contact field.
use crate::common;
use common::*;
use tactrace_geometry::Vec2;
use tactrace_sensor::{
    concentric_rings, hex_lattice, pin_count, skin_pins, PinLayout, SensorError, TacTipConfig,
    TacTipModel,
};

/// A 10-ring (331-pin) sensor on concentric rings: the default sensor's
/// extent on the dome, an unrotated and unmirrored camera.
fn rings_config(rings: usize, phases: Vec<f64>) -> TacTipConfig {
    let mut cfg = plain_model().config().clone();
    let scale = cfg.geometry.rings as f64 / rings as f64;
    cfg.geometry.layout = PinLayout::Rings;
    cfg.geometry.rings = rings;
    cfg.geometry.pin_spacing_mm *= scale;
    cfg.geometry.pin_radius_mm *= scale;
    cfg.geometry.ring_phase_deg = phases;
    cfg
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[test]
fn ring_k_holds_6k_pins_on_a_circle_of_radius_k_spacings() {
    let s = 2.5;
    for n in [1, 3, 10] {
        let pins = concentric_rings(n, s, &[]);
        assert_eq!(pins.len(), pin_count(n));
        assert_eq!(pins[0], [0.0, 0.0], "the centre pin comes first");
        let mut at = 1;
        for k in 1..=n {
            let ring = &pins[at..at + 6 * k];
            at += 6 * k;
            let chord = 2.0 * k as f64 * s * (std::f64::consts::PI / (6 * k) as f64).sin();
            let mut last = -1.0;
            for (j, p) in ring.iter().enumerate() {
                assert!((p[0].hypot(p[1]) - k as f64 * s).abs() < 1e-12, "ring {k}");
                // Counter-clockwise from the +x axis, evenly spaced.
                let angle = p[1].atan2(p[0]).rem_euclid(std::f64::consts::TAU);
                assert!(angle > last, "ring {k} pin {j} out of order");
                last = angle;
                let next = ring[(j + 1) % ring.len()];
                assert!(
                    (distance(*p, next) - chord).abs() < 1e-9,
                    "ring {k} pin {j}"
                );
            }
        }
    }
    assert_eq!(pin_count(10), 331);
}

#[test]
fn the_nearest_pin_is_one_to_1_05_spacings_away_in_either_layout_whatever_the_phases() {
    // What the rest-pin matching's limit (half the local spacing) rests on.
    let s = 3.0;
    let phases = [7.0, -11.0, 2.5, 13.0, -4.0, 0.5];
    for (name, pins) in [
        ("hex", hex_lattice(6, s)),
        ("rings", concentric_rings(6, s, &[])),
        ("turned rings", concentric_rings(6, s, &phases)),
    ] {
        for (i, a) in pins.iter().enumerate() {
            let nearest = pins
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| distance(*a, *b))
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest >= s - 1e-9,
                "{name}: pin {i} has a neighbour at {nearest}"
            );
            // On ring k the neighbours along the ring are the chord
            // 2 k s sin(30 / k deg) <= (pi / 3) s away.
            let most = std::f64::consts::FRAC_PI_3 * s + 1e-9;
            assert!(nearest < most, "{name}: pin {i} at {nearest}");
            if name == "hex" {
                assert!((nearest - s).abs() < 1e-9, "{name}: pin {i} at {nearest}");
            }
        }
    }
}

#[test]
fn rings_are_six_fold_and_mirror_symmetric_and_phases_turn_each_ring() {
    let s = 2.0;
    let plain = concentric_rings(5, s, &[]);
    let has = |pins: &[[f64; 2]], p: [f64; 2]| pins.iter().any(|q| distance(*q, p) < 1e-9);
    for p in &plain {
        assert!(has(&plain, rotate(*p, 60.0)), "60 deg turn of {p:?}");
        assert!(has(&plain, [p[0], -p[1]]), "mirror of {p:?}");
    }
    let phases = [10.0, -5.0, 3.0, 0.0, 7.5];
    let turned = concentric_rings(5, s, &phases);
    let mut at = 1;
    for k in 1..=5 {
        for p in &plain[at..at + 6 * k] {
            let q = rotate(*p, phases[k - 1]);
            assert!(has(&turned[at..at + 6 * k], q), "ring {k}: {q:?}");
        }
        at += 6 * k;
    }
    // Missing phases count as zero.
    assert_eq!(concentric_rings(5, s, &phases[..2])[19..], plain[19..]);
}

#[test]
fn the_layout_is_chosen_by_the_configuration_and_hex_stays_the_default() {
    let hex = TacTipConfig::default();
    assert_eq!(hex.geometry.layout, PinLayout::Hex);
    assert_eq!(skin_pins(&hex.geometry), hex_lattice(6, 4.243));
    let text = toml::to_string(&hex).unwrap();
    assert!(text.contains("layout = \"hex\""), "{text}");
    assert!(!text.contains("ring_phase_deg"), "{text}");
    let cfg: TacTipConfig = toml::from_str(
        "[geometry]\nlayout = \"rings\"\nrings = 3\nring_phase_deg = [1.0, 2.0, 3.0]\n",
    )
    .unwrap();
    assert_eq!(cfg.geometry.layout, PinLayout::Rings);
    let model = TacTipModel::new(cfg.clone()).unwrap();
    assert_eq!(model.rest_pins().len(), 37);
    assert_eq!(
        skin_pins(&cfg.geometry),
        concentric_rings(3, 4.243, &[1.0, 2.0, 3.0])
    );
    let back: TacTipConfig = toml::from_str(&toml::to_string(&cfg).unwrap()).unwrap();
    assert_eq!(back, cfg);
}

#[test]
fn ring_phases_must_fit_a_rings_layout() {
    let refused = |cfg: TacTipConfig, why: &str| {
        let err = TacTipModel::new(cfg).expect_err(why);
        assert!(
            matches!(
                err,
                SensorError::InvalidConfig {
                    field: "geometry.ring_phase_deg",
                    ..
                }
            ),
            "{why}: {err}"
        );
        assert!(err.is_config());
    };
    let mut hex = TacTipConfig::default();
    hex.geometry.ring_phase_deg = vec![0.0; 6];
    refused(hex, "phases on a lattice");
    refused(rings_config(10, vec![0.0; 9]), "one phase short");
    let mut nan = vec![0.0; 10];
    nan[3] = f64::NAN;
    refused(rings_config(10, nan), "a phase that is not a number");
    let err = toml::from_str::<TacTipConfig>("[geometry]\nlayout = \"spiral\"\n").unwrap_err();
    assert!(err.to_string().contains("spiral"), "{err}");
}

/// Image position of the skin point `g` by eqs. S2-S3 written out (an
/// unrotated, unmirrored camera).
fn projected(cfg: &TacTipConfig, g: [f64; 2]) -> [f64; 2] {
    let (r, c) = (cfg.geometry.dome_radius_mm, &cfg.camera);
    let s = g[0].hypot(g[1]);
    if s == 0.0 {
        return c.centre_px;
    }
    let phi = s / r;
    let k = c.focal_px * r * phi.sin() / (s * (c.height_mm - r * (1.0 - phi.cos())));
    [c.centre_px[0] + k * g[0], c.centre_px[1] + k * g[1]]
}

#[test]
fn a_rendered_rings_sensor_shows_its_pins_where_the_projection_puts_them() {
    let mut phases: Vec<f64> = (0..10).map(|k| 0.7 * k as f64 - 2.0).collect();
    phases[0] = 25.0;
    let mut cfg = rings_config(10, phases);
    cfg.camera.binarise_above = None;
    let model = TacTipModel::new(cfg.clone()).unwrap();
    let expected: Vec<[f64; 2]> = skin_pins(&cfg.geometry)
        .iter()
        .map(|g| projected(&cfg, *g))
        .collect();
    for (p, q) in model.rest_pins().iter().zip(&expected) {
        assert!(distance(*p, *q) < 1e-9, "{p:?} vs {q:?}");
    }
    let found = centroids(&model.render(model.rest_pins(), None));
    assert_eq!(found.len(), 331, "one blob per pin");
    for (weighted, _) in &found {
        let nearest = expected
            .iter()
            .map(|q| distance(*weighted, *q))
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.1, "centroid {weighted:?} is {nearest} px off");
    }
}

#[test]
fn turning_a_rings_sensor_by_60_degrees_permutes_and_turns_its_field() {
    // As for the lattice (tests/it/mechanics.rs): zero-phase rings and the
    // contact patch are both symmetric under 60 degree turns.
    let model = TacTipModel::new(rings_config(8, Vec::new())).unwrap();
    let sd = |p: Vec2| p.y + 2.0;
    let d0 = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, 5.0, 0.0), None));
    let d60 = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, 5.0, 60.0), None));
    let rest = model.rest_pins();
    assert!(mean_magnitude(&d0) > 0.5, "edge contact must move pins");
    for (i, got) in d60.iter().enumerate() {
        let j = partner(rest, i, |v| rotate(v, 60.0));
        let expected = rotate(d0[j], -60.0);
        let err = (got[0] - expected[0]).hypot(got[1] - expected[1]);
        assert!(err < 1e-3, "pin {i}: {got:?} vs {expected:?}");
    }
}

#[test]
fn measured_rings_pins_keep_their_order_and_a_stray_pin_names_the_layout() {
    let model = TacTipModel::new(rings_config(10, vec![3.0; 10])).unwrap();
    let mut measured: Vec<[f64; 2]> = model
        .rest_pins()
        .iter()
        .map(|p| [p[0] + 0.3, p[1] - 0.2])
        .collect();
    measured.reverse();
    measured.swap(5, 200);
    let real = TacTipModel::with_rest_pins(model.config().clone(), measured.clone()).unwrap();
    assert_eq!(real.rest_pins(), measured.as_slice());
    // An outer pin moved 20 px (the outer ring's pins are about 12 px
    // apart there).
    measured[7] = [measured[7][0] + 20.0, measured[7][1]];
    let Err(err) = TacTipModel::with_rest_pins(model.config().clone(), measured) else {
        panic!("a pin 20 px from its place was accepted");
    };
    let text = err.to_string();
    assert!(text.contains("concentric rings"), "{text}");
    assert!(matches!(err, SensorError::RestPins { .. }), "{text}");
}
