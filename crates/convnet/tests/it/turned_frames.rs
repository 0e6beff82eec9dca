//! Turned training frames (`ConvConfig::rotations`): a turned frame's spots
//! are the turned spots, an encoded angle turns as a vector, the option
//! is checked, kept in the model's JSON, and a fit with it trains on the
//! copies.
use crate::common;

use common::{moving_pair_frames, tiny_config, SIDE};
use tactrace_convnet::{
    turn_angles, turn_frame, ConvConfig, ConvError, ConvModel, FrameTurns, Frames, InputKind,
    ModelKind, Targets, TurnedColumns, TurnedVector, VectorColumns,
};

/// A ring of six pins (3 x 3 px each, 8 px from the centre of a 41 px
/// frame, the first at `start` deg) and one at the centre, as a 60 deg
/// turn carries onto itself.
fn ring_frame(start: f64) -> (Vec<u8>, Vec<[f64; 2]>) {
    const S: usize = 41;
    let mut f = vec![20u8; S * S];
    let mut pins = vec![[20.0, 20.0]];
    for k in 0..6 {
        let a = (start + 60.0 * k as f64).to_radians();
        pins.push([20.0 + 8.0 * a.cos(), 20.0 + 8.0 * a.sin()]);
    }
    for (i, v) in f.iter_mut().enumerate() {
        let (x, y) = ((i % S) as f64, (i / S) as f64);
        let lit: f64 = pins
            .iter()
            .map(|p| (-((x - p[0]).powi(2) + (y - p[1]).powi(2)) / 2.0).exp())
            .sum();
        *v = (20.0 + 220.0 * lit.min(1.0)).round() as u8;
    }
    (f, pins)
}

/// The centroid (above the background of 20) of the 5 x 5 px window
/// of a 41 px frame about `at`.
fn centroid_near(f: &[u8], at: [f64; 2]) -> [f64; 2] {
    let (cx, cy) = (at[0].round() as usize, at[1].round() as usize);
    let (mut m, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in cy - 2..=cy + 2 {
        for x in cx - 2..=cx + 2 {
            let v = f64::from(f[y * 41 + x]) - 20.0;
            m += v;
            sx += v * x as f64;
            sy += v * y as f64;
        }
    }
    [sx / m, sy / m]
}

fn mean_difference(a: &[u8], b: &[u8]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&a, &b)| f64::from((i32::from(a) - i32::from(b)).abs()))
        .sum::<f64>()
        / a.len() as f64
}

#[test]
fn a_turned_frame_holds_the_turned_pins() {
    // pins at 10 deg, turned by 40 deg (image coordinates, y down): each
    // pin lands where R(40 deg) carries it, the frame of pins at 50 deg
    let (frame, pins) = ring_frame(10.0);
    let (want, turned_pins) = ring_frame(50.0);
    let mut out = vec![0u8; frame.len()];
    turn_frame(&frame, (41, 41), [20.0, 20.0], 40.0, &mut out);
    for (p, q) in pins.iter().zip(&turned_pins) {
        let (s, c) = 40f64.to_radians().sin_cos();
        let (dx, dy) = (p[0] - 20.0, p[1] - 20.0);
        let expected = [20.0 + c * dx - s * dy, 20.0 + s * dx + c * dy];
        assert!((expected[0] - q[0]).hypot(expected[1] - q[1]) < 1e-9);
        let seen = centroid_near(&out, expected);
        let miss = (seen[0] - expected[0]).hypot(seen[1] - expected[1]);
        assert!(
            miss < 0.1,
            "pin {p:?}: seen at {seen:?}, expected {expected:?}"
        );
    }
    // bilinear resampling of a spot of sigma 1 px blurs it a little
    let mean = mean_difference(&out, &want);
    assert!(mean < 2.0, "mean pixel difference {mean}");
    // the wrong way round (-40 deg: pins at -30 deg) is far worse
    let (wrong, _) = ring_frame(-30.0);
    let mean_wrong = mean_difference(&out, &wrong);
    assert!(mean_wrong > 4.0 * mean, "{mean_wrong} against {mean}");
}

#[test]
fn a_turn_of_the_pattern_s_symmetry_keeps_the_frame() {
    let (frame, _) = ring_frame(0.0);
    let mut out = vec![0u8; frame.len()];
    turn_frame(&frame, (41, 41), [20.0, 20.0], 60.0, &mut out);
    let mean = mean_difference(&out, &frame);
    assert!(mean < 2.0, "mean pixel difference {mean}");
    turn_frame(&frame, (41, 41), [20.0, 20.0], 0.0, &mut out);
    assert_eq!(out, frame, "a turn of 0 deg is the frame");
}

