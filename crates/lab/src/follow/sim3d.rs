//! The simulated world of a 3D run (surface or edge): the arm started at
//! its first pose, the TacTip pressed into the object, and the pin
//! perception of the model, built one way for `task3d` and `edge3d`.
use super::Run3dSettings;
use crate::error::Result;
use std::path::Path;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, PoseProbe, SimArm, SimArmConfig};
use tactrace_sensor::{SimTacTip, TacTipModel};
use tactrace_servo::Perception3d;
use tactrace_shape3d::Surface;
use tactrace_store::StoredModel;
use tactrace_vision::PinExtractor;

/// What a simulated 3D run taps with.
pub(crate) struct Sim3d {
    /// The simulated arm (seeded noise), refusing moves out of the
    /// workspace or tilted past the limit, already at the start pose.
    pub arm: LimitedArm<SimArm>,
    /// The dome over the object, following the arm's actual pose.
    pub sensor: SimTacTip,
    /// Pins read over the simulated reference frame, `model` taking them.
    pub perception: Perception3d,
    /// The pose the arm physically reached, for the metrics after each
    /// step (never the loop).
    pub probe: PoseProbe,
}

/// The simulated 3D world of `run`: its rig (sensor, arm noise,
/// workspace, detector) seeded by its seed (the sensor by seed + 1), the
/// arm moved to `start`, the model's pose components `sensed`, contact
/// when a pin moves the run's `contact_threshold_px` or more.
pub(crate) fn sim_3d(
    run: &Run3dSettings,
    object: &Surface,
    start: Pose,
    model: &StoredModel,
    sensed: [bool; 6],
) -> Result<Sim3d> {
    let (rig, seed) = (&run.rig, run.seed);
    let (arm, probe) = sim_arm_3d(run, start)?;
    let sensor_model = TacTipModel::new(rig.sensor.clone())?;
    let seen = probe.clone();
    let pose_source = Box::new(move || seen.actual());
    let sensor = SimTacTip::over_object(
        sensor_model,
        object.clone(),
        pose_source,
        seed.wrapping_add(1),
    );
    let reference = sensor.reference_frame();
    let extractor = PinExtractor::from_reference_frame(&reference, rig.blob.clone())?;
    let net = model.for_pins(
        extractor.tracker.reference(),
        Path::new("the simulated sensor's reference frame"),
    )?;
    let perception = Perception3d::new(extractor, net.clone(), sensed, run.contact_threshold_px)?;
    Ok(Sim3d {
        arm,
        sensor,
        perception,
        probe,
    })
}

/// The simulated arm of a 3D run (its rig's noise seeded by its seed, its
/// workspace, tilts past its `max_tilt_deg` refused), moved to `start`,
/// and the probe that reads its actual pose (for the world, never the
/// loop).
pub(crate) fn sim_arm_3d(
    run: &Run3dSettings,
    start: Pose,
) -> Result<(LimitedArm<SimArm>, PoseProbe)> {
    let arm_cfg = SimArmConfig {
        seed: run.seed,
        ..run.rig.arm.clone()
    };
    let (sim_arm, probe) = SimArm::with_probe(arm_cfg, start);
    let mut arm = LimitedArm::new(sim_arm, run.rig.workspace.clone(), LimitMode::Refuse)
        .with_max_tilt_deg(run.max_tilt_deg);
    arm.move_to(start)?;
    Ok((arm, probe))
}
