//! Ensembles whose members diverge (issue 21, the 331-pin edge set): a
//! member that diverges restarts alone, from its own seed, with its rates
//! halved; the other members keep their results, so every member is bit
//! for bit the model its seed gives alone.
use crate::support;

use tactrace_learn::{Dataset, LearnError, ModelConfig, ModelKind, PoseModel, Preset};

/// `n` rows of `dim` correlated values and their two targets (a position
/// in mm and an angle in deg), a smooth function of them.
fn data(n: usize, dim: usize, seed: u64) -> Dataset {
    let (x, y) = support::correlated_rows(n, dim, seed);
    Dataset::new(x, y, n, dim, 2).expect("data")
}

/// A small PCADenNN at the default rates, an ensemble of six: on this
/// data the sixth member's seed diverges at these rates, the others not.
fn ensemble_of_six(retries: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    cfg.set_epochs(3);
    cfg.seed = 7;
    cfg.ensemble = 6;
    cfg.divergence_retries = retries;
    let net = cfg.pose.as_mut().expect("pose net");
    net.hidden = vec![40];
    net.n_components = Some(8);
    cfg.validate().expect("config");
    cfg
}

/// Member `m` of `cfg` trained alone: the single model of its seed.
fn solo(cfg: &ModelConfig, m: usize, d: &Dataset) -> Result<PoseModel, LearnError> {
    let one = ModelConfig {
        seed: cfg.member_seed(m),
        ensemble: 1,
        ..cfg.clone()
    };
    PoseModel::fit(&one, d, &mut |_| {}).map(|(model, _)| model)
}

#[test]
fn a_diverged_member_restarts_alone_and_the_others_are_bit_identical() {
    let d = data(80, 30, 1);
    // The case: only member 5 diverges at the starting rates.
    let strict = ensemble_of_six(0);
    for m in 0..6 {
        let alone = solo(&strict, m, &d);
        assert_eq!(
            alone.is_err(),
            m == 5,
            "member {m} alone: {:?}",
            alone.err()
        );
    }
    // Without retries the ensemble fails with that member's divergence.
    match PoseModel::fit(&strict, &d, &mut |_| {}) {
        Err(LearnError::Diverged { net, .. }) => assert_eq!(net, "pose#6"),
        other => panic!("expected member 6 to diverge, got {:?}", other.map(|_| ())),
    }

    let cfg = ensemble_of_six(3);
    let mut reports = 0;
    let (model, history) = PoseModel::fit(&cfg, &d, &mut |_| reports += 1).expect("ensemble");
    let want = solo(&ensemble_of_six(3), 5, &d).expect("member 6 restarted alone");
    let h5 = (want.config().pose.as_ref().unwrap().learning_rate
        / cfg.pose.as_ref().unwrap().learning_rate)
        .log2();
    assert_eq!(h5, -1.0, "member 6 alone trains after one halving");
    assert_eq!(history.member_lr_halvings, vec![0, 0, 0, 0, 0, 1]);
    assert_eq!(history.lr_halvings, 1);
    assert_eq!(model.member_lr_halvings(), vec![0, 0, 0, 0, 0, 1]);
    // The ensemble keeps its starting rates; the history has each net's
    // last fit, every epoch with all six nets.
    assert_eq!(model.config(), &cfg);
    assert_eq!(history.epochs.len(), 3);
    assert!(history.epochs.iter().all(|e| e.nets.len() == 6));
    assert!(reports >= 3, "progress after every epoch");

    let (json, weights) = model.to_bytes().expect("save");
    let loaded = PoseModel::from_bytes(&json, &weights).expect("load");
    assert_eq!(loaded.member_lr_halvings(), vec![0, 0, 0, 0, 0, 1]);
    for m in 0..6 {
        let alone = solo(&cfg, m, &d).expect("member alone");
        for from in [&model, &loaded] {
            let member = from.member(m).expect("member");
            assert_eq!(
                member.to_bytes().expect("member bytes"),
                alone.to_bytes().expect("solo bytes"),
                "member {m} differs from its solo run"
            );
        }
    }
}

#[test]
fn a_member_out_of_retries_fails_the_fit() {
    // A rate at which every seed diverges, however often halved twice.
    let d = data(80, 30, 1);
    let mut cfg = ensemble_of_six(2);
    cfg.ensemble = 2;
    cfg.scale_learning_rates(1e6);
    assert!(matches!(
        PoseModel::fit(&cfg, &d, &mut |_| {}),
        Err(LearnError::Diverged { .. })
    ));
}
