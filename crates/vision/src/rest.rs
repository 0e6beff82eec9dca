//! The rest pin layout of a sensor when no undeformed frame exists (a
//! collection of taps, every one in contact). The pins' rest positions are
//! estimated from the taps themselves:
//!
//! 1. a provisional layout: among some frames with exactly the expected
//!    pin count, the one against which most of the others can be ordered
//!    with no pin missing and no neighbour triangle turned over;
//! 2. every frame is ordered against the layout ([`crate::PinTracker`]);
//!    the frames whose pins moved least (median displacement over matched
//!    pins, among the frames with at most a few pins missing) are kept;
//! 3. each pin's new rest position is the coordinate-wise median of its
//!    matched positions over the kept frames;
//! 4. repeat 2-3 until no pin moves more than the tolerance. A layout
//!    pin matched in fewer than half of the frames, or closer than 0.6
//!    spacings to another (then the less matched of the two), is no pin
//!    (a speck the provisional frame happened to hold): it is dropped, and
//!    the round run again without it.
//!
//! The residual reported is the root mean square distance of the kept
//! frames' matched pins to their estimated rest positions: how far the
//! least displaced taps still are from the estimate (a lower bound on how
//! undeformed the estimate is, not an accuracy).

use serde::{Deserialize, Serialize};

use crate::detection::Detection;
use crate::error::VisionError;
use crate::tracker::{median_spacing, PinTracker, Tracked};

/// Layout pins closer than this many median spacings crowd each other:
/// one of them is no pin (the tightest real pair in a rest layout is
/// above 0.8).
const CROWDED: f64 = 0.6;

/// Settings of [`estimate_rest`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RestParams {
    /// Share of the usable frames (0..1] kept as least displaced.
    pub keep_share: f64,
    /// Most rounds of steps 2-3.
    pub max_rounds: usize,
    /// Stop when no pin moved more than this, px.
    pub tolerance: f64,
    /// Most frames compared for the provisional layout (spread evenly).
    pub medoid_candidates: usize,
    /// Most pins a frame may miss (filled from its neighbours) and still
    /// count in step 2.
    pub max_missing: usize,
}

impl Default for RestParams {
    fn default() -> Self {
        Self {
            keep_share: 0.25,
            max_rounds: 8,
            tolerance: 0.02,
            medoid_candidates: 24,
            max_missing: 0,
        }
    }
}

/// The estimated rest layout and how well the taps agree with it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RestEstimate {
    /// Rest pin centres, px, in the order of the provisional frame's pins.
    pub pins: Vec<[f64; 2]>,
    /// Root mean square distance of the kept frames' matched pins to
    /// their rest positions, px.
    pub residual: f64,
    /// Median over the kept frames of their median pin displacement, px.
    pub kept_displacement: f64,
    /// Index (into the detections) of the provisional frame.
    pub provisional: usize,
    /// Frames kept as least displaced in the last round.
    pub frames_kept: usize,
    /// Frames that could be ordered with at most `max_missing` pins missing.
    pub frames_usable: usize,
    /// Rounds run.
    pub rounds: usize,
    /// Largest pin move in the last round, px.
    pub last_shift: f64,
    /// Points of the provisional frame dropped from the layout as no pins:
    /// matched in fewer than half of the frames (a speck of dust, a fleck
    /// of the rim), px.
    pub dropped: Vec<[f64; 2]>,
}

