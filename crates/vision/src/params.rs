//! Blob-detector parameters: the knobs of OpenCV's `SimpleBlobDetector`
//! under their snake_case names, with OpenCV's defaults, the named presets
//! the project ships (report appendix, real 256 px frames, simulated frames)
//! and a strict TOML round trip so configuration files cannot silently
//! carry a misspelt key.

use serde::{Deserialize, Serialize};

use crate::error::VisionError;

/// Parameters of the multi-threshold blob detector (report ch. 4.1 and
/// appendix; OpenCV `SimpleBlobDetector::Params`). Areas are in px^2, the
/// thresholds are grey levels, the ratios are dimensionless. The `max_*`
/// bounds are exclusive, the `min_*` bounds inclusive, as in OpenCV.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlobParams {
    pub min_threshold: f32,
    pub max_threshold: f32,
    pub threshold_step: f32,
    pub min_dist_between_blobs: f32,
    pub min_repeatability: usize,
    pub filter_by_color: bool,
    pub blob_color: u8,
    pub filter_by_area: bool,
    pub min_area: f32,
    pub max_area: f32,
    pub filter_by_circularity: bool,
    pub min_circularity: f32,
    pub max_circularity: f32,
    pub filter_by_inertia: bool,
    pub min_inertia_ratio: f32,
    pub max_inertia_ratio: f32,
    pub filter_by_convexity: bool,
    pub min_convexity: f32,
    pub max_convexity: f32,
}

/// The keys a blob-parameter TOML table may contain.
pub const BLOB_PARAM_KEYS: [&str; 19] = [
    "min_threshold",
    "max_threshold",
    "threshold_step",
    "min_dist_between_blobs",
    "min_repeatability",
    "filter_by_color",
    "blob_color",
    "filter_by_area",
    "min_area",
    "max_area",
    "filter_by_circularity",
    "min_circularity",
    "max_circularity",
    "filter_by_inertia",
    "min_inertia_ratio",
    "max_inertia_ratio",
    "filter_by_convexity",
    "min_convexity",
    "max_convexity",
];

/// Names accepted by [`BlobParams::preset`].
pub const PRESET_NAMES: [&str; 4] = ["opencv", "report", "real256", "sim"];

impl Default for BlobParams {
    /// OpenCV's `SimpleBlobDetector::Params()` defaults.
    fn default() -> Self {
        Self {
            min_threshold: 50.0,
            max_threshold: 220.0,
            threshold_step: 10.0,
            min_dist_between_blobs: 10.0,
            min_repeatability: 2,
            filter_by_color: true,
            blob_color: 0,
            filter_by_area: true,
            min_area: 25.0,
            max_area: 5000.0,
            filter_by_circularity: false,
            min_circularity: 0.8,
            max_circularity: f32::MAX,
            filter_by_inertia: true,
            min_inertia_ratio: 0.1,
            max_inertia_ratio: f32::MAX,
            filter_by_convexity: true,
            min_convexity: 0.95,
            max_convexity: f32::MAX,
        }
    }
}

impl BlobParams {
    /// Parses a TOML table of blob parameters; missing keys take OpenCV's
    /// defaults, an unknown key is an error naming it. The result is validated.
    pub fn from_toml(text: &str) -> Result<Self, VisionError> {
        let table: toml::Table = toml::from_str(text).map_err(|e| VisionError::Toml {
            message: e.message().to_string(),
        })?;
        if let Some(key) = table
            .keys()
            .find(|key| !BLOB_PARAM_KEYS.contains(&key.as_str()))
        {
            return Err(VisionError::UnknownKey { key: key.clone() });
        }
        let params: Self = table
            .try_into()
            .map_err(|e: toml::de::Error| VisionError::Toml {
                message: e.message().to_string(),
            })?;
        params.validate()?;
        Ok(params)
    }

