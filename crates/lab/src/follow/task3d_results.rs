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
use super::task3d::Surface3dConfig;
use crate::error::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use tactrace_arm::Pose;
use tactrace_control::Task;
use tactrace_report::plot::{chart, chart_3d, Axes, Chart3d, Series, Style};
use tactrace_report::replay_3d::{replay_3d_html, Replay3dPage, Replay3dStep};
use tactrace_report::ReportError;
use tactrace_servo::{Ending, LoopSummary, Step3d};
use tactrace_shape3d::{normal_error_deg, surface_point, true_label, Surface, Vec3};
use tactrace_store::row_file::RowFile;
use tactrace_store::write_atomic;

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

#[derive(Serialize)]
struct MetricsDocument<'a> {
    #[serde(flatten)]
    metrics: &'a Surface3dMetrics,
    ending: Ending,
    succeeded: bool,
    message: &'a str,
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

/// A trajectory's commanded pose columns (every 3D run's).
pub(super) const POSE_COLUMNS: [&str; 6] = ["x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"];

/// A trajectory's last columns: the pose the arm reached (every 3D run's).
pub(super) const REACHED_COLUMNS: [&str; 6] = [
    "x_reached_mm",
    "y_reached_mm",
    "z_reached_mm",
    "rx_reached_deg",
    "ry_reached_deg",
    "rz_reached_deg",
];

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

/// A pose's six cells (mm, deg) for a trajectory row.
pub(super) fn pose_cells(p: Pose) -> impl Iterator<Item = String> {
    [p.x, p.y, p.z, p.rx, p.ry, p.rz]
        .into_iter()
        .map(|v| format!("{v:.4}"))
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
    let doc = MetricsDocument {
        metrics: &metrics,
        ending: summary.ending,
        succeeded: summary.ending.succeeded(),
        message: &summary.message,
    };
    let json = serde_json::to_string_pretty(&doc).expect("metrics serialise");
    write_atomic(&dir.join("metrics.json"), json.as_bytes())?;
    let wire = wire_mesh(object, steps);
    let path: Vec<[f64; 3]> = reached.iter().map(|p| [p.x, p.y, p.z]).collect();
    if !steps.is_empty() {
        let title = format!("surface_3d over the {name}");
        let paths = [("sensor tip (dome pole)", path)];
        chart_3d(
            &dir.join("trajectory_3d"),
            &Chart3d {
                title: &title,
                wire: &wire,
                paths: &paths,
            },
        )
        .map_err(ReportError::from)?;
        error_figure(dir, name, &truths)?;
    }
    let errors = truths
        .iter()
        .map(|t| (t.depth_error_mm, t.normal_error_deg));
    let title = format!("surface_3d over the {name}: {}", summary.message);
    write_replay_page(dir, &title, &wire, steps, errors)?;
    Ok(metrics)
}

/// `replay.html` of a 3D run: every step's pose (position and the sensor's
/// axis) and label, beside its true depth error (mm) and normal error
/// (deg) from `errors`, over the object's wire mesh.
pub(super) fn write_replay_page(
    dir: &Path,
    title: &str,
    wire: &[Vec<[f64; 3]>],
    steps: &[Step3d],
    errors: impl Iterator<Item = (f64, f64)>,
) -> Result<()> {
    let page_steps: Vec<Replay3dStep> = steps
        .iter()
        .zip(errors)
        .map(|(s, (depth_error_mm, normal_error_deg))| {
            let axis = s.pose.to_isometry().rotation * Vec3::z();
            Replay3dStep {
                pose: [s.pose.x, s.pose.y, s.pose.z, axis.x, axis.y, axis.z],
                label: s.label,
                depth_error_mm,
                normal_error_deg,
            }
        })
        .collect();
    let html = replay_3d_html(&Replay3dPage {
        title,
        wire,
        steps: &page_steps,
    });
    write_atomic(&dir.join("replay.html"), html.as_bytes())?;
    Ok(())
}

