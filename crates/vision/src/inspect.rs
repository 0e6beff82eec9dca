//! Inspection of an unknown TacTip from a few of its frames: proposes the
//! preprocessing (a threshold when the frames are grey, the circular mask
//! of the dome from its rim), the detector and its parameters (from the
//! pins' size and spacing), the pin count and the layout kind (hexagonal
//! lattice or concentric rings), and keeps what it found for a picture.
//!
//! How:
//! 1. binarise: frames with two grey levels are taken as they are, others
//!    through an adaptive Gaussian threshold (`C = -5`, the Bristol
//!    pipeline's) whose block spans about 4.5 pin spacings (a first pass
//!    with a block of an eighth of the frame measures the spacing);
//! 2. the white components of every frame: the typical pin is the median
//!    component size `m` (pins outnumber everything else); components over
//!    `6 m` pixels are the rim, a circle is fitted to their pixels;
//! 3. pins are components of `m / 6 ..= 1.75 m` pixels, clusters of
//!    touching pins up to `4 m`; the spacing is the median
//!    nearest-neighbour distance; the pin field's outer radius is the
//!    farthest pin of at least `m / 2` pixels with two neighbours within
//!    1.5 spacings (specks on the rim are smaller or alone) in nine frames
//!    out of ten (a tap pushes the outer pins out now and then);
//! 4. the mask (`field.rs`): reaching as far out as it can, short of the
//!    rim's inner edge (its 2nd-percentile radius) and of the static specks
//!    (pin-sized components beyond the pins found in the same place in at
//!    least a quarter of the frames), less half a pixel, but at least to
//!    that radius plus a quarter spacing (without a rim: at most a spacing
//!    beyond it);
//! 5. the pin count (`field.rs`): the 20th percentile over frames of the count inside
//!    the mask, a cluster counting as its size over the median size of the
//!    pins around it (specks add to a count more often than anything
//!    takes from it);
//! 6. the layout, judged on a frame with that count: a hexagonal lattice
//!    when the six-fold order of the pins' bond directions in the frame
//!    exceeds their order relative to the direction from the pins' centre
//!    by more than 0.5, else concentric rings (see `geometry.rs`).

mod field;
mod geometry;
mod picture;

use serde::{Deserialize, Serialize};

use crate::blob::Frame;
use crate::detection::DetectorParams;
use crate::error::VisionError;
use crate::params::BlobParams;
use crate::preprocess::{adaptive_threshold, MaskCircle, PreprocessParams, Threshold};
use crate::spots::{white_components, Connectivity, SpotParams};
use crate::tracker::median_spacing;
use field::{low_count, mask_circle, pin_sites};
use geometry::{distance, fit_circle, nearest_distances, orientational_order, rings};
pub use picture::draw_inspection;

/// Pins of at most this many pixels (median) get the small-pin detector,
/// larger ones OpenCV's blob detector.
const SMALL_PIN_PIXELS: f64 = 20.0;
/// A layout is a hexagonal lattice when its lattice order exceeds its
/// polar order by more than this (see `geometry::orientational_order`).
const HEXAGONAL_MARGIN: f64 = 0.5;
/// `C` of the proposed adaptive threshold (the Bristol pipeline's).
const ADAPTIVE_C: f64 = -5.0;

/// How the pins are laid out on the dome.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayoutKind {
    /// A hexagonal lattice (the 127-pin TacTip).
    Hexagonal,
    /// Concentric rings around a centre pin (the 331-pin TacTip: ring k
    /// holds 6k pins).
    Rings,
}

/// A pin layout described (see [`layout_of`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    /// Hexagonal lattice or rings.
    pub kind: LayoutKind,
    /// Six-fold order of the bond directions in the frame, 0..=1 (near 1
    /// for a lattice).
    pub lattice_order: f64,
    /// Six-fold order of the bond directions relative to the direction
    /// from the centre, 0..=1 (the higher of the two for rings).
    pub polar_order: f64,
    /// Pins per ring, innermost first (ring layouts; empty for a lattice).
    pub rings: Vec<usize>,
}

