//! A world's arm, sensor and perception, built for one run: the simulated
//! rig (the default TacTip or a calibrated sensor, mounted by its label
//! convention), the real-frame rig, the real UR5 and camera (connected,
//! moved to the start, its reference frame captured there) or a user's
//! own arm and camera; every arm behind the workspace limiter. After the
//! loop, what the run writes beside its trajectory (module
//! `crate::follow`'s results, and the real-frame world's `answers.csv`).
use super::replay::{answered_frames, write_answers};
use super::{ReplayStats, SimWorld};
use crate::error::{LabError, Result};
use crate::follow::{
    image_perception, perception_of, perception_with, write_results_with, Recorded, RunExtras,
    ServoSettings,
};
use std::path::Path;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, Workspace};
use tactrace_geometry::Contour;
use tactrace_report::replay_html::{PinFields, StepFrames};
use tactrace_sensor::{Frame, FrameBank, LabelConvention, TactileSensor};
use tactrace_servo::{
    start_pose, FollowMetrics, Perception, ReplayRig, RigConfig, SimRig, StartConfig,
};
use tactrace_store::{LoadedModel, SensorFolder};
use tactrace_vision::PinReader;

/// What an open world builds its rig from.
pub(crate) enum Parts {
    /// The simulated rig; with a calibrated sensor's TacTip when given.
    Sim(Box<SimParts>),
    Replay(Box<ReplayParts>),
    #[cfg(feature = "hardware")]
    Hardware(Box<crate::hardware::HardwareConfig>),
    /// A user's own arm (behind the limiter) and camera, and the
    /// undeformed frame taken at the start.
    Own {
        arm: Box<dyn Arm + Send>,
        sensor: Box<dyn TactileSensor + Send>,
        reference: Frame,
    },
}

/// The simulated world's parts.
pub(crate) struct SimParts {
    rig: RigConfig,
    start: StartConfig,
    sensor: Option<SensorFolder>,
}

/// The real-frame world's parts: the simulated arm, the bank, its
/// reader, a frame of its size (the reference frame, if it has one) and
/// label convention.
pub(crate) struct ReplayParts {
    pub rig: RigConfig,
    pub start: StartConfig,
    pub bank: FrameBank,
    pub reader: PinReader,
    pub reference: Frame,
    pub convention: LabelConvention,
    pub far_distance: f64,
}

/// An arm and a sensor built for one run, and the perception that reads
/// the sensor's frames for the model.
pub(crate) struct Rig {
    kind: Kind,
    perception: Perception,
}

enum Kind {
    Sim(Box<SimRig>),
    Replay {
        rig: Box<ReplayRig>,
        far_distance: f64,
    },
    #[cfg(feature = "hardware")]
    Hardware {
        arm: Box<LimitedArm<tactrace_hw::Ur5Arm>>,
        sensor: Box<dyn TactileSensor>,
    },
    Own {
        arm: Box<dyn Arm + Send>,
        sensor: Box<dyn TactileSensor + Send>,
    },
}

/// A real rig's stop request, where there is one.
#[cfg(feature = "hardware")]
pub(crate) type Stop = crate::hardware::StopFlag;
/// A real rig's stop request, where there is one.
#[cfg(not(feature = "hardware"))]
pub(crate) type Stop = ();

impl Parts {
    /// The simulated world `sim`, with the calibrated sensor `sensor`.
    pub(crate) fn sim(sim: &SimWorld, sensor: Option<SensorFolder>) -> Self {
        Parts::Sim(Box::new(SimParts {
            rig: sim.rig.clone(),
            start: sim.start.clone(),
            sensor,
        }))
    }

    /// A user's own `arm`, behind the limiter of `workspace`, and `sensor`.
    pub(crate) fn own<A, S>(arm: A, sensor: S, reference: Frame, workspace: Workspace) -> Self
    where
        A: Arm + Send + 'static,
        S: TactileSensor + Send + 'static,
    {
        Parts::Own {
            arm: Box::new(LimitedArm::new(arm, workspace, LimitMode::Refuse)),
            sensor: Box::new(sensor),
            reference,
        }
    }

