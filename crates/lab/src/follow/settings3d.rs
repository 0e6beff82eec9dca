//! What every 3D run in simulation is set with, whatever its task (the
//! surface run of [`super::task3d`], the edge runs of [`super::edge3d`]):
//! the simulated rig, the arm's tilt bound, contact, the approach left
//! out of the metrics and the seed. Each task's configuration flattens it
//! beside its own controller and path, and ends with a
//! [`tactrace_store::NoOtherKeys`] so that an unknown key is still refused
//! by name.
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use tactrace_servo::RigConfig;

/// The settings a surface and an edge run in simulation share (flattened
/// into their `config.toml`: the keys stand at its top level).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Run3dSettings {
    /// The simulated sensor, arm noise, workspace, tap (its `height_mm`
    /// is the lift between taps, along the sensor's axis) and detector.
    pub rig: RigConfig,
    /// The arm refuses a tilt of the tool beyond this, deg.
    pub max_tilt_deg: f64,
    /// Below this mean pin displacement (px) a tap counts as no contact.
    pub contact_threshold_px: f64,
    /// Taps in a row without contact before the run stops.
    pub max_no_contact: usize,
    /// Steps left out of the metrics at the start (the approach).
    pub settle_steps: usize,
    /// Seed of the arm's and the camera's noise.
    pub seed: u64,
}

impl Default for Run3dSettings {
    fn default() -> Self {
        Self {
            rig: RigConfig::default(),
            max_tilt_deg: 45.0,
            contact_threshold_px: 0.5,
            max_no_contact: 3,
            settle_steps: 5,
            seed: 1,
        }
    }
}

impl Run3dSettings {
    /// Check the rig and the bounds every 3D run shares.
    pub fn validate(&self) -> Result<()> {
        self.rig.validate()?;
        let ok = (0.0..=90.0).contains(&self.max_tilt_deg)
            && self.contact_threshold_px.is_finite()
            && self.max_no_contact > 0;
        if !ok {
            return Err(LabError::Config(
                "max_tilt_deg in [0, 90], a finite contact_threshold_px, max_no_contact >= 1"
                    .into(),
            ));
        }
        Ok(())
    }
}