/// What [`inspect`] proposes and found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Inspection {
    /// The proposed preprocessing (crop as given, mask, threshold).
    pub preprocess: PreprocessParams,
    /// The proposed detector.
    pub detect: DetectorParams,
    /// The proposed pin count.
    pub pins: usize,
    /// Median nearest-neighbour pin spacing, px.
    pub spacing: f64,
    /// Median pin size, pixels.
    pub pin_pixels: f64,
    /// Hexagonal lattice or rings, judged on a frame showing all the pins.
    pub layout: Layout,
    /// The rim of the dome, when one was seen.
    pub rim: Option<MaskCircle>,
    /// Whether the frames were already binary.
    pub binary: bool,
    /// Per frame, the pins found inside the mask (clusters counted as the
    /// pins they hold).
    pub counts: Vec<usize>,
    /// What was found in one frame, to draw.
    pub picture: Picture,
}

/// What the inspection found in one frame (cropped frame's pixels), for
/// a picture (see [`draw_inspection`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Picture {
    /// Index of the frame among those inspected.
    pub frame: usize,
    /// Pins kept (inside the mask, of pin size).
    pub pins: Vec<[f64; 2]>,
    /// Clusters of touching pins inside the mask (their centres).
    pub clusters: Vec<[f64; 2]>,
    /// Components left out: outside the mask, or too small or too large.
    pub rejected: Vec<[f64; 2]>,
}

/// One white component: pixel count and centre.
struct Blob {
    pixels: usize,
    centre: [f64; 2],
}

/// Proposes how to read a sensor's frames from a few of them (grey, the
/// same size; see the module docs). `crop` is kept in the proposal and
/// applied first.
pub fn inspect(frames: &[Frame], crop: Option<[u32; 4]>) -> Result<Inspection, VisionError> {
    let seen = Binarised::of(frames, crop)?;
    let no_pins = || VisionError::NoPins {
        frames: frames.len(),
    };
    let mut large = Vec::new();
    let found: Vec<Vec<Blob>> = seen
        .frames
        .iter()
        .map(|f| components(f, seen.level, &mut large))
        .collect();
    let m = median_pixels(&found).ok_or_else(no_pins)?;
    let rim_pixels: Vec<[f64; 2]> = large
        .iter()
        .filter(|(n, _)| *n as f64 > 6.0 * m)
        .flat_map(|(_, p)| p.iter().copied())
        .collect();
    let size = [f64::from(frames[0].width()), f64::from(frames[0].height())];
    let rim = fit_circle(&rim_pixels).filter(|c| plausible_rim(c, size));
    let sizes = Sizes::from_median(m);
    let pin_sets: Vec<Vec<[f64; 2]>> = found.iter().map(|b| sizes.pins(b)).collect();
    let spacing = median_spacing_of(&pin_sets).ok_or_else(no_pins)?;
    let centre = rim.map_or_else(|| field_centre(&pin_sets), |r| r.centre);
    let mask = mask_circle(&found, &sizes, centre, spacing, rim, &rim_pixels);
    let inside = |p: [f64; 2]| distance(p, mask.centre) <= mask.radius;
    let sites: Vec<usize> = found
        .iter()
        .map(|b| pin_sites(b, &sizes, spacing, &inside))
        .collect();
    let pins = low_count(&sites);
    // Judge the layout on a frame showing that many pins, clusters apart.
    let plain = |i: usize| pin_sets[i].iter().filter(|&&p| inside(p)).count();
    let judged = (0..sites.len())
        .find(|&i| sites[i] == pins && plain(i) == pins)
        .or_else(|| (0..sites.len()).find(|&i| sites[i] == pins))
        .unwrap_or(0);
    let judged_pins: Vec<[f64; 2]> = pin_sets[judged]
        .iter()
        .copied()
        .filter(|&p| inside(p))
        .collect();
    Ok(Inspection {
        preprocess: PreprocessParams {
            crop,
            mask: Some(mask),
            threshold: seen.threshold,
            ..PreprocessParams::default()
        },
        detect: sizes.detector(seen.level, spacing),
        pins,
        spacing,
        pin_pixels: m,
        layout: layout_of(&judged_pins),
        rim,
        binary: seen.binary,
        counts: sites,
        picture: picture_of(judged, &found[judged], &sizes, &inside),
    })
}

/// How a set of pin centres (px) is laid out: a hexagonal lattice when
/// the six-fold order of their bond directions in the frame exceeds their
/// order relative to the direction from their centre by more than 0.5,
/// else concentric rings (see `geometry::orientational_order`).
pub fn layout_of(pins: &[[f64; 2]]) -> Layout {
    let spacing = median_spacing(pins);
    let centre = field_centre(std::slice::from_ref(&pins.to_vec()));
    let order = orientational_order(pins, spacing, centre);
    let kind = if order.lattice - order.polar > HEXAGONAL_MARGIN {
        LayoutKind::Hexagonal
    } else {
        LayoutKind::Rings
    };
    Layout {
        kind,
        lattice_order: order.lattice,
        polar_order: order.polar,
        rings: match kind {
            LayoutKind::Rings => rings(pins, centre, spacing),
            LayoutKind::Hexagonal => Vec::new(),
        },
    }
}