    /// The rig over `shape` (required but on a real or own rig, which
    /// start where they are told) and its perception of `model`, refused
    /// when the model's pins are ordered otherwise than the rig's
    /// reference frame. A real rig connects here, moves to its start and
    /// captures its reference frame; `stop` interrupts it.
    #[cfg_attr(not(feature = "hardware"), allow(unused_variables))]
    pub(crate) fn build(
        self,
        shape: Option<(&str, &Contour)>,
        model: &LoadedModel,
        settings: &ServoSettings,
        stop: &Stop,
    ) -> Result<Rig> {
        match self {
            Parts::Sim(p) => build_sim(*p, contour(shape)?, model, settings),
            Parts::Replay(p) => {
                let p = *p;
                let perception = match model {
                    LoadedModel::Pins(net) => perception_with(p.reader, net, settings)?,
                    LoadedModel::Image(m) => image_perception(p.reader, &p.reference, m, settings)?,
                }
                .with_label_convention(p.convention.clone());
                let shape = contour(shape)?;
                let start = reachable_start(&p.rig, &p.start, shape)?;
                let seed = settings.follow().seed;
                let banked = (p.bank, p.convention);
                let rig = Box::new(ReplayRig::new(&p.rig, banked, shape.clone(), start, seed)?);
                let far_distance = p.far_distance;
                Ok(Rig {
                    kind: Kind::Replay { rig, far_distance },
                    perception,
                })
            }
            #[cfg(feature = "hardware")]
            Parts::Hardware(cfg) => {
                let (arm, sensor, reference) =
                    crate::hardware::connect_at(&cfg, cfg.start_pose(), stop)?;
                let perception = perception_of(&reference, model, settings)?;
                Ok(Rig {
                    kind: Kind::Hardware {
                        arm: Box::new(arm),
                        sensor,
                    },
                    perception,
                })
            }
            Parts::Own {
                arm,
                sensor,
                reference,
            } => Ok(Rig {
                perception: perception_of(&reference, model, settings)?,
                kind: Kind::Own { arm, sensor },
            }),
        }
    }
}

/// The simulated rig: the calibrated sensor's TacTip mounted so that the
/// controller's aligned pose is its label angle zero, its reference pins
/// ordering its taps' pins (as for its real frames; [`sensor_perception`]);
/// else the default TacTip and its rendered rest frame.
fn build_sim(
    p: SimParts,
    shape: &Contour,
    model: &LoadedModel,
    settings: &ServoSettings,
) -> Result<Rig> {
    let start = reachable_start(&p.rig, &p.start, shape)?;
    let seed = settings.follow().seed;
    let (rig, perception) = match &p.sensor {
        Some(s) => {
            let convention = s.label_convention();
            let mount = convention.mount_yaw_deg;
            let rig = SimRig::with_model(&p.rig, s.model()?, mount, shape.clone(), start, seed);
            let perception =
                sensor_perception(s, model, settings)?.with_label_convention(convention);
            (rig, perception)
        }
        None => {
            let rig = SimRig::new(&p.rig, shape.clone(), start, seed)?;
            let perception = perception_of(&rig.reference_frame(), model, settings)?;
            (rig, perception)
        }
    };
    Ok(Rig {
        kind: Kind::Sim(Box::new(rig)),
        perception,
    })
}

/// The perception of a calibrated sensor's simulated taps: the pins read
/// by the sensor's detector (its sensor settings', blob or small-pin, else
/// its blob detector) against its own reference pins, whether from an
/// undeformed frame or estimated from its taps
/// ([`crate::sim_sight::of_sensor`]), for a pin model and for an image
/// model's contact rule alike.
fn sensor_perception(
    sensor: &SensorFolder,
    model: &LoadedModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    let reader = crate::sim_sight::of_sensor(sensor)?.reader;
    match model {
        LoadedModel::Pins(net) => perception_with(reader, net, settings),
        LoadedModel::Image(m) => image_perception(reader, &sensor.reference, m, settings),
    }
}

