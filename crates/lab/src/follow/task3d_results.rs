//! What a surface run writes and how it is scored against the object
//! (which the loop never sees): `trajectory.csv` row by row with the true
//! depth and normal error beside the prediction, then `metrics.json`, the
//! 3D figure (`trajectory_3d.svg/.png`), the error curves
//! (`errors.svg/.png`) and `replay.html` (a view the mouse turns).
//!
//! Metrics, over the steps after `settle_steps`, at the poses the arm
//! reached (its repeatability noise included; the commanded ones are in
//! `trajectory.csv` beside them):
//! - `mean_distance_mm`, `max_distance_mm`: |true depth - reference
//!   depth|, the true depth being the pole's distance below the surface
//!   (minus its signed distance);
//! - `mean_normal_error_deg`, `max_normal_error_deg`: the angle between
//!   the sensor's axis and the surface normal at the point nearest the pole;
//! - `coverage`: the path's length over the surface (its nearest surface
//!   points, step to step, all steps) over the planned length, at most 1;
//! - `closed`: false (a path across a surface has no loop to close);
//! - `mean_abs_error`: the model's error on each sensed component against
//!   the true label (the pose in the feature frame at the nearest point);
//! - `heading_deg`, `mean_heading_error_deg`, `max_heading_error_deg`: the
//!   direction of travel held (the controller's `heading_deg`, else the
//!   path's start heading) and the angle, in the sensor's plane, from the
//!   sensor's y axis (its tangential step) to it
//!   (`tactrace_control::heading_error_deg`).
use super::recorder3d::StepRows;
use super::results3d::{
    mean_abs_errors, pose_cells, wire_mesh, write_chart_3d, write_error_curves, write_metrics,
    write_replay_page, Scored, POSE_COLUMNS, REACHED_COLUMNS,
};
use super::task3d::Surface3dConfig;
use crate::error::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use tactrace_arm::Pose;
use tactrace_control::Task;
use tactrace_servo::{LoopSummary, Step3d};
use tactrace_shape3d::{normal_error_deg, true_label, Surface, Vec3};
use tactrace_store::row_file::RowFile;

/// A surface run's scores (see the module header).
#[derive(Debug, Clone, Serialize)]
pub struct Surface3dMetrics {
    pub task: &'static str,
    pub object: String,
    pub steps: usize,
    pub settle_steps: usize,
    pub mean_distance_mm: f64,
    pub max_distance_mm: f64,
    pub mean_normal_error_deg: f64,
    pub max_normal_error_deg: f64,
    pub coverage: f64,
    pub closed: bool,
    pub path_length_mm: f64,
    pub planned_length_mm: f64,
    /// The model's mean absolute error per sensed component (mm, deg).
    pub mean_abs_error: BTreeMap<&'static str, f64>,
    /// The direction of travel held or started in, deg from +x.
    pub heading_deg: f64,
    /// The heading error's mean and max magnitude, deg.
    pub mean_heading_error_deg: f64,
    pub max_heading_error_deg: f64,
}

/// The truth at one reached pose.
struct Truth {
    depth_error_mm: f64,
    normal_error_deg: f64,
    label: Option<[f64; 6]>,
    surface: Vec3,
}

fn truth(object: &Surface, pose: Pose, depth_mm: f64) -> Truth {
    let p = Vec3::new(pose.x, pose.y, pose.z);
    Truth {
        depth_error_mm: -object.signed_distance(p) - depth_mm,
        normal_error_deg: normal_error_deg(object.as_ref(), pose),
        label: true_label(object.as_ref(), pose),
        surface: object.closest_point(p),
    }
}

/// `trajectory.csv` of a surface run, a whole row flushed per step.
pub struct TruthCsv {
    rows: RowFile<std::fs::File>,
    object: Surface,
    depth_mm: f64,
}

/// A surface trajectory's columns between the pose and the reached pose.
const SURFACE_COLUMNS: [&str; 7] = [
    "z_pred_mm",
    "rx_pred_deg",
    "ry_pred_deg",
    "mean_displacement_px",
    "contact",
    "depth_error_mm",
    "normal_error_deg",
];

impl TruthCsv {
    /// `dir/trajectory.csv` with its header.
    pub fn create(dir: &Path, object: Surface, depth_mm: f64) -> Result<Self> {
        let mut rows = RowFile::create(&dir.join("trajectory.csv"))?;
        let header = ["step"]
            .iter()
            .chain(&POSE_COLUMNS)
            .chain(&SURFACE_COLUMNS)
            .chain(&REACHED_COLUMNS);
        rows.write_row(header.copied())?;
        Ok(Self {
            rows,
            object,
            depth_mm,
        })
    }
}