fn score(
    name: &str,
    cfg: &Surface3dConfig,
    steps: &[Step3d],
    (truths, reached): (&[Truth], &[Pose]),
) -> Surface3dMetrics {
    let settle = cfg.settle_steps.min(truths.len().saturating_sub(1));
    let heading_deg = cfg.controller.heading_deg.unwrap_or(cfg.path.heading_deg);
    let headings: Vec<f64> = reached[settle.min(reached.len())..]
        .iter()
        .map(|p| tactrace_control::heading_error_deg(*p, heading_deg).abs())
        .collect();
    let nh = headings.len().max(1) as f64;
    let scored = &truths[settle..];
    let n = scored.len().max(1) as f64;
    let mean = |f: &dyn Fn(&Truth) -> f64| scored.iter().map(f).sum::<f64>() / n;
    let max = |f: &dyn Fn(&Truth) -> f64| scored.iter().map(f).fold(0.0, f64::max);
    let path_length_mm: f64 = truths
        .windows(2)
        .map(|w| (w[1].surface - w[0].surface).norm())
        .sum();
    let planned = cfg.path.length_mm;
    let mut mean_abs_error = BTreeMap::new();
    let sensed = Task::Surface3d.sensed();
    for k in (0..6).filter(|k| sensed[*k]) {
        let errs: Vec<f64> = steps[settle.min(steps.len())..]
            .iter()
            .zip(scored)
            .filter_map(|(s, t)| t.label.map(|l| (s.label[k] - l[k]).abs()))
            .collect();
        let m = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
        mean_abs_error.insert(tactrace_control::COMPONENTS[k], m);
    }
    Surface3dMetrics {
        task: "surface_3d",
        object: name.to_string(),
        steps: steps.len(),
        settle_steps: settle,
        mean_distance_mm: mean(&|t| t.depth_error_mm.abs()),
        max_distance_mm: max(&|t| t.depth_error_mm.abs()),
        mean_normal_error_deg: mean(&|t| t.normal_error_deg),
        max_normal_error_deg: max(&|t| t.normal_error_deg),
        coverage: (path_length_mm / planned).min(1.0),
        closed: false,
        path_length_mm,
        planned_length_mm: planned,
        mean_abs_error,
        heading_deg,
        mean_heading_error_deg: headings.iter().sum::<f64>() / nh,
        max_heading_error_deg: headings.iter().copied().fold(0.0, f64::max),
    }
}

/// Lines of the surface every 5 mm over the path's box widened by 20 mm.
pub(super) fn wire_mesh(object: &Surface, steps: &[Step3d]) -> Vec<Vec<[f64; 3]>> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for s in steps {
        for (k, v) in [s.pose.x, s.pose.y].into_iter().enumerate() {
            lo[k] = lo[k].min(v - 20.0);
            hi[k] = hi[k].max(v + 20.0);
        }
    }
    if !(lo[0].is_finite() && hi[0].is_finite()) {
        return Vec::new();
    }
    let ticks = |k: usize| {
        let n = ((hi[k] - lo[k]) / 5.0).ceil() as usize;
        (0..=n).map(move |i| lo[k] + i as f64 * 5.0)
    };
    let at = |x: f64, y: f64| surface_point(object.as_ref(), x, y).map(|q| [q.x, q.y, q.z]);
    let mut lines: Vec<Vec<[f64; 3]>> = Vec::new();
    for x in ticks(0) {
        lines.push(ticks(1).filter_map(|y| at(x, y)).collect());
    }
    for y in ticks(1) {
        lines.push(ticks(0).filter_map(|x| at(x, y)).collect());
    }
    lines.retain(|l| l.len() > 1);
    lines
}

/// The true depth error (mm) and normal error (deg) at every step.
fn error_figure(dir: &Path, name: &str, truths: &[Truth]) -> Result<()> {
    let series = |label: &str, f: &dyn Fn(&Truth) -> f64| Series {
        name: label.into(),
        points: truths
            .iter()
            .enumerate()
            .map(|(i, t)| (i as f64, f(t)))
            .collect(),
        style: Style::Line,
    };
    let axes = Axes::new(
        &format!("surface_3d over the {name}: true errors"),
        "step",
        "mm / deg",
    );
    chart(
        &dir.join("errors"),
        &axes,
        &[
            series("depth error (mm)", &|t| t.depth_error_mm),
            series("normal error (deg)", &|t| t.normal_error_deg),
        ],
    )
    .map_err(ReportError::from)?;
    Ok(())
}
