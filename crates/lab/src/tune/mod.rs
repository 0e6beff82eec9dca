//! `tactrace tune` (issue 12): the controller's gains, tangential step and
//! policy tuned by CMA-ES over simulated runs on a training set of
//! contours, runs in parallel, and the result judged only on held-out
//! contours.
//!
//! The output folder is built in `OUT.partial` and renamed to `OUT` when
//! the tuning and the held-out evaluation are over. After every generation
//! the best settings so far are written (atomically) to `tuned.toml`, with
//! `history.csv` and the convergence figure, so an interrupted tuning keeps
//! its best in `OUT.partial/tuned.toml`; a later `tune` into the same
//! `OUT` refuses to replace it without `--force`, and `--base` takes it as
//! the start of a new search.
mod outputs;
mod score;
mod space;
mod trial;

pub use outputs::{held_out_table, HeldOutRow, TuneOutcome};
pub use score::{evaluate_set, simulate, Objective, RunScore, TimedRun};
pub use space::{from_unit, to_unit, Knob, KNOBS};
pub use trial::{HeldOutContext, HeldOutRun, HeldOutTrial, TuneContext, TuneTrial};

use crate::error::{LabError, Result};
use crate::follow::SimFollowConfig;
use outputs::Outputs;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_control::PbtsConfig;
use tactrace_geometry::{Contour, ShapeSpec};
use tactrace_optim::{Cmaes, CmaesConfig, Executor};
use tactrace_report::figures::GenerationCost;
use tactrace_store::{load_shape, StoredModel};

/// What `tune` does (the tune TOML; flags override it).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TuneConfig {
    /// Seed of the search (every sample of CMA-ES).
    pub seed: u64,
    /// Candidate settings to try (each is run once on every training
    /// contour); rounded up to whole generations.
    pub trials: usize,
    /// CMA-ES population; `None`: 4 + floor(3 ln 13) = 11.
    pub population: Option<usize>,
    /// CMA-ES initial step size in the unit box of the settings.
    pub sigma: f64,
    /// The contours tuned on (shape specs: names, parametric, CSV files).
    pub training: Vec<String>,
    /// The contours the result is judged on; none may be a training one.
    pub held_out: Vec<String>,
    /// Seeds per held-out contour (the world's noise); the first is the
    /// follow seed + 1000, then +1001, ...
    pub held_out_seeds: usize,
    pub objective: Objective,
}

impl Default for TuneConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            trials: 200,
            population: None,
            sigma: 0.2,
            training: tactrace_geometry::TRAINING_SET.map(String::from).to_vec(),
            held_out: tactrace_geometry::HELD_OUT_SET.map(String::from).to_vec(),
            held_out_seeds: 2,
            objective: Objective::default(),
        }
    }
}

/// What a tuning reports as it goes.
#[derive(Debug, Clone, Copy)]
pub enum TuneEvent {
    /// The number of simulated runs the whole tuning will make.
    Planned { runs: usize },
    /// One more simulated run is over.
    RunDone,
    /// A generation is over; its best cost and the best so far.
    Generation {
        generation: usize,
        generation_best: f64,
        best_so_far: f64,
    },
}

/// A named contour ready to run.
type Named = (String, Contour);

/// Load the contours `specs` name (set names expanded), refusing an empty
/// list and a contour named twice; `what` names the list in errors.
pub fn load_set(specs: &[String], what: &str) -> Result<Vec<(String, Contour)>> {
    if specs.is_empty() {
        return Err(LabError::Config(format!("no {what} contours given")));
    }
    let mut out: Vec<Named> = Vec::new();
    for spec in expand(specs) {
        let spec = ShapeSpec::parse_checked(&spec)?;
        let name = spec.name();
        if out.iter().any(|(n, _)| *n == name) {
            return Err(LabError::Config(format!(
                "the {what} contour {name} is given twice"
            )));
        }
        out.push((name, load_shape(&spec)?));
    }
    Ok(out)
}

