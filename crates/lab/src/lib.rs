//! The lab: tactrace's experiments, one module a stage of the research
//! pipeline.
//!
//! [`calibrate`] fits the simulator to a user's real taps,
//! [`collect`] taps on an edge (the simulated rig of `tactrace-servo`),
//! [`import`] turns a labelled collection of real frames
//! (`tactrace_store::LabelledCollection`) into the same dataset format,
//! [`twin`] replays a real set's labels on the simulator, [`train`] fits
//! and validates pose models ([`train_image`] the image models, on the
//! datasets of [`train_sets`]: one, or several joined), [`follow`] runs the servo loop round an
//! object into a run folder in any [`world`] (the simulated TacTip, a
//! calibrated sensor, the real-frame world, the real rig of [`hardware`]),
//! [`reproduce`] regenerates the report, [`mod@bench`] times it, [`render`]
//! draws one simulated tap, [`mod@tune`] tunes the controller in simulation
//! (CMA-ES). Algorithms
//! live in the core crates, files in `tactrace-store`, figures and
//! documents in `tactrace-report`; this crate wires them together.

pub mod bench;
pub mod calibrate;
mod calibration_sweep;
pub mod collect;
pub mod collect3d;
pub mod error;
pub mod follow;
#[cfg(feature = "hardware")]
pub mod hardware;
pub mod held_out_copies;
pub mod image_base;
pub mod image_base_reuse;
pub mod image_fit;
pub mod import;
pub mod import_checks;
pub mod import_like;
pub mod import_reader;
pub mod import_request;
pub mod join_models;
pub mod numbers;
pub mod pin_jitter;
pub mod remote;
pub mod render;
pub mod reproduce;
pub mod reproduce3d;
mod reproduce_image;
pub mod search;
pub mod sensor_inspect;
pub mod sim_sight;
mod tap_images;
#[cfg(test)]
mod test_data;
pub mod train;
pub mod train_continue;
pub mod train_image;
pub mod train_sets;
pub mod trajectory_csv;
pub mod transfer_fit;
pub mod tune;
pub mod twin;
pub mod world;

pub use error::{LabError, Result};

/// The tactrace version recorded in every output.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
