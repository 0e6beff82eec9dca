//! An image model of several networks (issue 22, accuracy): `members`
//! networks trained side by side from seeds `seed`, `seed + 1`, ..., the
//! model predicting their mean. Each network is exactly the one-network
//! model of its seed; the mean is what every prediction path returns;
//! the files keep every network, and a one-network model's files are as
//! they were before ensembles.
use crate::common;

use tactrace_convnet::{ConvConfig, ConvError, ConvModel, Frames, ModelKind, Targets};

const SIDE: usize = 12;

/// Frames with a bright 2 x 2 spot at a seeded place; targets its column
/// and row.
fn spots(count: usize, seed: u64) -> (Vec<u8>, Vec<f64>) {
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut next = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    let (mut pixels, mut targets) = (Vec::new(), Vec::new());
    for _ in 0..count {
        let (cx, cy) = (1 + next(SIDE - 3), 1 + next(SIDE - 3));
        let mut frame = vec![10u8; SIDE * SIDE];
        for y in cy..cy + 2 {
            for x in cx..cx + 2 {
                frame[y * SIDE + x] = 240;
            }
        }
        pixels.extend(frame);
        targets.extend([cx as f64, cy as f64]);
    }
    (pixels, targets)
}

/// The shared tiny configuration with a wider dense layer, 4 epochs of
/// batches of 8 and `members` networks.
fn config(kind: ModelKind, members: usize) -> ConvConfig {
    let mut c = common::tiny_config(kind);
    c.dense = vec![12];
    c.epochs = 4;
    c.batch_size = 8;
    c.learning_rate = 3e-3;
    c.members = members;
    c
}

fn fit(kind: ModelKind, members: usize, seed: u64) -> ConvModel {
    let (pixels, targets) = spots(64, 3);
    let frames = Frames::new(&pixels, 64, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 64, 2).unwrap();
    ConvModel::fit(&frames, &targets, &config(kind, members), seed)
        .unwrap()
        .0
}

#[test]
fn each_member_is_the_one_network_model_of_its_seed_and_the_model_predicts_their_mean() {
    let (pixels, _) = spots(20, 9);
    let frames = Frames::new(&pixels, 20, SIDE, SIDE).unwrap();
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let ensemble = fit(kind, 3, 5);
        assert_eq!(ensemble.networks().len(), 3);
        let singles: Vec<ConvModel> = (5..8).map(|s| fit(kind, 1, s)).collect();
        for (member, single) in ensemble.networks().iter().zip(&singles) {
            assert_eq!(member, single.network(), "{}", kind.name());
        }
        assert_ne!(ensemble.networks()[0], ensemble.networks()[1]);
        let batch = ensemble.predict_batch(&frames).unwrap();
        let each: Vec<Vec<f64>> = singles
            .iter()
            .map(|m| m.predict_batch(&frames).unwrap())
            .collect();
        for (i, &got) in batch.iter().enumerate() {
            let mean = each.iter().map(|p| p[i]).sum::<f64>() / 3.0;
            assert!((got - mean).abs() < 1e-9, "{got} against {mean}");
        }
        // One frame at a time (the servo loop's path) gives the same mean
        // (to f32 rounding: the products are blocked by the chunk size).
        for i in 0..20 {
            let one = ensemble.predict(frames.frame(i)).unwrap();
            let single: Vec<Vec<f64>> = singles
                .iter()
                .map(|m| m.predict(frames.frame(i)).unwrap())
                .collect();
            for (j, v) in one.iter().enumerate() {
                let mean = single.iter().map(|p| p[j]).sum::<f64>() / 3.0;
                assert!((v - mean).abs() < 1e-9, "{v} against {mean}");
                assert!((v - batch[i * 2 + j]).abs() < 1e-4);
            }
        }
    }
}

#[test]
fn the_history_scores_the_ensemble_on_the_validation_frames() {
    let (pixels, targets) = spots(64, 3);
    let frames = Frames::new(&pixels, 64, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 64, 2).unwrap();
    let (vp, vt) = spots(30, 4);
    let (vf, vt) = (
        Frames::new(&vp, 30, SIDE, SIDE).unwrap(),
        Targets::new(&vt, 30, 2).unwrap(),
    );
    let cfg = config(ModelKind::ConvMlp, 2);
    let (model, history) =
        ConvModel::fit_with(&frames, &targets, &cfg, 1, Some((vf, vt)), &mut |_| ()).unwrap();
    assert_eq!(history.epochs.len(), cfg.epochs);
    let last = history.epochs.last().unwrap().validation.clone().unwrap();
    let now = model.score(&vf, &vt).unwrap();
    for (a, b) in last.mae.iter().zip(&now.mae) {
        assert!((a - b).abs() < 1e-9, "{a} against {b}");
    }
}

#[test]
fn an_ensemble_saves_every_network_and_a_single_network_file_is_unchanged() {
    let ensemble = fit(ModelKind::ConvMlp, 2, 0);
    let (json, tensors) = ensemble.to_bytes().unwrap();
    assert!(json.contains("\"members\": 2"), "{json}");
    let back = ConvModel::from_bytes(&json, &tensors).unwrap();
    assert_eq!(back, ensemble);
    let (pixels, _) = spots(5, 2);
    let frames = Frames::new(&pixels, 5, SIDE, SIDE).unwrap();
    assert_eq!(
        back.predict_batch(&frames).unwrap(),
        ensemble.predict_batch(&frames).unwrap()
    );
    // The second network's tensors are named apart; drop them and the
    // file is refused, not read as one network.
    let parsed = safetensors::SafeTensors::deserialize(&tensors).unwrap();
    assert!(parsed.names().contains(&"net2.W1"));
    let one_json = json.replace("\"members\": 2", "\"members\": 3");
    assert!(matches!(
        ConvModel::from_bytes(&one_json, &tensors),
        Err(ConvError::Corrupt { .. })
    ));
    // One network: no `members` key, no prefixed tensors (files as before).
    let single = fit(ModelKind::ConvMlp, 1, 0);
    let (json, tensors) = single.to_bytes().unwrap();
    assert!(!json.contains("members"), "{json}");
    let parsed = safetensors::SafeTensors::deserialize(&tensors).unwrap();
    assert!(parsed.names().iter().all(|n| !n.starts_with("net")));
    assert_eq!(single.network(), ensemble.network());
}

#[test]
fn members_out_of_range_are_refused() {
    for members in [0, 33] {
        let err = config(ModelKind::ConvMlp, members).validate().unwrap_err();
        assert!(err.to_string().contains("members"), "{err}");
    }
}