/// Shape specs with the set names (`training`, `held-out`) expanded.
pub fn expand(specs: &[String]) -> Vec<String> {
    specs
        .iter()
        .flat_map(|s| match tactrace_geometry::shape_set(s) {
            Some(set) => set.iter().map(|m| m.to_string()).collect(),
            None => vec![s.clone()],
        })
        .collect()
}

impl TuneConfig {
    /// Reject settings that cannot run, and held-out contours that are
    /// also training ones.
    fn check(&self) -> Result<(Vec<Named>, Vec<Named>)> {
        if self.trials == 0 {
            return Err(LabError::Config("tune needs at least 1 trial".into()));
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(LabError::Config("tune sigma must be > 0".into()));
        }
        if self.held_out_seeds == 0 {
            return Err(LabError::Config("held_out_seeds must be at least 1".into()));
        }
        self.objective.validate()?;
        let training = load_set(&self.training, "training")?;
        let held_out = load_set(&self.held_out, "held-out")?;
        if let Some((name, _)) = held_out
            .iter()
            .find(|(n, _)| training.iter().any(|(t, _)| t == n))
        {
            return Err(LabError::Config(format!(
                "{name} is both a training and a held-out contour: the result must be \
                 judged on contours not used in tuning"
            )));
        }
        Ok((training, held_out))
    }
}

/// Mean cost of `controller` over the `shapes` (one run each, the base
/// follow seed), and the runs.
fn score_candidate(
    base: &SimFollowConfig,
    controller: &PbtsConfig,
    model: &StoredModel,
    shapes: &[Named],
    objective: &Objective,
    done: &(dyn Fn() + Sync),
) -> Result<(f64, Vec<RunScore>)> {
    let cfg = SimFollowConfig {
        controller: controller.clone(),
        ..base.clone()
    };
    let runs: Vec<RunScore> = shapes
        .par_iter()
        .map(|(name, c)| {
            let r = simulate(&cfg, model, (name, c));
            done();
            r
        })
        .collect::<Result<_>>()?;
    let cost = runs.iter().map(|r| objective.cost(r)).sum::<f64>() / runs.len() as f64;
    Ok((cost, runs))
}

