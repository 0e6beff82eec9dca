//! An image model with turned frames (`turns` of its configuration):
//! trained with its circular target's sine and cosine turned, and, with
//! `at_prediction`, predicting one frame as it predicts a batch, the
//! angle the circular mean of the turned views.
use tactrace_convnet::{ConvConfig, ConvSpec, FrameTurns, Frames, ModelKind};
use tactrace_learn::{ImageModel, ModelTarget, Unit};

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
