//! The worlds a follow run can be in, as one typed value ([`World`]): the
//! simulated TacTip over the object, a calibrated sensor's simulated
//! TacTip, the real-frame world (a simulated arm whose taps are answered
//! by a real collection's frames) and the real rig (a UR5 and a camera).
//!
//! A [`World`] is the description (serde, `kind` tagged, unknown keys
//! refused; the CLI and the Python package build it from their flags and
//! configuration files: [`crate::follow::SimFollowConfig::world`], a rig
//! file for the real rig). [`World::open`] checks it whole and reads its
//! files once (a calibrated sensor folder, the real-frame bank and its
//! reference frame) into an [`OpenWorld`]; only an open world runs
//! ([`crate::follow::run`]), which builds its arm, sensor and perception
//! (module `rig`). A user's own arm and camera (the Python package's
//! `follow_rig`) open as a world of their own ([`OpenWorld::own_rig`]).
mod replay;
mod replay_stats;
mod rig;
mod surface_bank;

pub use replay::{load_bank, ReplayBank};
pub use replay_stats::ReplayStats;
pub use surface_bank::{SurfaceAnswer, SurfaceBank};

use crate::error::Result;
use crate::follow::{tactip_diameter_mm, ServoSettings, SimFollowConfig};
use rig::Parts;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use tactrace_arm::Arm;
use tactrace_control::PbtsConfig;
use tactrace_sensor::{read_frame, Frame, FrameBank, LabelConvention, TactileSensor};
use tactrace_servo::{LoopConfig, RigConfig, StartConfig};
use tactrace_store::SensorFolder;
use tactrace_vision::{DetectorParams, PinReader};

/// Where a follow run happens.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum World {
    /// The simulated TacTip of `rig.sensor` on the simulated arm.
    Simulated(SimWorld),
    /// A calibrated sensor's simulated TacTip (`--sensor`).
    Calibrated(CalibratedWorld),
    /// The real-frame world (`--replay`).
    Replay(Box<ReplayWorld>),
    /// A real UR5 and TacTip camera (`--hardware`), always behind the
    /// workspace limiter.
    #[cfg(feature = "hardware")]
    Hardware(crate::hardware::HardwareConfig),
}

/// The simulated rig (arm, workspace, tap, the simulated TacTip and its
/// blob detector), the controller, the loop and the start.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimWorld {
    pub rig: RigConfig,
    pub controller: PbtsConfig,
    pub follow: LoopConfig,
    pub start: StartConfig,
}

/// The simulated world's defaults (the controller tuned in simulation).
impl Default for SimWorld {
    fn default() -> Self {
        let c = SimFollowConfig::default();
        Self {
            rig: c.rig,
            controller: c.controller,
            follow: c.follow,
            start: c.start,
        }
    }
}

/// A calibrated sensor's world: its TacTip (parameters, field correction,
/// pin order and blob detector) on the simulated arm of `sim`, mounted by
/// its label convention, the model predicting in its labels.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibratedWorld {
    /// The sensor folder (`tactrace calibrate`).
    pub sensor: PathBuf,
    #[serde(default)]
    pub sim: SimWorld,
}

/// The real-frame world: the simulated arm of `sim`, every tap answered by
/// the frame of `bank` whose labels are nearest the pose reached, in the
/// label convention of the calibrated sensor `sensor` (else of
/// `sim.rig.sensor`), centred.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplayWorld {
    pub bank: ReplayBank,
    #[serde(default)]
    pub sensor: Option<PathBuf>,
    #[serde(default)]
    pub sim: SimWorld,
}

/// The configuration a run folder records (`config.toml`): the file that
/// runs the same world again (`follow --config`, or `--hardware`).
#[derive(Serialize)]
#[serde(untagged)]
pub(crate) enum Record {
    Sim(Box<SimFollowConfig>),
    #[cfg(feature = "hardware")]
    Hardware(Box<crate::hardware::HardwareConfig>),
}

