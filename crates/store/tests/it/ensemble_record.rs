//! A model folder records an ensemble's per-member learning-rate halvings
//! (issue 21: a member that diverges restarts alone) in `training.json`.
use tactrace_learn::{Dataset, ModelConfig, ModelKind, PoseModel, Preset, TrainingHistory};
use tactrace_store::{stage_model, StoredModel, TrainingRecord};

/// A small ensemble of two fitted on smooth synthetic rows.
fn small_ensemble() -> (PoseModel, TrainingHistory) {
    let (n, dim) = (40, 6);
    let mut x = Vec::new();
    let mut y = Vec::new();
    for i in 0..n {
        let (a, b) = ((i as f32 * 0.7).sin() * 4.0, (i as f32 * 0.3).cos() * 40.0);
        x.extend((0..dim).map(|j| a * (j as f32).sin() + 0.05 * b * (j as f32).cos()));
        y.extend([a, b]);
    }
    let d = Dataset::new(x, y, n, dim, 2).expect("data");
    let mut cfg = ModelConfig::preset(ModelKind::PDenNN, Preset::Default);
    cfg.set_epochs(2);
    cfg.ensemble = 2;
    cfg.scale_learning_rates(0.1);
    for net in [&mut cfg.position, &mut cfg.angle].into_iter().flatten() {
        net.hidden = vec![8];
        net.n_components = Some(4);
    }
    PoseModel::fit(&cfg, &d, &mut |_| {}).expect("fit")
}

#[test]
fn training_json_records_each_members_halvings() {
    let (model, mut history) = small_ensemble();
    assert_eq!(history.member_lr_halvings, vec![0, 0]);
    let record: TrainingRecord = serde_json::from_str(
        r#"{"format": 1, "dataset": {"path": null, "sha256": "sha256:00", "rows": 40,
            "source": "simulated"}, "split": null, "train_rows": [], "row_hashes": []}"#,
    )
    .expect("record");
    assert!(record.member_lr_halvings.is_empty(), "older folders: none");
    let tmp = tempfile::tempdir().expect("tmp");
    for (name, halvings) in [("none", vec![0, 0]), ("second", vec![0, 2])] {
        history.member_lr_halvings = halvings.clone();
        let stored =
            StoredModel::new(model.clone(), vec![[0.0, 0.0]; 3]).with_training(record.clone());
        let dir = tmp.path().join(name);
        let stage = stage_model(&dir, &stored, &history, false, &[]).expect("stage");
        stage.commit().expect("commit");
        let text = std::fs::read_to_string(dir.join("training.json")).expect("training.json");
        assert!(text.contains("member_lr_halvings"), "{text}");
        let back = StoredModel::load(&dir).expect("load");
        assert_eq!(
            back.training().expect("record").member_lr_halvings,
            halvings
        );
    }
}
