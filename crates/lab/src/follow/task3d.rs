//! Surface following in 3D (`follow --task surface_3d --object ...`): the
//! servo loop of `tactrace_servo::servo_3d` with the SE(3) controller, in
//! the simulated world of a 3D object, into a run folder.
//!
//! The path: the sensor starts level (its axis vertical) over the surface
//! point `path.start_mm`, pressed to the reference depth along the
//! vertical, turned so that its y axis points along `path.heading_deg`;
//! the controller's constant 1 mm step along the sensor's y axis then
//! carries it across the surface for `path.length_mm`, the tilt and depth
//! corrections keeping it on the surface and normal to it. The arm bounds
//! the tilt (`max_tilt_deg`: a larger tilt is refused and ends the run).
//! The model sees only the pins; the run is scored against the object
//! afterwards ([`super::task3d_results`]).
use super::recorder3d::{record_loop_3d, Outcome3d, Recorder3d};
use super::sim3d::{sim_3d, Sim3d};
use super::task3d_results::{write_surface_results, Surface3dMetrics, TruthCsv};
use super::{Run3dSettings, RunFolder};
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_arm::{Arm, Pose, PoseProbe};
use tactrace_control::{Se3Config, Task};
use tactrace_sensor::TactileSensor;
use tactrace_servo::{Loop3dConfig, LoopSummary, Sensed, Step3d};
use tactrace_shape3d::{surface_point, Surface};
use tactrace_store::{NoOtherKeys, StoredModel};

/// The path across the surface.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PathConfig {
    /// The start: the surface point over this (x, y), mm.
    pub start_mm: [f64; 2],
    /// The direction of travel in the work frame's xy plane, deg from +x.
    pub heading_deg: f64,
    /// The path's length, mm (one step per mm of the reference's y step).
    pub length_mm: f64,
}

impl Default for PathConfig {
    fn default() -> Self {
        Self {
            start_mm: [-40.0, 0.0],
            heading_deg: 0.0,
            length_mm: 80.0,
        }
    }
}

impl PathConfig {
    /// The path the built-in objects are followed along: 80 mm across the
    /// middle (the saddle's off its flat diagonal, at y = 10 mm), 40 mm
    /// over the plane and the ramps; the held-out round objects' paths
    /// start where their surface slopes 30-32 deg (the dome 60 mm from
    /// (-30, 10), the cylinder 40 mm from (-20, -10) at 20 deg to its
    /// cross-section, the small bowl 50 mm from (-25, 5)).
    pub fn for_object(name: &str) -> Self {
        let path = |start_mm, heading_deg, length_mm| Self {
            start_mm,
            heading_deg,
            length_mm,
        };
        match name {
            "saddle" => path([-40.0, 10.0], 0.0, 80.0),
            "plane" | "ramp" | "ramp-32" => path([-20.0, 0.0], 0.0, 40.0),
            "dome" => path([-30.0, 10.0], 0.0, 60.0),
            "cylinder" => path([-20.0, -10.0], 20.0, 40.0),
            "bowl-50" => path([-25.0, 5.0], 0.0, 50.0),
            _ => Self::default(),
        }
    }
}

/// A surface_3d run in simulation (the run folder's `config.toml`): the
/// settings every 3D run shares at the top level, the controller and the
/// path; any other key is refused by name.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Surface3dConfig {
    /// The rig, tilt bound, contact, settling steps and seed.
    #[serde(flatten)]
    pub run: Run3dSettings,
    /// The SE(3) controller (the anchors' surface_3d preset).
    pub controller: Se3Config,
    pub path: PathConfig,
    /// Refuses the keys no field above took.
    #[serde(flatten)]
    pub other_keys: NoOtherKeys,
}

impl Default for Surface3dConfig {
    fn default() -> Self {
        Self {
            run: Run3dSettings::default(),
            controller: Se3Config::surface_3d(),
            path: PathConfig::default(),
            other_keys: NoOtherKeys,
        }
    }
}

