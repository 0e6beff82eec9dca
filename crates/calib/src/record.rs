//! What a sensor file records of its correction: a serde description
//! (version, sizes, penalty, held-out figures, the tap selection) for the
//! TOML part, and W and b as named f32 tensors for the safetensors part.
//! No file is touched here: the store layer writes and reads both.
use crate::error::{CalibError, Result};
use crate::jitter::JitterFit;
use crate::ridge::{CorrectionParams, LinearCorrection};
use crate::stats::FieldStats;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Version of the record layout; a record of another version is refused.
pub const FORMAT_VERSION: u32 = 1;
/// Tensor name of W (D x D, row-major: row = output coordinate).
pub const W_NAME: &str = "correction.w";
/// Tensor name of b (D).
pub const B_NAME: &str = "correction.b";

/// A named f32 tensor: (name, shape, row-major values).
pub type Tensor = (String, Vec<usize>, Vec<f32>);

/// How the calibration taps were chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Selection {
    /// Seed of [`crate::select_taps`].
    pub seed: u64,
    /// Taps asked for.
    pub samples: usize,
    /// Chosen taps, as indices into the user's labelled taps (row order).
    pub indices: Vec<usize>,
}

/// The description of a fitted correction, stored next to its tensors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationRecord {
    /// [`FORMAT_VERSION`] when written.
    pub format_version: u32,
    /// Pins a field (D = 2 pins).
    pub pins: usize,
    /// Settings of the fit.
    pub params: CorrectionParams,
    /// Chosen penalty.
    pub penalty: f64,
    /// Leave-one-out RMS on the calibration taps, px.
    pub loo_rms_px: f64,
    pub selection: Selection,
    /// Twin vs real on the held-out taps, before correction.
    pub held_out_before: Option<FieldStats>,
    /// Corrected twin vs real on the held-out taps.
    pub held_out_after: Option<FieldStats>,
    /// The render pin jitter fitted to the calibration taps and its
    /// evidence (`calibrate --pin-jitter fit`; absent otherwise, so files
    /// written before read the same).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pin_jitter: Option<JitterFit>,
}

impl CalibrationRecord {
    /// Errors unless this version can read the record.
    pub fn check_version(&self) -> Result<()> {
        if self.format_version == FORMAT_VERSION {
            Ok(())
        } else {
            Err(CalibError::Record(format!(
                "format version {} (this tactrace reads version {FORMAT_VERSION}); recalibrate",
                self.format_version
            )))
        }
    }
}

impl LinearCorrection {
    /// W and b as named row-major f32 tensors.
    pub fn to_tensors(&self) -> Vec<Tensor> {
        let d = self.dim();
        let mut w = Vec::with_capacity(d * d);
        for row in self.w.row_iter() {
            w.extend(row.iter().map(|&v| v as f32));
        }
        vec![
            (W_NAME.into(), vec![d, d], w),
            (
                B_NAME.into(),
                vec![d],
                self.b.iter().map(|&v| v as f32).collect(),
            ),
        ]
    }

    /// The correction from tensors written by [`Self::to_tensors`], checked
    /// against the record's pin count.
    pub fn from_tensors(tensors: &[Tensor], record: &CalibrationRecord) -> Result<Self> {
        record.check_version()?;
        let d = 2 * record.pins;
        let get = |name: &str, shape: &[usize]| -> Result<&Vec<f32>> {
            let (_, s, v) = tensors
                .iter()
                .find(|t| t.0 == name)
                .ok_or_else(|| CalibError::Record(format!("no tensor `{name}`")))?;
            if s != shape || v.len() != shape.iter().product::<usize>() {
                let dims = |d: &[usize]| {
                    let parts: Vec<String> = d.iter().map(usize::to_string).collect();
                    parts.join(" x ")
                };
                return Err(CalibError::Record(format!(
                    "tensor `{name}` has shape {}, expected {}",
                    dims(s),
                    dims(shape)
                )));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(CalibError::Record(format!("tensor `{name}` is not finite")));
            }
            Ok(v)
        };
        let w = get(W_NAME, &[d, d])?;
        let b = get(B_NAME, &[d])?;
        Ok(LinearCorrection {
            w: DMatrix::from_row_iterator(d, d, w.iter().map(|&v| v as f64)),
            b: DVector::from_iterator(d, b.iter().map(|&v| v as f64)),
        })
    }
}