impl RestParams {
    fn check(&self) -> Result<(), VisionError> {
        let invalid =
            |name: &'static str, reason: String| VisionError::InvalidParam { name, reason };
        if !(self.keep_share > 0.0 && self.keep_share <= 1.0) {
            return Err(invalid(
                "keep_share",
                format!("{} is not in (0, 1]", self.keep_share),
            ));
        }
        if self.max_rounds == 0 || self.medoid_candidates == 0 {
            return Err(invalid(
                "max_rounds",
                "max_rounds and medoid_candidates must be at least 1".into(),
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(invalid(
                "tolerance",
                format!("{} must be finite and >= 0", self.tolerance),
            ));
        }
        Ok(())
    }
}

/// Estimates the rest layout of `pins` pins from the detections of many
/// taps (see the module docs; the layout may end with fewer pins, see
/// [`RestEstimate::dropped`]). Fails when no frame has exactly `pins`
/// points, or when no frame can be ordered against the layout.
pub fn estimate_rest(
    detections: &[Detection],
    pins: usize,
    params: &RestParams,
) -> Result<RestEstimate, VisionError> {
    params.check()?;
    let provisional = provisional_frame(detections, pins, params.medoid_candidates)
        .ok_or(VisionError::NoFrameWithPinCount { pins })?;
    let mut layout: Vec<[f64; 2]> = points_of(&detections[provisional]);
    let mut estimate = None;
    let mut dropped = Vec::new();
    for round in 1..=params.max_rounds {
        let tracker = PinTracker::new(layout.clone())?;
        let tracked: Vec<Tracked> = detections.iter().map(|d| tracker.track(d)).collect();
        let rare = no_pins(&tracked, &layout);
        if !rare.is_empty() && round < params.max_rounds {
            for &i in rare.iter().rev() {
                dropped.push(layout.remove(i));
            }
            continue;
        }
        let (kept, usable) = least_displaced(&tracked, &layout, params);
        if kept.is_empty() {
            return Err(VisionError::NoFrameTracked {
                frames: detections.len(),
            });
        }
        let next = per_pin_medians(&tracked, &kept, &layout);
        let shift = layout
            .iter()
            .zip(&next)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max);
        let (residual, kept_displacement) = agreement(&tracked, &kept, &next);
        layout = next;
        estimate = Some(RestEstimate {
            pins: layout.clone(),
            residual,
            kept_displacement,
            provisional,
            frames_kept: kept.len(),
            frames_usable: usable,
            rounds: round,
            last_shift: shift,
            dropped: dropped.clone(),
        });
        if shift <= params.tolerance {
            break;
        }
    }
    estimate.ok_or(VisionError::NoFrameTracked {
        frames: detections.len(),
    })
}

fn points_of(d: &Detection) -> Vec<[f64; 2]> {
    d.points.iter().map(|k| [k.x, k.y]).collect()
}

/// The best of up to `candidates` frames (spread evenly over the list)
/// that have exactly `pins` points, those without unsplit clusters first:
/// the one against which the most other candidates are ordered with no pin
/// missing and no neighbour triangle turned over, ties going to the
/// smallest summed median displacement. (A frame with a merged pair and a
/// speck also has `pins` points, but orders few others.)
fn provisional_frame(detections: &[Detection], pins: usize, candidates: usize) -> Option<usize> {
    let exact = |clean: bool| -> Vec<usize> {
        (0..detections.len())
            .filter(|&i| detections[i].points.len() == pins)
            .filter(|&i| !clean || detections[i].clusters.iter().all(|c| c.passed))
            .collect()
    };
    let mut full = exact(true);
    if full.len() < candidates.min(3) {
        full = exact(false);
    }
    let step = full.len().div_ceil(candidates).max(1);
    let chosen: Vec<usize> = full.iter().step_by(step).copied().collect();
    let mut best: Option<((usize, f64), usize)> = None;
    for &a in &chosen {
        let layout = points_of(&detections[a]);
        let Ok(tracker) = PinTracker::new(layout.clone()) else {
            continue;
        };
        let (mut good, mut moved) = (0usize, 0.0);
        for &b in chosen.iter().filter(|&&b| b != a) {
            let t = tracker.track(&detections[b]);
            if t.missing == 0 && tracker.turned_triangles(&t) == 0 {
                good += 1;
                moved += median_displacement(&t, &layout);
            }
        }
        let better = best
            .as_ref()
            .is_none_or(|&((g, m), _)| good > g || (good == g && moved < m));
        if better {
            best = Some(((good, moved), a));
        }
    }
    best.map(|(_, a)| a)
}

/// Ascending indices of the layout pins that are no pins: matched in
/// fewer than half of the frames, or crowding another pin (closer than
/// [`CROWDED`] spacings; of the two, the one matched less often).
fn no_pins(tracked: &[Tracked], layout: &[[f64; 2]]) -> Vec<usize> {
    let rate: Vec<usize> = (0..layout.len())
        .map(|i| tracked.iter().filter(|t| t.matched[i]).count())
        .collect();
    let mut out: Vec<usize> = (0..layout.len())
        .filter(|&i| 2 * rate[i] < tracked.len())
        .collect();
    let spacing = median_spacing(layout);
    for i in 0..layout.len() {
        for j in i + 1..layout.len() {
            let d = (layout[i][0] - layout[j][0]).hypot(layout[i][1] - layout[j][1]);
            if d < CROWDED * spacing {
                out.push(if rate[j] < rate[i] { j } else { i });
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Indices of the frames kept as least displaced, and how many were usable.
fn least_displaced(
    tracked: &[Tracked],
    layout: &[[f64; 2]],
    params: &RestParams,
) -> (Vec<usize>, usize) {
    let mut scored: Vec<(f64, usize)> = tracked
        .iter()
        .enumerate()
        .filter(|(_, t)| t.missing <= params.max_missing)
        .map(|(i, t)| (median_displacement(t, layout), i))
        .collect();
    let usable = scored.len();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let keep = ((usable as f64 * params.keep_share).ceil() as usize).clamp(usable.min(1), usable);
    (scored[..keep].iter().map(|&(_, i)| i).collect(), usable)
}

/// Median distance of a frame's matched pins from `layout`, px.
fn median_displacement(t: &Tracked, layout: &[[f64; 2]]) -> f64 {
    let mut d: Vec<f64> = t
        .pins
        .iter()
        .zip(layout)
        .zip(&t.matched)
        .filter(|(_, &m)| m)
        .map(|((p, r), _)| (p[0] - r[0]).hypot(p[1] - r[1]))
        .collect();
    median(&mut d).unwrap_or(f64::INFINITY)
}

/// Per pin, the coordinate-wise interquartile mean of its matched positions in the
/// kept frames (its old position if it was never matched there).
fn per_pin_medians(tracked: &[Tracked], kept: &[usize], layout: &[[f64; 2]]) -> Vec<[f64; 2]> {
    (0..layout.len())
        .map(|i| {
            let mut xs = Vec::with_capacity(kept.len());
            let mut ys = Vec::with_capacity(kept.len());
            for t in kept.iter().map(|&k| &tracked[k]).filter(|t| t.matched[i]) {
                xs.push(t.pins[i][0]);
                ys.push(t.pins[i][1]);
            }
            match (middle_mean(&mut xs), middle_mean(&mut ys)) {
                (Some(x), Some(y)) => [x, y],
                _ => layout[i],
            }
        })
        .collect()
}

/// (RMS distance of the kept frames' matched pins to `layout`, median of
/// their median displacements), px.
fn agreement(tracked: &[Tracked], kept: &[usize], layout: &[[f64; 2]]) -> (f64, f64) {
    let (mut sum, mut n) = (0.0, 0usize);
    let mut medians = Vec::with_capacity(kept.len());
    for t in kept.iter().map(|&k| &tracked[k]) {
        for ((p, r), _) in t
            .pins
            .iter()
            .zip(layout)
            .zip(&t.matched)
            .filter(|(_, &m)| m)
        {
            sum += (p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2);
            n += 1;
        }
        medians.push(median_displacement(t, layout));
    }
    let rms = if n == 0 { 0.0 } else { (sum / n as f64).sqrt() };
    (rms, median(&mut medians).unwrap_or(0.0))
}

/// Mean of the middle half of the values (the interquartile mean): as
/// robust as the median to the frames where the pin is pushed, but
/// smooth in the values, so the rounds settle (a median of centroids on a
/// pixel grid jumps between a few values).
fn middle_mean(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let n = values.len();
    let (lo, hi) = (n / 4, n - n / 4);
    let middle = &values[lo..hi.max(lo + 1)];
    Some(middle.iter().sum::<f64>() / middle.len() as f64)
}

/// Median (mean of the two middle values for an even count).
fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::KeyPoint;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A hexagonal patch of 61 pins, spacing 10 px.
    fn layout() -> Vec<[f64; 2]> {
        let mut pins = Vec::new();
        for q in -4i32..=4 {
            for r in -4i32..=4 {
                if (q + r).abs() <= 4 {
                    let x = 60.0 + 10.0 * (f64::from(q) + 0.5 * f64::from(r));
                    pins.push([x, 60.0 + 10.0 * 0.75f64.sqrt() * f64::from(r)]);
                }
            }
        }
        pins
    }

    /// Taps of the layout: a push from a random point (up to 6 px), a
    /// shift of up to 0.2 px and 0.05 px noise; `speck` (a point that is no
    /// pin) shows in 40 % of them.
    fn taps(rest: &[[f64; 2]], n: usize, speck: Option<[f64; 2]>) -> Vec<Detection> {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        (0..n)
            .map(|_| {
                let at = [rng.random_range(20.0..100.0), rng.random_range(20.0..100.0)];
                let push = rng.random_range(0.0..6.0);
                let shift = [rng.random_range(-0.2..0.2), rng.random_range(-0.2..0.2)];
                let mut points: Vec<KeyPoint> = rest
                    .iter()
                    .map(|p| {
                        let (dx, dy) = (p[0] - at[0], p[1] - at[1]);
                        let g = push * (-(dx * dx + dy * dy) / 450.0).exp() / 15.0;
                        let noise = [rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)];
                        KeyPoint {
                            x: p[0] + g * dx + shift[0] + noise[0],
                            y: p[1] + g * dy + shift[1] + noise[1],
                            size: 3.0,
                        }
                    })
                    .collect();
                if let Some(s) = speck.filter(|_| rng.random_bool(0.4)) {
                    points.push(KeyPoint {
                        x: s[0],
                        y: s[1],
                        size: 1.0,
                    });
                }
                Detection {
                    points,
                    clusters: Vec::new(),
                }
            })
            .collect()
    }

    fn worst_error(rest: &[[f64; 2]], est: &RestEstimate) -> f64 {
        rest.iter()
            .map(|t| {
                est.pins
                    .iter()
                    .map(|e| (e[0] - t[0]).hypot(e[1] - t[1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    /// Exact points (0.05 px noise, spacing 10 px): the estimate from taps
    /// alone is within 0.2 px of the rest layout, though no tap shows it
    /// undeformed (0.14 px when written: the least pushed taps still push
    /// a little).
    #[test]
    fn rest_layout_of_exact_points() {
        let rest = layout();
        let est = estimate_rest(&taps(&rest, 200, None), rest.len(), &RestParams::default())
            .expect("estimate");
        assert_eq!(est.pins.len(), rest.len());
        assert!(est.dropped.is_empty());
        let worst = worst_error(&rest, &est);
        assert!(worst < 0.2, "worst {worst:.3} px");
        assert!(est.residual > 0.0 && est.residual < 1.0, "{}", est.residual);
    }

    /// Counting a speck as a pin (one more pin than there are, so the
    /// provisional frame holds the speck): the speck is dropped, and the
    /// layout is as good as without it.
    #[test]
    fn a_speck_in_the_provisional_frame_is_dropped() {
        let rest = layout();
        let speck = [rest[30][0] + 3.0, rest[30][1] + 2.0];
        let est = estimate_rest(
            &taps(&rest, 200, Some(speck)),
            rest.len() + 1,
            &RestParams::default(),
        )
        .expect("estimate");
        assert_eq!(est.dropped.len(), 1, "{:?}", est.dropped);
        let d = &est.dropped[0];
        assert!((d[0] - speck[0]).hypot(d[1] - speck[1]) < 1e-9);
        assert_eq!(est.pins.len(), rest.len());
        assert!(worst_error(&rest, &est) < 0.2);
    }

    #[test]
    fn no_frame_with_the_count_is_an_error() {
        let rest = layout();
        assert_eq!(
            estimate_rest(
                &taps(&rest, 5, None),
                rest.len() + 3,
                &RestParams::default()
            ),
            Err(VisionError::NoFrameWithPinCount {
                pins: rest.len() + 3
            })
        );
        let bad = RestParams {
            keep_share: 0.0,
            ..RestParams::default()
        };
        assert!(estimate_rest(&taps(&rest, 5, None), rest.len(), &bad).is_err());
    }
}
