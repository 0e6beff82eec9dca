//! Calibrated sensor folders (`tactrace calibrate --out SENSOR`): everything
//! the simulator needs to behave like one real TacTip, self-described.
//!
//! - `sensor.toml`: the format and tactrace versions, the simulated
//!   sensor's parameters (`[sensor]`), the blob detector (`[blob]`), the
//!   real reference frame's pins in their order (`[reference]`), the label
//!   columns the taps were read with (`[labels]`), how `twin --sensor`
//!   builds a training set (`[training]`) and the calibration's record with
//!   its held-out field RMS and cosine (`[calibration]`);
//! - `reference.png`: the real undeformed frame (its pins order every
//!   simulated tap, so models move between the simulator and the sensor),
//!   or, for a sensor with none (rest layout estimated from its taps), the
//!   calibrated simulator's rest frame;
//! - `correction.safetensors`: the field correction W, b and the chosen
//!   real calibration taps (fields and labels).
use crate::error::{write_err, Result, StoreError};
use crate::fsutil::{read_text, StagedDir};
use crate::input_file::{read_bounded, MAX_BINARY_BYTES};
use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensors};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_calib::{CalibrationRecord, LinearCorrection, Tensor};
use tactrace_sensor::{FieldCorrection, Frame, LabelConvention, TacTipConfig, TacTipModel};
use tactrace_vision::{BlobParams, SightParams};

/// The `format` key of every sensor file.
pub const SENSOR_FORMAT: &str = "tactrace-sensor";
/// Layout version of sensor folders; another version is refused.
pub const SENSOR_FORMAT_VERSION: u32 = 1;
const TOML_NAME: &str = "sensor.toml";
const REFERENCE_NAME: &str = "reference.png";
const TENSORS_NAME: &str = "correction.safetensors";
const REAL_FIELDS: &str = "real_taps.fields";
const REAL_LABELS: &str = "real_taps.labels";

/// The label columns of the user's taps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabelColumnNames {
    pub image: String,
    pub r: String,
    pub theta: String,
    pub dz: Option<String>,
    pub shear: Option<[String; 3]>,
}

/// How `twin --sensor` builds a training set from a labels file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingRecipe {
    /// Renders of every labelled tap (seeds s, s + 1, ...), each corrected.
    pub renders: usize,
    /// Add the real calibration taps, repeated to about a third of the
    /// training set.
    pub add_real_taps: bool,
}

impl Default for TrainingRecipe {
    fn default() -> Self {
        Self {
            renders: 3,
            add_real_taps: true,
        }
    }
}

/// `sensor.toml`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    pub format: String,
    pub format_version: u32,
    pub tactrace_version: String,
    pub sensor: TacTipConfig,
    pub blob: BlobParams,
    /// The sensor settings (`tactrace sensor inspect`) its real frames
    /// were read with, when given: their detector reads its simulated
    /// taps (in place of `blob`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sight: Option<SightParams>,
    pub labels: LabelColumnNames,
    pub training: TrainingRecipe,
    /// The real reference's pins, px, in their order: an undeformed
    /// frame's in detection order, or the rest layout estimated from the
    /// taps (`reference.png` is then the simulator's rest frame).
    pub reference_pins: Vec<[f64; 2]>,
    pub calibration: CalibrationRecord,
    /// How `calibrate` found the label convention (the signs and offsets
    /// in `sensor.calibration`) from the calibration taps: the sensor's
    /// own kept or another chosen, with every convention's misfit. Absent
    /// in sensor folders written before it was estimated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convention: Option<tactrace_sensor::ConventionFit>,
    /// How `calibrate` found the tap depth law and the slide response (in
    /// `sensor.calibration` and `sensor.mechanics`) from the calibration
    /// taps. Absent in sensor folders written before they were fitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<tactrace_sensor::DepthFit>,
}

