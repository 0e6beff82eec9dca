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

impl StartConfig {
    /// Every value a number, the largest start distance positive: named by
    /// its key in the message (`[start] offset_mm = NaN` once read "NaN mm
    /// from the edge").
    pub fn validate(&self) -> Result<()> {
        for (key, value) in [
            ("offset_mm", self.offset_mm),
            ("angle_deg", self.angle_deg),
            ("max_start_distance_mm", self.max_start_distance_mm),
        ] {
            if !value.is_finite() {
                return Err(ServoError::Start(format!(
                    "[start] {key} = {value} is not a number"
                )));
            }
        }
        if self.max_start_distance_mm <= 0.0 {
            return Err(ServoError::Start(format!(
                "[start] max_start_distance_mm = {} must be > 0",
                self.max_start_distance_mm
            )));
        }
        if let Some(arc) = self.arc_mm.filter(|a| !a.is_finite()) {
            return Err(ServoError::Start(format!(
                "[start] arc_mm = {arc} is not a number"
            )));
        }
        Ok(())
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
    cfg.validate()?;
    let within = cfg.offset_mm.abs() <= cfg.max_start_distance_mm;
    if !within {
        return Err(ServoError::Start(format!(
            "the start pose is {:.1} mm from the edge; the sensor cannot feel an edge further than {:.1} mm away",
            cfg.offset_mm.abs(),
            cfg.max_start_distance_mm
        )));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 20: `[start] offset_mm = nan` exited 2 but read "NaN mm from
    /// the edge"; every start value that is not a number names its key.
    #[test]
    fn a_start_value_that_is_not_a_number_names_its_key() {
        let corners = [(0.0, 0.0), (40.0, 0.0), (40.0, 40.0), (0.0, 40.0)];
        let square = Contour::new(corners.iter().map(|&(x, y)| Vec2::new(x, y)).collect()).unwrap();
        for (key, cfg) in [
            (
                "offset_mm",
                StartConfig {
                    offset_mm: f64::NAN,
                    ..StartConfig::default()
                },
            ),
            (
                "angle_deg",
                StartConfig {
                    angle_deg: f64::INFINITY,
                    ..StartConfig::default()
                },
            ),
            (
                "arc_mm",
                StartConfig {
                    arc_mm: Some(f64::NAN),
                    ..StartConfig::default()
                },
            ),
        ] {
            let err = start_pose(&square, &cfg, 2.0).unwrap_err();
            let text = err.to_string();
            assert!(text.contains(&format!("[start] {key}")), "{text}");
            assert!(!text.contains("from the edge"), "{text}");
            assert!(err.is_bad_input(), "{text}");
        }
        assert!(start_pose(&square, &StartConfig::default(), 2.0).is_ok());
    }
}
