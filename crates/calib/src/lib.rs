//! Few-shot calibration of the simulated TacTip to a user's real taps
//! (issue 11): the twin-vs-real misfit of the pin displacement fields is
//! global and low-rank, so a linear correction `real ~ sim + W sim + b`
//! fitted on a few labelled real taps paired with their twin replays, and
//! applied to simulated taps before training, carries a model trained in
//! simulation over to the real sensor.
//!
//! Pure: no files, no printing. [`calibrate()`] is the whole of
//! `tactrace calibrate` between reading the taps and writing the sensor
//! file; the pieces:
//! - [`Fields`]: N taps of 2P-dimensional displacement fields (all x, then all y);
//! - [`LinearCorrection`]: the ridge fit (penalty by exact leave-one-out) and its
//!   application, [`CorrectionParams`] its settings, [`FittedCorrection`] its result;
//! - [`select_taps`] / [`check_span`]: the seeded rule that picks calibration
//!   taps spanning edge position r and angle theta;
//! - [`field_stats`]: per-coordinate RMS misfit and cosine of two sets of fields;
//! - [`PositionMap`]: the quadratic map from the edge position a twin-trained
//!   model reads off the real calibration taps to their labels;
//! - [`roughness`] / [`fit_jitter`]: the pins' detection noise estimated from
//!   the taps' scatter about a smooth field, and the render jitter that matches it;
//! - [`CalibrationRecord`]: the serialisable description of a sensor file's
//!   correction, with [`Tensor`] helpers for the store layer;
//! - [`CalibError`]: every way the input can be wrong.
pub mod calibrate;
pub mod error;
pub mod fields;
pub mod jitter;
pub mod position_map;
pub mod record;
pub mod ridge;
pub mod select;
pub mod stats;

pub use calibrate::{calibrate, real_tap_repeats, Calibration, CalibrationPlan};
pub use error::{CalibError, Result};
pub use fields::Fields;
pub use jitter::{fit_jitter, roughness, JitterFit, JitterPoint, Stencil, JITTER_GRID};
pub use position_map::PositionMap;
pub use record::{CalibrationRecord, Selection, Tensor, FORMAT_VERSION};
pub use ridge::{CorrectionParams, FittedCorrection, LinearCorrection, MIN_TAPS, RECOMMENDED_TAPS};
pub use select::{check_labels, check_span, select_taps, Label, SpanRule};
pub use stats::{field_stats, median, FieldStats};
