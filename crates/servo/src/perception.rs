//! Frame -> (r, theta): pin extraction against the undeformed frame, then
//! the pose model (report ch. 4: the displacement vector, then the network).
//! The pins are read by the sensor's own reader ([`PinReader`]: its
//! preprocessing, its detector, the blob detector or the small-pin one,
//! and its rest pins), the one `import` reads the same frames with.
//! An image model reads the frame's pixels instead, made as its training
//! frames were ([`ImageInput`]: the dataset's preprocessing, then
//! area-averaged to its input size); the pins still say whether the tap
//! made contact, and a pins-and-pixels image model reads the frame's
//! displacement vector beside its pixels.
//!
//! A follow run that keeps every tap's displacement vector asks for it
//! ([`Perception::displacement`]) before the loop perceives the same
//! frame: the pins of the frame last asked for are kept, so that frame is
//! extracted once, not twice (the extraction is most of a step's cost).
use crate::error::{Result, ServoError};
use crate::image_input::ImageInput;
use serde::Serialize;
use std::sync::{Mutex, PoisonError};
use tactrace_learn::{ImageModel, PoseModel};
use tactrace_sensor::{Frame, LabelConvention};
use tactrace_vision::{PinReader, Tracked};

/// What reads the pose from a tap: the pins' displacement vector, or the
/// frame's pixels.
enum Reader {
    Pins(PoseModel),
    Image(ImageModel, ImageInput),
}

/// Pin extraction and the pose model, with the contact rule.
pub struct Perception {
    reader: PinReader,
    model: Reader,
    /// Below this mean pin displacement (px) a tap counts as no contact.
    contact_threshold_px: f64,
    /// The model predicts in this collection's labels; the percept is in
    /// the controller's frame (`None`: the model's are the controller's).
    labels: Option<LabelConvention>,
    /// The frame [`Perception::displacement`] last extracted, with its
    /// pins, until [`Perception::perceive`] takes them.
    last: Mutex<Option<(Frame, Tracked)>>,
    /// Frames extracted so far (tests count them).
    #[cfg(test)]
    extractions: std::sync::atomic::AtomicUsize,
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
    /// Pair `reader` (ordered by the rest pins) with `model`; refuses a
    /// model whose input size is not twice the pin count.
    pub fn new(reader: PinReader, model: PoseModel, contact_threshold_px: f64) -> Result<Self> {
        let got = 2 * reader.tracker().reference().len();
        if model.input_dim() != got {
            return Err(ServoError::InputSize {
                expected: model.input_dim(),
                got,
            });
        }
        Ok(Self {
            reader,
            model: Reader::Pins(model),
            contact_threshold_px,
            labels: None,
            last: Mutex::new(None),
            #[cfg(test)]
            extractions: Default::default(),
        })
    }

