//! The simulated rig: a simulated UR5-class arm carrying a simulated TacTip
//! over an extruded object, run through the same traits a real rig uses.
//!
//! The arm's physical pose (with repeatability noise) reaches the simulated
//! sensor through a [`tactrace_arm::PoseProbe`]; nothing else sees it.
use crate::error::{Result, ServoError};
use serde::{Deserialize, Serialize};
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, SimArm, SimArmConfig, Workspace};
use tactrace_geometry::Contour;
use tactrace_sensor::{Frame, SimTacTip, TacTipConfig, TacTipModel, TactileSensor};
use tactrace_vision::BlobParams;

/// How a tap is made: from `height_mm` above the object's top face, down by
/// `depth_mm` +- `depth_jitter_mm` (uniform), capture, back up.
///
/// The report (ch. 4.1) taps 5 +- 1 mm down from 2 mm above, a 3 mm
/// indentation of its sensor. The simulated TacTip's depth scale is
/// calibrated on the real Bristol taps (docs/sensor-model.md): their fields
/// are reproduced at 6.25 mm of model indentation (the absolute zero of
/// depth differs between rigs and is not observable in the data). The
/// default therefore keeps the report's approach height and jitter and
/// moves down 8.25 mm, so a nominal simulated tap indents the model as far
/// as a nominal real tap, with fields of the real magnitude (mean |d| about
/// 5 px). With a 5 mm move the model's fields are about 7x weaker than the
/// real sensor's.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TapConfig {
    /// Height of the dome tip above the object's top face between taps, mm.
    pub height_mm: f64,
    /// Nominal downward move of a tap, mm.
    pub depth_mm: f64,
    /// Half-width of the uniform random variation of the tap move, mm.
    pub depth_jitter_mm: f64,
}

impl Default for TapConfig {
    fn default() -> Self {
        Self {
            height_mm: 2.0,
            depth_mm: 8.25,
            depth_jitter_mm: 1.0,
        }
    }
}

impl TapConfig {
    /// Check that the approach height and the move are finite and the move
    /// and its jitter not negative (a NaN depth once reached the arm as a
    /// pose and stopped the run as a fault).
    pub fn validate(&self) -> Result<()> {
        let fields = [
            ("height_mm", self.height_mm, f64::NEG_INFINITY),
            ("depth_mm", self.depth_mm, 0.0),
            ("depth_jitter_mm", self.depth_jitter_mm, 0.0),
        ];
        for (field, value, min) in fields {
            if !(value.is_finite() && value >= min) {
                let need = if min == 0.0 {
                    "a finite number >= 0"
                } else {
                    "a finite number"
                };
                return Err(ServoError::Config(format!(
                    "[tap] {field} = {value}: must be {need}"
                )));
            }
        }
        Ok(())
    }

    /// Indentation of a nominal tap (no jitter), mm.
    pub fn nominal_indentation_mm(&self) -> f64 {
        self.depth_mm - self.height_mm
    }
}

/// Everything that defines the simulated rig; a TOML file with these tables.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RigConfig {
    pub sensor: TacTipConfig,
    pub arm: SimArmConfig,
    pub workspace: Workspace,
    pub tap: TapConfig,
    pub blob: BlobParams,
}

impl RigConfig {
    /// Check every table (the sensor, the arm's noise, the workspace, the
    /// tap, the blob detector), so that a bad value is an error before any
    /// work, whichever part a command uses, and never a fault at the first
    /// tap.
    pub fn validate(&self) -> Result<()> {
        self.sensor.validate()?;
        self.arm.validate()?;
        self.workspace.validate()?;
        self.tap.validate()?;
        Ok(self.blob.validate()?)
    }
}

/// The defaults of the simulated rig, with the blob preset for simulated
/// frames (the one default: a partial file is overlaid on it).
impl Default for RigConfig {
    fn default() -> Self {
        Self {
            sensor: TacTipConfig::default(),
            arm: SimArmConfig::default(),
            workspace: Workspace::default(),
            tap: TapConfig::default(),
            blob: BlobParams::preset("sim").expect("built-in preset"),
        }
    }
}

/// A simulated arm and sensor over one object.
///
/// The fields are private: the arm's physically reached pose reaches the
/// sensor through a probe made with the arm, and callers get the arm and
/// the sensor only as trait objects ([`SimRig::parts`]), which show the
/// commanded pose and frames, never the true one.
pub struct SimRig {
    arm: LimitedArm<SimArm>,
    sensor: SimTacTip,
}

impl SimRig {
    /// Build the rig over `shape`, the arm starting at `start`; `seed` drives
    /// the arm's repeatability noise and the sensor's nuisance.
    pub fn new(cfg: &RigConfig, shape: Contour, start: Pose, seed: u64) -> Result<Self> {
        cfg.validate()?;
        let model = TacTipModel::new(cfg.sensor.clone())?;
        Ok(Self::with_model(cfg, model, 0.0, shape, start, seed))
    }

    /// As [`SimRig::new`] with the TacTip `model` instead of `cfg.sensor`
    /// (e.g. a calibrated sensor: `SensorFolder::model` in tactrace-store),
    /// mounted on the tool turned by `mount_yaw_deg` (a sensor whose labels
    /// follow its own convention: `LabelConvention::centred`). The caller
    /// checks `cfg` first ([`RigConfig::validate`]).
    pub fn with_model(
        cfg: &RigConfig,
        model: TacTipModel,
        mount_yaw_deg: f64,
        shape: Contour,
        start: Pose,
        seed: u64,
    ) -> Self {
        let arm_cfg = SimArmConfig {
            seed: seed ^ 0xA5A5_0001,
            ..cfg.arm.clone()
        };
        let (sim_arm, probe) = SimArm::with_probe(arm_cfg, start);
        let sensor = SimTacTip::new(
            model,
            shape,
            Box::new(move || {
                let mut tip = probe.actual();
                tip.rz += mount_yaw_deg;
                tip
            }),
            seed ^ 0x5E45_0002,
        );
        let arm = LimitedArm::new(sim_arm, cfg.workspace.clone(), LimitMode::Refuse);
        Self { arm, sensor }
    }

    /// The undeformed frame (sensor in the air).
    pub fn reference_frame(&self) -> Frame {
        self.sensor.reference_frame()
    }

    /// The arm (behind its limiter) and the sensor, as the loop sees them.
    pub fn parts(&mut self) -> (&mut dyn Arm, &mut dyn TactileSensor) {
        (&mut self.arm, &mut self.sensor)
    }
}

/// One tap through the traits: down by `depth_mm`, capture, back up.
pub fn tap(arm: &mut dyn Arm, sensor: &mut dyn TactileSensor, depth_mm: f64) -> Result<Frame> {
    arm.tap_down(depth_mm)?;
    let frame = sensor.capture();
    arm.tap_up(depth_mm)?;
    Ok(frame?)
}
