//! The real-frame world's sensor: at each capture it takes the tip's true
//! pose against the contour, turns it into the labels of a real labelled
//! collection ([`LabelConvention`]) and answers with the saved frame whose
//! labels are nearest.
//!
//! Nearness is the scaled label distance
//!
//! d = sqrt(((r - r_i) / s_r)^2 + ((theta - theta_i) / s_theta)^2
//!          + ((dz - dz_i) / s_dz)^2)
//!
//! with the scales s the labels' spreads (standard deviations over the
//! bank; [`FrameBank::new`]); the depth term only when the bank has depth
//! labels. d = 1 is a miss by one spread in one label. Every answer is kept
//! ([`NearestFrameSensor::answers`]) so a run can say how far its frames
//! were from the poses it reached.
//!
//! Like the replay sensor, this reads frame files (at capture time).
use crate::{read_frame, EdgeLabels, Frame, LabelConvention, PoseSource, SensorError};
use crate::{TactileSensor, ToolEdgePose};
use std::path::PathBuf;
use tactrace_geometry::{Contour, Vec2};

/// One saved real frame and its labels.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledFrame {
    pub path: PathBuf,
    pub labels: EdgeLabels,
}

/// The scales of the label distance (label units per unit of distance).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LabelScales {
    pub r_mm: f64,
    pub theta_deg: f64,
    /// `None`: depth does not count (a bank without depth labels).
    pub dz_mm: Option<f64>,
}

impl LabelScales {
    /// The scaled distance between two label sets.
    pub fn distance(&self, a: &EdgeLabels, b: &EdgeLabels) -> f64 {
        let dr = (a.r_mm - b.r_mm) / self.r_mm;
        let dt = (a.theta_deg - b.theta_deg) / self.theta_deg;
        let dz = self.dz_mm.map_or(0.0, |s| (a.dz_mm - b.dz_mm) / s);
        (dr * dr + dt * dt + dz * dz).sqrt()
    }
}

/// The frames a world can answer with, and the metric that picks one.
#[derive(Debug, Clone)]
pub struct FrameBank {
    frames: Vec<LabelledFrame>,
    scales: LabelScales,
}

impl FrameBank {
    /// A bank of `frames`, scaled by the spread of their labels (the depth
    /// term when `with_depth`). Refused when empty or when a label does not
    /// vary (no scale to measure it by).
    pub fn new(frames: Vec<LabelledFrame>, with_depth: bool) -> Result<Self, SensorError> {
        let spread = |f: &dyn Fn(&EdgeLabels) -> f64| {
            let n = frames.len() as f64;
            let mean = frames.iter().map(|x| f(&x.labels)).sum::<f64>() / n;
            let var = frames
                .iter()
                .map(|x| (f(&x.labels) - mean).powi(2))
                .sum::<f64>()
                / n;
            var.sqrt()
        };
        if frames.is_empty() {
            return Err(SensorError::Bank("no labelled frames".into()));
        }
        let scales = LabelScales {
            r_mm: spread(&|l| l.r_mm),
            theta_deg: spread(&|l| l.theta_deg),
            dz_mm: with_depth.then(|| spread(&|l| l.dz_mm)),
        };
        let usable = |s: f64| s.is_finite() && s > 0.0;
        if !(usable(scales.r_mm) && usable(scales.theta_deg) && scales.dz_mm.is_none_or(usable)) {
            let depth = scales
                .dz_mm
                .map_or(String::new(), |d| format!(", depth {d:.3} mm"));
            return Err(SensorError::Bank(format!(
                "the labels of its {} frames do not vary (spreads r {:.3} mm, theta {:.3} deg{depth}): \
                 nothing to choose between",
                frames.len(),
                scales.r_mm,
                scales.theta_deg,
            )));
        }
        Ok(Self { frames, scales })
    }

    /// The frames.
    pub fn frames(&self) -> &[LabelledFrame] {
        &self.frames
    }

    /// The metric's scales.
    pub fn scales(&self) -> LabelScales {
        self.scales
    }

    /// The index of the frame nearest `labels`, and its distance.
    pub fn nearest(&self, labels: &EdgeLabels) -> (usize, f64) {
        let mut best = (0, f64::INFINITY);
        for (i, f) in self.frames.iter().enumerate() {
            let d = self.scales.distance(labels, &f.labels);
            if d < best.1 {
                best = (i, d);
            }
        }
        best
    }
}

/// One capture: where the tip was, what the bank gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Answer {
    /// The labels of the tip's true pose.
    pub wanted: EdgeLabels,
    /// The index (in the bank) of the frame answered.
    pub frame: usize,
    /// The scaled label distance between the two.
    pub distance: f64,
}

/// A sensor whose frames are the real frames nearest the tip's true pose.
pub struct NearestFrameSensor {
    bank: FrameBank,
    convention: LabelConvention,
    shape: Contour,
    pose_source: PoseSource,
    answers: Vec<Answer>,
}

impl NearestFrameSensor {
    /// `pose_source` returns the PHYSICAL tip pose (from the simulated arm),
    /// `shape` the object's contour, `convention` how its edge pose maps to
    /// the bank's labels.
    pub fn new(
        bank: FrameBank,
        convention: LabelConvention,
        shape: Contour,
        pose_source: PoseSource,
    ) -> Self {
        Self {
            bank,
            convention,
            shape,
            pose_source,
            answers: Vec::new(),
        }
    }

    /// Every capture so far, in order.
    pub fn answers(&self) -> &[Answer] {
        &self.answers
    }

    /// The bank answered from.
    pub fn bank(&self) -> &FrameBank {
        &self.bank
    }
}

