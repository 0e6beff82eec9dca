//! Line and scatter charts, alone ([`chart`]) or in a grid of panels ([`grid`]).
//!
//! Used for the report's training curves (Fig. 4.5, log y), the
//! predicted-vs-true scatters (Fig. 4.4), the trajectories round the shapes
//! (Fig. 5.3, equal aspect) and the error curves (Fig. 5.4). Points are
//! cleaned first (non-finite, and non-positive y on a log axis, dropped),
//! then ranges are fitted to what is left.

use super::font::{AXIS_SIZE, FAMILY, LABEL_SIZE, TITLE_SIZE};
use super::legend::legend_corner;
use super::range::{bounds, equal_aspect, padded, padded_log, tick_label, whole_tick_count, Span};
use super::raster::Raster;
use super::render::{draw_err, write_both, Figure};
use super::series::draw_series;
use super::{Axes, PlotError, Series, Style};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Draws `series` on one chart and writes `<stem>.svg` and `<stem>.png` of
/// `axes.size` pixels. Ranges are fitted to the data with a 5 % margin; a
/// log y axis drops non-positive values; `equal_aspect` widens one axis so
/// millimetres are square. Fails with [`PlotError::NoData`] when no finite
/// point remains.
pub fn chart(stem: &Path, axes: &Axes, series: &[Series]) -> Result<Vec<PathBuf>, PlotError> {
    let panel = Panel::prepare(axes, series).ok_or_else(|| PlotError::NoData {
        path: stem.to_path_buf(),
    })?;
    write_both(
        stem,
        axes.size,
        &Grid {
            cols: 1,
            panels: vec![(axes, Some(panel))],
        },
    )
}

/// Draws several charts side by side, `cols` per row, in one figure of
/// `size` pixels (each panel's own `Axes::size` is ignored). A panel with no
/// finite data shows "no data"; the figure fails with
/// [`PlotError::NoData`] only when every panel is empty.
pub fn grid(
    stem: &Path,
    cols: usize,
    panels: &[(Axes, Vec<Series>)],
    size: (u32, u32),
) -> Result<Vec<PathBuf>, PlotError> {
    if cols == 0 {
        return Err(PlotError::InvalidInput {
            path: stem.to_path_buf(),
            reason: "a grid needs at least one column".to_owned(),
        });
    }
    let prepared: Vec<(&Axes, Option<Panel>)> = panels
        .iter()
        .map(|(axes, series)| (axes, Panel::prepare(axes, series)))
        .collect();
    if prepared.iter().all(|(_, panel)| panel.is_none()) {
        return Err(PlotError::NoData {
            path: stem.to_path_buf(),
        });
    }
    write_both(
        stem,
        size,
        &Grid {
            cols,
            panels: prepared,
        },
    )
}

/// One series after cleaning, with its palette index.
pub(crate) struct Cleaned<'a> {
    pub index: usize,
    pub series: &'a Series,
    pub points: Vec<(f64, f64)>,
}

/// A chart ready to draw: cleaned series and fitted ranges.
struct Panel<'a> {
    axes: &'a Axes,
    series: Vec<Cleaned<'a>>,
    x: Span,
    y: Span,
}

impl<'a> Panel<'a> {
    /// Cleans the series and fits the ranges; `None` when nothing is left.
    fn prepare(axes: &'a Axes, series: &'a [Series]) -> Option<Self> {
        let keep =
            |&(x, y): &(f64, f64)| x.is_finite() && y.is_finite() && (!axes.log_y || y > 0.0);
        let series: Vec<Cleaned> = series
            .iter()
            .enumerate()
            .map(|(index, s)| Cleaned {
                index,
                series: s,
                points: s.points.iter().copied().filter(keep).collect(),
            })
            .filter(|c| !c.points.is_empty())
            .collect();
        let all = || series.iter().flat_map(|c| c.points.iter());
        let x = padded(bounds(all().map(|p| p.0))?);
        let y = bounds(all().map(|p| p.1))?;
        let y = match (axes.log_y, axes.y_from_zero && y.lo >= 0.0) {
            (true, _) => padded_log(y),
            (false, true) => Span {
                lo: 0.0,
                hi: padded(y).hi,
            },
            (false, false) => padded(y),
        };
        Some(Panel { axes, series, x, y })
    }
}