/// The inspected frames, binary.
struct Binarised {
    frames: Vec<Frame>,
    /// Whether they came binary.
    binary: bool,
    /// The threshold that made them binary, if any.
    threshold: Option<Threshold>,
    /// White above this grey level.
    level: u8,
}

impl Binarised {
    /// The frames cropped, and binarised when they are grey (step 1).
    fn of(frames: &[Frame], crop: Option<[u32; 4]>) -> Result<Self, VisionError> {
        let first = frames.first().ok_or(VisionError::NoFrames)?;
        let base = PreprocessParams {
            crop,
            ..PreprocessParams::default()
        };
        let stage = base.check()?.stage(first.width(), first.height())?;
        let grey: Vec<Frame> = frames
            .iter()
            .map(|f| stage.apply_grey(f))
            .collect::<Result<_, _>>()?;
        if grey.iter().all(is_binary) {
            let level = binary_level(&grey);
            return Ok(Self {
                frames: grey,
                binary: true,
                threshold: None,
                level,
            });
        }
        let (threshold, frames) = binarise(&grey);
        Ok(Self {
            frames,
            binary: false,
            threshold,
            level: 127,
        })
    }
}

/// At most two grey levels.
fn is_binary(frame: &Frame) -> bool {
    let mut seen = [false; 256];
    let mut distinct = 0;
    for &v in frame.as_raw() {
        if !seen[usize::from(v)] {
            seen[usize::from(v)] = true;
            distinct += 1;
            if distinct > 2 {
                return false;
            }
        }
    }
    true
}

