//! The real-frame world: a simulated arm over an object whose taps are
//! answered by saved real frames (the nearest-labelled frame of a real
//! collection on a straight edge, [`NearestFrameSensor`]).
//!
//! As in [`crate::SimRig`], the arm's physically reached pose reaches the
//! sensor through a probe, and callers get arm and sensor only as trait
//! objects; after the run, [`ReplayRig::answers`] says which frame answered
//! each tap and how far its labels were from the pose reached.
use crate::error::Result;
use crate::rig::RigConfig;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, SimArm, SimArmConfig};
use tactrace_geometry::Contour;
use tactrace_sensor::{Answer, FrameBank, LabelConvention, NearestFrameSensor, TactileSensor};

/// A simulated arm carrying a sensor that answers with real frames.
pub struct ReplayRig {
    arm: LimitedArm<SimArm>,
    sensor: NearestFrameSensor,
}

impl ReplayRig {
    /// The arm of `cfg` (its limits and repeatability noise, seeded by
    /// `seed` as in [`crate::SimRig::new`]) starting at `start` over
    /// `shape`; taps answered from `bank` through `convention`.
    pub fn new(
        cfg: &RigConfig,
        (bank, convention): (FrameBank, LabelConvention),
        shape: Contour,
        start: Pose,
        seed: u64,
    ) -> Result<Self> {
        cfg.validate()?;
        let arm_cfg = SimArmConfig {
            seed: seed ^ 0xA5A5_0001,
            ..cfg.arm.clone()
        };
        let (sim_arm, probe) = SimArm::with_probe(arm_cfg, start);
        let sensor =
            NearestFrameSensor::new(bank, convention, shape, Box::new(move || probe.actual()));
        let arm = LimitedArm::new(sim_arm, cfg.workspace.clone(), LimitMode::Refuse);
        Ok(Self { arm, sensor })
    }

    /// The arm (behind its limiter) and the sensor, as the loop sees them.
    pub fn parts(&mut self) -> (&mut dyn Arm, &mut dyn TactileSensor) {
        (&mut self.arm, &mut self.sensor)
    }

    /// Every tap so far: the labels of the pose reached, the frame that
    /// answered and the label distance.
    pub fn answers(&self) -> &[Answer] {
        self.sensor.answers()
    }

    /// The bank the taps are answered from.
    pub fn bank(&self) -> &FrameBank {
        self.sensor.bank()
    }
}