/// A world checked whole, its files read: ready to run.
pub struct OpenWorld {
    parts: Parts,
    settings: ServoSettings,
    record: Record,
    sensor_diameter_mm: f64,
}

impl World {
    /// Check every setting and read the world's files (a calibrated
    /// sensor folder once; the real-frame bank, every frame present, and
    /// its reference frame): what can be refused is refused here, before
    /// any output is touched or anything moves.
    pub fn open(&self) -> Result<OpenWorld> {
        match self {
            World::Simulated(sim) => {
                let settings = sim_settings(sim)?;
                Ok(OpenWorld {
                    sensor_diameter_mm: 2.0 * sim.rig.sensor.geometry.dome_radius_mm,
                    parts: Parts::sim(sim, None),
                    settings,
                    record: Record::Sim(Box::new(SimFollowConfig::of(sim, None, None))),
                })
            }
            World::Calibrated(w) => {
                let folder = SensorFolder::read(&w.sensor)?;
                let detect = crate::sim_sight::sensor_detect(&folder.spec);
                let settings = sim_settings(&w.sim)?.with_detector(detect)?;
                let record = SimFollowConfig::of(&w.sim, Some(w.sensor.clone()), None);
                Ok(OpenWorld {
                    sensor_diameter_mm: 2.0 * folder.spec.sensor.geometry.dome_radius_mm,
                    parts: Parts::sim(&w.sim, Some(folder)),
                    settings,
                    record: Record::Sim(Box::new(record)),
                })
            }
            World::Replay(w) => open_replay(w),
            #[cfg(feature = "hardware")]
            World::Hardware(cfg) => {
                cfg.validate()?;
                Ok(OpenWorld {
                    settings: cfg.servo_settings()?,
                    parts: Parts::Hardware(Box::new(cfg.clone())),
                    record: Record::Hardware(Box::new(cfg.clone())),
                    sensor_diameter_mm: tactip_diameter_mm(),
                })
            }
        }
    }
}

/// The simulated rig checked whole, and its loop settings.
fn sim_settings(sim: &SimWorld) -> Result<ServoSettings> {
    sim.rig.validate()?;
    sim.start.validate()?;
    ServoSettings::new(
        sim.rig.blob.clone(),
        sim.controller.clone(),
        sim.follow.clone(),
        sim.rig.tap,
    )
}

/// The real-frame world: its bank, its reader (the collection's sensor
/// settings or blob detector over its reference pins, as `import` reads
/// it), a frame of its size and label convention.
fn open_replay(w: &ReplayWorld) -> Result<OpenWorld> {
    let collection = w.bank.collection();
    let detect = match collection.sight() {
        Some(s) => s.detect.clone(),
        None => DetectorParams::Blobs(collection.blob().clone()),
    };
    let settings = sim_settings(&w.sim)?.with_detector(detect)?;
    let bank = load_bank(&w.bank)?;
    let (reader, reference) = replay_reader(collection, &bank)?;
    let calibration = match &w.sensor {
        Some(dir) => SensorFolder::read(dir)?.spec.sensor.calibration,
        None => w.sim.rig.sensor.calibration.clone(),
    };
    let record = SimFollowConfig::of(&w.sim, w.sensor.clone(), Some(w.bank.clone()));
    Ok(OpenWorld {
        parts: Parts::Replay(Box::new(rig::ReplayParts {
            rig: w.sim.rig.clone(),
            start: w.sim.start.clone(),
            bank,
            reader,
            reference,
            convention: LabelConvention::centred(calibration),
            far_distance: w.bank.far_distance(),
        })),
        settings,
        record: Record::Sim(Box::new(record)),
        sensor_diameter_mm: tactip_diameter_mm(),
    })
}

