//! Image-oriented charts and displacement arrows for the pin pictures.
//!
//! Pin positions are camera pixels with the y axis pointing down, as in the
//! frame itself; these helpers build such a chart (equal aspect, y reversed)
//! and draw pins and quiver arrows on it, shared by Fig. 4.1 and the
//! simulated-vs-real displacement comparisons.

use super::chart::{builder, plot_pixels};
use super::font::{AXIS_SIZE, FAMILY, LABEL_SIZE};
use super::legend::legend_corner;
use super::range::{equal_aspect, Span};
use super::raster::ImageChart;
use super::render::draw_err;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Half-angle between an arrow's shaft and each barb of its head, degrees.
const HEAD_ANGLE_DEG: f64 = 25.0;
/// Head length as a fraction of the arrow length.
const HEAD_FRACTION: f64 = 0.3;
/// Largest head length as a fraction of the chart width.
const HEAD_MAX_FRACTION: f64 = 0.015;

/// One arrow in data units: a shaft and a triangular head.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Arrow {
    /// From the tail to the base of the head.
    pub shaft: [(f64, f64); 2],
    /// The tip, then the two barb ends.
    pub head: [(f64, f64); 3],
}

/// The arrow from `from` to `to`, its head 30 % of its length but at most
/// `max_head` long; `None` when it has no length or is not finite.
pub(crate) fn arrow(from: [f64; 2], to: [f64; 2], max_head: f64) -> Option<Arrow> {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let length = dx.hypot(dy);
    if !(length.is_finite() && length > 0.0 && from.iter().all(|v| v.is_finite())) {
        return None;
    }
    let head = (HEAD_FRACTION * length).min(max_head);
    let (ux, uy) = (-dx / length, -dy / length);
    let barb = |sign: f64| {
        let (s, c) = (sign * HEAD_ANGLE_DEG).to_radians().sin_cos();
        (
            to[0] + head * (c * ux - s * uy),
            to[1] + head * (s * ux + c * uy),
        )
    };
    let back = head * HEAD_ANGLE_DEG.to_radians().cos();
    Some(Arrow {
        shaft: [(from[0], from[1]), (to[0] + back * ux, to[1] + back * uy)],
        head: [(to[0], to[1]), barb(1.0), barb(-1.0)],
    })
}

/// Builds a chart on `area` (already titled, see [`titled`](super::chart::titled)) showing at
/// least `[x.lo, x.hi] x [y.lo, y.hi]` pixels, with square pixels and the y
/// axis pointing down as in the camera frame.
pub(crate) fn image_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    x: Span,
    y: Span,
) -> Result<ImageChart<'a, DB>, String> {
    let (x, y) = equal_aspect(x, y, plot_pixels(area)?);
    let mut chart = builder(area)
        .build_cartesian_2d(x.lo..x.hi, y.hi..y.lo)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .x_desc("x (px)")
        .y_desc("y (px)")
        .label_style((FAMILY, LABEL_SIZE))
        .axis_desc_style((FAMILY, AXIS_SIZE))
        .draw()
        .map_err(draw_err)?;
    Ok(chart)
}

/// Draws one arrow per pin from `from[k]` to `from[k] + scale * delta[k]`,
/// labelled `label` in the legend.
pub(crate) fn draw_arrows<'a, DB: DrawingBackend + 'a>(
    chart: &mut ImageChart<'a, DB>,
    from: &[[f64; 2]],
    delta: &[[f64; 2]],
    scale: f64,
    colour: RGBColor,
    label: &str,
) -> Result<(), String> {
    let range = chart.x_range();
    let max_head = HEAD_MAX_FRACTION * (range.end - range.start).abs();
    let line = colour.stroke_width(2);
    let arrows: Vec<Arrow> = from
        .iter()
        .zip(delta)
        .filter_map(|(p, d)| arrow(*p, [p[0] + scale * d[0], p[1] + scale * d[1]], max_head))
        .collect();
    chart
        .draw_series(
            arrows
                .iter()
                .map(|a| Polygon::new(a.head.to_vec(), colour.filled())),
        )
        .map_err(draw_err)?;
    chart
        .draw_series(
            arrows
                .iter()
                .map(|a| PathElement::new(a.shaft.to_vec(), line)),
        )
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new([(0, 0), (14, 0)], line)
                + Polygon::new([(20, 0), (12, -4), (12, 4)], colour.filled())
        });
    Ok(())
}

/// Draws pins as circles of `radius` pixels, labelled `label` in the legend.
pub(crate) fn draw_pins<'a, DB: DrawingBackend + 'a>(
    chart: &mut ImageChart<'a, DB>,
    pins: &[[f64; 2]],
    radius: u32,
    style: ShapeStyle,
    label: &str,
) -> Result<(), String> {
    let finite = pins.iter().filter(|p| p.iter().all(|v| v.is_finite()));
    chart
        .draw_series(finite.map(|p| Circle::new((p[0], p[1]), radius, style)))
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| Circle::new((x + 10, y), radius.max(3), style));
    Ok(())
}

/// Draws the legend of an image chart in the corner that `points` (the
/// pins and arrow tips drawn, in pixels) leave emptiest.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ImageChart<'a, DB>,
    points: &[[f64; 2]],
) -> Result<(), String> {
    // The y axis points down, so flip it to count "upper" corners on screen.
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let x = Span {
        lo: xr.start,
        hi: xr.end,
    };
    let y = Span {
        lo: -yr.start,
        hi: -yr.end,
    };
    let flipped: Vec<(f64, f64)> = points.iter().map(|p| (p[0], -p[1])).collect();
    let corner = legend_corner(std::iter::once((flipped.as_slice(), false)), x, y, false);
    chart
        .configure_series_labels()
        .position(corner)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .label_font((FAMILY, LABEL_SIZE))
        .draw()
        .map_err(draw_err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrow_head_geometry() {
        let a = arrow([0.0, 0.0], [10.0, 0.0], 100.0).expect("an arrow");
        assert_eq!(a.head[0], (10.0, 0.0));
        for barb in [a.head[1], a.head[2]] {
            let (dx, dy) = (barb.0 - 10.0, barb.1);
            assert!(
                (dx.hypot(dy) - 3.0).abs() < 1e-12,
                "head is 30 % of the length"
            );
            assert!(
                (dy.abs().atan2(-dx).to_degrees() - 25.0).abs() < 1e-9,
                "25 degree barbs"
            );
        }
        let base = 10.0 - 3.0 * 25f64.to_radians().cos();
        assert!(
            (a.shaft[1].0 - base).abs() < 1e-12 && a.shaft[1].1.abs() < 1e-12,
            "shaft stops at the head"
        );
        let capped = arrow([0.0, 0.0], [0.0, 10.0], 1.0).expect("an arrow");
        assert!(
            (capped.head[1].1 - (10.0 - 25f64.to_radians().cos())).abs() < 1e-12,
            "head capped"
        );
        assert!(arrow([1.0, 1.0], [1.0, 1.0], 1.0).is_none());
        assert!(arrow([f64::NAN, 1.0], [1.0, 1.0], 1.0).is_none());
    }
}
