//! The image model as the CLI will use it (issue 22): fit on frames and
//! targets, predict N outputs, serialise to JSON + safetensors and back;
//! seeded runs reproduce bit for bit whatever the thread count; bad input
//! is a typed error, never a panic.
use tactrace_convnet::{
    ClampedPhase, ConvConfig, ConvError, ConvModel, ConvSpec, Frames, ModelKind, Targets,
    CONV_FORMAT_VERSION,
};

const SIDE: usize = 16;

/// Frames with a bright 3 x 3 spot at a known place: targets are its
/// column and row in "mm" (px / 2) and a third, constant target.
fn spots(count: usize, seed: u64) -> (Vec<u8>, Vec<f64>) {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = |n: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) % n as u64) as usize
    };
    let (mut pixels, mut targets) = (Vec::new(), Vec::new());
    for _ in 0..count {
        let (cx, cy) = (2 + next(SIDE - 4), 2 + next(SIDE - 4));
        let mut frame = vec![20u8; SIDE * SIDE];
        for y in cy - 1..=cy + 1 {
            for x in cx - 1..=cx + 1 {
                frame[y * SIDE + x] = 230;
            }
        }
        pixels.extend(frame);
        targets.extend([cx as f64 / 2.0, cy as f64 / 2.0, 7.0]);
    }
    (pixels, targets)
}

fn small_config(kind: ModelKind) -> ConvConfig {
    let mut c = ConvConfig::new(kind);
    c.conv = vec![
        ConvSpec {
            channels: 4,
            kernel: 3,
            stride: 1,
        },
        ConvSpec {
            channels: 8,
            kernel: 3,
            stride: 2,
        },
    ];
    c.dense = vec![32];
    c.epochs = 12;
    c.batch_size = 16;
    c.chunk_size = 4;
    c.learning_rate = 3e-3;
    c
}

fn fit(kind: ModelKind, seed: u64) -> (ConvModel, tactrace_convnet::TrainingHistory) {
    fit_with(small_config(kind), seed)
}

fn fit_with(config: ConvConfig, seed: u64) -> (ConvModel, tactrace_convnet::TrainingHistory) {
    let (pixels, targets) = spots(160, 1);
    let frames = Frames::new(&pixels, 160, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 160, 3).unwrap();
    ConvModel::fit(&frames, &targets, &config, seed).unwrap()
}

#[test]
fn both_rules_learn_where_a_spot_is() {
    let (pixels, targets) = spots(160, 1);
    let seen = Frames::new(&pixels, 160, SIDE, SIDE).unwrap();
    let seen_t = Targets::new(&targets, 160, 3).unwrap();
    let (pixels, targets) = spots(100, 2);
    let new = Frames::new(&pixels, 100, SIDE, SIDE).unwrap();
    let new_t = Targets::new(&targets, 100, 3).unwrap();
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        let (model, history) = fit(kind, 3);
        let first = history.epochs[0].loss;
        let last = history.epochs.last().unwrap().loss;
        assert!(last < first * 0.02, "{kind:?}: loss {first} -> {last}");
        // The targets spread over about 1.6 "mm"; predicting their mean
        // would be off by about 1.4.
        let fitted = model.score(&seen, &seen_t).unwrap();
        let held_out = model.score(&new, &new_t).unwrap();
        eprintln!(
            "{kind:?}: fitted {:?} held out {:?}",
            fitted.mae, held_out.mae
        );
        assert!(
            fitted.mae.iter().all(|&e| e < 0.1),
            "{kind:?}: {:?}",
            fitted.mae
        );
        assert!(
            held_out.mae.iter().all(|&e| e < 0.4),
            "{kind:?}: {:?}",
            held_out.mae
        );
        let one = model.predict(new.frame(0)).unwrap();
        let batch = model.predict_batch(&new).unwrap();
        // One frame or a chunk of frames: the same numbers up to f32
        // rounding (the matrix products' summation order depends on shape).
        assert_eq!(one.len(), 3);
        for (a, b) in batch[..3].iter().zip(&one) {
            assert!((a - b).abs() < 1e-5 * b.abs().max(1.0), "{a} vs {b}");
        }
    }
}

#[test]
fn seeded_fits_reproduce_whatever_the_thread_count() {
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        // With the shifts drawn per frame and epoch, and an uneven last
        // batch and chunk (160 frames, batches of 16 in chunks of 4 -> 48
        // in chunks of 5).
        let mut config = small_config(kind);
        config.shift_augment = 1;
        config.batch_size = 48;
        config.chunk_size = 5;
        let run = |threads: usize, seed: u64| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| fit_with(config.clone(), seed))
        };
        let (a, ha) = run(1, 5);
        let (b, hb) = run(3, 5);
        assert_eq!(a.to_bytes().unwrap(), b.to_bytes().unwrap(), "{kind:?}");
        assert_eq!(ha, hb);
        let (c, _) = run(2, 6);
        assert_ne!(a.network().parameters(), c.network().parameters());
    }
}

