//! The sensor settings file (`tactrace sensor inspect --out SENSOR.toml`):
//! how to read one TacTip's camera frames (the preprocessing and the
//! detector, [`SightParams`]) and what inspection found (pin count,
//! layout kind, pin spacing and size, the input frame size). Every command
//! that reads frames takes it as `--sensor SENSOR.toml`. Checked as it is
//! read: unknown keys refused, the preprocessing and the detector checked
//! for the frame size it records.
use crate::error::{Result, StoreError};
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_vision::{DetectorParams, LayoutKind, PreprocessParams, SightParams};

/// A sensor settings file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SightFile {
    /// What inspection found.
    pub sensor: SensorSummary,
    /// Camera image -> frame.
    #[serde(default)]
    pub preprocess: PreprocessParams,
    /// Frame -> pins.
    pub detect: DetectorParams,
}

/// What inspection found about the sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSummary {
    /// The number of pins inside the dome mask.
    pub pins: usize,
    /// Hexagonal lattice or concentric rings.
    pub layout: LayoutKind,
    /// Median nearest-neighbour pin spacing in the preprocessed frame, px.
    pub spacing_px: f64,
    /// Median pin size in the preprocessed frame, pixels.
    pub pin_pixels: f64,
    /// The camera frames' `[width, height]`, px, the settings were made for.
    pub frame_size: [u32; 2],
}

impl SightFile {
    /// The preprocessing and the detector.
    pub fn sight(&self) -> SightParams {
        SightParams {
            preprocess: self.preprocess.clone(),
            detect: self.detect.clone(),
        }
    }

    /// Parses and checks the text of a sensor file (`what` names it in
    /// errors).
    pub fn from_toml(text: &str, what: &Path) -> Result<Self> {
        let bad = |reason: String| StoreError::Format {
            path: what.to_path_buf(),
            reason,
        };
        let file: Self = toml::from_str(text).map_err(|e| bad(e.message().to_string()))?;
        let [w, h] = file.sensor.frame_size;
        file.sight()
            .check(w, h)
            .map_err(|e| bad(format!("settings that cannot be used: {e}")))?;
        if file.sensor.pins < 3 {
            return Err(bad(format!(
                "sensor.pins is {}: a sensor has at least 3 pins",
                file.sensor.pins
            )));
        }
        Ok(file)
    }

    /// Reads and checks a sensor file.
    pub fn read(path: &Path) -> Result<Self> {
        Self::from_toml(&crate::fsutil::read_text(path)?, path)
    }

    /// The file's text, with a header saying what made it.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).expect("sensor settings serialise");
        format!(
            "# TacTip sensor settings (tactrace sensor inspect): how to read its frames.\n\
             # Pass to import and predict --image as --sensor FILE.\n\n{}\n",
            body.trim_end()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactrace_vision::{MaskCircle, SpotParams, Threshold};

    fn file() -> SightFile {
        SightFile {
            sensor: SensorSummary {
                pins: 331,
                layout: LayoutKind::Rings,
                spacing_px: 4.6,
                pin_pixels: 6.0,
                frame_size: [128, 128],
            },
            preprocess: PreprocessParams {
                mask: Some(MaskCircle {
                    centre: [64.0, 64.0],
                    radius: 50.0,
                }),
                threshold: Some(Threshold::AdaptiveGaussian { block: 21, c: -5.0 }),
                ..PreprocessParams::default()
            },
            detect: DetectorParams::Spots(SpotParams {
                level: 127,
                min_pixels: 1,
                max_pixels: 10,
                max_cluster_pixels: 24,
                connectivity: Default::default(),
            }),
        }
    }

    #[test]
    fn a_sensor_file_round_trips_and_refuses_unknown_keys_and_bad_settings() {
        let f = file();
        let text = f.to_toml();
        let p = Path::new("s.toml");
        assert_eq!(SightFile::from_toml(&text, p).unwrap(), f);
        let unknown = text.replacen("pins = 331", "pins = 331\npin_count = 3", 1);
        let err = SightFile::from_toml(&unknown, p).unwrap_err().to_string();
        assert!(err.contains("pin_count"), "{err}");
        let mut cropped = f.clone();
        cropped.preprocess.crop = Some([0, 0, 400, 400]);
        let crop = cropped.to_toml();
        let err = SightFile::from_toml(&crop, p).unwrap_err().to_string();
        assert!(err.contains("cannot be used"), "{err}");
    }
}
