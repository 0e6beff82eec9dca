//! How each [`Style`] is drawn, and its legend sample.
//!
//! Kept apart from the chart layout so every style (solid, dashed, markers,
//! line with markers) has one place defining its look on both backends.
//!
//! Solid lines are one path in SVG but separate segments on the bitmap
//! backend: plotters turns a path wider than one pixel into a single
//! polygon whose inner corners, where a jagged curve turns back on itself
//! (an L2 error curve of 1000 points on 600 pixels), are mitred with no
//! limit, so the PNG showed spikes reaching far outside the plot, through
//! the tick labels. A two-point path has no corner to mitre.

use super::chart::Cleaned;
use super::palette::colour;
use super::raster::Raster;
use super::render::draw_err;
use super::Style;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// Line width of solid and dashed lines, in pixels.
const LINE_WIDTH: u32 = 2;
/// Dash and gap lengths of [`Style::Dashed`], in pixels.
const DASH: (u32, u32) = (8, 5);
/// Marker radius of [`Style::Points`] (thousands of points stay readable).
const SCATTER_RADIUS: u32 = 2;
/// Marker opacity of [`Style::Points`], so dense clouds show their density.
const SCATTER_ALPHA: f64 = 0.5;
/// Marker radius of [`Style::LinePoints`].
const VERTEX_RADIUS: u32 = 3;
/// Length of the legend sample line, in pixels.
const SAMPLE: i32 = 24;

/// Draws one cleaned series on `chart` and registers its legend entry;
/// `raster` says which backend draws (see the module docs for why lines
/// differ).
pub(crate) fn draw_series<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    cleaned: &Cleaned,
    raster: Raster,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64>,
{
    let rgb = colour(cleaned.index);
    let line = rgb.stroke_width(LINE_WIDTH);
    let points = cleaned.points.iter().copied();
    let anno = match cleaned.series.style {
        Style::Line => solid_line(chart, &cleaned.points, line, raster),
        Style::Dashed => chart.draw_series(DashedLineSeries::new(points, DASH.0, DASH.1, line)),
        Style::Points => {
            let fill = rgb.mix(SCATTER_ALPHA).filled();
            chart.draw_series(points.map(|p| Circle::new(p, SCATTER_RADIUS, fill)))
        }
        Style::LinePoints => {
            solid_line(chart, &cleaned.points, line, raster).map_err(draw_err)?;
            chart.draw_series(points.map(|p| Circle::new(p, VERTEX_RADIUS, rgb.filled())))
        }
    }
    .map_err(draw_err)?;
    let name = &cleaned.series.name;
    if name.is_empty() {
        return Ok(());
    }
    let anno = anno.label(name.as_str());
    match cleaned.series.style {
        Style::Line => anno.legend(move |(x, y)| PathElement::new([(x, y), (x + SAMPLE, y)], line)),
        Style::Dashed => anno.legend(move |(x, y)| {
            DashedPathElement::new([(x, y), (x + SAMPLE, y)], DASH.0, DASH.1, line)
        }),
        Style::Points => {
            anno.legend(move |(x, y)| Circle::new((x + SAMPLE / 2, y), VERTEX_RADIUS, rgb.filled()))
        }
        Style::LinePoints => anno.legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new([(0, 0), (SAMPLE, 0)], line)
                + Circle::new((SAMPLE / 2, 0), VERTEX_RADIUS, rgb.filled())
        }),
    };
    Ok(())
}

/// A solid polyline through `points`: one path in SVG, one two-point path
/// per segment on a bitmap (no mitred corners; see the module docs).
fn solid_line<'a, 'c, DB, Y>(
    chart: &'c mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    points: &[(f64, f64)],
    line: ShapeStyle,
    raster: Raster,
) -> Result<
    &'c mut plotters::chart::SeriesAnno<'a, DB>,
    plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>,
>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64>,
{
    match raster {
        Raster::Placeholder => chart.draw_series(LineSeries::new(points.iter().copied(), line)),
        Raster::Blit => chart.draw_series(
            points
                .windows(2)
                .map(|pair| PathElement::new(vec![pair[0], pair[1]], line)),
        ),
    }
}
