//! The lab: tactrace's experiments and everything that touches files.
//!
//! The research pipeline, one module a stage: [`collect`] taps on an edge
//! (simulated rig, [`rig`]), [`import`] turns real frames into the same
//! [`dataset`] format, [`train`] fits pose models ([`model_io`] stores
//! them), [`servo`] closes the loop round an object, [`metrics`] scores the
//! trajectory, [`figures`] and [`report`] regenerate the report's tables and
//! figures. Algorithms live in the `tactrace-*` core crates; this crate
//! wires them to files, progress bars and plots.

pub mod bench;
pub mod collect;
pub mod dataset;
pub mod error;
pub mod figures;
pub mod follow;
pub mod fsutil;
pub mod hardware;
pub mod html;
pub mod images;
pub mod import;
pub mod metrics;
pub mod model_io;
pub mod pin_order;
pub mod plot;
pub mod report;
pub mod report_doc;
pub mod rig;
pub mod servo;
pub mod settings;
pub mod shape_io;
pub mod train;
pub mod twin;

pub use error::{LabError, Result};

/// The tactrace version recorded in every output.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
