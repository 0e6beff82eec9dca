//! How the real rig reads its camera's images: a sensor file
//! (`sensor = "sensor.toml"` in the rig file, written by `tactrace sensor
//! inspect`: the preprocessing, the detector and the camera image size
//! they were made for), or, in older rig files, the rig's own
//! `[preprocess]` and `[blob]` tables. Both give the one preprocessing
//! type `import` and `predict --image` use
//! ([`tactrace_vision::Preprocess`]) and the detector (a sensor file's:
//! the blob detector or the small-pin one); a rig file giving both ways
//! is refused, so there is one way to read the camera.
use super::{real_blob, HardwareConfig};
use crate::error::{LabError, Result};
use std::path::Path;
use tactrace_hw::PreprocessConfig;
use tactrace_store::SightFile;
use tactrace_vision::{DetectorParams, Preprocess};

/// What a rig's camera images go through, resolved: the preprocessing,
/// the image size it was made for (a sensor file's), the detector.
#[derive(Debug, Clone)]
pub struct RigSight {
    /// Camera image -> frame.
    pub preprocess: Preprocess,
    /// The camera's `[width, height]` the sensor file was made for (other
    /// sizes are refused); `None` for the rig's own table (any size).
    pub frame_size: Option<[u32; 2]>,
    /// Frame -> pins: the rig's blob detector, or the sensor file's
    /// detector (blob or small-pin).
    pub detect: DetectorParams,
}

/// Refuses a rig file text that names a sensor file and also has its own
/// `[preprocess]` or `[blob]` table (`what` names the file).
pub(super) fn check_one_way(text: &str, what: &str) -> Result<()> {
    let Ok(table) = text.parse::<toml::Table>() else {
        return Ok(()); // the parse proper reports it
    };
    if !table.contains_key("sensor") {
        return Ok(());
    }
    match ["preprocess", "blob"]
        .iter()
        .find(|k| table.contains_key(**k))
    {
        Some(key) => Err(conflict(what, key)),
        None => Ok(()),
    }
}

fn conflict(what: &str, key: &str) -> LabError {
    LabError::Config(format!(
        "{what}: `sensor` names a sensor file, which says how to read the camera's images, \
         and the rig file has its own [{key}] table: keep one way (the sensor file; or, \
         without `sensor`, the [preprocess] and [blob] tables)"
    ))
}

impl HardwareConfig {
    /// Reads and parses the rig file at `path` ([`HardwareConfig::from_toml`]),
    /// a relative `sensor` path taken from the rig file's folder (and made
    /// absolute, so the run folder's copy of the configuration names the
    /// same file).
    pub fn read(path: &Path) -> Result<Self> {
        let text = tactrace_store::read_text(path)?;
        let mut cfg = Self::from_toml(&text, &path.display().to_string())?;
        if let Some(sensor) = cfg.sensor.take() {
            let dir = path.parent().unwrap_or(Path::new(""));
            let joined = dir.join(sensor);
            cfg.sensor = Some(std::path::absolute(&joined).unwrap_or(joined));
        }
        Ok(cfg)
    }

    /// How this rig reads its camera's images, checked: the sensor file's
    /// settings (read here), else the `[preprocess]` and `[blob]` tables. With a sensor file the tables
    /// must be left at their defaults.
    pub fn sight(&self) -> Result<RigSight> {
        let Some(path) = &self.sensor else {
            return Ok(RigSight {
                preprocess: self.preprocess.validate()?,
                frame_size: None,
                detect: DetectorParams::Blobs(self.blob.clone()),
            });
        };
        if self.preprocess != PreprocessConfig::default() {
            return Err(conflict("the rig", "preprocess"));
        }
        if self.blob != real_blob() {
            return Err(conflict("the rig", "blob"));
        }
        let file = SightFile::read(path)?;
        Ok(RigSight {
            preprocess: file.preprocess.clone().check()?,
            frame_size: Some(file.sensor.frame_size),
            detect: file.detect.clone(),
        })
    }
}
