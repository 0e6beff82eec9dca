//! Frame -> (r, theta): pin extraction against the undeformed frame, then
//! the pose model (report ch. 4: the displacement vector, then the network).
use crate::error::{Result, ServoError};
use serde::Serialize;
use tactrace_learn::PoseModel;
use tactrace_sensor::{Frame, LabelConvention};
use tactrace_vision::PinExtractor;

/// Pin extraction and the pose model, with the contact rule.
pub struct Perception {
    extractor: PinExtractor,
    model: PoseModel,
    /// Below this mean pin displacement (px) a tap counts as no contact.
    contact_threshold_px: f64,
    /// The model predicts in this collection's labels; the percept is in
    /// the controller's frame (`None`: the model's are the controller's).
    labels: Option<LabelConvention>,
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

    /// The model predicts in the labels of a real collection whose
    /// convention is `labels`: its predictions are mapped into the
    /// controller's frame ([`LabelConvention::to_pose`]).
    pub fn with_label_convention(self, labels: LabelConvention) -> Self {
        Self {
            labels: Some(labels),
            ..self
        }
    }

    /// The reference pins (px) the displacement vectors are ordered by.
    pub fn reference_pins(&self) -> &[[f64; 2]] {
        self.extractor.tracker.reference()
    }

    /// The displacement vector of one frame (x of every pin, then y, px,
    /// in the reference frame's pin order), as the model sees it.
    pub fn displacement(&self, frame: &Frame) -> Result<Vec<f32>> {
        let tracked = self.extractor.extract(frame)?;
        Ok(tracked.displacement(self.extractor.tracker.reference()))
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
        let (r, theta) = LabelConvention::edge_pose_of(self.labels.as_ref(), r, theta);
        Ok(Percept {
            r_mm: r,
            theta_deg: theta,
            mean_displacement_px: mean,
            contact: mean >= self.contact_threshold_px,
            missing_pins: tracked.missing,
        })
    }
}
