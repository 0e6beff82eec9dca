//! The pin pictures: Fig. 4.1 of the report and displacement-field pairs.
//!
//! Fig. 4.1 shows the pipeline from camera frame to feature vector: (a) the
//! binarised frame, (b) the pin centres the blob detector found on it and
//! (c) the reference pins with arrows to the deformed ones, whose
//! differences form the network's input (the report's data collection,
//! step 4: keypoints minus the initial keypoints). [`quiver_pair`]
//! puts two such fields side by side, e.g. simulated against real taps.
//! Everything is drawn in image pixels with the y axis pointing down.

use super::arrows::{draw_arrows, draw_legend, draw_pins, image_chart};
use super::chart::titled;
use super::palette::{colour, GREY};
use super::range::{bounds, padded, Span};
use super::raster::{draw_frame, Raster};
use super::render::{write_both, Figure};
use super::PlotError;
use image::GrayImage;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Size of [`pins_figure`]'s three panels together, in pixels.
const PINS_SIZE: (u32, u32) = (1320, 480);
/// Size of [`quiver_pair`]'s two panels together, in pixels.
const QUIVER_SIZE: (u32, u32) = (1100, 560);

/// Fig. 4.1: (a) `frame`, (b) `frame` with the extracted `pins` marked and
/// (c) the `reference` pins and the deformed `pins`, each reference joined
/// to `reference + arrow_scale * (pin - reference)` by an arrow. Pins are
/// (x, y) pixels of `frame`; non-finite pins are skipped.
pub fn pins_figure(
    stem: &Path,
    frame: &GrayImage,
    reference: &[[f64; 2]],
    pins: &[[f64; 2]],
    arrow_scale: f64,
) -> Result<Vec<PathBuf>, PlotError> {
    let invalid = |reason: String| PlotError::InvalidInput {
        path: stem.to_path_buf(),
        reason,
    };
    if frame.width() == 0 || frame.height() == 0 {
        return Err(invalid("the camera frame is empty".to_owned()));
    }
    if reference.len() != pins.len() {
        return Err(invalid(format!(
            "{} reference pins but {} deformed pins",
            reference.len(),
            pins.len()
        )));
    }
    check_scale(stem, arrow_scale)?;
    let deltas = reference
        .iter()
        .zip(pins)
        .map(|(r, p)| [p[0] - r[0], p[1] - r[1]])
        .collect();
    let figure = PinsFigure {
        frame,
        reference,
        pins,
        deltas,
        scale: arrow_scale,
    };
    write_both(stem, PINS_SIZE, &figure)
}

/// Two displacement fields over the same `pins`, side by side under
/// `titles`: each pin gets an arrow to `pin + arrow_scale * field[k]`.
/// Both panels share one pixel range so their arrows compare directly.
pub fn quiver_pair(
    stem: &Path,
    titles: [&str; 2],
    pins: &[[f64; 2]],
    fields: [&[[f64; 2]]; 2],
    arrow_scale: f64,
) -> Result<Vec<PathBuf>, PlotError> {
    for field in fields {
        if field.len() != pins.len() {
            return Err(PlotError::InvalidInput {
                path: stem.to_path_buf(),
                reason: format!("{} pins but a field of {} vectors", pins.len(), field.len()),
            });
        }
    }
    check_scale(stem, arrow_scale)?;
    let tips = fields.iter().flat_map(|f| tips(pins, f, arrow_scale));
    let corners: Vec<[f64; 2]> = pins.iter().copied().chain(tips).collect();
    let (Some(x), Some(y)) = (
        bounds(corners.iter().map(|p| p[0])),
        bounds(corners.iter().map(|p| p[1])),
    ) else {
        return Err(PlotError::NoData {
            path: stem.to_path_buf(),
        });
    };
    let figure = QuiverPair {
        titles,
        pins,
        fields,
        scale: arrow_scale,
        x: padded(x),
        y: padded(y),
    };
    write_both(stem, QUIVER_SIZE, &figure)
}

fn check_scale(stem: &Path, arrow_scale: f64) -> Result<(), PlotError> {
    if arrow_scale.is_finite() {
        return Ok(());
    }
    Err(PlotError::InvalidInput {
        path: stem.to_path_buf(),
        reason: format!("arrow scale {arrow_scale} is not finite"),
    })
}