/// A calibrated sensor in memory.
#[derive(Debug, Clone)]
pub struct SensorFolder {
    pub spec: SensorSpec,
    pub reference: Frame,
    pub correction: LinearCorrection,
    /// The chosen real taps: fields (N x 2P, row-major) and labels (r, theta).
    pub real_fields: Vec<f32>,
    pub real_labels: Vec<[f32; 2]>,
    /// Where it was read from (empty when made in memory).
    pub source: PathBuf,
}

impl SensorFolder {
    /// The field correction for the simulated sensor.
    pub fn field_correction(
        &self,
    ) -> std::result::Result<FieldCorrection, tactrace_sensor::SensorError> {
        let d = self.correction.dim();
        let w: Vec<f32> = (0..d)
            .flat_map(|i| (0..d).map(move |j| (i, j)))
            .map(|(i, j)| self.correction.w[(i, j)] as f32)
            .collect();
        let b = self.correction.b.iter().map(|v| *v as f32).collect();
        FieldCorrection::new(d / 2, w, b)
    }

    /// The calibrated simulated sensor: its parameters, the real
    /// reference's pins as the rest layout (so its taps list their pins in
    /// the real reference's order) and its field correction.
    pub fn model(&self) -> std::result::Result<TacTipModel, tactrace_sensor::SensorError> {
        TacTipModel::with_rest_pins(self.spec.sensor.clone(), self.spec.reference_pins.clone())?
            .with_correction(self.field_correction()?)
    }

    /// Its label convention, mounted on the tool so that the controller's
    /// aligned pose is the label angle zero (`LabelConvention::centred`).
    pub fn label_convention(&self) -> LabelConvention {
        LabelConvention::centred(self.spec.sensor.calibration.clone())
    }

    /// Write the folder `dir` (refused when it exists unless `force`).
    pub fn write(&self, dir: &Path, force: bool) -> Result<PathBuf> {
        self.stage(dir, force)?.commit()
    }

    /// Write the folder into a staging folder for `dir`; the caller may add
    /// files (figures) before it commits.
    pub fn stage(&self, dir: &Path, force: bool) -> Result<StagedDir> {
        let stage = StagedDir::new(dir, force)?;
        let text = toml::to_string(&self.spec).map_err(|e| StoreError::Format {
            path: dir.join(TOML_NAME),
            reason: e.to_string(),
        })?;
        let p = stage.path().join(TOML_NAME);
        std::fs::write(&p, text).map_err(write_err(&p))?;
        let p = stage.path().join(REFERENCE_NAME);
        self.reference.save(&p).map_err(|e| StoreError::Write {
            path: p.clone(),
            source: std::io::Error::other(e),
        })?;
        let mut tensors = self.correction.to_tensors();
        let n = self.real_labels.len();
        tensors.push((
            REAL_FIELDS.into(),
            vec![n, self.correction.dim()],
            self.real_fields.clone(),
        ));
        let labels = self.real_labels.iter().flatten().copied().collect();
        tensors.push((REAL_LABELS.into(), vec![n, 2], labels));
        let p = stage.path().join(TENSORS_NAME);
        std::fs::write(&p, serialise(&tensors, &p)?).map_err(write_err(&p))?;
        Ok(stage)
    }

