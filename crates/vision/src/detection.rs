//! One detector for any TacTip: OpenCV's multi-threshold blob detector
//! ([`crate::detect_blobs`], for pins of tens of pixels such as the
//! 127-pin sensor's 256 x 256 frames) or the small-pin detector
//! ([`crate::SpotDetector`], for pins of a few pixels), chosen by a typed
//! setting so a sensor file says which. Either gives a [`Detection`]: the
//! pin centres, and the components the tracker may split when touching
//! pins left some missing.

use serde::{Deserialize, Serialize};

use crate::blob::{detect_blob_centres, detect_blobs, Frame, KeyPoint};
use crate::error::VisionError;
use crate::merged::{find_clusters, Cluster};
use crate::params::BlobParams;
use crate::spots::{SpotDetector, SpotParams};

/// Which detector, with its settings, as a configuration file holds it:
/// `kind = "blobs"` with the [`BlobParams`] keys, or `kind = "spots"` with
/// the [`SpotParams`] keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DetectorParams {
    /// OpenCV's blob detector (contour polygons; pins of tens of pixels).
    Blobs(BlobParams),
    /// Connected components counted in pixels (pins of a few pixels).
    Spots(SpotParams),
}

/// A checked detector, made by [`DetectorParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub enum Detector {
    /// OpenCV's blob detector with validated parameters.
    Blobs(BlobParams),
    /// The small-pin detector.
    Spots(SpotDetector),
}

/// What a detector found in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Detection {
    /// Pin centres (px) and sizes.
    pub points: Vec<KeyPoint>,
    /// Components that may hold touching pins (see
    /// [`crate::PinTracker::order_with_clusters`]); for the blob detector
    /// they are found only by [`Detector::add_clusters`].
    pub clusters: Vec<Cluster>,
}

impl DetectorParams {
    /// Checks the settings (the ranges of [`BlobParams::validate`] or
    /// [`SpotParams::check`]).
    pub fn check(self) -> Result<Detector, VisionError> {
        match self {
            Self::Blobs(p) => {
                p.validate()?;
                Ok(Detector::Blobs(p))
            }
            Self::Spots(p) => Ok(Detector::Spots(p.check()?)),
        }
    }
}

impl Detector {
    /// The settings it was made from.
    pub fn params(&self) -> DetectorParams {
        match self {
            Self::Blobs(p) => DetectorParams::Blobs(p.clone()),
            Self::Spots(d) => DetectorParams::Spots(d.params().clone()),
        }
    }

    /// The pins of `frame`, with the clusters of touching pins for the
    /// spot detector (found on the way); the blob detector's need a second
    /// pass ([`Detector::add_clusters`]).
    pub fn detect(&self, frame: &Frame) -> Detection {
        match self {
            Self::Blobs(p) => Detection {
                points: detect_blobs(frame, p),
                clusters: Vec::new(),
            },
            Self::Spots(d) => {
                let spots = d.detect(frame);
                Detection {
                    points: spots.keypoints(),
                    clusters: spots.clusters,
                }
            }
        }
    }

    /// [`Detector::detect`] for a caller that reads the pins' centres
    /// only (the tracker): the same centres, bit for bit, and for the
    /// blob detector the sizes left NaN wherever they were not needed to
    /// group the blobs (`crate::blob::detect_blob_centres`).
    pub(crate) fn detect_centres(&self, frame: &Frame) -> Detection {
        match self {
            Self::Blobs(p) => Detection {
                points: detect_blob_centres(frame, p),
                clusters: Vec::new(),
            },
            Self::Spots(_) => self.detect(frame),
        }
    }

    /// Fills in the clusters of a blob detection of `frame` (the spot
    /// detector's are there already).
    pub fn add_clusters(&self, frame: &Frame, detection: &mut Detection) {
        if let Self::Blobs(p) = self {
            if detection.clusters.is_empty() {
                detection.clusters = find_clusters(frame, p);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        detect: DetectorParams,
    }

    #[test]
    fn both_detector_kinds_read_from_toml_and_unknown_keys_are_refused() {
        let spots = "[detect]\nkind = \"spots\"\nlevel = 127\nmin_pixels = 3\n\
                     max_pixels = 11\nmax_cluster_pixels = 40\n";
        let file: File = toml::from_str(spots).expect("spots");
        assert!(matches!(file.detect, DetectorParams::Spots(_)));
        let blobs = "[detect]\nkind = \"blobs\"\nmin_area = 5.0\nblob_color = 255\n";
        let file: File = toml::from_str(blobs).expect("blobs");
        let DetectorParams::Blobs(p) = file.detect else {
            panic!("blobs")
        };
        assert_eq!((p.min_area, p.blob_color, p.max_area), (5.0, 255, 5000.0));
        for bad in [
            format!("{spots}min_pixel = 2\n"),
            format!("{blobs}min_aera = 2.0\n"),
            "[detect]\nkind = \"dots\"\n".to_string(),
        ] {
            assert!(toml::from_str::<File>(&bad).is_err(), "{bad}");
        }
    }
}
