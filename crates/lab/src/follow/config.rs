//! A follow run's settings: the configuration file of the simulated
//! worlds ([`SimFollowConfig`], read by `follow --config` and written into
//! every run folder as `config.toml`) and the loop settings every world
//! shares, checked when made ([`ServoSettings`]).
use crate::error::Result;
use crate::world::{CalibratedWorld, ReplayBank, ReplayWorld, SimWorld, World};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use tactrace_control::PbtsConfig;
use tactrace_servo::{LoopConfig, RigConfig, StartConfig, TapConfig};
use tactrace_vision::{BlobParams, Detector, DetectorParams};

/// A follow run in the simulated world: one TOML file with these tables,
/// laid over [`SimFollowConfig::default`]; with `calibrated_sensor`, in a
/// calibrated sensor's world; with a `[replay]` table, in the real-frame
/// world ([`SimFollowConfig::world`] says which).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimFollowConfig {
    /// A calibrated sensor folder (`tactrace calibrate`, `--sensor`): it
    /// replaces `rig.sensor`, and the model is taken to predict labels in
    /// its convention (mapped to the loop's edge pose by eq. L1).
    pub calibrated_sensor: Option<PathBuf>,
    pub rig: RigConfig,
    pub controller: PbtsConfig,
    pub follow: LoopConfig,
    pub start: StartConfig,
    /// The real-frame world (`follow --replay`), if the run is in it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayBank>,
}

/// The simulated world's defaults, with the controller tuned in simulation
/// ([`PbtsConfig::tuned`], issue 12), which beats the report's on the
/// held-out contours (docs/results.md).
impl Default for SimFollowConfig {
    fn default() -> Self {
        Self {
            controller: PbtsConfig::tuned(),
            ..Self::report()
        }
    }
}

impl SimFollowConfig {
    /// The report's settings: its PI controller ([`PbtsConfig::report`]),
    /// as `reproduce` runs them.
    pub fn report() -> Self {
        Self {
            calibrated_sensor: None,
            rig: RigConfig::default(),
            controller: PbtsConfig::report(),
            follow: LoopConfig::default(),
            start: StartConfig::default(),
            replay: None,
        }
    }

    /// The loop settings of this configuration (the simulated rig's blob
    /// detector), checked.
    pub fn servo_settings(&self) -> Result<ServoSettings> {
        ServoSettings::new(
            self.rig.blob.clone(),
            self.controller.clone(),
            self.follow.clone(),
            self.rig.tap,
        )
    }

    /// The world this configuration describes: the real-frame world when
    /// it has a `[replay]` table (in the calibrated sensor's label
    /// convention when it names one), else the calibrated sensor's world
    /// when it names one, else the simulated world.
    pub fn world(&self) -> World {
        let sim = SimWorld {
            rig: self.rig.clone(),
            controller: self.controller.clone(),
            follow: self.follow.clone(),
            start: self.start.clone(),
        };
        match (&self.replay, &self.calibrated_sensor) {
            (Some(bank), sensor) => World::Replay(Box::new(ReplayWorld {
                bank: bank.clone(),
                sensor: sensor.clone(),
                sim,
            })),
            (None, Some(sensor)) => World::Calibrated(CalibratedWorld {
                sensor: sensor.clone(),
                sim,
            }),
            (None, None) => World::Simulated(sim),
        }
    }

    /// The configuration of a simulated world `sim`, with a calibrated
    /// sensor and a real-frame bank when given: the inverse of
    /// [`SimFollowConfig::world`].
    pub(crate) fn of(sim: &SimWorld, sensor: Option<PathBuf>, replay: Option<ReplayBank>) -> Self {
        Self {
            calibrated_sensor: sensor,
            rig: sim.rig.clone(),
            controller: sim.controller.clone(),
            follow: sim.follow.clone(),
            start: sim.start.clone(),
            replay,
        }
    }
}

/// What the servo loop needs besides the arm, the sensor and the model:
/// the same on every rig. Made only by [`ServoSettings::new`], which checks
/// every part, so settings in hand are settings the loop can run.
#[derive(Debug, Clone, Serialize)]
pub struct ServoSettings {
    detect: DetectorParams,
    controller: PbtsConfig,
    follow: LoopConfig,
    tap: TapConfig,
}

impl ServoSettings {
    /// The settings, refused (naming the key) when the blob detector, the
    /// controller, the loop or the tap cannot work.
    pub fn new(
        blob: BlobParams,
        controller: PbtsConfig,
        follow: LoopConfig,
        tap: TapConfig,
    ) -> Result<Self> {
        Self::of_detector(DetectorParams::Blobs(blob), controller, follow, tap)
    }

    /// [`ServoSettings::new`] with the pins found by `detect` (the blob
    /// detector or the small-pin one).
    pub fn of_detector(
        detect: DetectorParams,
        controller: PbtsConfig,
        follow: LoopConfig,
        tap: TapConfig,
    ) -> Result<Self> {
        detect.clone().check()?;
        controller.validate()?;
        follow.validate()?;
        tap.validate()?;
        Ok(Self {
            detect,
            controller,
            follow,
            tap,
        })
    }

    /// The same settings with the pins found by the blob detector `blob`
    /// (a real collection's detector).
    pub fn with_blob(self, blob: BlobParams) -> Result<Self> {
        self.with_detector(DetectorParams::Blobs(blob))
    }

    /// The same settings with the pins found by `detect` (a sensor file's
    /// or a calibrated sensor's detector: the blob detector or the
    /// small-pin one).
    pub fn with_detector(self, detect: DetectorParams) -> Result<Self> {
        Self::of_detector(detect, self.controller, self.follow, self.tap)
    }

    /// The detector that finds the pins, as its settings.
    pub fn detect(&self) -> &DetectorParams {
        &self.detect
    }

    /// The detector that finds the pins (checked when the settings were made).
    pub fn detector(&self) -> Result<Detector> {
        Ok(self.detect.clone().check()?)
    }

    /// The controller's settings.
    pub fn controller(&self) -> &PbtsConfig {
        &self.controller
    }

    /// The loop's settings (steps, seed, closure, contact).
    pub fn follow(&self) -> &LoopConfig {
        &self.follow
    }

    /// How a tap is made.
    pub fn tap(&self) -> &TapConfig {
        &self.tap
    }
}