/// The tool's pose against the nearest edge of `shape` for the tip at
/// `(x, y)` mm with yaw `rz_deg` and height `z_mm` above the top face.
pub fn edge_pose(shape: &Contour, (x, y, z_mm): (f64, f64, f64), rz_deg: f64) -> ToolEdgePose {
    let hit = shape.nearest(Vec2::new(x, y));
    let normal_yaw = hit.normal.y.atan2(hit.normal.x).to_degrees();
    ToolEdgePose {
        r_mm: hit.signed_distance,
        theta_deg: crate::wrap_deg(rz_deg - normal_yaw),
        depth_mm: -z_mm,
    }
}

impl TactileSensor for NearestFrameSensor {
    /// Reads the tip pose, finds the nearest labelled frame and reads it.
    fn capture(&mut self) -> Result<Frame, SensorError> {
        let tip = (self.pose_source)();
        let pose = edge_pose(&self.shape, (tip.x, tip.y, tip.z), tip.rz);
        let wanted = self.convention.to_labels(pose);
        let (frame, distance) = self.bank.nearest(&wanted);
        self.answers.push(Answer {
            wanted,
            frame,
            distance,
        });
        read_frame(&self.bank.frames[frame].path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Calibration, LabelConvention};
    use tactrace_geometry::Pose;

    /// A 100 mm square centred on the origin.
    fn square() -> Contour {
        let v = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)];
        Contour::new(v.iter().map(|&(x, y)| Vec2::new(x, y)).collect()).unwrap()
    }

    fn labels(r: f64, t: f64, z: f64) -> EdgeLabels {
        EdgeLabels {
            r_mm: r,
            theta_deg: t,
            dz_mm: z,
        }
    }

    /// Frames whose single grey level names them, with the labels given.
    fn bank_on_disk(dir: &std::path::Path, labels: &[EdgeLabels]) -> Vec<LabelledFrame> {
        labels
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let path = dir.join(format!("f{i}.png"));
                image::GrayImage::from_pixel(4, 4, image::Luma([10 * i as u8 + 5]))
                    .save(&path)
                    .unwrap();
                LabelledFrame { path, labels: *l }
            })
            .collect()
    }

    #[test]
    fn the_edge_pose_is_measured_from_the_outward_normal() {
        let p = edge_pose(&square(), (52.0, 10.0, -6.0), 30.0);
        assert!((p.r_mm - 2.0).abs() < 1e-9 && (p.theta_deg - 30.0).abs() < 1e-9);
        assert!((p.depth_mm - 6.0).abs() < 1e-9);
        let top = edge_pose(&square(), (0.0, 49.0, -5.0), 80.0);
        assert!((top.r_mm + 1.0).abs() < 1e-9 && (top.theta_deg + 10.0).abs() < 1e-9);
    }

    #[test]
    fn the_metric_scales_each_label_by_its_spread() {
        let s = LabelScales {
            r_mm: 2.0,
            theta_deg: 20.0,
            dz_mm: None,
        };
        let d = s.distance(&labels(0.0, 0.0, 0.0), &labels(2.0, 20.0, 5.0));
        assert!((d - 2f64.sqrt()).abs() < 1e-12, "{d}");
        let with = LabelScales {
            dz_mm: Some(0.5),
            ..s
        };
        let d = with.distance(&labels(0.0, 0.0, 0.0), &labels(0.0, 0.0, 1.0));
        assert!((d - 2.0).abs() < 1e-12, "{d}");
    }

    #[test]
    fn a_bank_without_frames_or_spread_is_refused() {
        assert!(FrameBank::new(Vec::new(), false).is_err());
        let same = vec![
            LabelledFrame {
                path: "a".into(),
                labels: labels(1.0, 2.0, 0.0),
            };
            3
        ];
        let err = FrameBank::new(same, false).unwrap_err().to_string();
        assert!(err.contains("do not vary"), "{err}");
    }

    /// The tip over the square's right edge at r = 0.9 mm (controller
    /// frame), label r = -(0.9 + edge offset + pivot, eq. L3): answered by the frame
    /// labelled nearest, and the answer recorded with its distance.
    #[test]
    fn each_capture_answers_the_frame_nearest_the_true_pose() {
        let dir = tempfile::tempdir().unwrap();
        let cal = Calibration::default();
        let conv = LabelConvention::centred(cal.clone());
        let set = [
            labels(-5.0, 0.0, 0.0),
            labels(-3.2, 1.0, 0.0),
            labels(-3.2, 30.0, 0.0),
            labels(2.0, 0.0, 0.0),
        ];
        let bank = FrameBank::new(bank_on_disk(dir.path(), &set), false).unwrap();
        let depth = cal.tap_depth_mm;
        let tip = Pose::planar(50.9, 5.0, -depth, 0.0);
        let mut sensor = NearestFrameSensor::new(bank, conv, square(), Box::new(move || tip));
        let frame = sensor.capture().unwrap();
        assert_eq!(frame.get_pixel(0, 0).0[0], 15, "frame 1 answered");
        let a = sensor.answers()[0];
        assert_eq!(a.frame, 1);
        let pivot = cal.pivot_offset(cal.angle_offset_deg)[1];
        assert!((a.wanted.r_mm + 0.9 + cal.edge_offset_mm + pivot).abs() < 1e-9);
        assert!(a.wanted.theta_deg.abs() < 1e-9 && a.wanted.dz_mm.abs() < 1e-9);
        let s = sensor.bank().scales();
        let expected = s.distance(&a.wanted, &set[1]);
        assert!((a.distance - expected).abs() < 1e-12 && a.distance > 0.0);
    }
}