/// The level between the two values of binary frames (white above it):
/// the lower value, or 127 for frames of one value.
fn binary_level(frames: &[Frame]) -> u8 {
    let (lo, hi) = frames
        .iter()
        .flat_map(|f| f.as_raw().iter().copied())
        .fold((u8::MAX, u8::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo < hi {
        lo
    } else {
        127
    }
}

/// Grey frames through the proposed adaptive threshold: a first pass with
/// a block of an eighth of the frame measures the spacing, the second
/// uses a block of about 4.5 spacings.
fn binarise(grey: &[Frame]) -> (Option<Threshold>, Vec<Frame>) {
    let side = grey[0].width().min(grey[0].height());
    let odd = |v: f64| ((v / 2.0).floor() as u32 * 2 + 1).clamp(3, 1001);
    let first = odd(f64::from(side) / 8.0);
    let pass = |block: u32| -> Vec<Frame> {
        grey.iter()
            .map(|f| adaptive_threshold(f, block, ADAPTIVE_C, true))
            .collect()
    };
    let bw = pass(first);
    let mut sink = Vec::new();
    let found: Vec<Vec<Blob>> = bw.iter().map(|f| components(f, 127, &mut sink)).collect();
    let block = median_pixels(&found)
        .and_then(|m| {
            median_spacing_of(
                &found
                    .iter()
                    .map(|b| Sizes::from_median(m).pins(b))
                    .collect::<Vec<_>>(),
            )
        })
        .map_or(first, |s| odd(4.5 * s));
    let threshold = Threshold::AdaptiveGaussian {
        block,
        c: ADAPTIVE_C,
    };
    let bw = if block == first { bw } else { pass(block) };
    (Some(threshold), bw)
}

/// The white components of a binary frame; large ones also go, with their
/// pixels, to `large` (kept when over 30 pixels, the rim candidates).
fn components(frame: &Frame, level: u8, large: &mut Vec<(usize, Vec<[f64; 2]>)>) -> Vec<Blob> {
    white_components(frame, level, Connectivity::Eight)
        .into_iter()
        .map(|pixels| {
            let n = pixels.len() as f64;
            let centre = [
                pixels.iter().map(|q| f64::from(q[0])).sum::<f64>() / n,
                pixels.iter().map(|q| f64::from(q[1])).sum::<f64>() / n,
            ];
            if pixels.len() > 30 {
                let points = pixels.iter().map(|q| [f64::from(q[0]), f64::from(q[1])]);
                large.push((pixels.len(), points.collect()));
            }
            Blob {
                pixels: pixels.len(),
                centre,
            }
        })
        .collect()
}

/// Median component size over all frames, pixels.
fn median_pixels(found: &[Vec<Blob>]) -> Option<f64> {
    let mut sizes: Vec<usize> = found.iter().flatten().map(|b| b.pixels).collect();
    if sizes.is_empty() {
        return None;
    }
    sizes.sort_unstable();
    Some(sizes[sizes.len() / 2] as f64)
}

/// A rim circle worth trusting: centred within the frame, its radius
/// between a quarter and the whole of the frame's larger side.
fn plausible_rim(c: &MaskCircle, size: [f64; 2]) -> bool {
    let side = size[0].max(size[1]);
    let inside = (0.0..=size[0]).contains(&c.centre[0]) && (0.0..=size[1]).contains(&c.centre[1]);
    inside && c.radius > 0.25 * side && c.radius < side
}

/// The pin and cluster size ranges, from the median pin size.
struct Sizes {
    median: f64,
    min: usize,
    max: usize,
    max_cluster: usize,
}

impl Sizes {
    fn from_median(m: f64) -> Self {
        let min = ((m / 6.0).floor() as usize).max(1);
        let max = ((1.75 * m).floor() as usize).max(min);
        Self {
            median: m,
            min,
            max,
            max_cluster: ((4.0 * m).floor() as usize).max(max),
        }
    }

    fn pins(&self, blobs: &[Blob]) -> Vec<[f64; 2]> {
        blobs
            .iter()
            .filter(|b| (self.min..=self.max).contains(&b.pixels))
            .map(|b| b.centre)
            .collect()
    }

    /// Small pins: the spot detector with these ranges; larger ones:
    /// OpenCV's blob detector with the `real256` shape filters, its areas
    /// (contour polygons, smaller than pixel counts) and merge distance
    /// scaled from the pin size and spacing as `real256`'s are from the
    /// 127-pin sensor's (median 26 px, spacing 13 px).
    fn detector(&self, level: u8, spacing: f64) -> DetectorParams {
        if self.median <= SMALL_PIN_PIXELS {
            return DetectorParams::Spots(SpotParams {
                level,
                min_pixels: self.min,
                max_pixels: self.max,
                max_cluster_pixels: self.max_cluster,
                connectivity: Connectivity::Eight,
            });
        }
        let round = |v: f64| (v * 10.0).round() as f32 / 10.0;
        let real = BlobParams::preset("real256").unwrap_or_default();
        DetectorParams::Blobs(BlobParams {
            min_area: round(0.2 * self.median).max(1.0),
            max_area: round(2.7 * self.median),
            min_dist_between_blobs: round(0.3 * spacing).max(1.0),
            ..real
        })
    }
}

/// Median over frames of the median nearest-neighbour distance, px.
fn median_spacing_of(pin_sets: &[Vec<[f64; 2]>]) -> Option<f64> {
    let mut per_frame: Vec<f64> = pin_sets
        .iter()
        .filter(|s| s.len() >= 3)
        .map(|s| {
            let mut d = nearest_distances(s);
            d.sort_unstable_by(f64::total_cmp);
            d[d.len() / 2]
        })
        .collect();
    if per_frame.is_empty() {
        return None;
    }
    per_frame.sort_unstable_by(f64::total_cmp);
    Some(per_frame[per_frame.len() / 2])
}

/// Mean of the pin centres of the frame with the most pins.
fn field_centre(pin_sets: &[Vec<[f64; 2]>]) -> [f64; 2] {
    let most = pin_sets.iter().max_by_key(|s| s.len());
    match most {
        Some(s) if !s.is_empty() => {
            let n = s.len() as f64;
            [
                s.iter().map(|p| p[0]).sum::<f64>() / n,
                s.iter().map(|p| p[1]).sum::<f64>() / n,
            ]
        }
        _ => [0.0, 0.0],
    }
}

fn picture_of(
    frame: usize,
    blobs: &[Blob],
    sizes: &Sizes,
    inside: &dyn Fn([f64; 2]) -> bool,
) -> Picture {
    let mut picture = Picture {
        frame,
        ..Picture::default()
    };
    for b in blobs {
        let pin = (sizes.min..=sizes.max).contains(&b.pixels);
        let cluster = b.pixels > sizes.max && b.pixels <= sizes.max_cluster;
        match (inside(b.centre), pin, cluster) {
            (true, true, _) => picture.pins.push(b.centre),
            (true, _, true) => picture.clusters.push(b.centre),
            _ => picture.rejected.push(b.centre),
        }
    }
    picture
}
