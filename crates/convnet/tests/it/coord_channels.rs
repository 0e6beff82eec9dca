//! The coordinate channels (CoordConv; issue 22, accuracy item 1): two
//! fixed planes beside the frame, each pixel's column and row in [-1, 1].
//! They are clamped inputs like the frame, so the EP estimate must still
//! approach the backprop gradient, the planes must reach the first layer,
//! and a model with them must survive its file.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_convnet::{
    Activation, ClampedPhase, ConvConfig, ConvModel, ConvSpec, EpSettings, Frames, FreePhase,
    Layout, ModelKind, Network, Nudging, Rule, Targets,
};

const SIDE: usize = 10;

fn conv() -> Vec<ConvSpec> {
    vec![ConvSpec {
        channels: 3,
        kernel: 3,
        stride: 2,
    }]
}

fn coord_net(seed: u64) -> Network {
    let layout = Layout::with_channels(3, (SIDE, SIDE), &conv(), &[6], 2).expect("layout");
    Network::new(layout, Activation::Tanh, seed)
}

fn random(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-1.0..1.0)).collect()
}

#[test]
fn coord_layout_has_three_input_planes() {
    let layout = Layout::with_channels(3, (SIDE, SIDE), &conv(), &[6], 2).unwrap();
    let plain = Layout::new(SIDE, SIDE, &conv(), &[6], 2).unwrap();
    assert_eq!(layout.input_channels(), 3);
    assert_eq!(plain.input_channels(), 1);
    assert_eq!(layout.layers()[0].fan_in(), 3 * plain.layers()[0].fan_in());
    assert_eq!(layout.input_size(), (SIDE, SIDE));
    let mut cfg = ConvConfig::new(ModelKind::ConvMlp);
    assert_eq!(cfg.input_channels(), 1);
    cfg.coord_channels = true;
    assert_eq!(cfg.input_channels(), 3);
}

#[test]
fn coord_planes_reach_the_first_layer() {
    // A blank frame: without the planes every position of the first layer
    // would see the same window (but for the zero padding at the border);
    // with them, changing only the weights on the planes moves the output.
    let mut net = coord_net(3);
    let x = vec![0.0f32; SIDE * SIDE];
    let before = net.feed_forward(&x, 1).unwrap();
    let k = 9; // kernel 3 x 3: columns 9..27 of each row weigh the planes
    for row in net.parameters_mut().weights[0].chunks_mut(27) {
        row[k..].iter_mut().for_each(|w| *w += 0.5);
    }
    let after = net.feed_forward(&x, 1).unwrap();
    let moved: f32 = before.iter().zip(&after).map(|(a, b)| (a - b).abs()).sum();
    assert!(
        moved > 1e-3,
        "the coordinate weights change nothing: {moved}"
    );
    // And the backprop gradient on those weights is not zero.
    let t = vec![0.3f32, -0.2];
    let g = net.gradient(&x, &t, 1, Rule::Backprop).unwrap();
    let on_planes: f32 = g.weights[0]
        .chunks(27)
        .flat_map(|row| row[k..].iter())
        .map(|v| v.abs())
        .sum();
    assert!(
        on_planes > 1e-6,
        "no gradient reaches the coordinate weights"
    );
}

#[test]
fn coord_ep_estimate_matches_backprop() {
    let net = coord_net(7);
    let n = 3;
    let x = random(n * SIDE * SIDE, 1);
    let t = random(n * 2, 2);
    let bp = net.gradient(&x, &t, n, Rule::Backprop).unwrap();
    let ep = Rule::Ep(EpSettings {
        beta: 0.01,
        nudging: Nudging::Symmetric,
        free_phase: FreePhase::FeedForward,
        clamped_phase: ClampedPhase::Sweeps { iterations: 1 },
    });
    let est = net.gradient(&x, &t, n, ep).unwrap();
    let cos = est.cosine(&bp);
    assert!(cos > 0.99, "cosine {cos}");
}

/// Frames with one bright 2 x 2 spot at a seeded place; targets its corner.
fn spots(count: usize) -> (Vec<u8>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut pixels, mut targets) = (Vec::new(), Vec::new());
    for _ in 0..count {
        let (cx, cy) = (rng.random_range(1..SIDE - 2), rng.random_range(1..SIDE - 2));
        let mut frame = vec![10u8; SIDE * SIDE];
        for y in cy..cy + 2 {
            frame[y * SIDE + cx..y * SIDE + cx + 2].fill(240);
        }
        pixels.extend(frame);
        targets.extend([cx as f64, cy as f64]);
    }
    (pixels, targets)
}

#[test]
fn coord_model_round_trips_through_its_file() {
    let (pixels, targets) = spots(32);
    let frames = Frames::new(&pixels, 32, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 32, 2).unwrap();
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let mut cfg = ConvConfig::new(kind);
        cfg.conv = conv();
        cfg.dense = vec![8];
        cfg.epochs = 2;
        cfg.batch_size = 8;
        cfg.chunk_size = 4;
        cfg.coord_channels = true;
        let (model, _) = ConvModel::fit(&frames, &targets, &cfg, 1).unwrap();
        assert_eq!(model.network().layout().input_channels(), 3);
        let (json, bytes) = model.to_bytes().unwrap();
        assert!(
            json.contains("\"coord_channels\": true") || json.contains("\"coord_channels\":true")
        );
        let back = ConvModel::from_bytes(&json, &bytes).unwrap();
        assert_eq!(back, model);
        let frame = frames.frame(3);
        assert_eq!(back.predict(frame).unwrap(), model.predict(frame).unwrap());
    }
    // Without the option the file does not name it (older files load).
    let plain = serde_json::to_string(&ConvConfig::new(ModelKind::ConvMlp)).unwrap();
    assert!(!plain.contains("coord_channels"));
}
