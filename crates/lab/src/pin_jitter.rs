//! The render pin jitter of a calibrated sensor, as `calibrate
//! --pin-jitter` asks: the sensor's own, a given value, or fitted to the
//! calibration taps (docs/calibration.md, "Pin jitter fitted from the
//! taps"). The fit measures the real taps' roughness (their scatter
//! about a smooth field, `tactrace_calib::roughness`) and the
//! simulator's at a grid of render jitters, each tap rendered and read
//! as the twin does, and keeps the jitter whose roughness matches
//! (`tactrace_calib::fit_jitter`).
use crate::calibrate::paired;
use crate::error::Result;
use crate::import::Imported;
use crate::sim_sight::SimSight;
use crate::twin::simulate_twin_rows;
use std::str::FromStr;
use tactrace_calib::{fit_jitter, roughness, JitterFit, JitterPoint, Stencil, JITTER_GRID};
use tactrace_sensor::TacTipConfig;
use tactrace_store::LabelledCollection;

/// `sensor` with its renders' pin jitter set to `px` (each rendered pin
/// centre moved by N(0, px^2) per axis before the frame is drawn and read,
/// docs/sensor-model.md "Rendering and nuisance", `[sensor.nuisance]
/// pin_jitter_px`): what `twin --pin-jitter` and `calibrate --pin-jitter`
/// set. A sensor whose jitter and image noise are both 0 renders every
/// labelled row the same at every seed (`twin::renders_differ`); with a
/// jitter each render is a new draw of the detection noise the real
/// frames carry (docs/calibration.md, "Pin jitter in the twin").
/// Refused unless `px` is finite and at least 0.
pub fn with_pin_jitter(sensor: &TacTipConfig, px: f64) -> Result<TacTipConfig> {
    let mut out = sensor.clone();
    out.nuisance.pin_jitter_px = px;
    out.validate()?;
    Ok(out)
}

/// What a calibration does with the sensor's render pin jitter
/// (`[sensor.nuisance] pin_jitter_px`).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PinJitter {
    /// Keep the sensor's own (0 for the built-in simulator).
    #[default]
    Own,
    /// This jitter, px per axis (`--pin-jitter PX`).
    Given(f64),
    /// Fitted to the calibration taps (`--pin-jitter fit`).
    Fit,
}

/// A `--pin-jitter` that is neither `fit` nor a jitter in px.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{0}` is not a pin jitter: give `fit` or a jitter in px (0 or more)")]
pub struct PinJitterParseError(String);

impl FromStr for PinJitter {
    type Err = PinJitterParseError;

    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        if s.eq_ignore_ascii_case("fit") {
            return Ok(PinJitter::Fit);
        }
        match s.parse::<f64>() {
            Ok(px) if px.is_finite() && px >= 0.0 => Ok(PinJitter::Given(px)),
            _ => Err(PinJitterParseError(s.into())),
        }
    }
}

/// The render jitter of `sensor` (the calibrated simulator, without its
/// field correction) whose roughness on the label rows `chosen` of
/// `collection` matches the real frames' of the same rows in `real`;
/// renders drawn with `seed`.
pub(crate) fn fit_pin_jitter(
    collection: &LabelledCollection,
    sight: &SimSight,
    sensor: &TacTipConfig,
    (chosen, real): (&[usize], &Imported),
    seed: u64,
) -> Result<JitterFit> {
    let stencil = Stencil::new(&real.data.meta.reference_pins)?;
    let mut curve = Vec::with_capacity(JITTER_GRID.len());
    let mut measured = None;
    for &px in &JITTER_GRID {
        let at = with_pin_jitter(sensor, px)?;
        let twin = simulate_twin_rows(collection, sight, &at, seed, (Some(chosen), &|| {}))?;
        let (sim, real_fields, _) = paired(real, &twin)?.fields()?;
        if measured.is_none() {
            measured = Some((roughness(&real_fields, &stencil)?, real_fields.len()));
        }
        curve.push(JitterPoint {
            jitter_px: px,
            roughness_px: roughness(&sim, &stencil)?,
        });
    }
    let (real_roughness, taps) = measured.unwrap_or((f64::NAN, 0));
    Ok(fit_jitter(real_roughness, &curve, taps)?)
}
