//! The shipped search spaces (`configs/search/*.toml`) parse and fit their
//! models, and a trial is a pure function of its configuration: the local
//! executor's batch gives what one-by-one evaluation gives (issue 24).
use tactrace_convnet::ConvConfig;
use tactrace_lab::search::{PoseTrial, SpaceFile, TrialConfig};
use tactrace_learn::{edge_targets, Dataset, ModelConfig, ModelKind, Preset};
use tactrace_optim::{Evaluation, Executor, Local, Tpe, TpeConfig};

fn shipped(name: &str) -> SpaceFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/search")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn shipped_search_spaces_parse_and_fit_their_models() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/search");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let pins = |kind| TrialConfig::Pins(ModelConfig::preset(kind, Preset::Default));
        let image = |kind| TrialConfig::Image(ConvConfig::new(kind));
        let base = match name.as_str() {
            "pdennn.toml" => pins(ModelKind::PDenNN),
            "pcadennn.toml" => pins(ModelKind::PcaDenNN),
            "mlp.toml" => pins(ModelKind::Mlp),
            "conv-dennn.toml" => image(tactrace_convnet::ModelKind::ConvDennn),
            "conv-mlp.toml" => image(tactrace_convnet::ModelKind::ConvMlp),
            other => panic!("{other}: a space for which model?"),
        };
        let space = shipped(&name);
        let domains = space
            .domains(&base)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        // Random points of the space give valid configurations.
        let tpe = Tpe::new(domains, TpeConfig::default()).unwrap();
        for k in 0..20 {
            space.apply(&base, &tpe.suggest(k, &[])).unwrap();
        }
        seen += 1;
    }
    assert_eq!(seen, 5);
    // A PDenNN space on a one-net model is refused, and a pin model's
    // space on an image model.
    let pca = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    assert!(shipped("pdennn.toml")
        .domains(&TrialConfig::Pins(pca))
        .is_err());
    let conv = ConvConfig::new(tactrace_convnet::ModelKind::ConvDennn);
    assert!(shipped("pdennn.toml")
        .domains(&TrialConfig::Image(conv))
        .is_err());
}

/// A small learnable set: y = (x0 + x1, x2 - x3).
fn data(n: usize, seed: u64) -> Dataset {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let dim = 12;
    let x: Vec<f32> = (0..n * dim).map(|_| next()).collect();
    let y: Vec<f32> = (0..n)
        .flat_map(|i| {
            [
                x[i * dim] + x[i * dim + 1],
                10.0 * (x[i * dim + 2] - x[i * dim + 3]),
            ]
        })
        .collect();
    Dataset::new(x, y, n, dim, 2).unwrap()
}

#[test]
fn a_trial_is_pure_and_the_local_executor_changes_nothing() {
    let trial = PoseTrial::new(data(80, 1), data(30, 2), edge_targets()).unwrap();
    let space = shipped("pdennn.toml");
    let mut base = ModelConfig::preset(ModelKind::PDenNN, Preset::Default);
    base.epochs = 3;
    for net in [&mut base.position, &mut base.angle].into_iter().flatten() {
        net.n_components = Some(8);
        net.hidden = vec![20];
    }
    let small = SpaceFile {
        param: space
            .param
            .into_iter()
            .filter(|p| !p.name.contains("n_components"))
            .collect(),
    };
    let base = TrialConfig::Pins(base);
    let tpe = Tpe::new(small.domains(&base).unwrap(), TpeConfig::default()).unwrap();
    let configs: Vec<TrialConfig> = (0..6)
        .map(|k| small.apply(&base, &tpe.suggest(k, &[])).unwrap())
        .collect();
    let batch = Local.run(&trial, &configs).unwrap();
    let one_by_one: Vec<_> = configs
        .iter()
        .rev()
        .map(|c| trial.evaluate(c).unwrap())
        .collect();
    let one_by_one: Vec<_> = one_by_one.into_iter().rev().collect();
    assert_eq!(batch, one_by_one);
    assert!(batch.iter().any(|s| s.score.is_finite()));
    // The configuration crosses a process boundary unchanged (TOML writes
    // and parses floats exactly; serde_json's default parser can be one
    // ulp off, so JSON transport needs exact float parsing).
    let text = toml::to_string(&configs[0]).unwrap();
    assert_eq!(toml::from_str::<TrialConfig>(&text).unwrap(), configs[0]);
}
