//! Regression tests for inputs found by the mutation fuzz of the CLI
//! (tests/it/fuzz_inputs/mod.rs at the workspace root), one per bug.
use tactrace_learn::{ClampedPhase, LearnError, ModelConfig, ModelKind, Preset};

fn pdennn() -> ModelConfig {
    ModelConfig::preset(ModelKind::PDenNN, Preset::Default)
}

/// `hidden = [9223372036854775807]` in a training TOML overflowed a
/// buffer's capacity (a panic in `Layers::new`); 2^32 aborted the process.
#[test]
fn hidden_layer_of_i64_max_is_a_config_error() {
    for size in [i64::MAX as usize, 1 << 32, 1 << 17] {
        let mut cfg = pdennn();
        cfg.position.as_mut().expect("position net").hidden = vec![size];
        let err = cfg.validate().expect_err("too large");
        assert!(
            matches!(
                err,
                LearnError::NetConfig {
                    net: "position",
                    field: "hidden",
                    ..
                }
            ),
            "{err}"
        );
    }
    let mut cfg = pdennn();
    cfg.angle.as_mut().expect("angle net").hidden = vec![30_000, 30_000];
    assert!(cfg.validate().is_err(), "9e8 weights between two layers");
    pdennn().validate().expect("the default stays valid");
}

/// Iteration counts and retries that would run for ever are refused too.
#[test]
fn euler_steps_and_retries_are_bounded() {
    let mut cfg = ModelConfig::preset(ModelKind::PDenNN, Preset::Report);
    cfg.validate().expect("the report preset stays valid");
    cfg.clamped_phase = ClampedPhase::Euler {
        n_i: usize::MAX,
        dt: 1.0,
    };
    assert!(cfg.validate().is_err());
    let mut cfg = pdennn();
    cfg.divergence_retries = usize::MAX;
    assert!(cfg.validate().is_err());
}

/// Five grid lists of 100 values (a few kB of TOML) listed 10^10 points
/// before sampling any: found by reading `grid` after the fuzz's search-space
/// findings; refused before any allocation now.
#[test]
fn search_grid_of_ten_billion_points_is_refused() {
    use tactrace_learn::{hyperparameter_search, Dataset, SearchSpace, MAX_GRID_POINTS};
    let values: Vec<f64> = (1..=100).map(f64::from).collect();
    let space = SearchSpace {
        learning_rates: values.clone(),
        output_learning_rates: values.clone(),
        betas: values,
        hidden: (1..=100).collect(),
        n_components: (1..=100).collect(),
        trials: 1,
        seed: 0,
        goals: Vec::new(),
    };
    let data = Dataset::new(vec![0.5; 8], vec![1.0, 2.0, 3.0, 4.0], 2, 4, 2).expect("dataset");
    let base = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
    let edge = tactrace_learn::edge_targets();
    let err = hyperparameter_search(&base, &space, &edge, &data, &data, &mut |_| {})
        .expect_err("grid too large");
    assert!(
        err.to_string().contains(&MAX_GRID_POINTS.to_string()),
        "{err}"
    );
}
