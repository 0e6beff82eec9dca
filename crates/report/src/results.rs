//! What `reproduce` measured, as the documents show it.
use serde::Serialize;
use tactrace_servo::{Ending, FollowMetrics};

/// The report's Table 4.1 errors (angle deg, position mm).
pub const REPORT_TABLE_4_1: [(&str, Option<f64>, Option<f64>); 3] = [
    ("DisDenNN", Some(6.55), Some(1.34)),
    ("PCADenNN", Some(5.89), Some(0.53)),
    ("PDenNN", Some(5.36), Some(0.38)),
];

/// The literature's figure on the real edge set (a CNN on the images, on
/// another split): angle deg, position mm. Quoted, not measured here.
pub const LITERATURE_CNN: (f64, f64) = (1.45, 0.15);

/// One row of the networks table.
#[derive(Debug, Clone, Serialize)]
pub struct NetRow {
    pub name: String,
    pub data: String,
    pub position_mae_mm: f64,
    pub angle_mae_deg: f64,
    pub train_seconds: f64,
    /// Learning-rate halvings after divergence (`divergence_retries`).
    pub lr_halvings: usize,
}

/// One row of the calibration table: the simulator calibrated on some
/// real taps (`tactrace calibrate`), a PDenNN trained on its twin
/// (`twin --sensor`), scored on held-out real frames.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationRow {
    /// Calibration taps asked for (`None`: every tap of the pool).
    pub taps: Option<usize>,
    /// Taps actually used.
    pub taps_used: usize,
    /// Which real taps could be chosen ("training part", "r < 0", ...).
    pub pool: String,
    /// Which held-out real frames score it ("validation part", "r > 0", ...).
    pub scored_on: String,
    pub position_mae_mm: f64,
    pub angle_mae_deg: f64,
    /// Twin against real fields on the scoring frames, before and after
    /// the correction (per-coordinate RMS, px; mean cosine).
    pub field_rms_before_px: Option<f64>,
    pub field_rms_after_px: Option<f64>,
    pub cosine_before: Option<f64>,
    pub cosine_after: Option<f64>,
}

/// One row of the contour table.
#[derive(Debug, Clone, Serialize)]
pub struct ShapeRow {
    pub shape: String,
    pub metrics: FollowMetrics,
    pub ending: Ending,
    pub report_l2_mm: f64,
}

/// One row of the real-frame world's contour table: the shape followed by
/// a model trained on real frames, every tap answered by held-out real
/// frames, with how near their labels were to the poses reached.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayShapeRow {
    pub shape: String,
    pub metrics: FollowMetrics,
    pub ending: Ending,
    pub report_l2_mm: f64,
    /// Frames in the bank (the held-out part).
    pub bank_frames: usize,
    /// Scaled label distance of the answered frames: mean, p95, max.
    pub label_distance_mean: f64,
    pub label_distance_p95: f64,
    pub label_distance_max: f64,
}

/// Everything `reproduce` measured.
#[derive(Debug, Clone, Serialize)]
pub struct ReproduceResults {
    pub networks: Vec<NetRow>,
    /// The same networks trained and validated on real frames (`--real`).
    pub real_networks: Vec<NetRow>,
    /// The PDenNN and its backprop twin trained on the simulated twin of
    /// the real set and validated on the same held-out real frames
    /// (`--real`): the simulator judged by real data.
    pub sim_to_real: Vec<NetRow>,
    /// The simulator calibrated with few real taps (`--real`): the PDenNN
    /// trained on the calibrated twin, per number of taps and split.
    pub calibration: Vec<CalibrationRow>,
    /// The PDenNN trained on real frames following the four shapes in the
    /// simulator calibrated with 100 of its training taps (`--real`).
    pub real_model_shapes: Vec<ShapeRow>,
    /// The calibrated sensor folder the simulated world is (`--sensor`).
    pub calibrated_sensor: Option<String>,
    pub shapes: Vec<ShapeRow>,
    /// The four shapes in the real-frame world (`--real`).
    pub real_shapes: Vec<ReplayShapeRow>,
    /// Surface following in 3D (`--3d`); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_3d: Option<crate::document3d::Surface3dSection>,
    /// The same with the image model `conv-dennn` (`--real --image-model`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub real_image_shapes: Vec<ReplayShapeRow>,
    pub seconds: f64,
    pub seed: u64,
    pub tactrace_version: String,
}

/// File-name form of a network name ("MLP (backprop)" -> "mlpbackprop").
pub fn slug(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_lowercase()
}