/// Arrow tips `pin + scale * delta`.
fn tips<'a>(
    pins: &'a [[f64; 2]],
    deltas: &'a [[f64; 2]],
    scale: f64,
) -> impl Iterator<Item = [f64; 2]> + 'a {
    pins.iter()
        .zip(deltas)
        .map(move |(p, d)| [p[0] + scale * d[0], p[1] + scale * d[1]])
}

/// Legend text of the arrows, e.g. "displacement x5".
fn arrow_label(scale: f64) -> String {
    format!("displacement \u{d7}{scale}")
}

struct PinsFigure<'a> {
    frame: &'a GrayImage,
    reference: &'a [[f64; 2]],
    pins: &'a [[f64; 2]],
    deltas: Vec<[f64; 2]>,
    scale: f64,
}

impl PinsFigure<'_> {
    fn frame_spans(&self) -> (Span, Span) {
        let span = |side: u32| Span {
            lo: 0.0,
            hi: f64::from(side),
        };
        (span(self.frame.width()), span(self.frame.height()))
    }

    fn draw_frame_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        title: &str,
        raster: Raster,
        with_pins: bool,
    ) -> Result<(), String> {
        let (x, y) = self.frame_spans();
        let inner = titled(area, title)?;
        let mut chart = image_chart(&inner, x, y)?;
        draw_frame(&mut chart, self.frame, raster)?;
        if with_pins {
            draw_pins(
                &mut chart,
                self.pins,
                3,
                colour(1).stroke_width(2),
                "pin centre",
            )?;
            draw_legend(&mut chart, self.pins)?;
        }
        Ok(())
    }

    fn draw_field_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), String> {
        let (x, y) = self.frame_spans();
        let inner = titled(area, "(c) displacements")?;
        let mut chart = image_chart(&inner, x, y)?;
        draw_pins(
            &mut chart,
            self.reference,
            3,
            GREY.stroke_width(1),
            "reference pin",
        )?;
        draw_pins(&mut chart, self.pins, 2, colour(0).filled(), "deformed pin")?;
        let label = arrow_label(self.scale);
        draw_arrows(
            &mut chart,
            self.reference,
            &self.deltas,
            self.scale,
            colour(1),
            &label,
        )?;
        let crowd: Vec<[f64; 2]> = self
            .reference
            .iter()
            .copied()
            .chain(tips(self.reference, &self.deltas, self.scale))
            .collect();
        draw_legend(&mut chart, &crowd)
    }
}

impl Figure for PinsFigure<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: Raster,
    ) -> Result<(), String> {
        let panels = root.split_evenly((1, 3));
        self.draw_frame_panel(&panels[0], "(a) camera frame", raster, false)?;
        self.draw_frame_panel(&panels[1], "(b) pin centres", raster, true)?;
        self.draw_field_panel(&panels[2])
    }

    fn frame(&self) -> Option<&GrayImage> {
        Some(self.frame)
    }
}

struct QuiverPair<'a> {
    titles: [&'a str; 2],
    pins: &'a [[f64; 2]],
    fields: [&'a [[f64; 2]]; 2],
    scale: f64,
    x: Span,
    y: Span,
}

impl Figure for QuiverPair<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _: Raster,
    ) -> Result<(), String> {
        let label = arrow_label(self.scale);
        for (k, area) in root.split_evenly((1, 2)).iter().enumerate() {
            let inner = titled(area, self.titles[k])?;
            let mut chart = image_chart(&inner, self.x, self.y)?;
            draw_pins(&mut chart, self.pins, 2, GREY.filled(), "pin")?;
            draw_arrows(
                &mut chart,
                self.pins,
                self.fields[k],
                self.scale,
                colour(k),
                &label,
            )?;
            let crowd: Vec<[f64; 2]> = self
                .pins
                .iter()
                .copied()
                .chain(tips(self.pins, self.fields[k], self.scale))
                .collect();
            draw_legend(&mut chart, &crowd)?;
        }
        Ok(())
    }
}