/// The contour a simulated world needs.
fn contour<'a>(shape: Option<(&str, &'a Contour)>) -> Result<&'a Contour> {
    shape.map(|s| s.1).ok_or_else(|| {
        LabError::Config("a simulated world needs the object's contour (--shape)".into())
    })
}

/// The start pose of `start` on `shape` at `rig`'s tap height, refused
/// when the arm's workspace does not hold it.
fn reachable_start(rig: &RigConfig, start: &StartConfig, shape: &Contour) -> Result<Pose> {
    let pose = start_pose(shape, start, rig.tap.height_mm)?;
    rig.workspace.validate()?;
    rig.workspace.check_inside(pose).map_err(|e| {
        LabError::Config(format!(
            "the arm cannot reach the start on this contour ({:.1}, {:.1}) mm: {e}",
            pose.x, pose.y
        ))
    })?;
    Ok(pose)
}

impl Rig {
    /// The arm (behind its limiter) and the sensor as the loop sees them,
    /// and the perception.
    pub(crate) fn split(&mut self) -> (&mut dyn Arm, &mut dyn TactileSensor, &Perception) {
        let (arm, sensor): (&mut dyn Arm, &mut dyn TactileSensor) = match &mut self.kind {
            Kind::Sim(rig) => rig.parts(),
            Kind::Replay { rig, .. } => rig.parts(),
            #[cfg(feature = "hardware")]
            Kind::Hardware { arm, sensor } => (arm.as_mut(), sensor.as_mut()),
            Kind::Own { arm, sensor } => (arm.as_mut(), sensor.as_mut()),
        };
        (arm, sensor, &self.perception)
    }

    /// After a stop request: a real arm is sent `stopl` (the error of a
    /// run stopped by `signal`, or why `stopl` could not be sent); a
    /// simulated one simply stops.
    #[cfg(feature = "hardware")]
    pub(crate) fn stop(&mut self, signal: tactrace_hw::StopSignal, stop: &Stop) -> LabError {
        match &mut self.kind {
            Kind::Hardware { arm, .. } => {
                crate::hardware::stopped(signal, stop, Some(arm.as_mut()))
            }
            _ => crate::hardware::stopped(signal, stop, None),
        }
    }

    /// Score the finished loop `recorded` against `shape` (if known) and
    /// write `metrics.json`, the figures and `replay.html` into `dir`; in
    /// the real-frame world also `answers.csv`, and the label distances of
    /// the answers (with the bank frames `model` was trained on).
    pub(crate) fn write_results(
        &self,
        recorded: &Recorded,
        shape: Option<(&str, &Contour)>,
        (model, settings): (&LoadedModel, &ServoSettings),
        (dir, sensor_diameter_mm): (&Path, f64),
    ) -> Result<(Option<FollowMetrics>, Vec<f64>, Option<ReplayStats>)> {
        let turned_views = model.views_at_prediction();
        let fields = Some(PinFields {
            reference_pins: self.perception.reference_pins(),
            fields: &recorded.fields,
        });
        let written = |extras: &RunExtras| {
            write_results_with(
                shape,
                &recorded.records,
                &recorded.summary,
                settings.follow(),
                sensor_diameter_mm,
                dir,
                extras,
            )
        };
        let Kind::Replay { rig, far_distance } = &self.kind else {
            let (metrics, curve) = written(&RunExtras {
                fields,
                turned_views,
                ..RunExtras::default()
            })?;
            return Ok((metrics, curve, None));
        };
        let (answers, bank) = (rig.answers(), rig.bank());
        let stats = ReplayStats::of(answers, bank, *far_distance).with_training(
            model.training(),
            answers,
            bank,
        );
        write_answers(&dir.join("answers.csv"), answers, bank)?;
        let answered = answered_frames(answers, bank)?;
        let (metrics, curve) = written(&RunExtras {
            replay: Some(&stats),
            fields,
            frames: Some(StepFrames {
                images: &answered.images,
                names: &answered.names,
                per_step: &answered.per_step,
                distances: &answered.distances,
            }),
            turned_views,
        })?;
        Ok((metrics, curve, Some(stats)))
    }
}
