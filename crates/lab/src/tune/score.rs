//! One simulated run scored against its true contour, in memory (no run
//! folder), and the cost the tuning minimises.
use crate::error::{LabError, Result};
use crate::follow::{perception_for, SimFollowConfig};
use serde::{Deserialize, Serialize};
use tactrace_control::PbtsController;
use tactrace_geometry::{Contour, Vec2};
use tactrace_servo::{evaluate, servo_loop, start_pose, Ending, FollowMetrics, SimRig, StepRecord};
use tactrace_store::StoredModel;

/// A finished simulated run: how it ended and its metrics.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunScore {
    pub shape: String,
    pub seed: u64,
    pub ending: Ending,
    pub metrics: FollowMetrics,
    /// The contour's perimeter, mm.
    pub perimeter_mm: f64,
}

/// Run `cfg` on `contour` in the simulated world with `model`, as
/// `follow` does, keeping the trajectory in memory only.
pub fn simulate(
    cfg: &SimFollowConfig,
    model: &StoredModel,
    (name, contour): (&str, &Contour),
) -> Result<RunScore> {
    let settings = cfg.servo_settings()?;
    let start = start_pose(contour, &cfg.start, cfg.rig.tap.height_mm)?;
    let mut rig = SimRig::new(&cfg.rig, contour.clone(), start, cfg.follow.seed)?;
    let perception = perception_for(&rig.reference_frame(), model, &settings)?;
    let mut controller = PbtsController::new(cfg.controller.clone());
    let mut records: Vec<StepRecord> = Vec::new();
    let (arm, sensor) = rig.parts();
    let summary = servo_loop(
        arm,
        sensor,
        &perception,
        &mut controller,
        settings.follow(),
        settings.tap(),
        &mut [&mut records],
    )?;
    let traj: Vec<Vec2> = records
        .iter()
        .map(|r| Vec2::new(r.pose.x, r.pose.y))
        .collect();
    let metrics = evaluate(
        contour,
        &traj,
        cfg.follow.close_radius_mm,
        cfg.follow.min_excursion_mm,
    );
    Ok(RunScore {
        shape: name.to_string(),
        seed: cfg.follow.seed,
        ending: summary.ending,
        metrics,
        perimeter_mm: contour.perimeter(),
    })
}

/// The weights of the cost of one run (the `[objective]` table): the
/// cost is `mean_l2` x mean L2 error, plus `max_track` x max track error,
/// plus `coverage` x (1 - coverage), plus `taps_per_mm` x steps /
/// perimeter, plus `failed` when the run did not close its loop.
/// Millimetres throughout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Objective {
    /// Weight of the mean L2 error (the report's metric), per mm.
    pub mean_l2: f64,
    /// Weight of the largest distance of a tap from the contour, per mm.
    pub max_track: f64,
    /// Weight of the fraction of the contour not traced.
    pub coverage: f64,
    /// Weight of the taps spent per mm of contour (slowness).
    pub taps_per_mm: f64,
    /// Added when the loop did not close.
    pub failed: f64,
}

impl Default for Objective {
    fn default() -> Self {
        Self {
            mean_l2: 1.0,
            max_track: 0.5,
            coverage: 5.0,
            taps_per_mm: 0.02,
            failed: 5.0,
        }
    }
}

impl Objective {
    /// The cost of one run (lower is better); never NaN.
    pub fn cost(&self, run: &RunScore) -> f64 {
        let m = &run.metrics;
        let finite = |v: f64, worst: f64| if v.is_finite() { v } else { worst };
        let cost = self.mean_l2 * finite(m.mean_l2_mm, 100.0)
            + self.max_track * finite(m.max_track_error_mm, 100.0)
            + self.coverage * (1.0 - finite(m.coverage, 0.0))
            + self.taps_per_mm * m.steps as f64 / run.perimeter_mm.max(1e-9)
            + if m.closed && run.ending == Ending::Closed {
                0.0
            } else {
                self.failed
            };
        finite(cost, 1e6)
    }

    /// Reject weights that cannot rank runs.
    pub fn validate(&self) -> Result<()> {
        let all = [
            self.mean_l2,
            self.max_track,
            self.coverage,
            self.taps_per_mm,
            self.failed,
        ];
        if all.iter().any(|w| !(w.is_finite() && *w >= 0.0)) || self.mean_l2 <= 0.0 {
            return Err(LabError::Config(
                "the objective's weights must be finite and >= 0, with mean_l2 > 0".into(),
            ));
        }
        Ok(())
    }
}

/// One run of [`evaluate_set`]: its score and how long it took.
#[derive(Debug, Clone, Serialize)]
pub struct TimedRun {
    pub score: RunScore,
    /// Wall time of this run on its thread, s.
    pub seconds: f64,
}

/// Every contour of `shapes` with `seeds` seeds (the follow seed, +1, ...),
/// in parallel: the runs and the wall time of the whole sweep, s.
pub fn evaluate_set(
    cfg: &SimFollowConfig,
    model: &StoredModel,
    shapes: &[(String, Contour)],
    seeds: usize,
    done: &(dyn Fn() + Sync),
) -> Result<(Vec<TimedRun>, f64)> {
    use rayon::prelude::*;
    let jobs: Vec<(&(String, Contour), u64)> = shapes
        .iter()
        .flat_map(|s| (0..seeds as u64).map(move |k| (s, k)))
        .collect();
    let t0 = std::time::Instant::now();
    let runs = jobs
        .par_iter()
        .map(|((name, contour), k)| {
            let mut c = cfg.clone();
            c.follow.seed = cfg.follow.seed + k;
            let t = std::time::Instant::now();
            let score = simulate(&c, model, (name, contour));
            done();
            Ok(TimedRun {
                score: score?,
                seconds: t.elapsed().as_secs_f64(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((runs, t0.elapsed().as_secs_f64()))
}
