//! Detection and ordering in one call, with a floor on how many pins must
//! be found: what the sensor pipeline runs on every tap (report ch. 4.1),
//! over frames already preprocessed, with either detector ([`Detector`]:
//! the blob detector or the small-pin one). The passes are
//! [`crate::PinReader`]'s ([`track`]), so both read a frame alike.

use crate::blob::Frame;
use crate::detection::{Detection, Detector};
use crate::error::VisionError;
use crate::params::BlobParams;
use crate::tracker::{PinTracker, Tracked};

/// Default share of reference pins that must be matched in a frame.
pub const DEFAULT_MIN_MATCHED_FRACTION: f64 = 0.9;

/// A detector plus the pin tracker of one sensor.
pub struct PinExtractor {
    /// Frame -> pins.
    pub detector: Detector,
    /// The reference pins and their order.
    pub tracker: PinTracker,
    /// Share of reference pins (0..=1) that must be matched, else `extract` fails.
    pub min_matched_fraction: f64,
}

impl PinExtractor {
    /// The blob detector `params` over an undeformed frame: its detected
    /// blobs, in detection order, define the pins and their count.
    pub fn from_reference_frame(
        reference: &Frame,
        params: BlobParams,
    ) -> Result<Self, VisionError> {
        params.validate()?;
        Self::with_detector(reference, Detector::Blobs(params))
    }

    /// [`PinExtractor::from_reference_frame`] with any checked detector.
    pub fn with_detector(reference: &Frame, detector: Detector) -> Result<Self, VisionError> {
        let pins = detector
            .detect(reference)
            .points
            .iter()
            .map(|k| [k.x, k.y])
            .collect();
        Ok(Self {
            tracker: PinTracker::new(pins)?,
            detector,
            min_matched_fraction: DEFAULT_MIN_MATCHED_FRACTION,
        })
    }

    /// Detects and orders the pins of `frame` (splitting clusters of touching
    /// pins when some are missing); fails when fewer than
    /// `ceil(min_matched_fraction * P)` pins are matched.
    pub fn extract(&self, frame: &Frame) -> Result<Tracked, VisionError> {
        let (tracked, _) = track(&self.detector, &self.tracker, frame);
        check_found(&tracked, tracked.matched_count(), self.min_matched_fraction)?;
        Ok(tracked)
    }
}

/// The pins of `frame` ordered by `tracker`, and the detection they came
/// from (its centres: the blob detector's sizes may be NaN, see
/// [`Detector::detect_centres`]): a first pass over the detected points,
/// then, when pins are missing, a pass splitting the clusters of touching
/// pins (found here for the blob detector).
pub(crate) fn track(
    detector: &Detector,
    tracker: &PinTracker,
    frame: &Frame,
) -> (Tracked, Detection) {
    let mut detection = detector.detect_centres(frame);
    let first = tracker.first_pass(&detection.points);
    let tracked = if first.tracked().missing > 0 {
        detector.add_clusters(frame, &mut detection);
        tracker.split_pass(first, &detection.clusters)
    } else {
        first.into_tracked()
    };
    (tracked, detection)
}

/// Fails when `found` pins of `tracked` fall short of `ceil(fraction * P)`.
pub(crate) fn check_found(
    tracked: &Tracked,
    found: usize,
    fraction: f64,
) -> Result<(), VisionError> {
    if !(0.0..=1.0).contains(&fraction) {
        return Err(VisionError::InvalidFraction { value: fraction });
    }
    let required = (fraction * tracked.pins.len() as f64).ceil() as usize;
    if found < required {
        return Err(VisionError::TooFewPins {
            matched: found,
            total: tracked.pins.len(),
            required,
        });
    }
    Ok(())
}
