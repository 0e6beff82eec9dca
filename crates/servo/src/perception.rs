//! Frame -> (r, theta): pin extraction against the undeformed frame, then
//! the pose model (report ch. 4: the displacement vector, then the network).
use crate::error::{Result, ServoError};
use serde::Serialize;
use tactrace_geometry::Pose;
use tactrace_learn::PoseModel;
use tactrace_sensor::{Calibration, Frame};
use tactrace_vision::PinExtractor;

/// Pin extraction and the pose model, with the contact rule.
pub struct Perception {
    extractor: PinExtractor,
    model: PoseModel,
    /// Below this mean pin displacement (px) a tap counts as no contact.
    contact_threshold_px: f64,
    /// When the model predicts a sensor's own labels (a calibrated sensor,
    /// real frames), the sensor's label convention: predictions are mapped
    /// to the loop's edge pose by it (eq. L1). `None`: the model predicts
    /// the loop's edge pose (taps collected in the simulated rig).
    labels: Option<Calibration>,
}

/// What one tap told the controller.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Percept {
    pub r_mm: f64,
    pub theta_deg: f64,
    /// Mean pin displacement, px.
    pub mean_displacement_px: f64,
    pub contact: bool,
    pub missing_pins: usize,
}

impl Perception {
    /// Pair `extractor` (ordered against the undeformed frame) with `model`;
    /// refuses a model whose input size is not twice the pin count.
    pub fn new(
        extractor: PinExtractor,
        model: PoseModel,
        contact_threshold_px: f64,
    ) -> Result<Self> {
        let got = 2 * extractor.tracker.reference().len();
        if model.input_dim() != got {
            return Err(ServoError::InputSize {
                expected: model.input_dim(),
                got,
            });
        }
        Ok(Self {
            extractor,
            model,
            contact_threshold_px,
            labels: None,
        })
    }

    /// The same perception for a model that predicts labels in the
    /// convention `labels` (a sensor's `calibration` table): each
    /// prediction is mapped to the loop's edge pose (eq. L1) and given in
    /// the servo frame ([`Self::servo_frame_yaw_deg`]).
    pub fn with_sensor_labels(mut self, labels: Calibration) -> Self {
        self.labels = Some(labels);
        self
    }

    /// The yaw (deg) of the servo frame in the sensor's tool frame: the
    /// frame whose x axis is the edge's outward normal and y its tangent
    /// when the sensor sits at its own label angle zero (eq. L2). Zero for
    /// a model of the simulated rig's taps; for a sensor's own labels,
    /// `angle_offset - object_side 90 deg`, so the loop keeps the sensor
    /// at the angles it was trained on. Percepts are in this frame, and
    /// the controller's moves are turned from it into the tool frame.
    pub fn servo_frame_yaw_deg(&self) -> f64 {
        match &self.labels {
            Some(cal) => cal.loop_pose(0.0, 0.0).theta_deg,
            None => 0.0,
        }
    }

    /// A move computed in the servo frame, in the tool frame (eq. L2).
    pub fn to_tool_frame(&self, delta: Pose) -> Pose {
        let phi = self.servo_frame_yaw_deg();
        if phi == 0.0 {
            return delta;
        }
        let (s, c) = (-phi).to_radians().sin_cos();
        Pose {
            x: c * delta.x - s * delta.y,
            y: s * delta.x + c * delta.y,
            ..delta
        }
    }

    /// The reference pins (px) the displacement vectors are ordered by.
    pub fn reference_pins(&self) -> &[[f64; 2]] {
        self.extractor.tracker.reference()
    }

    /// Extract pins and predict the edge pose from one frame.
    pub fn perceive(&self, frame: &Frame) -> Result<Percept> {
        let tracked = self.extractor.extract(frame)?;
        let disp = tracked.displacement(self.extractor.tracker.reference());
        let p = disp.len() / 2;
        let mean = (0..p)
            .map(|i| f64::hypot(disp[i] as f64, disp[p + i] as f64))
            .sum::<f64>()
            / p.max(1) as f64;
        let [r, theta] = self.model.predict(&disp)?;
        let (r, theta) = match &self.labels {
            Some(cal) => {
                let p = cal.loop_pose(r, theta);
                (p.r_mm, wrap_deg(p.theta_deg - self.servo_frame_yaw_deg()))
            }
            None => (r, theta),
        };
        Ok(Percept {
            r_mm: r,
            theta_deg: theta,
            mean_displacement_px: mean,
            contact: mean >= self.contact_threshold_px,
            missing_pins: tracked.missing,
        })
    }
}

/// `deg` wrapped into (-180, 180].
fn wrap_deg(deg: f64) -> f64 {
    let w = deg.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}
