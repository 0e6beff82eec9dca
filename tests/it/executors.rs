//! What runs through the executor of `search`, `sim-fit` and `tune`
//! (issue 24): a tuning's start and held-out judgement as well as its
//! generations (the same files as on this machine when every evaluation
//! is sent as a remote worker gets it), and a search, sim-fit or tune
//! none of whose trials gave a score ending with exit 1 and no best.
use crate::util;
use std::sync::Mutex;
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::remote::evaluate;
use tactrace_lab::tune::{tune, TuneConfig};
use tactrace_lab::LabError;
use tactrace_optim::{Evaluation, Executor, Local, RunError};
use tactrace_store::StoredModel;
use util::{real_data, tactrace, TempDir};

/// Every configuration sent as a Ray worker gets it: the evaluation's
/// name, its context and the configuration as JSON, through
/// `tactrace_lab::remote::evaluate`, the score parsed back; the names
/// seen are kept.
#[derive(Default)]
struct AsWorker {
    seen: Mutex<Vec<(String, usize)>>,
}

impl Executor for AsWorker {
    fn run<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RunError<E::Error>> {
        let context = evaluation.context().expect("a remote form");
        self.seen
            .lock()
            .unwrap()
            .push((E::NAME.to_string(), configs.len()));
        let scores = configs
            .iter()
            .map(|c| {
                let config = serde_json::to_string(c).unwrap();
                let score = evaluate(E::NAME, &context, &config).unwrap();
                serde_json::from_str(&score).unwrap()
            })
            .collect();
        Ok(scores)
    }
}

/// Every evaluation "fails": each score is the one JSON text given.
struct AllFail(&'static str);

impl Executor for AllFail {
    fn run<E: Evaluation>(
        &self,
        _: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RunError<E::Error>> {
        Ok(configs
            .iter()
            .map(|_| serde_json::from_str(self.0).expect("a score of this evaluation"))
            .collect())
    }
}

/// A 2-epoch model `m` and a tiny tuning's settings (runs of 25 taps).
fn tuning(t: &TempDir) -> (TuneConfig, SimFollowConfig, StoredModel) {
    let ok = |args: &[&str]| {
        let r = tactrace(&t.0, args);
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
    };
    ok(&["collect", "--samples", "40", "--seed", "3", "--out", "ds"]);
    ok(&[
        "train", "--model", "pdennn", "--train", "ds", "--epochs", "2", "--out", "m",
    ]);
    let cfg = TuneConfig {
        seed: 5,
        trials: 4,
        population: Some(2),
        training: vec!["square:50".into()],
        held_out: vec!["star:36,4,6".into()],
        held_out_seeds: 2,
        ..TuneConfig::default()
    };
    let mut base = SimFollowConfig::default();
    base.follow.max_steps = 25;
    (cfg, base, StoredModel::load(&t.join("m")).unwrap())
}

#[test]
fn tune_runs_its_start_and_judgement_through_the_executor() {
    let t = TempDir::new("tune-exec");
    let (cfg, base, model) = tuning(&t);
    let m = t.join("m");
    let quiet = |_| {};
    tune(
        &cfg,
        &base,
        (&model, &m),
        (&t.join("local"), false),
        &Local,
        &quiet,
    )
    .unwrap();
    let worker = AsWorker::default();
    tune(
        &cfg,
        &base,
        (&model, &m),
        (&t.join("worker"), false),
        &worker,
        &quiet,
    )
    .unwrap();
    for f in ["history.csv", "tuned.toml", "held_out.json", "held_out.md"] {
        let a = std::fs::read(t.join("local").join(f)).unwrap();
        let b = std::fs::read(t.join("worker").join(f)).unwrap();
        assert!(
            a == b,
            "{f} differs between the local executor and a worker's"
        );
    }
    let seen = worker.seen.lock().unwrap().clone();
    let tune_name = tactrace_lab::tune::TuneTrial::NAME.to_string();
    let judge_name = tactrace_lab::tune::HeldOutTrial::NAME.to_string();
    // The start (one candidate), two generations of two, then the
    // judgement: 1 contour x 2 seeds x (base, tuned).
    assert_eq!(
        seen,
        vec![
            (tune_name.clone(), 1),
            (tune_name.clone(), 2),
            (tune_name, 2),
            (judge_name, 4)
        ]
    );
}

#[test]
fn a_tuning_whose_every_candidate_failed_is_a_failed_run() {
    let t = TempDir::new("tune-fail");
    let (cfg, base, model) = tuning(&t);
    let out = t.join("tuned");
    let e = tune(
        &cfg,
        &base,
        (&model, &t.join("m")),
        (&out, false),
        &AllFail("null"),
        &|_| {},
    )
    .unwrap_err();
    assert!(matches!(e, LabError::AllFailed { tried: 5, .. }), "{e}");
    assert!(!e.is_bad_input(), "{e}");
    assert!(!out.exists());
    let partial = t.join("tuned.partial");
    assert!(!partial.join("tuned.toml").exists(), "a best from nothing");
    let history = std::fs::read_to_string(partial.join("history.csv")).unwrap();
    let failed: Vec<&str> = history
        .lines()
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    assert_eq!(failed, ["failed", "1", "2", "2"], "{history}");
}

#[test]
fn a_sim_fit_whose_every_candidate_failed_is_a_failed_run() {
    use tactrace_lab::transfer_fit::{fit_transfer, TransferFitConfig};
    use tactrace_store::collection::RowSelection;
    use tactrace_store::LabelledCollection;
    let Some(data) = real_data() else { return };
    let cfg = TransferFitConfig {
        collection: LabelledCollection::bristol(&data).with_rows(RowSelection {
            limit: Some(60),
            keep: None,
        }),
        render_seed: 1,
        generations: 2,
        population: Some(3),
        sigma: 0.3,
        seed: 1,
        val_fraction: 0.15,
        deg_per_mm: 5.0,
        renders: 1,
    };
    let sensor = tactrace_sensor::TacTipConfig::default();
    let mut told = Vec::new();
    let failing = AllFail(r#"{"mae": null, "failure": "the training diverged"}"#);
    let e = fit_transfer(&cfg, &sensor, &failing, &mut |c, best| {
        told.push((c.status(), best.is_some()))
    });
    let e = e.err().expect("no best from failed candidates");
    assert!(matches!(e, LabError::AllFailed { tried: 7, .. }), "{e}");
    assert!(!e.is_bad_input());
    assert!(e.to_string().contains("the training diverged"), "{e}");
    assert_eq!(told.len(), 7);
    assert!(told
        .iter()
        .all(|(s, best)| s == "failed: the training diverged" && !best));
}
