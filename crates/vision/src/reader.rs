//! A sensor's frames read into ordered pins, end to end: the
//! preprocessing stage, the detector, and the tracker against the rest
//! layout, with per-frame counts of how each pin was found. This is what a
//! sensor file describes (preprocessing + detector + rest pins), for any
//! TacTip; [`crate::PinExtractor`] remains the blob-detector path of the
//! 127-pin sensor.

use image::DynamicImage;
use serde::{Deserialize, Serialize};

use crate::blob::Frame;
use crate::detection::{Detection, Detector, DetectorParams};
use crate::error::VisionError;
use crate::extractor::{check_found, track, DEFAULT_MIN_MATCHED_FRACTION};
use crate::preprocess::{PreprocessParams, PreprocessStage};
use crate::tracker::{PinTracker, Tracked};

/// How to see pins in a sensor's frames: what a sensor file holds besides
/// the rest pins.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SightParams {
    /// Camera image -> frame.
    #[serde(default)]
    pub preprocess: PreprocessParams,
    /// Frame -> pins.
    pub detect: DetectorParams,
}

/// Camera images of one size -> detections: the checked
/// [`SightParams`], made by [`SightParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameDetector {
    stage: PreprocessStage,
    detector: Detector,
}

/// How the pins of one frame were found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TrackCounts {
    /// Pins matched to a detected pin of their own.
    pub matched: usize,
    /// Pins matched to a centre split from a cluster of touching pins.
    pub split: usize,
    /// Pins with no detection: placed where the field of their neighbours
    /// puts them.
    pub filled: usize,
}

/// One frame read: the ordered pins and the counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    /// Pins in rest-layout order.
    pub tracked: Tracked,
    /// How they were found.
    pub counts: TrackCounts,
}

/// A [`FrameDetector`] and the tracker of the rest layout.
pub struct PinReader {
    frames: FrameDetector,
    tracker: PinTracker,
    /// Share of the pins (0..=1) that must be found (matched or split),
    /// else [`PinReader::read`] fails.
    pub min_found_fraction: f64,
}

impl SightParams {
    /// Checks the settings for camera images of `width` x `height` px.
    pub fn check(self, width: u32, height: u32) -> Result<FrameDetector, VisionError> {
        let stage = self.preprocess.check()?.stage(width, height)?;
        Ok(FrameDetector {
            stage,
            detector: self.detect.check()?,
        })
    }
}

impl TrackCounts {
    /// True when no pin had to be filled in.
    pub fn fully_tracked(&self) -> bool {
        self.filled == 0
    }

    /// The counts of `tracked` given the points it was ordered from: a
    /// matched pin sits exactly (to 1e-9 px) on a detected point, or else
    /// on a centre split from a cluster.
    pub fn of(tracked: &Tracked, detection: &Detection) -> Self {
        let mut xs: Vec<[f64; 2]> = detection.points.iter().map(|k| [k.x, k.y]).collect();
        xs.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]));
        let on_point = |p: [f64; 2]| {
            let from = xs.partition_point(|q| q[0] < p[0] - 1e-9);
            xs[from..]
                .iter()
                .take_while(|q| q[0] <= p[0] + 1e-9)
                .any(|q| (q[1] - p[1]).abs() <= 1e-9)
        };
        let mut counts = Self::default();
        for (p, &m) in tracked.pins.iter().zip(&tracked.matched) {
            match (m, m && on_point(*p)) {
                (false, _) => counts.filled += 1,
                (true, true) => counts.matched += 1,
                (true, false) => counts.split += 1,
            }
        }
        counts
    }
}

impl FrameDetector {
    /// `detector` on frames taken as they are: no preprocessing step (for
    /// frames of `[width, height]` px, though [`PinReader::read_grey`]
    /// takes any size then).
    pub fn unprocessed(detector: Detector, [width, height]: [u32; 2]) -> Result<Self, VisionError> {
        let stage = PreprocessParams::default().check()?.stage(width, height)?;
        Ok(Self { stage, detector })
    }

    /// The preprocessing stage.
    pub fn stage(&self) -> &PreprocessStage {
        &self.stage
    }

    /// The detector.
    pub fn detector(&self) -> &Detector {
        &self.detector
    }

