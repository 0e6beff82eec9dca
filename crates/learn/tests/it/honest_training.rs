//! Training refuses what it cannot fit (issue 20): settings that are not
//! numbers in range, too few samples for the model, and a loss that grows
//! far beyond the loss of predicting the mean (a divergence even while it
//! is still a finite number).
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_learn::{Dataset, LearnError, ModelConfig, ModelKind, PoseModel, Preset};

/// Inputs that depend smoothly on (r, theta).
fn synthetic(n: usize, dim: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let r: f32 = rng.random_range(-5.0..5.0);
        let theta: f32 = rng.random_range(-45.0..45.0);
        for k in 0..dim {
            let v = ((k as f32 + 1.0) * r / 5.0 + theta / 45.0).sin();
            x.push(v + 0.01 * rng.random_range(-1.0..1.0));
        }
        y.extend([r, theta]);
    }
    Dataset::new(x, y, n, dim, 2).unwrap()
}

fn pdennn() -> ModelConfig {
    ModelConfig::preset(ModelKind::PDenNN, Preset::Default)
}

#[test]
fn an_anneal_fraction_that_is_not_in_0_1_is_refused_naming_the_key() {
    for bad in [f64::NAN, f64::INFINITY, -0.1, 1.5] {
        let mut cfg = pdennn();
        cfg.anneal_fraction = bad;
        let err = cfg.validate().expect_err("refused");
        assert!(
            matches!(
                err,
                LearnError::Config {
                    field: "anneal_fraction",
                    ..
                }
            ),
            "{bad}: {err}"
        );
        assert!(err.to_string().contains("anneal_fraction"), "{err}");
    }
    for good in [0.0, 0.25, 1.0] {
        let mut cfg = pdennn();
        cfg.anneal_fraction = good;
        cfg.validate().expect("in range");
    }
}

#[test]
fn errors_of_a_nets_table_name_the_net_and_the_key() {
    let mut cfg = pdennn();
    cfg.angle.as_mut().unwrap().n_components = Some(1 << 20);
    let err = cfg.validate().expect_err("too many components");
    assert!(
        matches!(
            err,
            LearnError::NetConfig {
                net: "angle",
                field: "n_components",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("[angle] n_components"), "{err}");
    let mut cfg = pdennn();
    cfg.position.as_mut().unwrap().beta = f64::NAN;
    let err = cfg.validate().expect_err("NaN beta");
    assert!(err.to_string().contains("[position] beta"), "{err}");
}

#[test]
fn too_few_samples_for_the_components_are_refused_before_training() {
    let cfg = {
        let mut c = pdennn();
        c.epochs = 1;
        for net in [&mut c.position, &mut c.angle].into_iter().flatten() {
            net.hidden = vec![16];
            net.n_components = Some(8);
        }
        c
    };
    assert_eq!(cfg.min_train_samples(24).0, 9);
    // Components beyond the inputs are not kept, so they need no samples.
    assert_eq!(cfg.min_train_samples(4).0, 5);
    let mut epochs = 0;
    let err = PoseModel::fit(&cfg, &synthetic(8, 24, 1), &mut |_| epochs += 1)
        .expect_err("8 samples for 8 components");
    assert!(
        matches!(
            err,
            LearnError::TooFewSamples {
                got: 8,
                needed: 9,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(epochs, 0, "refused before any epoch");
    assert!(err.to_string().contains("n_components = 8"), "{err}");
    PoseModel::fit(&cfg, &synthetic(9, 24, 1), &mut |_| {}).expect("9 samples fit");
    // One sample is too few for any model, with or without components.
    let mut dis = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
    dis.epochs = 1;
    let err = PoseModel::fit(&dis, &synthetic(1, 24, 1), &mut |_| {}).expect_err("1 sample");
    assert!(
        matches!(err, LearnError::TooFewSamples { needed: 2, .. }),
        "{err}"
    );
}

/// `[position] hidden = []` once reached a loss of 7e56 and was saved:
/// only a NaN or infinite loss counted as diverged.
#[test]
fn a_loss_far_above_the_means_is_a_divergence_while_still_finite() {
    let data = synthetic(200, 16, 3);
    let mut cfg = ModelConfig::preset(ModelKind::Mlp, Preset::Default);
    cfg.epochs = 3;
    cfg.divergence_retries = 0;
    for net in [&mut cfg.position, &mut cfg.angle].into_iter().flatten() {
        net.hidden = vec![];
        net.n_components = Some(8);
        net.learning_rate = 2.0;
        net.output_learning_rate = None;
    }
    let err = PoseModel::fit(&cfg, &data, &mut |_| {}).expect_err("diverges");
    match err {
        LearnError::Diverged { loss, limit, .. } => {
            assert!(loss.is_finite() && limit.is_finite() && loss > limit);
            // Standardised targets: the mean's loss is 0.5 for one target.
            assert_eq!(limit, 500.0);
        }
        other => panic!("{other}"),
    }
    // Halving the rates (the default retries) recovers.
    cfg.divergence_retries = 4;
    let (_, history) = PoseModel::fit(&cfg, &data, &mut |_| {}).expect("recovers");
    assert!(history.lr_halvings >= 1);
    let last = history.epochs.last().unwrap();
    assert!(last.nets.iter().all(|n| n.loss < 0.5), "{last:?}");
}