    /// Pair `reader` (for the contact rule and the recorded pins) with
    /// the image model `model`, which reads each frame's pixels made by
    /// `input`; refuses an input of another size than the model takes.
    pub fn with_image_model(
        reader: PinReader,
        model: ImageModel,
        input: ImageInput,
        contact_threshold_px: f64,
    ) -> Result<Self> {
        let (expected, got) = (model.input_size(), input.size());
        if expected != got {
            return Err(ServoError::Config(format!(
                "the image model takes {} x {} px frames, its input is made at {} x {} px",
                expected.0, expected.1, got.0, got.1
            )));
        }
        let pins = 2 * reader.tracker().reference().len();
        if model.pin_inputs() > 0 && model.pin_inputs() != pins {
            return Err(ServoError::InputSize {
                expected: model.pin_inputs(),
                got: pins,
            });
        }
        Ok(Self {
            reader,
            model: Reader::Image(model, input),
            contact_threshold_px,
            labels: None,
            last: Mutex::new(None),
            #[cfg(test)]
            extractions: Default::default(),
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
        self.reader.tracker().reference()
    }

    /// The displacement vector of one frame (x of every pin, then y, px,
    /// in the reference frame's pin order), as the model sees it.
    /// Its pins are kept for a [`Perception::perceive`] of the same frame.
    pub fn displacement(&self, frame: &Frame) -> Result<Vec<f32>> {
        let tracked = self.extract(frame)?;
        let disp = tracked.displacement(self.reader.tracker().reference());
        *self.last.lock().unwrap_or_else(PoisonError::into_inner) = Some((frame.clone(), tracked));
        Ok(disp)
    }

    /// The pins of `frame`: those [`Perception::displacement`] kept when it
    /// was the frame last asked for (equal pixels), else extracted now.
    fn pins(&self, frame: &Frame) -> Result<Tracked> {
        let kept = self
            .last
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        match kept {
            Some((seen, tracked)) if seen == *frame => Ok(tracked),
            _ => self.extract(frame),
        }
    }

    fn extract(&self, frame: &Frame) -> Result<Tracked> {
        #[cfg(test)]
        self.extractions
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(self.reader.read_grey(frame)?)
    }

    /// Extract pins and predict the edge pose from one frame.
    pub fn perceive(&self, frame: &Frame) -> Result<Percept> {
        let tracked = self.pins(frame)?;
        let disp = tracked.displacement(self.reader.tracker().reference());
        let p = disp.len() / 2;
        let mean = (0..p)
            .map(|i| f64::hypot(disp[i] as f64, disp[p + i] as f64))
            .sum::<f64>()
            / p.max(1) as f64;
        let [r, theta] = match &self.model {
            Reader::Pins(model) => model.predict(&disp)?,
            Reader::Image(model, input) => {
                model.predict_with_pins(&input.of_frame(frame)?, &disp)?
            }
        };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{pose_at_edge, RigConfig};
    use std::sync::atomic::Ordering;
    use tactrace_geometry::{builtin_shape, BuiltinShape};
    use tactrace_learn::{Dataset, ModelConfig, ModelKind, Preset};
    use tactrace_sensor::TacTipModel;

    /// A perception of the default simulated sensor (an untrained small
    /// net: only the extraction matters here) and two tapped frames.
    fn perception_and_frames() -> (Perception, [Frame; 2]) {
        let rig = RigConfig::default();
        let sensor = TacTipModel::new(rig.sensor.clone()).expect("sensor");
        let reference = sensor.render(sensor.rest_pins(), None);
        let detector = tactrace_vision::DetectorParams::Blobs(rig.blob)
            .check()
            .expect("blob");
        let extractor = PinReader::from_reference_frame(detector, &reference).expect("pins");
        let disk = builtin_shape(BuiltinShape::Disk);
        let (edge, normal) = disk.at_arc_length(0.0);
        let depth = -rig.tap.nominal_indentation_mm();
        let frames = [(1.0, 10.0), (-2.0, -20.0)].map(|(r, t)| {
            sensor.render(
                &sensor.pins(&disk, pose_at_edge(edge, normal, r, t, depth), None),
                None,
            )
        });
        let dim = 2 * extractor.tracker().reference().len();
        let n = 8;
        let x = (0..n * dim).map(|k| (k % 7) as f32 - 3.0).collect();
        let y = (0..2 * n).map(|k| k as f32).collect();
        let data = Dataset::new(x, y, n, dim, 2).expect("data");
        let mut cfg = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
        cfg.set_epochs(1);
        if let Some(net) = cfg.pose.as_mut() {
            net.hidden = vec![4];
        }
        let (model, _) = PoseModel::fit(&cfg, &data, &mut |_| {}).expect("model");
        (
            Perception::new(extractor, model, 0.5).expect("perception"),
            frames,
        )
    }

    /// A pins-and-pixels image model of 8 x 8 px frames taking `pins`
    /// values a frame (an untrained tiny net: only the wiring matters).
    fn hybrid_image_model(pins: usize) -> ImageModel {
        use tactrace_convnet::{ConvConfig, Frames, InputKind, ModelKind as Kind};
        let n = 8;
        let pixels: Vec<u8> = (0..n * 64).map(|k| (k * 37 % 251) as u8).collect();
        let values: Vec<f32> = (0..n * pins).map(|k| (k % 5) as f32 - 2.0).collect();
        let frames = Frames::new(&pixels, n, 8, 8)
            .and_then(|f| f.with_pins(&values, pins))
            .expect("frames");
        let targets: Vec<f32> = (0..2 * n).map(|k| k as f32).collect();
        let mut cfg = ConvConfig::new(Kind::ConvMlp);
        (cfg.conv, cfg.dense, cfg.epochs, cfg.input) =
            (vec![], vec![4], 1, InputKind::PinsAndPixels);
        let outputs = tactrace_learn::edge_targets();
        ImageModel::fit(&frames, &targets, &outputs, &cfg, 1, None, &mut |_| {})
            .expect("model")
            .0
    }

    /// The follow perception gives a pins-and-pixels image model the
    /// tap's displacement vector beside its pixels, and refuses a model
    /// of another pin count.
    #[test]
    fn a_pins_and_pixels_model_reads_the_taps_pins() {
        let reader = || perception_and_frames().0.reader;
        let [a, b] = perception_and_frames().1;
        let pins = 2 * reader().tracker().reference().len();
        let input = || ImageInput::new(None, (8, 8)).expect("input");
        let model = hybrid_image_model(pins);
        let hybrid = Perception::with_image_model(reader(), model.clone(), input(), 0.5)
            .expect("perception");
        for frame in [&a, &b] {
            let percept = hybrid.perceive(frame).expect("percept");
            let disp = hybrid.displacement(frame).expect("pins");
            let small = input().of_frame(frame).expect("pixels");
            let want = model.predict_with_pins(&small, &disp).expect("pose");
            assert_eq!([percept.r_mm, percept.theta_deg], want);
        }
        let other = hybrid_image_model(pins - 2);
        assert!(matches!(
            Perception::with_image_model(reader(), other, input(), 0.5),
            Err(ServoError::InputSize { .. })
        ));
    }

    /// A follow run's field recorder asks for a frame's displacement, then
    /// the loop perceives it: one extraction, the same percept as without
    /// the recorder; another frame is never answered with the kept pins.
    #[test]
    fn a_frame_recorded_then_perceived_is_extracted_once() {
        let (p, [a, b]) = perception_and_frames();
        let alone = p.perceive(&a).expect("percept");
        assert_eq!(p.extractions.load(Ordering::Relaxed), 1);
        let field = p.displacement(&a).expect("field");
        let again = p.perceive(&a).expect("percept");
        assert_eq!(p.extractions.load(Ordering::Relaxed), 2, "extracted twice");
        assert_eq!(format!("{alone:?}"), format!("{again:?}"));
        assert_eq!(field, p.displacement(&a).expect("field"));
        let other = p.perceive(&b).expect("percept");
        assert_eq!(p.extractions.load(Ordering::Relaxed), 4);
        assert_ne!(other.mean_displacement_px, alone.mean_displacement_px);
        let fresh = perception_and_frames().0.perceive(&b).expect("percept");
        assert_eq!(format!("{other:?}"), format!("{fresh:?}"));
    }
}
