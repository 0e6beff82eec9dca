//! Pin detection for small pins: the white connected components of a
//! (preprocessed) frame, counted in pixels. OpenCV's blob detector
//! ([`crate::detect_blobs`]) measures a blob on the polygon through its
//! border pixels' centres, so a pin of one or two pixels, or a three-pixel
//! line, has zero area and is lost; at 2-3 px per pin (a 331-pin TacTip in
//! 128 x 128 frames) that is a pin in every frame. Here a pin is a
//! component whose pixel count lies in a range, its centre the weighted
//! mean of its pixels (sub-pixel: weights are the grey levels above the
//! threshold, all equal on a binary frame), and a larger component of up to
//! a few pins is kept as a [`Cluster`] of touching pins that the tracker
//! may split (see [`crate::PinTracker::order_with_clusters`]).

use serde::{Deserialize, Serialize};

use crate::blob::{Frame, KeyPoint};
use crate::error::VisionError;
use crate::merged::Cluster;
use crate::spot_runs::SpotRuns;

/// Which neighbours join two white pixels into one component.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Connectivity {
    /// Edge neighbours only: two pins touching at a corner stay apart.
    Four,
    /// Edge and corner neighbours (OpenCV's components of white pixels).
    #[default]
    Eight,
}

/// Settings of the small-pin detector, as a configuration file holds them
/// (check them with [`SpotParams::check`]). Counts are in pixels of the
/// frame the detector sees (after preprocessing).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpotParams {
    /// A pixel is white when its grey level exceeds this (0..=254).
    pub level: u8,
    /// Smallest pin, pixels (inclusive): smaller specks are ignored.
    pub min_pixels: usize,
    /// Largest single pin, pixels (inclusive).
    pub max_pixels: usize,
    /// Largest cluster of touching pins, pixels (inclusive): larger
    /// components (the rim of the dome) are ignored.
    pub max_cluster_pixels: usize,
    /// Which neighbours join pixels into one component.
    #[serde(default)]
    pub connectivity: Connectivity,
}

/// Checked [`SpotParams`]: the detector itself.
#[derive(Clone, Debug, PartialEq)]
pub struct SpotDetector {
    params: SpotParams,
}

/// One detected pin: centre (x right, y down, px) and size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spot {
    /// Centre, px (weighted mean of the pixel centres).
    pub x: f64,
    /// Centre, px.
    pub y: f64,
    /// Number of pixels.
    pub pixels: usize,
}

/// What the detector found in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spots {
    /// Components of pin size, in raster order of their first pixel.
    pub pins: Vec<Spot>,
    /// Every component of pin or cluster size (`passed` when it is also
    /// in `pins`): the tracker splits those that hold missing pins.
    pub clusters: Vec<Cluster>,
}

impl SpotParams {
    /// Checks the ranges: `1 <= min_pixels <= max_pixels <=
    /// max_cluster_pixels` and `level < 255` (else nothing is white).
    pub fn check(self) -> Result<SpotDetector, VisionError> {
        let invalid =
            |name: &'static str, reason: String| VisionError::InvalidParam { name, reason };
        if self.level == 255 {
            return Err(invalid("level", "must be below 255".into()));
        }
        if self.min_pixels == 0 {
            return Err(invalid("min_pixels", "must be at least 1".into()));
        }
        if self.max_pixels < self.min_pixels {
            return Err(invalid(
                "max_pixels",
                format!(
                    "{} is below min_pixels {}",
                    self.max_pixels, self.min_pixels
                ),
            ));
        }
        if self.max_cluster_pixels < self.max_pixels {
            return Err(invalid(
                "max_cluster_pixels",
                format!(
                    "{} is below max_pixels {}",
                    self.max_cluster_pixels, self.max_pixels
                ),
            ));
        }
        Ok(SpotDetector { params: self })
    }
}

impl Spot {
    /// As a keypoint (size: the diameter of a disc of as many pixels).
    pub fn keypoint(&self) -> KeyPoint {
        KeyPoint {
            x: self.x,
            y: self.y,
            size: 2.0 * (self.pixels as f64 / std::f64::consts::PI).sqrt(),
        }
    }
}

impl Spots {
    /// The pins as keypoints, for [`crate::PinTracker`].
    pub fn keypoints(&self) -> Vec<KeyPoint> {
        self.pins.iter().map(Spot::keypoint).collect()
    }
}

impl SpotDetector {
    /// The settings.
    pub fn params(&self) -> &SpotParams {
        &self.params
    }

    /// The pins and clusters of `frame`: its white components of pin or
    /// cluster size from pixel runs (`spot_runs.rs`), in raster order of
    /// their first pixels, each with its pixels in raster order.
    pub fn detect(&self, frame: &Frame) -> Spots {
        let p = &self.params;
        let mut out = Spots::default();
        let sizes = p.min_pixels..=p.max_cluster_pixels;
        SPOT_RUNS.with_borrow_mut(|runs| {
            runs.for_each_component(frame, p.level, p.connectivity, sizes, |pixels| {
                let n = pixels.len();
                let passed = n <= p.max_pixels;
                if passed {
                    let [x, y] = weighted_centre(frame, pixels, p.level);
                    out.pins.push(Spot { x, y, pixels: n });
                }
                out.clusters.push(Cluster {
                    pixels: pixels.to_vec(),
                    passed,
                });
            });
        });
        out
    }
}

thread_local! {
    /// The run-based component finder's buffers, kept between frames.
    static SPOT_RUNS: std::cell::RefCell<SpotRuns> = std::cell::RefCell::new(SpotRuns::default());
}