#[test]
fn an_encoded_angle_turns_as_a_vector() {
    for (a, d) in [(10.0f64, 60.0), (-170.0, -120.0), (179.0, 300.0)] {
        let (s, c) = a.to_radians().sin_cos();
        let mut row = [2.5, s, c, 7.0];
        turn_angles(&mut row, &[1], d);
        let (ws, wc) = (a + d).to_radians().sin_cos();
        assert!((row[1] - ws).abs() < 1e-12 && (row[2] - wc).abs() < 1e-12);
        assert_eq!([row[0], row[3]], [2.5, 7.0]);
    }
}

#[test]
fn angle_columns_must_fit_the_row() {
    let values = [0.0; 6];
    let t = Targets::new(&values, 2, 3).unwrap();
    assert!(t.with_angles(&[1]).is_ok());
    for bad in [&[2][..], &[0, 1][..]] {
        assert!(matches!(
            t.with_angles(bad),
            Err(ConvError::AngleColumns { .. })
        ));
    }
}

/// The columns a turn moves in the spot sets below: the angle at column 1.
fn angle_one() -> TurnedColumns<'static> {
    TurnedColumns {
        angles: &[1],
        vectors: &[],
    }
}

fn turns() -> FrameTurns {
    FrameTurns {
        order: 6,
        angle_sign: -1,
        centre: Some([5.5, 5.5]),
        at_prediction: false,
        vectors: Vec::new(),
    }
}

#[test]
fn the_option_is_checked() {
    let mut c = ConvConfig::new(ModelKind::ConvMlp);
    for (order, sign) in [(1, 1), (13, 1), (6, 0), (6, 2)] {
        c.rotations = Some(FrameTurns {
            order,
            angle_sign: sign,
            ..turns()
        });
        assert!(matches!(c.validate(), Err(ConvError::Config { .. })));
    }
    c.rotations = Some(FrameTurns {
        centre: Some([f64::NAN, 1.0]),
        ..turns()
    });
    assert!(c.validate().is_err());
    c.rotations = Some(turns());
    assert!(c.validate().is_ok());
    c.input = InputKind::PinsAndPixels;
    assert!(matches!(
        c.validate(),
        Err(ConvError::Config {
            field: "rotations",
            ..
        })
    ));
}

#[test]
fn a_vector_is_checked_and_its_columns_kept_apart() {
    let mut c = ConvConfig::new(ModelKind::ConvMlp);
    let vector = |a: &str, b: &str, sign| TurnedVector {
        targets: [a.into(), b.into()],
        sign,
    };
    for v in [
        vector("a", "b", 0),
        vector("a", "b", 2),
        vector("a", "a", 1),
    ] {
        c.rotations = Some(FrameTurns {
            vectors: vec![v],
            ..turns()
        });
        assert!(matches!(c.validate(), Err(ConvError::Config { .. })));
    }
    c.rotations = Some(FrameTurns {
        vectors: vec![vector("a", "b", -1)],
        ..turns()
    });
    assert!(c.validate().is_ok());
    let values = [0.0; 5];
    let t = Targets::new(&values, 1, 5)
        .unwrap()
        .with_angles(&[0])
        .unwrap();
    let at = |columns, sign| [VectorColumns { columns, sign }];
    assert!(t.with_vectors(&at([2, 3], 1)).is_ok());
    for bad in [[1, 2], [2, 5], [3, 3]] {
        assert!(
            matches!(
                t.with_vectors(&at(bad, 1)),
                Err(ConvError::VectorColumns { .. })
            ),
            "{bad:?}"
        );
    }
}

#[test]
fn the_vectors_are_kept_in_the_model_json() {
    let text = r#"{"order": 6, "angle_sign": -1, "vectors": [{"targets": ["pose_4", "pose_5"], "sign": 1}]}"#;
    let t: FrameTurns = serde_json::from_str(text).unwrap();
    assert_eq!(
        t.vectors[0].targets,
        ["pose_4".to_string(), "pose_5".into()]
    );
    let back: FrameTurns = serde_json::from_str(&serde_json::to_string(&t).unwrap()).unwrap();
    assert_eq!(back, t);
    let none = serde_json::to_string(&turns()).unwrap();
    assert!(!none.contains("vectors"), "no vectors, no key: {none}");
}

