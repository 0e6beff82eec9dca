//! Pin extraction for the TacTip optical tactile sensor (report ch. 4.1):
//! find the white pin tips in a camera frame with an OpenCV-compatible
//! multi-threshold blob detector, put them in the order of the undeformed
//! reference, and turn them into the displacement vector the pose models
//! learn from. For any TacTip: one typed preprocessing stage (grey, crop,
//! dome mask, threshold, resize; [`preprocess`]), a small-pin detector
//! ([`SpotDetector`]), the inspection that proposes how to read an unknown
//! sensor's frames ([`inspect`]), the rest layout estimated from taps when
//! no undeformed frame exists ([`estimate_rest`]) and the reader that runs
//! it all with per-frame counts ([`PinReader`]). Pure algorithms: no files,
//! no printing.

mod assign;
mod binary;
mod blob;
mod chain;
mod components;
mod contour;
mod detection;
mod error;
mod extractor;
mod field;
mod fold;
mod grouping;
mod inspect;
mod merged;
mod params;
pub mod preprocess;
mod reader;
mod rest;
mod row_bits;
mod runs;
mod shape;
mod spot_runs;
mod spots;
mod tracker;

pub use assign::{assign, Assignment, Edge};
pub use blob::{detect_blobs, detect_blobs_by_threshold, Frame, KeyPoint};
pub use detection::{Detection, Detector, DetectorParams};
pub use error::VisionError;
pub use extractor::PinExtractor;
pub use field::EXACT_TOLERANCE;
pub use fold::TURNED_RATIO;
pub use inspect::{draw_inspection, inspect, layout_of, Inspection, Layout, LayoutKind, Picture};
pub use merged::{find_clusters, Cluster};
pub use params::{BlobParams, BLOB_PARAM_KEYS, MAX_THRESHOLDS, PRESET_NAMES};
pub use preprocess::{
    MaskCircle, Preprocess, PreprocessParams, PreprocessStage, Resize, ResizeMethod, Threshold,
};
pub use reader::{FrameDetector, PinReader, Reading, SightParams, TrackCounts};
pub use rest::{estimate_rest, RestEstimate, RestParams};
pub use spots::{Connectivity, Spot, SpotDetector, SpotParams, Spots};
pub use tracker::{median_spacing, FirstPass, PinTracker, Tracked, CUT_MIN_PINS, CUT_TOLERANCE};
