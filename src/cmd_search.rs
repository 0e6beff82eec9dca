//! `tactrace search`: Bayesian hyper-parameter search (TPE) of a pose
//! model on an inner validation part of the training data.
use crate::cmd_learn::{PresetArg, TrainModelArg};
use crate::inputs::Inputs;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::remote::{Exec, RayExecutor, RaySettings};
use tactrace_lab::search::{self, SearchSettings, SpaceFile, TrialConfig};
use tactrace_store::{fsutil, read_dataset};

#[derive(Args)]
pub struct SearchArgs {
    /// Kind of model: a pin model, or an image model (conv-dennn,
    /// conv-mlp: needs a dataset with frames, import --frames-size).
    #[arg(long, value_enum, default_value = "pdennn")]
    model: TrainModelArg,
    /// Training dataset directory: each trial fits on part of it and is
    /// scored on the rest (--val-fraction); nothing else is read.
    #[arg(long)]
    train: PathBuf,
    /// TOML listing the settings to search (`[[param]]` tables;
    /// configs/search/*.toml).
    #[arg(long)]
    space: PathBuf,
    /// Trials in all (a resumed search may be given more).
    #[arg(long, default_value_t = 30)]
    trials: usize,
    /// Output folder (built in OUT.partial until the search ends).
    #[arg(long)]
    out: PathBuf,
    /// Seed of the search and of the inner split.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Continue the search stopped in OUT.partial from its trials.
    #[arg(long)]
    resume: bool,
    /// Fraction of --train held out as the inner validation part.
    #[arg(long, default_value_t = 0.25)]
    val_fraction: f64,
    /// Trials trained at once (in parallel); each batch sees the trials before it.
    #[arg(long, default_value_t = 1)]
    batch: usize,
    /// Random trials before the TPE's model is used.
    #[arg(long, default_value_t = 10)]
    startup: usize,
    /// Hyper-parameter preset the trials' settings are laid over.
    #[arg(long, value_enum, default_value = "default")]
    preset: PresetArg,
    /// TOML overriding any hyper-parameter of the preset (as `train --config`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Training epochs of every trial (default: the preset's).
    #[arg(long)]
    epochs: Option<usize>,
    /// Replace an existing output folder (or a stopped search's trials).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    executor: ExecutorArgs,
}

/// Where the evaluations of `search`, `sim-fit` and `tune` run.
#[derive(Args)]
pub struct ExecutorArgs {
    /// Where evaluations run: `local` (this machine's cores) or `ray` (a
    /// Ray cluster at --ray-address, through the Python package; data
    /// paths must be visible to every worker).
    #[arg(long, value_enum, default_value = "local")]
    executor: ExecutorKind,
    /// The Ray cluster's address: the head's HOST:PORT, or `auto` (the
    /// cluster started on this machine, or RAY_ADDRESS).
    #[arg(long, default_value = "auto")]
    ray_address: String,
    /// CPUs each Ray task asks for (and threads it trains on).
    #[arg(long, default_value_t = 1)]
    ray_cpus_per_task: usize,
    /// Python interpreter with ray and the tactrace package (default:
    /// TACTRACE_PYTHON, else python3).
    #[arg(long)]
    python: Option<PathBuf>,
}

/// The executors `--executor` names.
#[derive(Clone, Copy, clap::ValueEnum)]
enum ExecutorKind {
    /// rayon threads on this machine.
    Local,
    /// Ray tasks on a cluster.
    Ray,
}