/// The reader of the real-frame world's taps: `import`'s for the bank's
/// collection ([`crate::sim_sight::sim_sight`]: its sensor settings or
/// blob detector over the pins of its undeformed frame or its rest
/// layout, estimated from its frames when asked), and a frame of the
/// collection's size (its undeformed frame, else its first).
pub(crate) fn replay_reader(
    collection: &tactrace_store::LabelledCollection,
    bank: &FrameBank,
) -> Result<(PinReader, Frame)> {
    let sight = crate::sim_sight::sim_sight(collection)?;
    let frame = match collection.reference().frame() {
        Some(path) => path.to_path_buf(),
        None => bank.frames()[0].path.clone(),
    };
    Ok((sight.reader, read_frame(&frame)?))
}

impl OpenWorld {
    /// A user's own arm and camera (the Python package's `follow_rig`):
    /// `arm` behind the limiter of `cfg.rig.workspace`, `sensor` giving
    /// frames, `reference` its undeformed frame (taken at the start, out
    /// of contact); the loop settings, the recorded configuration and the
    /// sensor's size are `cfg`'s.
    pub fn own_rig<A, S>(arm: A, sensor: S, reference: Frame, cfg: &SimFollowConfig) -> Result<Self>
    where
        A: Arm + Send + 'static,
        S: TactileSensor + Send + 'static,
    {
        Ok(Self {
            parts: Parts::own(arm, sensor, reference, cfg.rig.workspace.clone()),
            settings: cfg.servo_settings()?,
            record: Record::Sim(Box::new(cfg.clone())),
            sensor_diameter_mm: 2.0 * cfg.rig.sensor.geometry.dome_radius_mm,
        })
    }

    /// The diameter of the world's sensor, mm (a contour smaller than it
    /// cannot be followed).
    pub fn sensor_diameter_mm(&self) -> f64 {
        self.sensor_diameter_mm
    }

    /// The loop settings the run will use.
    pub fn settings(&self) -> &ServoSettings {
        &self.settings
    }

    /// The parts a run builds its rig from, its settings and the
    /// configuration its folder records.
    pub(crate) fn into_parts(self) -> (Parts, ServoSettings, Record) {
        (self.parts, self.settings, self.record)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    use tactrace_store::LabelledCollection;

    fn round_trip(world: &World) -> String {
        let text = toml::to_string(world).unwrap();
        let back: World = toml::from_str(&text).unwrap();
        assert_eq!(toml::to_string(&back).unwrap(), text);
        text
    }

    #[test]
    fn a_world_is_a_kind_tagged_value_that_round_trips_and_refuses_unknown_keys() {
        let sim = SimFollowConfig::default();
        let text = round_trip(&sim.world());
        assert!(text.starts_with("kind = \"simulated\""), "{text}");
        let calibrated = SimFollowConfig {
            calibrated_sensor: Some("sensors/mine".into()),
            ..sim.clone()
        };
        assert!(matches!(calibrated.world(), World::Calibrated(_)));
        round_trip(&calibrated.world());
        let bank = ReplayBank::new(LabelledCollection::bristol(Path::new("set")), 0.5).unwrap();
        let replay = SimFollowConfig {
            replay: Some(bank),
            ..calibrated
        };
        let World::Replay(w) = replay.world() else {
            panic!("a [replay] table is the real-frame world");
        };
        assert_eq!(w.sensor.as_deref(), Some(Path::new("sensors/mine")));
        round_trip(&World::Replay(w));
        // Only the kind is needed; every table has its defaults.
        let bare: World = toml::from_str("kind = \"simulated\"\n").unwrap();
        assert_eq!(toml::to_string(&bare).unwrap(), text);
        for bad in [
            "kind = \"simulated\"\nsurprise = 1\n",
            "kind = \"simulated\"\n[rig]\nsurprise = 1\n",
            "kind = \"dream\"\n",
            "[rig]\n",
            "kind = \"calibrated\"\n",
        ] {
            assert!(toml::from_str::<World>(bad).is_err(), "{bad}");
        }
    }
}

#[cfg(test)]
mod replay_tests;