    /// Read a folder written by [`Self::write`]; another format version, a
    /// missing part or inconsistent sizes are errors naming the file.
    pub fn read(dir: &Path) -> Result<Self> {
        let toml_path = dir.join(TOML_NAME);
        if !toml_path.is_file() {
            return Err(StoreError::Format {
                path: dir.into(),
                reason: format!(
                    "not a sensor folder: no {TOML_NAME} (make one with `tactrace calibrate`)"
                ),
            });
        }
        let text = read_text(&toml_path)?;
        let fmt = |reason: String| StoreError::Format {
            path: toml_path.clone(),
            reason,
        };
        let value: toml::Value = toml::from_str(&text).map_err(|e| fmt(e.to_string()))?;
        let version = value
            .get("format_version")
            .and_then(toml::Value::as_integer);
        if value.get("format").and_then(toml::Value::as_str) != Some(SENSOR_FORMAT) {
            return Err(fmt(format!("not a {SENSOR_FORMAT} file")));
        }
        if version != Some(i64::from(SENSOR_FORMAT_VERSION)) {
            return Err(fmt(format!(
                "sensor format version {} (this tactrace reads version {SENSOR_FORMAT_VERSION}); calibrate again",
                version.map_or("missing".to_string(), |v| v.to_string())
            )));
        }
        let spec: SensorSpec = value
            .try_into()
            .map_err(|e: toml::de::Error| fmt(e.to_string()))?;
        spec.calibration
            .check_version()
            .map_err(|e| fmt(e.to_string()))?;
        let reference_path = dir.join(REFERENCE_NAME);
        let reference =
            tactrace_sensor::read_frame(&reference_path).map_err(|e| StoreError::Format {
                path: reference_path.clone(),
                reason: e.to_string(),
            })?;
        let tensors_path = dir.join(TENSORS_NAME);
        let bytes = read_bounded(&tensors_path, MAX_BINARY_BYTES, "tensor file")?;
        let tensors = deserialise(&bytes, &tensors_path)?;
        let correction =
            LinearCorrection::from_tensors(&tensors, &spec.calibration).map_err(|e| {
                StoreError::Format {
                    path: tensors_path.clone(),
                    reason: e.to_string(),
                }
            })?;
        let d = correction.dim();
        let find = |name: &str, cols: usize| -> Result<(usize, Vec<f32>)> {
            let t = tensors
                .iter()
                .find(|t| t.0 == name)
                .ok_or_else(|| StoreError::Format {
                    path: tensors_path.clone(),
                    reason: format!("no tensor `{name}`"),
                })?;
            match t.1.as_slice() {
                [n, c] if *c == cols => Ok((*n, t.2.clone())),
                shape => Err(StoreError::Format {
                    path: tensors_path.clone(),
                    reason: format!(
                        "tensor `{name}` has shape {}, expected N x {cols}",
                        shape
                            .iter()
                            .map(usize::to_string)
                            .collect::<Vec<_>>()
                            .join(" x ")
                    ),
                }),
            }
        };
        let (n, real_fields) = find(REAL_FIELDS, d)?;
        let (m, labels) = find(REAL_LABELS, 2)?;
        if n != m || d != 2 * spec.reference_pins.len() {
            return Err(StoreError::Format {
                path: tensors_path,
                reason: format!(
                    "{n} real tap fields, {m} labels, {} reference pins for {d} coordinates",
                    spec.reference_pins.len()
                ),
            });
        }
        Ok(Self {
            spec,
            reference,
            correction,
            real_fields,
            real_labels: labels.chunks(2).map(|c| [c[0], c[1]]).collect(),
            source: dir.to_path_buf(),
        })
    }
}

fn serialise(tensors: &[Tensor], path: &Path) -> Result<Vec<u8>> {
    let bad = |e: safetensors::SafeTensorError| StoreError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    };
    let bytes: Vec<(String, Vec<usize>, Vec<u8>)> = tensors
        .iter()
        .map(|(name, shape, values)| {
            let b = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            (name.clone(), shape.clone(), b)
        })
        .collect();
    let views = bytes
        .iter()
        .map(|(name, shape, b)| {
            TensorView::new(Dtype::F32, shape.clone(), b).map(|v| (name.clone(), v))
        })
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(bad)?;
    safetensors::serialize(views, None).map_err(bad)
}

fn deserialise(bytes: &[u8], path: &Path) -> Result<Vec<Tensor>> {
    let bad = |reason: String| StoreError::Format {
        path: path.to_path_buf(),
        reason,
    };
    let st = SafeTensors::deserialize(bytes).map_err(|e| bad(e.to_string()))?;
    st.tensors()
        .into_iter()
        .map(|(name, view)| {
            if view.dtype() != Dtype::F32 {
                return Err(bad(format!("tensor `{name}` is not f32")));
            }
            let values = view
                .data()
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            Ok((name, view.shape().to_vec(), values))
        })
        .collect()
}
