//! Where a chart's legend goes: the corner its data leaves emptiest.
//!
//! A fixed upper-right legend hides the top of a predicted-vs-true cloud
//! (Fig. 4.4) while the upper-left corner is empty; counting the data in
//! each corner, lines included, picks a corner that hides least.

use super::range::Span;
use plotters::chart::SeriesLabelPosition;

/// Fraction of the width and height a legend is assumed to cover.
const BOX: (f64, f64) = (0.4, 0.3);
/// Samples taken along each line segment when counting.
const SEGMENT_SAMPLES: usize = 16;

/// The least crowded corner for data drawn as `polylines` (each a list of
/// points; `joined` tells whether consecutive points are connected) on
/// axes `x`, `y`, with `log_y` for a logarithmic y axis.
pub(crate) fn legend_corner<'a>(
    polylines: impl Iterator<Item = (&'a [(f64, f64)], bool)>,
    x: Span,
    y: Span,
    log_y: bool,
) -> SeriesLabelPosition {
    let to_unit = |&(px, py): &(f64, f64)| {
        let v = if log_y {
            (py.log10() - y.lo.log10()) / (y.hi.log10() - y.lo.log10())
        } else {
            (py - y.lo) / y.width()
        };
        ((px - x.lo) / x.width(), v)
    };
    let mut counts = [0usize; 4];
    for (points, joined) in polylines {
        let unit: Vec<(f64, f64)> = points.iter().map(to_unit).collect();
        for p in samples(&unit, joined) {
            if let Some(k) = corner_of(p) {
                counts[k] += 1;
            }
        }
    }
    // The first of equally crowded corners wins, in the order of `corner`.
    match (0..4).min_by_key(|&k| counts[k]) {
        Some(1) => SeriesLabelPosition::UpperLeft,
        Some(2) => SeriesLabelPosition::LowerRight,
        Some(3) => SeriesLabelPosition::LowerLeft,
        _ => SeriesLabelPosition::UpperRight,
    }
}

/// The points themselves, plus samples along segments when `joined`.
fn samples(unit: &[(f64, f64)], joined: bool) -> Vec<(f64, f64)> {
    let mut out = unit.to_vec();
    if joined {
        for pair in unit.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            out.extend((1..SEGMENT_SAMPLES).map(|i| {
                let t = i as f64 / SEGMENT_SAMPLES as f64;
                (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            }));
        }
    }
    out
}

/// The corner box holding unit point `p`, if any: 0 upper right, 1 upper
/// left, 2 lower right, 3 lower left.
fn corner_of((u, v): (f64, f64)) -> Option<usize> {
    let right = u > 1.0 - BOX.0;
    let left = u < BOX.0;
    let top = v > 1.0 - BOX.1;
    let bottom = v < BOX.1;
    match (top, bottom, right, left) {
        (true, _, true, _) => Some(0),
        (true, _, _, true) => Some(1),
        (_, true, true, _) => Some(2),
        (_, true, _, true) => Some(3),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: Span = Span { lo: 0.0, hi: 1.0 };

    #[test]
    fn diagonal_cloud_puts_legend_upper_left() {
        let diagonal: Vec<(f64, f64)> = (0..=100)
            .map(|k| (k as f64 / 100.0, k as f64 / 100.0))
            .collect();
        let corner = legend_corner(
            std::iter::once((diagonal.as_slice(), false)),
            UNIT,
            UNIT,
            false,
        );
        assert!(matches!(corner, SeriesLabelPosition::UpperLeft));
    }

    #[test]
    fn joined_lines_count_between_vertices() {
        // Two vertices only, but the segment crosses the upper-right corner.
        let line = [(0.0, 0.5), (1.0, 0.95)];
        let lower = [(0.9, 0.1), (0.1, 0.1)];
        let data = [(&line[..], true), (&lower[..], false)];
        let corner = legend_corner(data.into_iter(), UNIT, UNIT, false);
        assert!(matches!(corner, SeriesLabelPosition::UpperLeft));
    }

    #[test]
    fn decreasing_log_curve_leaves_upper_right() {
        let loss: Vec<(f64, f64)> = (1..=100)
            .map(|e| (e as f64, 10.0 / (e * e) as f64))
            .collect();
        let (x, y) = (Span { lo: 1.0, hi: 100.0 }, Span { lo: 1e-3, hi: 10.0 });
        let corner = legend_corner(std::iter::once((loss.as_slice(), true)), x, y, true);
        assert!(matches!(corner, SeriesLabelPosition::UpperRight));
    }
}
