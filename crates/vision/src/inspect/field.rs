//! The pin field of the inspected frames: the mask that keeps every pin
//! and leaves out the rim and its specks (steps 3-4 of the inspection), and
//! how many pins a frame holds (step 5).

use super::geometry::{distance, neighbour_counts};
use super::{Blob, Sizes};
use crate::preprocess::MaskCircle;

/// The mask (steps 3-4 of the module docs).
pub(super) fn mask_circle(
    found: &[Vec<Blob>],
    sizes: &Sizes,
    centre: [f64; 2],
    spacing: f64,
    rim: Option<MaskCircle>,
    rim_pixels: &[[f64; 2]],
) -> MaskCircle {
    let mut outers = Vec::with_capacity(found.len());
    for blobs in found {
        let mut outer = 0.0f64;
        let solid: Vec<[f64; 2]> = blobs
            .iter()
            .filter(|b| b.pixels as f64 >= 0.5 * sizes.median && b.pixels <= sizes.max)
            .map(|b| b.centre)
            .collect();
        let near = neighbour_counts(&solid, 1.5 * spacing);
        for (p, n) in solid.iter().zip(near) {
            let r = distance(*p, centre);
            let inside_rim = rim.is_none_or(|c| r < c.radius);
            if n >= 2 && inside_rim {
                outer = outer.max(r);
            }
        }
        outers.push(outer);
    }
    outers.sort_unstable_by(f64::total_cmp);
    let outer = outers[(outers.len() - 1) * 9 / 10];
    let lower = outer + 0.25 * spacing;
    let upper = match rim {
        Some(c) => {
            let mut d: Vec<f64> = rim_pixels.iter().map(|&p| distance(p, c.centre)).collect();
            d.sort_unstable_by(f64::total_cmp);
            d[d.len() / 50] - 0.5
        }
        None => outer + spacing,
    };
    let speck = static_specks(found, sizes, centre, lower)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    let radius = (speck - 0.5).min(upper).max(lower);
    let round = |v: f64| (v * 100.0).round() / 100.0;
    MaskCircle {
        centre: [round(centre[0]), round(centre[1])],
        radius: round(radius),
    }
}

/// Radii (from `centre`) of the static specks beyond `lower`: components
/// of pin or cluster size there with a component within half a pixel in
/// at least a quarter of the frames (the rim is still, though a speck of a
/// pixel or two comes and goes; a pin pushed out by a tap is somewhere
/// else each time).
fn static_specks(found: &[Vec<Blob>], sizes: &Sizes, centre: [f64; 2], lower: f64) -> Vec<f64> {
    let beyond = |b: &&Blob| {
        (sizes.min..=sizes.max_cluster).contains(&b.pixels) && distance(b.centre, centre) > lower
    };
    let mut out = Vec::new();
    for b in found.iter().flatten().filter(beyond) {
        let seen = found
            .iter()
            .filter(|f| {
                f.iter()
                    .filter(beyond)
                    .any(|o| distance(o.centre, b.centre) <= 0.5)
            })
            .count();
        if 4 * seen >= found.len() {
            out.push(distance(b.centre, centre));
        }
    }
    out
}

/// The pins a frame holds inside the mask: its pins, plus for each
/// cluster its pixel count over the median size of the pins within two
/// spacings of it, rounded (a merged pair of small pins counts two, one
/// large pin among large pins one).
pub(super) fn pin_sites(
    blobs: &[Blob],
    sizes: &Sizes,
    spacing: f64,
    inside: &dyn Fn([f64; 2]) -> bool,
) -> usize {
    let kept: Vec<&Blob> = blobs.iter().filter(|b| inside(b.centre)).collect();
    let single = |b: &Blob| (sizes.min..=sizes.max).contains(&b.pixels);
    let mut sites = kept.iter().filter(|b| single(b)).count();
    for c in kept
        .iter()
        .filter(|b| b.pixels > sizes.max && b.pixels <= sizes.max_cluster)
    {
        let mut near: Vec<usize> = kept
            .iter()
            .filter(|b| single(b) && distance(b.centre, c.centre) < 2.0 * spacing)
            .map(|b| b.pixels)
            .collect();
        near.sort_unstable();
        let local = near.get(near.len() / 2).map_or(sizes.median, |&n| n as f64);
        sites += ((c.pixels as f64 / local).round() as usize).max(1);
    }
    sites
}

/// The pin count from the per-frame counts: their 20th percentile. A
/// speck inside the mask (dust on the lens, a fleck of the rim) adds to a
/// frame's count; counts fall short only when a cluster is miscounted.
pub(super) fn low_count(counts: &[usize]) -> usize {
    let mut sorted = counts.to_vec();
    sorted.sort_unstable();
    sorted
        .get(sorted.len().saturating_sub(1) / 5)
        .copied()
        .unwrap_or(0)
}
