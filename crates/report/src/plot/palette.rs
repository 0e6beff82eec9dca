//! The fixed colour-blind-friendly palette, assigned in series order.
//!
//! Okabe & Ito's eight colours, reordered so that the first ones contrast
//! well on white (the pale yellow comes last). Series `k` always gets
//! colour `k mod 8`, so the same network keeps its colour across figures.

use plotters::style::RGBColor;

const OKABE_ITO: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(240, 228, 66),  // yellow
];

/// The colour of the `index`-th series.
pub(crate) fn colour(index: usize) -> RGBColor {
    OKABE_ITO[index % OKABE_ITO.len()]
}

/// Light grey for the reference pins and grid lines.
pub(crate) const GREY: RGBColor = RGBColor(150, 150, 150);