    /// A camera image preprocessed.
    pub fn preprocess(&self, image: &DynamicImage) -> Result<Frame, VisionError> {
        self.stage.apply(image)
    }

    /// The pins and clusters of a camera image.
    pub fn detect(&self, image: &DynamicImage) -> Result<Detection, VisionError> {
        let frame = self.preprocess(image)?;
        let mut detection = self.detector.detect(&frame);
        self.detector.add_clusters(&frame, &mut detection);
        Ok(detection)
    }
}

impl PinReader {
    /// A reader of `frames` against the rest pins `rest` (px, in the
    /// preprocessed frame).
    pub fn new(frames: FrameDetector, rest: Vec<[f64; 2]>) -> Result<Self, VisionError> {
        Ok(Self {
            frames,
            tracker: PinTracker::new(rest)?,
            min_found_fraction: DEFAULT_MIN_MATCHED_FRACTION,
        })
    }

    /// The detector `detector` on frames taken as they are (no
    /// preprocessing step), over the pins it finds in the undeformed
    /// frame `reference`, in detection order (as
    /// [`crate::PinExtractor::with_detector`] orders them).
    pub fn from_reference_frame(
        detector: Detector,
        reference: &Frame,
    ) -> Result<Self, VisionError> {
        let size = [reference.width(), reference.height()];
        let rest = detector
            .detect(reference)
            .points
            .iter()
            .map(|k| [k.x, k.y])
            .collect();
        Self::new(FrameDetector::unprocessed(detector, size)?, rest)
    }

    /// The frame detector.
    pub fn frames(&self) -> &FrameDetector {
        &self.frames
    }

    /// The tracker (its reference is the rest layout).
    pub fn tracker(&self) -> &PinTracker {
        &self.tracker
    }

    /// A camera image read into ordered pins; fails when fewer than
    /// `ceil(min_found_fraction * pins)` pins were found.
    pub fn read(&self, image: &DynamicImage) -> Result<Reading, VisionError> {
        let frame = self.frames.preprocess(image)?;
        self.read_preprocessed(&frame)
    }

    /// [`PinReader::read`] for a frame already preprocessed. The blob
    /// detector's clusters are looked for only when pins are missing.
    pub fn read_preprocessed(&self, frame: &Frame) -> Result<Reading, VisionError> {
        let (tracked, detection) = track(self.frames.detector(), &self.tracker, frame);
        let counts = TrackCounts::of(&tracked, &detection);
        check_found(
            &tracked,
            counts.matched + counts.split,
            self.min_found_fraction,
        )?;
        Ok(Reading { tracked, counts })
    }

    /// The ordered pins of a grey frame (a camera image made grey by
    /// [`crate::preprocess::grey_of`]): through the preprocessing stage,
    /// or, when the stage has no step, the frame as it is whatever its
    /// size (as `import` reads frames); then as
    /// [`PinReader::read_preprocessed`], without the counts. The servo
    /// loop's perception reads every tap with it.
    pub fn read_grey(&self, frame: &Frame) -> Result<Tracked, VisionError> {
        let (detector, tracker) = (self.frames.detector(), &self.tracker);
        let tracked = match self.preprocessed_grey(frame)? {
            Some(seen) => track(detector, tracker, &seen).0,
            None => track(detector, tracker, frame).0,
        };
        check_found(&tracked, tracked.matched_count(), self.min_found_fraction)?;
        Ok(tracked)
    }

    /// The detection of a grey frame as [`PinReader::read_grey`] sees it
    /// (without the clusters the blob detector finds only when pins are
    /// missing, and the blobs' sizes NaN where the tracker's detection
    /// leaves them unmeasured): what `bench` times as detection.
    pub fn detect_grey(&self, frame: &Frame) -> Result<Detection, VisionError> {
        let detector = self.frames.detector();
        Ok(match self.preprocessed_grey(frame)? {
            Some(seen) => detector.detect_centres(&seen),
            None => detector.detect_centres(frame),
        })
    }

    /// A grey frame through the stage; `None` when the stage has no step
    /// (the frame is seen as it is).
    fn preprocessed_grey(&self, frame: &Frame) -> Result<Option<Frame>, VisionError> {
        let stage = &self.frames.stage;
        if *stage.params() == PreprocessParams::default() {
            return Ok(None);
        }
        stage.apply_grey(frame).map(Some)
    }
}
