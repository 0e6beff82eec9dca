//! Edge following in 3D (`follow --task edge_5d|edge_3d --object ...`):
//! the servo loop of `tactrace_servo::servo_3d` with the SE(3) controller
//! of an edge task, round the edge curve of a 3D object (the foil's rim,
//! the bowl's rim, an extruded shape's top rim), into a run folder.
//!
//! The start: the sensor in the edge's own frame (z the pressed face's
//! normal, x across the edge out of the object, y along it) at the edge
//! sample nearest `start_mm` (the first sample by default), pressed to the
//! reference depth. Every step the model predicts the pose in the edge's
//! frame (edge_5d: x, z, rx, ry, rz; edge_3d: x, z, rz); the controller
//! corrects it towards the reference (x = 0 on the edge, 3 mm deep, level
//! to the face, rz = 0 so that y runs along the edge), and its constant
//! step along the sensor's y carries the sensor along the edge; the
//! predicted rz turns the heading. The run stops when the commanded path
//! comes back to its start (the 2D loop's closure detector on (x, y)), at
//! the step cap, or on a lost contact or refused move. The model sees only
//! the pins; the run is scored against the edge afterwards
//! ([`super::edge3d_results`]).
use super::edge3d_results::{write_edge_results, Edge3dMetrics, EdgeCsv};
use super::recorder3d::{record_loop_3d, Outcome3d, Recorder3d};
use super::sim3d::{sim_3d, Sim3d};
use super::{Run3dSettings, RunFolder};
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_arm::Pose;
use tactrace_control::{Se3Config, Task};
use tactrace_sensor::TactileSensor;
use tactrace_servo::{Loop3dConfig, Step3d};
use tactrace_shape3d::{pose_of_label, EdgeCurve, EdgeSample, Surface};
use tactrace_store::{NoOtherKeys, StoredModel};

/// An edge run in simulation (the run folder's `config.toml`): the
/// settings every 3D run shares at the top level, the controller and the
/// edge's start, step cap and closure; any other key is refused by name.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Edge3dConfig {
    /// The rig, tilt bound, contact, settling steps (left out of the
    /// distance and normal metrics) and seed.
    #[serde(flatten)]
    pub run: Run3dSettings,
    /// The SE(3) controller of an edge task (edge_5d's preset by default).
    pub controller: Se3Config,
    /// The start: the edge sample nearest this (x, y), mm; the edge's
    /// first sample when absent.
    pub start_mm: Option<[f64; 2]>,
    /// Step cap; absent: 1.5 times the edge's length in steps, plus 10.
    pub max_steps: Option<usize>,
    /// The path closes when it comes within this of its start, mm...
    pub close_radius_mm: f64,
    /// ...after getting at least this far from it, mm.
    pub min_excursion_mm: f64,
    /// Refuses the keys no field above took.
    #[serde(flatten)]
    pub other_keys: NoOtherKeys,
}

impl Default for Edge3dConfig {
    fn default() -> Self {
        Self {
            run: Run3dSettings::default(),
            controller: Se3Config::edge_5d(),
            start_mm: None,
            max_steps: None,
            close_radius_mm: 3.0,
            min_excursion_mm: 20.0,
            other_keys: NoOtherKeys,
        }
    }
}

impl Edge3dConfig {
    /// Check the settings before anything runs.
    pub fn validate(&self) -> Result<()> {
        self.run.validate()?;
        self.controller.validate()?;
        if !matches!(self.controller.task, Task::Edge5d | Task::Edge3d) {
            return Err(LabError::Config(format!(
                "controller.task is {}: an edge run needs edge_5d or edge_3d",
                self.controller.task
            )));
        }
        let start_ok = self
            .start_mm
            .is_none_or(|s| s.iter().all(|v| v.is_finite()));
        let ok = start_ok
            && self.controller.reference[1] > 0.0
            && self.max_steps != Some(0)
            && self.close_radius_mm > 0.0
            && self.min_excursion_mm > self.close_radius_mm
            && self.min_excursion_mm.is_finite();
        if !ok {
            return Err(LabError::Config(
                "edge run: finite start_mm, the reference's y step > 0, max_steps >= 1, \
                 0 < close_radius_mm < min_excursion_mm"
                    .into(),
            ));
        }
        Ok(())
    }

