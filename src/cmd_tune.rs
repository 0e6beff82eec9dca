//! `tactrace tune`: the controller tuned by CMA-ES over simulated runs
//! (issue 12), judged on held-out contours.
use crate::inputs::Inputs;
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
    /// held_out_seeds and the `[objective]` weights).
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
    #[command(flatten)]
    executor: crate::cmd_search::ExecutorArgs,
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
    let inputs = Inputs::new()
        .add("--model", &a.model)
        .opt("--config", a.config.as_deref())
        .opt("--base", a.base.as_deref());
    let shapes = cfg.training.iter().chain(&cfg.held_out);
    let inputs = shapes.fold(inputs, |i, s| i.file_arg("--shapes", s));
    inputs.check_apart("--out", &a.out)?;
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
    let executor = a.executor.executor()?;
    let res = run_tune(
        &cfg,
        &base,
        (&model, &a.model),
        (&a.out, a.force),
        &executor,
        &progress,
    );
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

#[derive(Args)]
pub struct EvaluateArgs {
    /// Model directory (as for follow).
    #[arg(long)]
    model: PathBuf,
    /// Contours, as for tune --shapes (set names, shapes, specs, CSV files).
    #[arg(long, num_args = 1.., required = true)]
    shapes: Vec<String>,
    /// Follow configuration (e.g. a tuning's tuned.toml; default: follow's defaults).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Runs per contour, seeds S, S+1, ... (S: --seed or the configuration's).
    #[arg(long, default_value_t = 1)]
    seeds: usize,
    /// First seed of the simulated world's noise.
    #[arg(long)]
    seed: Option<u64>,
    /// Print JSON (every run, its metrics and seconds) instead of a table.
    #[arg(long)]
    json: bool,
}

/// `tactrace evaluate`: simulated follow runs on a set of contours, in
/// parallel and in memory, with their metrics and the sweep's throughput.
pub fn evaluate(a: EvaluateArgs) -> Result<()> {
    use tactrace_lab::tune::{evaluate_set, load_set};
    let mut cfg: SimFollowConfig = load_config(a.config.as_deref(), "follow configuration")?;
    cfg.follow.seed = a.seed.unwrap_or(cfg.follow.seed);
    if a.seeds == 0 {
        return Err(tactrace_lab::LabError::Config("--seeds must be at least 1".into()).into());
    }
    let shapes = load_set(&a.shapes, "evaluated")?;
    let model = StoredModel::load(&a.model)?;
    let pb = bar((shapes.len() * a.seeds) as u64, "evaluate");
    let res = evaluate_set(&cfg, &model, &shapes, a.seeds, &|| pb.inc(1));
    pb.finish_and_clear();
    let (runs, wall) = res?;
    // Printed first (the table shows which run), refused after.
    let scored = || -> Result<()> {
        for r in &runs {
            tactrace_lab::numbers::require_finite_run(&r.score.shape, &r.score.metrics)?;
        }
        Ok(())
    };
    let taps: usize = runs.iter().map(|r| r.score.metrics.steps).sum();
    let threads = tactrace_lab::tune::worker_threads();
    if a.json {
        let doc = serde_json::json!({
            "runs": runs,
            "wall_seconds": wall,
            "threads": threads,
            "runs_per_second": runs.len() as f64 / wall,
            "taps_per_second": taps as f64 / wall,
        });
        crate::say!("{}", serde_json::to_string_pretty(&doc)?);
        return scored();
    }
    crate::say!("| contour | perimeter (mm) | seed | mean L2 (mm) | max track error (mm) | coverage | closed | taps | s |");
    crate::say!("|---|---|---|---|---|---|---|---|---|");
    for r in &runs {
        let (s, m) = (&r.score, &r.score.metrics);
        crate::say!(
            "| {} | {:.0} | {} | {:.2} | {:.2} | {:.1} % | {} | {} | {:.2} |",
            s.shape,
            s.perimeter_mm,
            s.seed,
            m.mean_l2_mm,
            m.max_track_error_mm,
            100.0 * m.coverage,
            m.closed,
            m.steps,
            r.seconds
        );
    }
    let n = runs.len() as f64;
    let mean = |f: &dyn Fn(&tactrace_servo::FollowMetrics) -> f64| {
        runs.iter().map(|r| f(&r.score.metrics)).sum::<f64>() / n
    };
    crate::say!(
        "| **mean** | | | {:.2} | {:.2} | {:.1} % | {}/{} | {:.0} | |",
        mean(&|m| m.mean_l2_mm),
        mean(&|m| m.max_track_error_mm),
        100.0 * mean(&|m| m.coverage),
        runs.iter().filter(|r| r.score.metrics.closed).count(),
        runs.len(),
        mean(&|m| m.steps as f64)
    );
    crate::say!(
        "{} runs, {taps} taps in {wall:.1} s on {threads} threads: {:.2} runs/s, {:.0} taps/s",
        runs.len(),
        n / wall,
        taps as f64 / wall
    );
    scored()
}
