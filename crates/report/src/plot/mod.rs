//! Figures for the report: a small plotting vocabulary over plotters.
//!
//! Why this module exists: every figure of the report (training curves,
//! predicted-vs-true scatters, trajectories round the shapes, the pin
//! pictures of Fig. 4.1) is one of four kinds of picture. Callers describe
//! *what* to draw with [`Series`] and [`Axes`]; this module decides *how*
//! (palette, margins, legend, fonts) and writes every figure twice, as
//! `<stem>.svg` and `<stem>.png`, so the HTML report and papers can pick.
//!
//! Conventions: chart coordinates are the caller's units (mm, deg, epochs);
//! pin pictures are in image pixels with the y axis pointing down, as in the
//! camera frame. Non-finite points (and non-positive ones on a log axis) are
//! skipped; a figure with nothing left to draw is a [`PlotError::NoData`].
//! Fonts are the embedded DejaVu Sans, so no system fonts are needed.

mod arrows;
mod chart;
mod chart3d;
mod font;
mod legend;
mod palette;
mod pins;
mod range;
mod raster;
mod render;
mod series;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_clip;

use std::path::PathBuf;

pub use chart::{chart, grid};
pub use chart3d::{chart_3d, Chart3d};
pub use pins::{pins_figure, quiver_pair};

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// A solid line through the points in order.
    Line,
    /// A dashed line through the points in order (references such as y = x).
    Dashed,
    /// Small translucent markers only (scatters of up to thousands of points).
    Points,
    /// A solid line with a marker on every point (trajectories).
    LinePoints,
}

/// One named set of points; its colour is fixed by its position in the list.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry; an empty name leaves the series out of the legend.
    pub name: String,
    /// (x, y) in the chart's units.
    pub points: Vec<(f64, f64)>,
    /// Line or marker style.
    pub style: Style,
}

/// Titles and scales of one chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Axes {
    /// Caption above the chart (may be empty).
    pub title: String,
    /// Label of the horizontal axis, with its unit.
    pub x_label: String,
    /// Label of the vertical axis, with its unit.
    pub y_label: String,
    /// Logarithmic y axis; non-positive y values are skipped.
    pub log_y: bool,
    /// One x unit spans as many pixels as one y unit (keeps mm square).
    pub equal_aspect: bool,
    /// A linear y axis over non-negative data starts at 0 (errors,
    /// distances) instead of padding below it.
    pub y_from_zero: bool,
    /// The x axis counts whole things (epochs): ticks only at whole
    /// numbers, never at 1.5 on a short run.
    pub whole_x: bool,
    /// Figure size in pixels for [`chart`]; ignored by [`grid`] panels.
    pub size: (u32, u32),
}

impl Axes {
    /// Linear axes of 640 x 480 pixels with the given title and labels.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Axes {
            title: title.to_owned(),
            x_label: x_label.to_owned(),
            y_label: y_label.to_owned(),
            log_y: false,
            equal_aspect: false,
            y_from_zero: false,
            whole_x: false,
            size: (640, 480),
        }
    }
}

/// Why a figure could not be written; every variant names the figure.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Nothing finite (or positive, on a log axis) was left to draw.
    #[error("figure {path}: no finite data to plot")]
    NoData { path: PathBuf },
    /// The requested figure size is outside 64..=8192 pixels a side.
    #[error("figure {path}: size {width}x{height} px is outside 64..=8192")]
    InvalidSize {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    /// Inconsistent inputs, e.g. pin lists of different lengths.
    #[error("figure {path}: {reason}")]
    InvalidInput { path: PathBuf, reason: String },
    /// The embedded font could not be loaded.
    #[error("figure {path}: cannot load the embedded DejaVu font")]
    Font { path: PathBuf },
    /// plotters failed while drawing.
    #[error("figure {path}: drawing failed: {message}")]
    Draw { path: PathBuf, message: String },
    /// The PNG could not be encoded.
    #[error("figure {path}: PNG encoding failed")]
    Encode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// The file could not be written.
    #[error("figure {path}: cannot write file")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}
