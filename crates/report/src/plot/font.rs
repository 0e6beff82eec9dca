//! Registers the embedded DejaVu Sans font with plotters, once per process.
//!
//! plotters' ab_glyph text backend only knows fonts registered by name; the
//! machines that build the report may have no system fonts at all, so the
//! family every figure uses, [`FAMILY`], is bound to DejaVu Sans here.

use std::sync::OnceLock;

/// The font family name every figure draws its text with.
pub(crate) const FAMILY: &str = "sans-serif";

// Text sizes in pixels. They are even on purpose: plotters' ab_glyph
// backend places each glyph at `size / 2 + top` truncated to an integer,
// which with odd sizes lifts small glyphs such as "." by a pixel.
/// Tick labels and legend entries.
pub(crate) const LABEL_SIZE: u32 = 14;
/// Axis descriptions.
pub(crate) const AXIS_SIZE: u32 = 16;
/// Chart titles.
pub(crate) const TITLE_SIZE: u32 = 18;

static REGISTERED: OnceLock<bool> = OnceLock::new();

/// Registers DejaVu Sans under [`FAMILY`]; returns whether it is available.
pub(crate) fn ensure_font() -> bool {
    *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            FAMILY,
            plotters::style::FontStyle::Normal,
            dejavu::sans::regular(),
        )
        .is_ok()
    })
}