#[test]
fn twins_start_from_the_same_weights() {
    // One epoch at a negligible step size: both kinds keep their start,
    // which must be the same for the same seed.
    let (pixels, targets) = spots(8, 1);
    let frames = Frames::new(&pixels, 8, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 8, 3).unwrap();
    let start = |kind: ModelKind| {
        let mut cfg = small_config(kind);
        cfg.epochs = 1;
        cfg.learning_rate = 1e-20;
        let (model, _) = ConvModel::fit(&frames, &targets, &cfg, 9).unwrap();
        model.network().parameters().flatten()
    };
    let (a, b) = (start(ModelKind::ConvDennn), start(ModelKind::ConvMlp));
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-15, "{worst}");
    let other = {
        let mut cfg = small_config(ModelKind::ConvMlp);
        cfg.epochs = 1;
        cfg.learning_rate = 1e-20;
        let (model, _) = ConvModel::fit(&frames, &targets, &cfg, 10).unwrap();
        model.network().parameters().flatten()
    };
    assert!(a.iter().zip(&other).any(|(x, y)| (x - y).abs() > 1e-3));
}

#[test]
fn model_round_trips_through_json_and_safetensors() {
    let (model, _) = fit(ModelKind::ConvDennn, 4);
    let (json, weights) = model.to_bytes().unwrap();
    let back = ConvModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(back.config(), model.config());
    assert_eq!(back.network(), model.network());
    assert_eq!(back.input_scaling(), model.input_scaling());
    assert_eq!(back.target_scaling(), model.target_scaling());
    assert_eq!(back, model);
    let (pixels, _) = spots(1, 3);
    assert_eq!(
        back.predict(&pixels).unwrap(),
        model.predict(&pixels).unwrap()
    );

    let newer = json.replace(
        &format!("\"version\": {CONV_FORMAT_VERSION}"),
        "\"version\": 99",
    );
    assert!(matches!(
        ConvModel::from_bytes(&newer, &weights),
        Err(ConvError::Version { found: 99, .. })
    ));
    assert!(matches!(
        ConvModel::from_bytes(&json, &weights[..weights.len() / 2]),
        Err(ConvError::Corrupt { .. })
    ));
    let other_shape = json.replace("\"channels\": 8", "\"channels\": 9");
    let err = ConvModel::from_bytes(&other_shape, &weights).unwrap_err();
    assert!(err.to_string().contains("tensor W2"), "{err}");
    assert!(matches!(
        ConvModel::from_bytes("{\"format\": \"tactrace-pose-model\"}", &weights),
        Err(ConvError::Corrupt { .. })
    ));
}

#[test]
fn bad_input_is_a_typed_error() {
    let (pixels, targets) = spots(10, 1);
    let frames = Frames::new(&pixels, 10, SIDE, SIDE).unwrap();
    let t = Targets::new(&targets, 10, 3).unwrap();
    assert!(Frames::new(&pixels[1..], 10, SIDE, SIDE).is_err());
    let mut nan = targets.clone();
    nan[4] = f64::NAN;
    assert!(matches!(
        Targets::new(&nan, 10, 3),
        Err(ConvError::NonFinite {
            row: 1,
            column: 1,
            ..
        })
    ));
    let short = Targets::new(&targets[..27], 9, 3).unwrap();
    let cfg = small_config(ModelKind::ConvMlp);
    assert!(ConvModel::fit(&frames, &short, &cfg, 0).is_err());
    let empty = Frames::new(&[], 0, SIDE, SIDE).unwrap();
    let none = Targets::new(&[], 0, 3).unwrap();
    assert!(matches!(
        ConvModel::fit(&empty, &none, &cfg, 0),
        Err(ConvError::Empty)
    ));
    for (field, change) in [
        (
            "ep.beta",
            Box::new(|c: &mut ConvConfig| c.ep.beta = 1.0) as Box<dyn Fn(&mut ConvConfig)>,
        ),
        (
            "chunk_size",
            Box::new(|c: &mut ConvConfig| c.chunk_size = 0),
        ),
        (
            "learning_rate",
            Box::new(|c: &mut ConvConfig| c.learning_rate = f64::NAN),
        ),
        (
            "conv.kernel",
            Box::new(|c: &mut ConvConfig| c.conv[0].kernel = 0),
        ),
        (
            "ep.clamped_phase.iterations",
            Box::new(|c: &mut ConvConfig| {
                c.ep.clamped_phase = ClampedPhase::Sweeps { iterations: 0 }
            }),
        ),
    ] {
        let mut bad = cfg.clone();
        change(&mut bad);
        match ConvModel::fit(&frames, &t, &bad, 0) {
            Err(e @ ConvError::Config { field: f, .. }) if f == field => assert!(e.is_bad_input()),
            other => panic!("{field}: {other:?}"),
        }
    }
    let (model, _) = fit(ModelKind::ConvMlp, 1);
    assert!(matches!(
        model.predict(&pixels[..10]),
        Err(ConvError::Shape { .. })
    ));
    let wrong = Frames::new(&pixels[..8 * 8 * 10], 10, 8, 8).unwrap();
    assert!(matches!(
        model.predict_batch(&wrong),
        Err(ConvError::FrameSize { .. })
    ));
}

#[test]
fn a_diverging_fit_is_an_error_not_a_model() {
    let mut cfg = small_config(ModelKind::ConvMlp);
    cfg.learning_rate = 1e6;
    cfg.final_lr_fraction = 1.0;
    let (pixels, targets) = spots(64, 1);
    let frames = Frames::new(&pixels, 64, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 64, 3).unwrap();
    let err = ConvModel::fit(&frames, &targets, &cfg, 0).unwrap_err();
    assert!(matches!(err, ConvError::Diverged { .. }), "{err}");
    assert!(!err.is_bad_input());
}