/// Mean of the pixel centres weighted by their grey level above `level`.
/// Every product and partial sum is an integer, exact in f64 while below
/// 2^53 (weights below 2^8: any pin of fewer than 2^20 pixels in a frame
/// less than 2^25 pixels wide and high), so the centre does not depend on
/// the order of the pixels.
fn weighted_centre(frame: &Frame, pixels: &[[i32; 2]], level: u8) -> [f64; 2] {
    let (width, raw) = (frame.width() as usize, frame.as_raw());
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for q in pixels {
        let w = f64::from(raw[q[1] as usize * width + q[0] as usize] - level);
        sw += w;
        sx += w * f64::from(q[0]);
        sy += w * f64::from(q[1]);
    }
    [sx / sw, sy / sw]
}

/// The white components (pixels above `level`) of `frame`, each as its
/// pixels, in raster order of their first pixel (a flood fill from it).
pub(crate) fn white_components(
    frame: &Frame,
    level: u8,
    connectivity: Connectivity,
) -> Vec<Vec<[i32; 2]>> {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    let raw = frame.as_raw();
    let mut seen = vec![false; w * h];
    let mut stack = Vec::new();
    let mut pixels: Vec<[i32; 2]> = Vec::new();
    let mut out = Vec::new();
    let offsets: &[(i32, i32)] = match connectivity {
        Connectivity::Four => &[(1, 0), (-1, 0), (0, 1), (0, -1)],
        Connectivity::Eight => &[
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ],
    };
    for start in 0..w * h {
        if seen[start] || raw[start] <= level {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        // The component's pixels gather in one buffer kept across
        // components and are copied out at their final size: one
        // allocation a component, not one each time its list doubles.
        pixels.clear();
        while let Some(i) = stack.pop() {
            let (x, y) = ((i % w) as i32, (i / w) as i32);
            pixels.push([x, y]);
            for &(dx, dy) in offsets {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx as usize >= w || ny as usize >= h {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if !seen[j] && raw[j] > level {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        out.push(pixels.to_vec());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SpotParams {
        SpotParams {
            level: 127,
            min_pixels: 2,
            max_pixels: 9,
            max_cluster_pixels: 30,
            connectivity: Connectivity::Eight,
        }
    }

    fn frame(white: &[[u32; 2]], value: u8) -> Frame {
        let mut f = Frame::new(20, 20);
        for q in white {
            f.put_pixel(q[0], q[1], image::Luma([value]));
        }
        f
    }

    /// A single pixel and a two-pixel line (zero polygon area, lost by the
    /// blob detector) are pins here, at their pixel centroids; a speck
    /// below `min_pixels` is not.
    #[test]
    fn tiny_pins_are_found_at_their_centroids() {
        let p = SpotParams {
            min_pixels: 1,
            ..params()
        };
        let f = frame(&[[3, 3], [10, 5], [11, 5]], 255);
        let spots = p.clone().check().expect("valid").detect(&f);
        assert_eq!(spots.pins.len(), 2);
        assert_eq!((spots.pins[0].x, spots.pins[0].y), (3.0, 3.0));
        assert_eq!((spots.pins[1].x, spots.pins[1].y), (10.5, 5.0));
        let p2 = SpotParams { min_pixels: 2, ..p };
        assert_eq!(p2.check().expect("valid").detect(&f).pins.len(), 1);
    }

    /// Grey levels above the threshold weight the centre.
    #[test]
    fn grey_levels_weight_the_centre() {
        let mut f = frame(&[[4, 4]], 137);
        f.put_pixel(5, 4, image::Luma([157]));
        let spots = params().check().expect("valid").detect(&f);
        assert!((spots.pins[0].x - (4.0 * 10.0 + 5.0 * 30.0) / 40.0).abs() < 1e-12);
    }

    /// Corner contact joins two pins under 8-connectivity only; an
    /// oversize component is a cluster, not a pin.
    #[test]
    fn connectivity_and_clusters() {
        let f = frame(&[[2, 2], [3, 2], [4, 3], [5, 3]], 255);
        let eight = params().check().expect("valid").detect(&f);
        assert_eq!((eight.pins.len(), eight.clusters.len()), (1, 1));
        let four = SpotParams {
            connectivity: Connectivity::Four,
            ..params()
        };
        assert_eq!(four.check().expect("valid").detect(&f).pins.len(), 2);
        let small = SpotParams {
            max_pixels: 3,
            ..params()
        };
        let spots = small.check().expect("valid").detect(&f);
        assert!(spots.pins.is_empty());
        assert_eq!(spots.clusters.len(), 1);
        assert!(!spots.clusters[0].passed);
    }

    /// The buffer the flood fill keeps across components hands each
    /// component exactly its own pixels: a large one (grown past any first
    /// capacity) between two small ones, in raster order of their first
    /// pixels, every pixel once.
    #[test]
    fn each_component_gets_only_its_own_pixels() {
        let bar: Vec<[u32; 2]> = (0..20).map(|x| [x, 5]).collect();
        let white: Vec<[u32; 2]> = [[1, 1]]
            .into_iter()
            .chain(bar.iter().copied())
            .chain([[3, 9], [4, 9], [3, 10]])
            .collect();
        let components = white_components(&frame(&white, 200), 127, Connectivity::Eight);
        let sizes: Vec<usize> = components.iter().map(Vec::len).collect();
        assert_eq!(sizes, [1, 20, 3]);
        let mut all: Vec<[i32; 2]> = components.into_iter().flatten().collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), white.len(), "every white pixel exactly once");
    }

    #[test]
    fn ranges_are_checked() {
        for bad in [
            SpotParams {
                min_pixels: 0,
                ..params()
            },
            SpotParams {
                max_pixels: 1,
                ..params()
            },
            SpotParams {
                max_cluster_pixels: 5,
                ..params()
            },
            SpotParams {
                level: 255,
                ..params()
            },
        ] {
            assert!(bad.check().is_err());
        }
    }
}
