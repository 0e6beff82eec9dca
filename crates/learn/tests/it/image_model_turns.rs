//! An image model with turned frames (`turns` of its configuration):
//! trained with its circular target's sine and cosine turned, and, with
//! `at_prediction`, predicting one frame as it predicts a batch, the
//! angle the circular mean of the turned views; two targets named a
//! vector turn as one, checked against the model's targets.
use tactrace_convnet::{ConvConfig, ConvSpec, FrameTurns, Frames, ModelKind, TurnedVector};
use tactrace_learn::{ImageModel, LearnError, ModelTarget, Unit};

const SIDE: usize = 12;

/// Frames with a bright pixel at a place that moves with the index;
/// targets its distance from the centre (mm) and its angle about it (deg).
fn spot_frames(count: usize) -> (Vec<u8>, Vec<f32>) {
    let (mut pixels, mut values) = (Vec::new(), Vec::new());
    for k in 0..count {
        let (x, y) = (1 + (k * 7) % (SIDE - 2), 1 + (k * 5) % (SIDE - 2));
        let mut f = vec![10u8; SIDE * SIDE];
        f[y * SIDE + x] = 240;
        pixels.extend(f);
        let (dx, dy) = (x as f32 - 5.5, y as f32 - 5.5);
        values.extend([dx.hypot(dy), dy.atan2(dx).to_degrees()]);
    }
    (pixels, values)
}

fn config(at_prediction: bool) -> ConvConfig {
    let mut c = ConvConfig::new(ModelKind::ConvMlp);
    c.conv = vec![ConvSpec {
        channels: 4,
        kernel: 3,
        stride: 2,
    }];
    c.dense = vec![8];
    c.epochs = 2;
    c.batch_size = 12;
    c.chunk_size = 4;
    c.rotations = Some(FrameTurns {
        order: 6,
        angle_sign: 1,
        centre: Some([5.5, 5.5]),
        at_prediction,
        vectors: Vec::new(),
    });
    c
}

#[test]
fn turned_views_change_only_the_prediction_and_one_frame_is_a_batch_row() {
    let (pixels, values) = spot_frames(24);
    let frames = Frames::new(&pixels, 24, SIDE, SIDE).unwrap();
    let outputs = [
        ModelTarget::new("r", Unit::Mm),
        ModelTarget::circular("theta"),
    ];
    let fit = |c: &ConvConfig| {
        ImageModel::fit(&frames, &values, &outputs, c, 3, None, &mut |_| ())
            .unwrap()
            .0
    };
    let (plain, viewed) = (fit(&config(false)), fit(&config(true)));
    let (p, v) = (
        plain.predict_batch(&frames).unwrap(),
        viewed.predict_batch(&frames).unwrap(),
    );
    assert_ne!(p, v, "the views change the prediction");
    for i in [0, 7, 23] {
        let one = viewed.predict_targets(frames.frame(i)).unwrap();
        // one frame and a batch differ only by f32 rounding (the barely
        // trained net's short sine-cosine vector makes its angle sensitive)
        for (a, b) in one.iter().zip(&v[i]) {
            assert!((a - b).abs() < 1e-3, "frame {i}: {a} against {b}");
        }
        assert!(one[1] > -180.0 && one[1] <= 180.0);
        let alone = plain.predict_targets(frames.frame(i)).unwrap();
        for (a, b) in alone.iter().zip(&p[i]) {
            assert!(
                (a - b).abs() < 1e-3,
                "without the views, frame {i}: {a} against {b}"
            );
        }
    }
}

/// The spot frames' targets as a depth (mm) and the spot's offset from
/// the centre as two "tilts" (deg) that turn as a vector.
fn vector_targets(values: &[f32]) -> Vec<f32> {
    values
        .chunks(2)
        .flat_map(|t| {
            let a = t[1].to_radians();
            [1.5, t[0] * a.cos(), t[0] * a.sin()]
        })
        .collect()
}

fn vector_config(a: &str, b: &str) -> ConvConfig {
    let mut c = config(true);
    if let Some(t) = c.rotations.as_mut() {
        t.vectors = vec![TurnedVector {
            targets: [a.into(), b.into()],
            sign: 1,
        }];
    }
    c
}

#[test]
fn turned_vectors_name_two_targets_of_one_unit_and_survive_the_file() {
    let (pixels, values) = spot_frames(24);
    let frames = Frames::new(&pixels, 24, SIDE, SIDE).unwrap();
    let values = vector_targets(&values);
    let outputs = [
        ModelTarget::new("depth", Unit::Mm),
        ModelTarget::new("tilt_x", Unit::Deg),
        ModelTarget::new("tilt_y", Unit::Deg),
    ];
    let fit = |c: &ConvConfig| ImageModel::fit(&frames, &values, &outputs, c, 3, None, &mut |_| ());
    for (a, b) in [("tilt_x", "nope"), ("depth", "tilt_y")] {
        assert!(
            matches!(
                fit(&vector_config(a, b)),
                Err(LearnError::Config {
                    field: "rotations.vectors",
                    ..
                })
            ),
            "{a}, {b}"
        );
    }
    let model = fit(&vector_config("tilt_x", "tilt_y")).unwrap().0;
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("tilt_x"));
    let back = ImageModel::from_bytes(&json, &weights).unwrap();
    let (p, q) = (
        model.predict_batch(&frames).unwrap(),
        back.predict_batch(&frames).unwrap(),
    );
    assert_eq!(p, q);
    // the views' mean of a vector that turns: not the plain prediction
    let plain = fit(&config(true)).unwrap().0;
    let swapped = fit(&vector_config("tilt_y", "tilt_x")).unwrap().0;
    assert_ne!(
        plain.predict_batch(&frames).unwrap(),
        p,
        "the vector's copies change the fit"
    );
    assert_ne!(swapped.predict_batch(&frames).unwrap(), p);
}