/// Panels laid out row by row; `None` panels had no data.
struct Grid<'a> {
    cols: usize,
    panels: Vec<(&'a Axes, Option<Panel<'a>>)>,
}

impl Figure for Grid<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: Raster,
    ) -> Result<(), String> {
        let cols = self.cols.min(self.panels.len()).max(1);
        let rows = self.panels.len().div_ceil(cols);
        let areas = root.split_evenly((rows, cols));
        for (area, (axes, panel)) in areas.iter().zip(&self.panels) {
            match panel {
                Some(panel) => draw_panel(area, panel, raster)?,
                None => draw_empty(area, &axes.title)?,
            }
        }
        Ok(())
    }
}

/// The area below the title (the whole area when the title is empty).
pub(crate) fn titled<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, String> {
    if title.is_empty() {
        return Ok(area.clone());
    }
    area.titled(title, (FAMILY, TITLE_SIZE)).map_err(draw_err)
}

/// Margins and label areas shared by every chart.
pub(crate) fn builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(8)
        .margin_right(16)
        .x_label_area_size(42)
        .y_label_area_size(64);
    builder
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    raster: Raster,
) -> Result<(), String> {
    let area = titled(area, &panel.axes.title)?;
    let (x, y) = (panel.x, panel.y);
    if panel.axes.log_y {
        let chart = builder(&area)
            .build_cartesian_2d(x.lo..x.hi, (y.lo..y.hi).log_scale())
            .map_err(draw_err)?;
        return fill_chart(chart, panel, raster);
    }
    let (x, y) = if panel.axes.equal_aspect {
        equal_aspect(x, y, plot_pixels(&area)?)
    } else {
        (x, y)
    };
    let chart = builder(&area)
        .build_cartesian_2d(x.lo..x.hi, y.lo..y.hi)
        .map_err(draw_err)?;
    fill_chart(chart, panel, raster)
}

/// Pixel size of the plotting area [`builder`] leaves inside `area`.
pub(crate) fn plot_pixels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
) -> Result<(u32, u32), String> {
    let probe = builder(area)
        .build_cartesian_2d(0.0..1.0, 0.0..1.0)
        .map_err(draw_err)?;
    Ok(probe.plotting_area().dim_in_pixel())
}

fn fill_chart<'a, DB, Y>(
    mut chart: ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    panel: &Panel,
    raster: Raster,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let (x_width, y_width) = (panel.x.width(), panel.y.width());
    {
        let mut mesh = chart.configure_mesh();
        if let Some(count) = whole_tick_count(panel.x).filter(|_| panel.axes.whole_x) {
            mesh.x_labels(count);
        }
        mesh.x_label_formatter(&|v| tick_label(*v, x_width))
            .y_label_formatter(&|v| tick_label(*v, y_width))
            .x_desc(panel.axes.x_label.as_str())
            .y_desc(panel.axes.y_label.as_str())
            .label_style((FAMILY, LABEL_SIZE))
            .axis_desc_style((FAMILY, AXIS_SIZE))
            .bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(240, 240, 240))
            .draw()
            .map_err(draw_err)?;
    }
    for cleaned in &panel.series {
        draw_series(&mut chart, cleaned, raster)?;
    }
    if panel.series.iter().any(|c| !c.series.name.is_empty()) {
        chart
            .configure_series_labels()
            .position(legend_position(panel))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font((FAMILY, LABEL_SIZE))
            .draw()
            .map_err(draw_err)?;
    }
    Ok(())
}

/// The corner of `panel` its data crowds least.
fn legend_position(panel: &Panel) -> SeriesLabelPosition {
    let polylines = panel
        .series
        .iter()
        .map(|c| (c.points.as_slice(), c.series.style != Style::Points));
    legend_corner(polylines, panel.x, panel.y, panel.axes.log_y)
}

/// A panel without data: its title and a grey "no data".
fn draw_empty<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<(), String> {
    let area = titled(area, title)?;
    let (w, h) = area.dim_in_pixel();
    let style = TextStyle::from((FAMILY, AXIS_SIZE))
        .color(&RGBColor(120, 120, 120))
        .pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Center,
        ));
    area.draw_text("no data", &style, (w as i32 / 2, h as i32 / 2))
        .map_err(draw_err)
}