#[test]
fn the_frame_centre_is_the_default() {
    let t = FrameTurns {
        centre: None,
        ..turns()
    };
    assert_eq!(t.centre_for((64, 48)), [23.5, 31.5]);
    assert_eq!(turns().centre_for((64, 48)), [5.5, 5.5]);
}

/// 24 tiny frames of a moving bright pair; targets its column and its
/// angle about the frame's centre as a sine and a cosine (column 1).
fn spot_angle_frames() -> (Vec<u8>, Vec<f64>) {
    let (pixels, targets) = moving_pair_frames(24);
    let values = targets
        .chunks(2)
        .flat_map(|t| {
            let a = (t[1] - 5.5).atan2(t[0] - 5.5);
            [t[0], a.sin(), a.cos()]
        })
        .collect();
    (pixels, values)
}

/// The spot frames as a training set, the angle's (sin, cos) pair at
/// column 1.
fn spot_angle_set<'a>(pixels: &'a [u8], values: &'a [f64]) -> (Frames<'a>, Targets<'a>) {
    let frames = Frames::new(pixels, 24, SIDE, SIDE).unwrap();
    let t = Targets::new(values, 24, 3)
        .unwrap()
        .with_angles(&[1])
        .unwrap();
    (frames, t)
}

#[test]
fn a_fit_with_turns_keeps_them_and_differs() {
    let (pixels, values) = spot_angle_frames();
    let (frames, t) = spot_angle_set(&pixels, &values);
    let plain = tiny_config(ModelKind::ConvMlp);
    let mut turned = plain.clone();
    turned.rotations = Some(turns());
    let (m0, h0) = ConvModel::fit(&frames, &t, &plain, 1).unwrap();
    let (m1, h1) = ConvModel::fit(&frames, &t, &turned, 1).unwrap();
    assert_ne!(h0.epochs[0].loss, h1.epochs[0].loss);
    assert_ne!(
        m0.predict(frames.frame(3)).unwrap(),
        m1.predict(frames.frame(3)).unwrap()
    );
    let (json, weights) = m1.to_bytes().unwrap();
    assert!(json.contains("\"rotations\""));
    assert!(!m0.to_bytes().unwrap().0.contains("\"rotations\""));
    let back = ConvModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(back.config().rotations, Some(turns()));
    assert_eq!(
        back.predict(frames.frame(3)).unwrap(),
        m1.predict(frames.frame(3)).unwrap()
    );
}

#[test]
fn turned_views_at_prediction_are_the_mean_of_the_views_turned_back() {
    let (pixels, values) = spot_angle_frames();
    let (frames, t) = spot_angle_set(&pixels, &values);
    let mut config = tiny_config(ModelKind::ConvMlp);
    config.rotations = Some(turns());
    let (plain, _) = ConvModel::fit(&frames, &t, &config, 2).unwrap();
    config.rotations = Some(FrameTurns {
        at_prediction: true,
        ..turns()
    });
    let (viewed, _) = ConvModel::fit(&frames, &t, &config, 2).unwrap();
    // the option changes prediction only
    assert_eq!(
        plain.predict_batch(&frames).unwrap(),
        viewed.predict_batch(&frames).unwrap()
    );
    assert_eq!(
        plain.predict_batch_turned(&frames, angle_one()).unwrap(),
        plain.predict_batch(&frames).unwrap()
    );
    let mut want = vec![0.0; 24 * 3];
    let mut turned = vec![0u8; pixels.len()];
    for k in 0..6 {
        let deg = 60.0 * k as f64;
        for i in 0..24 {
            let hw = SIDE * SIDE;
            turn_frame(
                frames.frame(i),
                (SIDE, SIDE),
                [5.5, 5.5],
                deg,
                &mut turned[i * hw..(i + 1) * hw],
            );
        }
        let view = Frames::new(&turned, 24, SIDE, SIDE).unwrap();
        let mut out = plain.predict_batch(&view).unwrap();
        for row in out.chunks_exact_mut(3) {
            turn_angles(row, &[1], deg); // angle_sign -1: back by +deg
        }
        want.iter_mut().zip(&out).for_each(|(w, o)| *w += o / 6.0);
    }
    let got = viewed.predict_batch_turned(&frames, angle_one()).unwrap();
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-9, "{g} against {w}");
    }
}