    /// The step cap round `edge`: 1.5 times its length in steps, plus 10;
    /// doubled with the curvature policy on, whose steps may be shorter.
    pub fn steps(&self, edge: &EdgeCurve) -> usize {
        self.max_steps.unwrap_or_else(|| {
            let policy = if self.controller.policy.is_off() {
                1.0
            } else {
                2.0
            };
            (policy * 1.5 * edge.length() / self.controller.reference[1]).ceil() as usize + 10
        })
    }

    /// The loop's settings round `edge`: the step cap, closing at the start.
    fn loop_config(&self, edge: &EdgeCurve) -> Loop3dConfig {
        Loop3dConfig {
            steps: self.steps(edge),
            max_no_contact: self.run.max_no_contact,
            lift_mm: self.run.rig.tap.height_mm,
            closure: Some([self.close_radius_mm, self.min_excursion_mm]),
        }
    }
}

/// A finished edge run.
pub type Edge3dOutcome = Outcome3d<Edge3dMetrics>;

/// The object's edge, or bad input naming the object.
pub fn edge_of(object: &Surface, name: &str) -> Result<EdgeCurve> {
    object
        .edge()
        .filter(|e| e.samples.len() >= 2)
        .ok_or_else(|| LabError::Config(format!("the object {name} has no edge to follow")))
}

/// The edge sample nearest `start` in (x, y), the first without one.
pub fn start_sample(edge: &EdgeCurve, start: Option<[f64; 2]>) -> EdgeSample {
    let Some([x, y]) = start else {
        return edge.samples[0];
    };
    let near = |s: &&EdgeSample| (s.point.x - x).hypot(s.point.y - y);
    *edge
        .samples
        .iter()
        .min_by(|a, b| near(a).total_cmp(&near(b)))
        .expect("an edge has samples")
}

/// The start pose: the reference pose (its step along y left out) in the
/// edge's frame at the start sample.
pub fn start_pose(edge: &EdgeCurve, cfg: &Edge3dConfig) -> Pose {
    let mut reference = cfg.controller.reference;
    reference[1] = 0.0;
    pose_of_label(&start_sample(edge, cfg.start_mm).frame(), reference)
}

/// Follow the edge of `object` (named `name`) with `model` in simulation
/// into the run folder `out` (refused when it exists, unless `force`);
/// `progress` hears every step. A run that did not close is still written
/// (its metrics say how it ended).
pub fn run_edge(
    cfg: &Edge3dConfig,
    object: &Surface,
    name: &str,
    model: &StoredModel,
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&Step3d),
) -> Result<Edge3dOutcome> {
    cfg.validate()?;
    let edge = edge_of(object, name)?;
    let _claim = tactrace_store::check_output_dir(out, force)?;
    let start = start_pose(&edge, cfg);
    let Sim3d {
        mut arm,
        mut sensor,
        perception,
        probe,
    } = sim_3d(&cfg.run, object, start, model, cfg.controller.task.sensed())?;
    let run = RunFolder::start(out, force, cfg)?;
    let csv = EdgeCsv::create(run.path(), &edge, cfg.controller.reference)?;
    let recorder = Recorder3d::new(csv, probe, progress, false);
    let mut tap = || perception.perceive(&sensor.capture()?);
    let loop_cfg = cfg.loop_config(&edge);
    let (summary, kept) =
        record_loop_3d(&mut arm, &mut tap, (&cfg.controller, &loop_cfg), recorder)?;
    let metrics = write_edge_results(
        run.path(),
        (name, object, &edge),
        cfg,
        (&kept.steps, &kept.reached),
        &summary,
    )?;
    let dir = run.finish()?;
    Ok(Edge3dOutcome {
        summary,
        metrics,
        dir,
    })
}
