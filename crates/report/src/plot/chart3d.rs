//! A 3D chart (plotters' 3D coordinates): a surface as a wire mesh and a
//! path over it, seen from a fixed oblique view. Used for the 3D tasks'
//! runs (the sensor's path over a saddle, bowl or wave).
use super::font::{FAMILY, LABEL_SIZE};
use super::palette::colour;
use super::range::{bounds, padded};
use super::raster::Raster;
use super::render::{draw_err, write_both, Figure};
use super::PlotError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// A 3D figure: a wire mesh (lines of points, mm) and named paths (mm).
pub struct Chart3d<'a> {
    /// Caption above the chart.
    pub title: &'a str,
    /// The surface's wire lines, each a polyline (x, y, z) in mm.
    pub wire: &'a [Vec<[f64; 3]>],
    /// Named paths (x, y, z) in mm, drawn over the wire in palette order.
    pub paths: &'a [(&'a str, Vec<[f64; 3]>)],
}

/// Draws `chart` and writes `<stem>.svg` and `<stem>.png` (900 x 700 px).
/// Fails with [`PlotError::NoData`] when nothing finite is left to draw.
pub fn chart_3d(stem: &Path, chart: &Chart3d) -> Result<Vec<PathBuf>, PlotError> {
    let points = || {
        chart
            .wire
            .iter()
            .flatten()
            .chain(chart.paths.iter().flat_map(|(_, p)| p))
            .filter(|p| p.iter().all(|v| v.is_finite()))
    };
    let span = |k: usize| bounds(points().map(|p| p[k])).map(padded);
    let (Some(x), Some(y), Some(z)) = (span(0), span(1), span(2)) else {
        return Err(PlotError::NoData {
            path: stem.to_path_buf(),
        });
    };
    let figure = Figure3d {
        chart,
        ranges: [(x.lo, x.hi), (y.lo, y.hi), (z.lo, z.hi)],
    };
    write_both(stem, (900, 700), &figure)
}

/// A tick label of the axis named `axis`: its value in millimetres, to
/// `decimals` places.
fn tick(axis: &'static str, decimals: usize) -> impl Fn(&f64) -> String {
    move |v| format!("{axis} {v:.decimals$} mm")
}

struct Figure3d<'a> {
    chart: &'a Chart3d<'a>,
    ranges: [(f64, f64); 3],
}

impl Figure for Figure3d<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _raster: Raster,
    ) -> Result<(), String> {
        let [x, y, z] = self.ranges;
        let area = super::chart::titled(root, self.chart.title)?;
        // plotters' 3D axes: x across, y up, z into the page; our z (up) is
        // its y, our y its z.
        let mut chart = ChartBuilder::on(&area)
            .margin(10)
            .build_cartesian_3d(x.0..x.1, z.0..z.1, y.0..y.1)
            .map_err(draw_err)?;
        chart.with_projection(|mut p| {
            p.yaw = 0.6;
            p.pitch = 0.35;
            p.scale = 0.8;
            p.into_matrix()
        });
        // Every tick names its axis and unit (plotters' 3D axes take no
        // axis titles).
        let (x_tick, z_tick, y_tick) = (tick("x", 0), tick("z", 1), tick("y", 0));
        chart
            .configure_axes()
            .label_style((FAMILY, LABEL_SIZE))
            .x_labels(6)
            .y_labels(4)
            .z_labels(6)
            .x_formatter(&x_tick)
            .y_formatter(&z_tick)
            .z_formatter(&y_tick)
            .draw()
            .map_err(draw_err)?;
        let grey = RGBColor(170, 170, 170);
        for line in self.chart.wire {
            let pts = line.iter().map(|p| (p[0], p[2], p[1]));
            chart
                .draw_series(LineSeries::new(pts, grey.stroke_width(1)))
                .map_err(draw_err)?;
        }
        for (i, (name, path)) in self.chart.paths.iter().enumerate() {
            let c = colour(i);
            let pts = path.iter().map(|p| (p[0], p[2], p[1]));
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                .map_err(draw_err)?
                .label(*name)
                .legend(move |(px, py)| {
                    PathElement::new(vec![(px, py), (px + 16, py)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .label_font((FAMILY, LABEL_SIZE))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(draw_err)?;
        Ok(())
    }
}
