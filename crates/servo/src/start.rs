//! Where a run starts: the sensor set down above an edge, roughly aligned
//! with it (report ch. 5.2: "2 mm above the surface, roughly aligned with
//! an edge"), as an operator places the arm. The true contour is used here
//! and only here, before the loop starts.
use crate::error::{Result, ServoError};
use serde::{Deserialize, Serialize};
use tactrace_arm::Pose;
use tactrace_geometry::{Contour, Vec2};

/// Where the run starts: on the edge point at `arc_mm`, offset along the
/// outward normal and rotated, at tap height.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StartConfig {
    /// Arc length of the start point along the contour, mm. `None` (the
    /// default): the middle of the flattest 20 mm of the contour, as an
    /// operator would align the sensor with an edge rather than a corner.
    pub arc_mm: Option<f64>,
    pub offset_mm: f64,
    pub angle_deg: f64,
    /// Refuse to start further than this from the edge, mm.
    pub max_start_distance_mm: f64,
}

impl Default for StartConfig {
    fn default() -> Self {
        Self {
            arc_mm: None,
            offset_mm: 0.0,
            angle_deg: 0.0,
            max_start_distance_mm: 6.0,
        }
    }
}

/// The sensor pose (tip, work frame) for edge position `r` and angle `theta`
/// at edge point `edge` with outward normal `normal`; `height` above the top.
pub fn pose_at_edge(edge: Vec2, normal: Vec2, r_mm: f64, theta_deg: f64, height_mm: f64) -> Pose {
    let p = edge + normal * r_mm;
    let yaw = normal.y.atan2(normal.x).to_degrees();
    Pose::planar(p.x, p.y, height_mm, yaw + theta_deg)
}

/// The start pose for `cfg` on `shape`.
pub fn start_pose(shape: &Contour, cfg: &StartConfig, height_mm: f64) -> Result<Pose> {
    let within = cfg.offset_mm.abs() <= cfg.max_start_distance_mm;
    if !within {
        return Err(ServoError::Start(format!(
            "the start pose is {:.1} mm from the edge; the sensor cannot feel an edge further than {:.1} mm away",
            cfg.offset_mm.abs(),
            cfg.max_start_distance_mm
        )));
    }
    if let Some(arc) = cfg.arc_mm {
        if !arc.is_finite() {
            return Err(ServoError::Start(format!(
                "start arc_mm = {arc} is not a number"
            )));
        }
    }
    let arc = cfg.arc_mm.unwrap_or_else(|| flattest_arc_mm(shape, 20.0));
    let (edge, normal) = shape.at_arc_length(arc);
    Ok(pose_at_edge(
        edge,
        normal,
        cfg.offset_mm,
        cfg.angle_deg,
        height_mm,
    ))
}

/// Arc length (mm) of the middle of the stretch of length `window_mm` over
/// which the outward normal turns least: the place to set the sensor down.
pub fn flattest_arc_mm(shape: &Contour, window_mm: f64) -> f64 {
    let n = (shape.perimeter() / 0.5).ceil().clamp(8.0, 20_000.0) as usize;
    let step = shape.perimeter() / n as f64;
    let heading: Vec<f64> = (0..n)
        .map(|i| {
            let (_, normal) = shape.at_arc_length(i as f64 * step);
            normal.y.atan2(normal.x)
        })
        .collect();
    let turn = |i: usize| {
        let d = heading[(i + 1) % n] - heading[i];
        (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    let k = ((window_mm / step).round() as usize).clamp(1, n);
    let total = |start: usize| (0..k).map(|j| turn((start + j) % n).abs()).sum::<f64>();
    let best = (0..n)
        .min_by(|&a, &b| total(a).total_cmp(&total(b)))
        .unwrap_or(0);
    (best as f64 + k as f64 / 2.0) * step % shape.perimeter()
}