    /// Writes every key as TOML (the inverse of [`BlobParams::from_toml`]).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# could not serialise: {e}\n"))
    }

    /// A named parameter set: `opencv` (OpenCV defaults), `report` (the
    /// report's appendix values, for its full-resolution camera), `real256`
    /// (the real 256 x 256 binarised 127-pin frames) and `sim` (tactrace's
    /// simulated 256 x 256 frames).
    pub fn preset(name: &str) -> Result<Self, VisionError> {
        match name {
            "opencv" => Ok(Self::default()),
            "report" => Ok(Self::report()),
            "real256" => Ok(Self::real256()),
            "sim" => Ok(Self::sim()),
            _ => Err(VisionError::UnknownPreset {
                name: name.to_string(),
                known: PRESET_NAMES.join(", "),
            }),
        }
    }

    /// The appendix values of the report; unlisted keys keep OpenCV defaults.
    fn report() -> Self {
        Self {
            min_threshold: 82.39,
            max_threshold: 215.98,
            filter_by_color: true,
            blob_color: 255,
            filter_by_area: true,
            min_area: 82.39,
            max_area: 190.96,
            filter_by_circularity: true,
            min_circularity: 0.44,
            filter_by_inertia: true,
            min_inertia_ratio: 0.27,
            filter_by_convexity: true,
            min_convexity: 0.57,
            ..Self::default()
        }
    }

    /// White pins of about 15-60 px^2 (pixel count; 6-45 px^2 as contour
    /// polygons) on the 256 x 256 binarised real frames; the shape bounds
    /// reject the white rim arcs and corner specks. The merge distance is
    /// below the smallest compressed pin spacing (about 6 px), else a pin
    /// joins its neighbour's group at the second threshold and is lost.
    fn real256() -> Self {
        Self {
            min_dist_between_blobs: 4.0,
            blob_color: 255,
            min_area: 5.0,
            max_area: 70.0,
            filter_by_circularity: true,
            min_circularity: 0.5,
            min_inertia_ratio: 0.3,
            min_convexity: 0.8,
            ..Self::report()
        }
    }

    /// Simulated frames are drawn to resemble the real ones.
    fn sim() -> Self {
        Self::real256()
    }

    /// Checks the ranges OpenCV enforces (`validateParameters`) plus
    /// finiteness and `min_repeatability >= 1`.
    pub fn validate(&self) -> Result<(), VisionError> {
        positive("threshold_step", self.threshold_step)?;
        ordered("threshold", self.min_threshold, self.max_threshold, true)?;
        threshold_count(self)?;
        positive("min_dist_between_blobs", self.min_dist_between_blobs)?;
        if self.min_repeatability == 0 {
            return Err(invalid("min_repeatability", "must be at least 1".into()));
        }
        ordered("area", self.min_area, self.max_area, false)?;
        ordered(
            "circularity",
            self.min_circularity,
            self.max_circularity,
            false,
        )?;
        ordered(
            "inertia_ratio",
            self.min_inertia_ratio,
            self.max_inertia_ratio,
            false,
        )?;
        ordered("convexity", self.min_convexity, self.max_convexity, false)?;
        Ok(())
    }

    /// The thresholds the detector visits, in order: `min_threshold`,
    /// `+ threshold_step`, ... while below `max_threshold` (accumulated in
    /// f64 like OpenCV's loop).
    pub fn thresholds(&self) -> Vec<f64> {
        let mut out = Vec::new();
        let step = f64::from(self.threshold_step);
        if !step.is_finite() || step <= 0.0 || step.is_nan() {
            return out;
        }
        let mut t = f64::from(self.min_threshold);
        while t < f64::from(self.max_threshold) && out.len() < MAX_THRESHOLDS {
            out.push(t);
            let next = t + step;
            if next <= t {
                break; // step below the precision of t: avoid looping forever
            }
            t = next;
        }
        out
    }
}

/// At most this many thresholds per frame (an 8-bit frame has 256 grey
/// levels; OpenCV's defaults visit 17). More would take unbounded time and
/// memory: `max_threshold = 1e308` once tried to allocate terabytes.
pub const MAX_THRESHOLDS: usize = 4096;

/// Error when the threshold range and step visit more than [`MAX_THRESHOLDS`].
fn threshold_count(p: &BlobParams) -> Result<(), VisionError> {
    let span = f64::from(p.max_threshold) - f64::from(p.min_threshold);
    let count = (span / f64::from(p.threshold_step)).ceil();
    if count.is_finite() && count <= MAX_THRESHOLDS as f64 {
        return Ok(());
    }
    Err(invalid(
        "max_threshold",
        format!(
            "{} to {} by {} gives more than {MAX_THRESHOLDS} thresholds",
            p.min_threshold, p.max_threshold, p.threshold_step
        ),
    ))
}

fn invalid(name: &'static str, reason: String) -> VisionError {
    VisionError::InvalidParam { name, reason }
}

fn positive(name: &'static str, value: f32) -> Result<(), VisionError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            name,
            format!("must be finite and > 0, got {value}"),
        ))
    }
}

/// `min_<name> <= max_<name>`, min finite and >= 0 (`allow_zero`) or > 0.
fn ordered(name: &'static str, min: f32, max: f32, allow_zero: bool) -> Result<(), VisionError> {
    let min_ok = min.is_finite() && (min > 0.0 || (allow_zero && min == 0.0));
    if !min_ok {
        let bound = if allow_zero { ">= 0" } else { "> 0" };
        return Err(invalid(
            name,
            format!("min must be finite and {bound}, got {min}"),
        ));
    }
    if max.is_nan() || min > max {
        return Err(invalid(name, format!("min {min} exceeds max {max}")));
    }
    Ok(())
}