/// Tune `base`'s controller on the training contours with `model` (read
/// from the folder `model_dir`, where a remote executor's workers read it
/// too): the start, each generation's candidates and the held-out
/// judgement run through `executor`; the best is judged on the held-out
/// contours, into `out` (refused when it exists, unless `force`). A
/// tuning none of whose candidates (the start included) gave a cost is
/// [`LabError::AllFailed`], its history kept in `OUT.partial`.
pub fn tune(
    cfg: &TuneConfig,
    base: &SimFollowConfig,
    (model, model_dir): (&StoredModel, &Path),
    (out, force): (&Path, bool),
    executor: &impl Executor,
    progress: &(dyn Fn(TuneEvent) + Sync),
) -> Result<TuneOutcome> {
    let (_, held_out) = cfg.check()?;
    let model_path = std::path::absolute(model_dir).map_err(|e| LabError::Config(e.to_string()))?;
    let trial = TuneTrial::new(
        TuneContext {
            base: base.clone(),
            model: model_path.clone(),
            training: cfg.training.clone(),
            objective: cfg.objective.clone(),
        },
        model.clone(),
    )?;
    let training = trial.training();
    base.controller
        .validate()
        .map_err(|e| LabError::Config(format!("the base controller: {e}")))?;
    let mut es = Cmaes::new(&CmaesConfig {
        start: to_unit(&base.controller),
        sigma: cfg.sigma,
        population: cfg.population,
        seed: cfg.seed,
    })?;
    let generations = cfg.trials.div_ceil(es.population());
    let held_out_runs = 2 * held_out.len() * cfg.held_out_seeds;
    progress(TuneEvent::Planned {
        runs: (1 + generations * es.population()) * training.len() + held_out_runs,
    });
    let mut outputs = Outputs::start(out, force, cfg, base)?;
    let runs_done = |n: usize| (0..n).for_each(|_| progress(TuneEvent::RunDone));
    let start = executor.run(&trial, std::slice::from_ref(&base.controller))?;
    runs_done(training.len());
    let start_cost = start[0].unwrap_or(f64::INFINITY);
    let mut best = start_cost
        .is_finite()
        .then(|| (base.controller.clone(), start_cost));
    let mut history = vec![GenerationCost {
        evaluations: training.len(),
        generation_best: start_cost,
        best_so_far: start_cost,
    }];
    let mut failed = vec![(!start_cost.is_finite()) as usize];
    outputs.generation(best.as_ref(), &history, &failed)?;
    let mut evaluated = training.len();
    for generation in 1..=generations {
        let (controllers, outside): (Vec<PbtsConfig>, Vec<f64>) = es
            .ask()
            .iter()
            .map(|u| from_unit(&base.controller, u))
            .unzip();
        let costs = executor.run(&trial, &controllers)?;
        runs_done(controllers.len() * training.len());
        evaluated += controllers.len() * training.len();
        failed.push(costs.iter().filter(|c| c.is_none()).count());
        let scored: Vec<(PbtsConfig, f64)> = controllers
            .into_iter()
            .zip(costs.iter().zip(outside))
            .map(|(c, (cost, out))| (c, cost.unwrap_or(f64::INFINITY) + 10.0 * out))
            .collect();
        let costs: Vec<f64> = scored.iter().map(|(_, c)| *c).collect();
        es.tell(&costs)?;
        let (gen_best, gen_cost) = scored
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .cloned()
            .expect("a generation has points");
        if gen_cost.is_finite() && best.as_ref().is_none_or(|b| gen_cost < b.1) {
            best = Some((gen_best, gen_cost));
        }
        let best_so_far = best.as_ref().map_or(f64::INFINITY, |b| b.1);
        history.push(GenerationCost {
            evaluations: evaluated,
            generation_best: gen_cost,
            best_so_far,
        });
        outputs.generation(best.as_ref(), &history, &failed)?;
        progress(TuneEvent::Generation {
            generation,
            generation_best: gen_cost,
            best_so_far,
        });
    }
    let Some(best) = best else {
        return Err(LabError::AllFailed {
            what: "tune candidates (the start included)".into(),
            tried: 1 + generations * es.population(),
            reason: "every one stopped with an error or gave a cost that is not a number".into(),
            kept: Some(tactrace_store::fsutil::partial_path(out)),
        });
    };
    let judge_trial = HeldOutTrial::new(
        HeldOutContext {
            base: base.clone(),
            model: model_path,
            held_out: cfg.held_out.clone(),
        },
        model.clone(),
    )?;
    let rows = judge(&judge_trial, base, &best.0, cfg.held_out_seeds, executor)?;
    runs_done(held_out_runs);
    outputs.finish(&best, &history, &failed, rows)
}

/// The held-out table: every held-out contour and seed, run with the base
/// controller and with the tuned one, through `executor`.
fn judge(
    trial: &HeldOutTrial,
    base: &SimFollowConfig,
    tuned: &PbtsConfig,
    seeds: usize,
    executor: &impl Executor,
) -> Result<Vec<HeldOutRow>> {
    let runs: Vec<HeldOutRun> = (0..trial.held_out().len())
        .flat_map(|contour| (0..seeds as u64).map(move |k| (contour, k)))
        .flat_map(|(contour, seed_offset)| {
            [&base.controller, tuned].map(|c| HeldOutRun {
                controller: c.clone(),
                contour,
                seed_offset,
            })
        })
        .collect();
    let scores = executor.run(trial, &runs)?;
    let mut scores = scores.into_iter();
    let mut rows = Vec::new();
    while let (Some(before), Some(after)) = (scores.next(), scores.next()) {
        rows.push(HeldOutRow { before, after });
    }
    Ok(rows)
}

/// The threads the runs are spread over (rayon's pool: one per core
/// unless `RAYON_NUM_THREADS` says otherwise).
pub fn worker_threads() -> usize {
    rayon::current_num_threads()
}