impl Surface3dConfig {
    /// Check the settings before anything runs.
    pub fn validate(&self) -> Result<()> {
        self.run.validate()?;
        self.controller.validate()?;
        if self.controller.task != Task::Surface3d {
            return Err(LabError::Config(format!(
                "controller.task is {}: a surface run needs surface_3d",
                self.controller.task
            )));
        }
        let p = &self.path;
        let finite = p
            .start_mm
            .iter()
            .chain([&p.heading_deg])
            .all(|v| v.is_finite());
        let step = self.controller.reference[1].abs();
        let ok = finite && p.length_mm.is_finite() && p.length_mm >= step && step > 0.0;
        if !ok {
            return Err(LabError::Config(
                "path: finite start and heading, length_mm at least one step (the reference's y, \
                 not 0)"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Steps of the path: its length over the reference's step.
    pub fn steps(&self) -> usize {
        (self.path.length_mm / self.controller.reference[1].abs()).round() as usize + 1
    }

    /// The loop's settings: the path's steps, no closure.
    fn loop_config(&self) -> Loop3dConfig {
        Loop3dConfig {
            steps: self.steps(),
            max_no_contact: self.run.max_no_contact,
            lift_mm: self.run.rig.tap.height_mm,
            closure: None,
        }
    }
}

/// A finished surface run.
pub type Surface3dOutcome = Outcome3d<Surface3dMetrics>;

/// The start pose: level over the surface point at the path's start,
/// pressed the reference depth below it, its y axis along the heading.
pub fn start_pose(object: &Surface, cfg: &Surface3dConfig) -> Result<Pose> {
    let [x, y] = cfg.path.start_mm;
    let q = surface_point(object.as_ref(), x, y)
        .ok_or_else(|| LabError::Config(format!("no surface over the start ({x}, {y}) mm")))?;
    let depth = cfg.controller.reference[2];
    Ok(Pose::new(
        q.x,
        q.y,
        q.z - depth,
        0.0,
        0.0,
        cfg.path.heading_deg - 90.0,
    ))
}

/// Follow `object` (named `name`) with `model` in simulation into the run
/// folder `out` (refused when it exists, unless `force`); `progress`
/// hears every step. A run that did not finish its path is still written
/// (its metrics say how it ended).
pub fn run_surface(
    cfg: &Surface3dConfig,
    object: &Surface,
    name: &str,
    model: &StoredModel,
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&Step3d),
) -> Result<Surface3dOutcome> {
    cfg.validate()?;
    let _claim = tactrace_store::check_output_dir(out, force)?;
    let start = start_pose(object, cfg)?;
    let Sim3d {
        mut arm,
        mut sensor,
        perception,
        probe,
    } = sim_3d(&cfg.run, object, start, model, Task::Surface3d.sensed())?;
    let reference_pins = perception.reference_pins().to_vec();
    let run = RunFolder::start(out, force, cfg)?;
    let mut tap = || perception.perceive(&sensor.capture()?);
    let (summary, metrics) = follow_surface(
        cfg,
        (object, name),
        &run,
        (&mut arm, &mut tap, probe),
        &reference_pins,
        progress,
    )?;
    let dir = run.finish()?;
    Ok(Surface3dOutcome {
        summary,
        metrics,
        dir,
    })
}

/// A surface run in a built world, into `run`: the arm, each tap's
/// percept (at the arm's pose) and the probe of the pose it reached; its
/// `trajectory.csv`, then its scores, figures and page (the model's
/// `reference_pins` kept for them); how the loop ended and the scores.
pub(super) fn follow_surface(
    cfg: &Surface3dConfig,
    (object, name): (&Surface, &str),
    run: &RunFolder,
    (arm, tap, probe): (
        &mut dyn Arm,
        &mut dyn FnMut() -> tactrace_servo::Result<Sensed>,
        PoseProbe,
    ),
    reference_pins: &[[f64; 2]],
    progress: &mut dyn FnMut(&Step3d),
) -> Result<(LoopSummary, Surface3dMetrics)> {
    let csv = TruthCsv::create(run.path(), object.clone(), cfg.controller.reference[2])?;
    let recorder = Recorder3d::new(csv, probe, progress, true);
    let loop_cfg = cfg.loop_config();
    let (summary, kept) = record_loop_3d(arm, tap, (&cfg.controller, &loop_cfg), recorder)?;
    let metrics = write_surface_results(
        run.path(),
        (name, object),
        cfg,
        (&kept.steps, &kept.reached),
        &summary,
        (reference_pins, &kept.fields),
    )?;
    Ok((summary, metrics))
}