impl StepRows for TruthCsv {
    /// One step's row: the commanded pose and prediction, then the truth
    /// at `reached` (the pose the arm reached) and that pose.
    fn write(&mut self, s: &Step3d, reached: Pose) -> tactrace_store::Result<()> {
        let t = truth(&self.object, reached, self.depth_mm);
        let p = s.pose;
        let nums = [
            p.x, p.y, p.z, p.rx, p.ry, p.rz, s.label[2], s.label[3], s.label[4],
        ];
        let mut row = vec![s.step.to_string()];
        row.extend(nums.iter().map(|v| format!("{v:.4}")));
        row.push(format!("{:.4}", s.mean_displacement_px));
        row.push(s.contact.to_string());
        row.push(format!("{:.4}", t.depth_error_mm));
        row.push(format!("{:.4}", t.normal_error_deg));
        row.extend(pose_cells(reached));
        self.rows.write_row(row)
    }
}

/// Score the run at the poses the arm reached (`reached`, one per step)
/// and write `metrics.json`, the figures and `replay.html` into `dir`;
/// the reference pins and each tap's field are kept for later pages
/// (unused by the 3D page).
pub fn write_surface_results(
    dir: &Path,
    (name, object): (&str, &Surface),
    cfg: &Surface3dConfig,
    (steps, reached): (&[Step3d], &[Pose]),
    summary: &LoopSummary,
    _fields: (&[[f64; 2]], &[Vec<f32>]),
) -> Result<Surface3dMetrics> {
    let depth = cfg.controller.reference[2];
    let truths: Vec<Truth> = reached.iter().map(|p| truth(object, *p, depth)).collect();
    let metrics = score(name, cfg, steps, (&truths, reached));
    write_metrics(dir, &metrics, summary)?;
    let wire = wire_mesh(object, steps);
    let path: Vec<[f64; 3]> = reached.iter().map(|p| [p.x, p.y, p.z]).collect();
    if !steps.is_empty() {
        let title = format!("surface_3d over the {name}");
        write_chart_3d(dir, &title, &wire, &[("sensor tip (dome pole)", path)])?;
        write_error_curves(
            dir,
            &format!("surface_3d over the {name}: true errors"),
            &truths,
            &[
                ("depth error (mm)", &|t: &Truth| t.depth_error_mm),
                ("normal error (deg)", &|t: &Truth| t.normal_error_deg),
            ],
        )?;
    }
    let errors = truths
        .iter()
        .map(|t| (t.depth_error_mm, t.normal_error_deg));
    let title = format!("surface_3d over the {name}: {}", summary.message);
    write_replay_page(dir, &title, &wire, steps, errors)?;
    Ok(metrics)
}

fn score(
    name: &str,
    cfg: &Surface3dConfig,
    steps: &[Step3d],
    (truths, reached): (&[Truth], &[Pose]),
) -> Surface3dMetrics {
    let settle = cfg.run.settle_steps.min(truths.len().saturating_sub(1));
    let heading_deg = cfg.controller.heading_deg.unwrap_or(cfg.path.heading_deg);
    let headings: Vec<f64> = reached[settle.min(reached.len())..]
        .iter()
        .map(|p| tactrace_control::heading_error_deg(*p, heading_deg).abs())
        .collect();
    let headings = Scored(&headings);
    let scored = Scored(&truths[settle..]);
    let path_length_mm: f64 = truths
        .windows(2)
        .map(|w| (w[1].surface - w[0].surface).norm())
        .sum();
    let planned = cfg.path.length_mm;
    let steps_scored = &steps[settle.min(steps.len())..];
    let mean_abs_error = mean_abs_errors(Task::Surface3d.sensed(), |k| {
        steps_scored
            .iter()
            .zip(scored.0)
            .filter_map(|(s, t)| t.label.map(|l| (s.label[k] - l[k]).abs()))
            .collect()
    });
    Surface3dMetrics {
        task: "surface_3d",
        object: name.to_string(),
        steps: steps.len(),
        settle_steps: settle,
        mean_distance_mm: scored.mean(|t| t.depth_error_mm.abs()),
        max_distance_mm: scored.max(|t| t.depth_error_mm.abs()),
        mean_normal_error_deg: scored.mean(|t| t.normal_error_deg),
        max_normal_error_deg: scored.max(|t| t.normal_error_deg),
        coverage: (path_length_mm / planned).min(1.0),
        closed: false,
        path_length_mm,
        planned_length_mm: planned,
        mean_abs_error,
        heading_deg,
        mean_heading_error_deg: headings.mean(|h| *h),
        max_heading_error_deg: headings.max(|h| *h),
    }
}
