//! Detection and ordering in one call, with a floor on how many pins must
//! be found: what the sensor pipeline runs on every tap (report ch. 4.1).

use crate::blob::{detect_blobs, Frame};
use crate::error::VisionError;
use crate::merged::find_clusters;
use crate::params::BlobParams;
use crate::tracker::{PinTracker, Tracked};

/// Default share of reference pins that must be matched in a frame.
pub const DEFAULT_MIN_MATCHED_FRACTION: f64 = 0.9;

/// Blob detector plus pin tracker for one sensor.
pub struct PinExtractor {
    pub params: BlobParams,
    pub tracker: PinTracker,
    /// Share of reference pins (0..=1) that must be matched, else `extract` fails.
    pub min_matched_fraction: f64,
}

impl PinExtractor {
    /// Reference from an undeformed frame: its detected blobs, in detection
    /// order, define the pins and their count.
    pub fn from_reference_frame(
        reference: &Frame,
        params: BlobParams,
    ) -> Result<Self, VisionError> {
        params.validate()?;
        let pins = detect_blobs(reference, &params)
            .iter()
            .map(|k| [k.x, k.y])
            .collect();
        Ok(Self {
            tracker: PinTracker::new(pins)?,
            params,
            min_matched_fraction: DEFAULT_MIN_MATCHED_FRACTION,
        })
    }

    /// Detects and orders the pins of `frame` (splitting clusters of touching
    /// pins when some are missing); fails when fewer than
    /// `ceil(min_matched_fraction * P)` pins are matched.
    pub fn extract(&self, frame: &Frame) -> Result<Tracked, VisionError> {
        let required = self.required_matches()?;
        let keypoints = detect_blobs(frame, &self.params);
        let first = self.tracker.first_pass(&keypoints);
        let tracked = if first.tracked().missing > 0 {
            let clusters = find_clusters(frame, &self.params);
            self.tracker.split_pass(first, &clusters)
        } else {
            first.into_tracked()
        };
        let matched = tracked.matched_count();
        if matched < required {
            return Err(VisionError::TooFewPins {
                matched,
                total: tracked.pins.len(),
                required,
            });
        }
        Ok(tracked)
    }

    fn required_matches(&self) -> Result<usize, VisionError> {
        let f = self.min_matched_fraction;
        if !(0.0..=1.0).contains(&f) {
            return Err(VisionError::InvalidFraction { value: f });
        }
        Ok((f * self.tracker.reference().len() as f64).ceil() as usize)
    }
}