impl ExecutorArgs {
    /// The executor asked for (a Ray one has joined its cluster).
    pub fn executor(&self) -> Result<Exec> {
        Ok(match self.executor {
            ExecutorKind::Local => Exec::Local,
            ExecutorKind::Ray => {
                if self.ray_cpus_per_task == 0 {
                    return Err(tactrace_lab::LabError::Config(
                        "--ray-cpus-per-task must be at least 1".into(),
                    )
                    .into());
                }
                let python = self.python.clone().unwrap_or_else(|| {
                    std::env::var_os("TACTRACE_PYTHON")
                        .map(PathBuf::from)
                        .unwrap_or_else(|| "python3".into())
                });
                let ray = RayExecutor::new(RaySettings {
                    address: self.ray_address.clone(),
                    python,
                    cpus_per_task: self.ray_cpus_per_task,
                });
                let info = ray.connect().map_err(tactrace_lab::LabError::from)?;
                eprintln!(
                    "Ray cluster at {}: {} nodes, {} CPUs, {} workers",
                    self.ray_address, info.nodes, info.cpus, info.workers
                );
                Exec::Ray(ray)
            }
        })
    }
}

pub fn search(a: SearchArgs) -> Result<()> {
    let base = match a.model.pins() {
        Ok(model) => TrialConfig::Pins(crate::cmd_learn::model_config(
            model,
            a.preset,
            a.config.as_deref(),
            a.epochs,
        )?),
        Err(kind) => {
            if !matches!(a.preset, PresetArg::Default) {
                return Err(tactrace_lab::LabError::Config(format!(
                    "{}: --preset is the pin models' (an image model's settings: --config FILE, --epochs)",
                    kind.name()
                ))
                .into());
            }
            let text = a.config.as_deref().map(fsutil::read_text).transpose()?;
            let cfg =
                tactrace_lab::train_image::resolve_image_config(kind, text.as_deref(), a.epochs)
                    .with_context(|| {
                        a.config
                            .as_ref()
                            .map(|p| p.display().to_string())
                            .unwrap_or_default()
                    })?;
            TrialConfig::Image(cfg)
        }
    };
    let space_text = fsutil::read_text(&a.space)?;
    let space: SpaceFile = toml::from_str(&space_text)
        .with_context(|| format!("search space {}", a.space.display()))?;
    Inputs::new()
        .add("--train", &a.train)
        .add("--space", &a.space)
        .opt("--config", a.config.as_deref())
        .check_apart("--out", &a.out)?;
    let executor = a.executor.executor()?;
    let data = read_dataset(&a.train)?;
    let (data_sha256, data_rows) = search::data_id(&data);
    let settings = SearchSettings {
        trials: a.trials,
        seed: a.seed,
        val_fraction: a.val_fraction,
        batch: a.batch,
        startup: a.startup,
        data_sha256,
        data_rows,
        base,
        space,
    };
    let targets = tactrace_lab::train::data_targets(&data)?;
    let t0 = std::time::Instant::now();
    let outcome = search::search(
        &settings,
        (&data, &a.train),
        &a.out,
        (a.force, a.resume),
        &executor,
        &mut |t| {
            let named: Vec<String> = t
                .settings
                .iter()
                .map(|(n, v)| format!("{n} {v:.4}"))
                .collect();
            let result = match t.score.status().as_str() {
                "ok" => format!(
                    "{}, score {:.4}",
                    search::describe_mae(&targets, &t.score.val_mae),
                    t.score.score
                ),
                status => status.to_string(),
            };
            eprintln!(
                "trial {}: {} -> {result} ({:.0} s so far)",
                t.trial,
                named.join(", "),
                t0.elapsed().as_secs_f64()
            );
        },
    )?;
    let best = &outcome.trials[outcome.best];
    let failed = outcome
        .trials
        .iter()
        .filter(|t| !t.score.score.is_finite())
        .count();
    if failed > 0 {
        eprintln!(
            "{failed} of {} trials failed (status in trials.csv)",
            outcome.trials.len()
        );
    }
    crate::say!(
        "best: trial {} of {}, inner validation {}; {}",
        best.trial,
        outcome.trials.len(),
        search::describe_mae(&outcome.targets, &best.score.val_mae),
        outcome.dir.join("best.toml").display()
    );
    Ok(())
}
