//! `tactrace tune`: the controller tuned by CMA-ES over simulated runs
//! (issue 12), judged on held-out contours.
use crate::progress::bar;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::tune::{tune as run_tune, TuneConfig, TuneEvent};
use tactrace_store::{load_config, StoredModel};

#[derive(Args)]
pub struct TuneArgs {
    /// Model directory: the pose model the runs use (a PDenNN trained on
    /// the disk, e.g. `reproduce`'s models/pdennn).
    #[arg(long)]
    model: PathBuf,
    /// Training contours: `training` or `held-out` (the built-in sets,
    /// docs/control.md), shape names, parametric specs (square:S,
    /// rect:W,H, star:R,A,K, each with an optional rotation) or CSV files.
    /// Default: the training set.
    #[arg(long, num_args = 1..)]
    shapes: Vec<String>,
    /// Held-out contours the result is judged on, as --shapes; none may be
    /// a training contour. Default: the held-out set.
    #[arg(long, num_args = 1..)]
    held_out: Vec<String>,
    /// Candidate settings to try, each run on every training contour
    /// (rounded up to whole CMA-ES generations; default 200).
    #[arg(long)]
    trials: Option<usize>,
    /// Seed of the search (default 1, or the config's).
    #[arg(long)]
    seed: Option<u64>,
    /// Tune TOML (keys seed, trials, population, sigma, training, held_out,
    /// held_out_seeds and the [objective] weights).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Follow configuration to start the search from and compare with
    /// (default: follow's defaults); e.g. an interrupted tuning's
    /// OUT.partial/tuned.toml.
    #[arg(long)]
    base: Option<PathBuf>,
    /// Output folder (written as OUT.partial, renamed to OUT when over).
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing output folder (or an interrupted one's best).
    #[arg(long)]
    force: bool,
}

pub fn tune(a: TuneArgs) -> Result<()> {
    let mut cfg: TuneConfig = load_config(a.config.as_deref(), "tune configuration")?;
    if !a.shapes.is_empty() {
        cfg.training = a.shapes.clone();
    }
    if !a.held_out.is_empty() {
        cfg.held_out = a.held_out.clone();
    }
    cfg.trials = a.trials.unwrap_or(cfg.trials);
    cfg.seed = a.seed.unwrap_or(cfg.seed);
    let base: SimFollowConfig = load_config(a.base.as_deref(), "follow configuration")?;
    let model = StoredModel::load(&a.model)?;
    let pb = bar(0, "tune");
    let progress = |e: TuneEvent| match e {
        TuneEvent::Planned { runs } => pb.set_length(runs as u64),
        TuneEvent::RunDone => pb.inc(1),
        TuneEvent::Generation {
            generation,
            best_so_far,
            ..
        } => pb.set_message(format!("gen {generation} {best_so_far:.3}")),
    };
    let res = run_tune(&cfg, &base, &model, (&a.out, a.force), &progress);
    pb.finish_and_clear();
    let res = res?;
    crate::say!(
        "training cost {:.4} -> {:.4} after {} generations (seed {})",
        res.start_cost,
        res.best_cost,
        res.history.len() - 1,
        cfg.seed
    );
    crate::say!("held-out contours, base -> tuned:");
    crate::say!(
        "{}",
        tactrace_lab::tune::held_out_table(&res.held_out).trim_end()
    );
    crate::say!(
        "tuned controller: {} (use with follow --config)",
        res.dir.join("tuned.toml").display()
    );
    Ok(())
}
