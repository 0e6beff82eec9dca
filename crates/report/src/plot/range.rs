//! Axis ranges: data bounds, padding, log-scale limits and equal aspect.
//!
//! Pure arithmetic kept apart from drawing so it can be tested exactly.
//! Every range returned is finite with `lo < hi`, which plotters' tick
//! generator requires (it asserts on NaN).

/// A closed interval `[lo, hi]` of one axis, in data units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Span {
    pub lo: f64,
    pub hi: f64,
}

impl Span {
    /// Width of the span.
    pub fn width(self) -> f64 {
        self.hi - self.lo
    }

    fn centre(self) -> f64 {
        0.5 * (self.lo + self.hi)
    }

    /// The span widened to `width` about its centre.
    fn with_width(self, width: f64) -> Span {
        let c = self.centre();
        Span {
            lo: c - 0.5 * width,
            hi: c + 0.5 * width,
        }
    }
}

/// Fraction of the data width added on each side of an axis.
pub(crate) const MARGIN: f64 = 0.05;

/// Smallest and largest of `values`, ignoring non-finite ones.
pub(crate) fn bounds(values: impl IntoIterator<Item = f64>) -> Option<Span> {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(None, |acc: Option<Span>, v| match acc {
            None => Some(Span { lo: v, hi: v }),
            Some(s) => Some(Span {
                lo: s.lo.min(v),
                hi: s.hi.max(v),
            }),
        })
}

/// Linear axis: the bounds padded by [`MARGIN`]; a single value gets a
/// width of 10 % of its magnitude (or 1 when it is zero).
pub(crate) fn padded(span: Span) -> Span {
    let width = span.width();
    if width > f64::EPSILON * span.lo.abs().max(span.hi.abs()).max(1.0) {
        return Span {
            lo: span.lo - MARGIN * width,
            hi: span.hi + MARGIN * width,
        };
    }
    let half = if span.lo == 0.0 {
        0.5
    } else {
        0.05 * span.lo.abs()
    };
    Span {
        lo: span.lo - half,
        hi: span.hi + half,
    }
}

/// Log axis over positive bounds: padded by [`MARGIN`] in decades and at
/// least one decade wide, so the axis always carries labelled ticks.
pub(crate) fn padded_log(span: Span) -> Span {
    let decades = Span {
        lo: span.lo.log10(),
        hi: span.hi.log10(),
    };
    let decades = decades.with_width(decades.width().max(1.0) * (1.0 + 2.0 * MARGIN));
    Span {
        lo: 10f64.powf(decades.lo),
        hi: 10f64.powf(decades.hi),
    }
}

/// Widens one of the spans so a data unit spans the same number of pixels
/// on both axes of a plotting area of `pixels` (width, height).
pub(crate) fn equal_aspect(x: Span, y: Span, pixels: (u32, u32)) -> (Span, Span) {
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    let per_pixel = (x.width() / w).max(y.width() / h);
    (x.with_width(per_pixel * w), y.with_width(per_pixel * h))
}

/// How many x labels to ask plotters for so that every tick of `span`
/// falls on a whole number: at most 10, and never more than the whole
/// numbers inside it (plotters picks the finest step of 10^k times 1, 2
/// or 5 that gives no more labels than asked; a step under 1 gives more
/// ticks than there are whole numbers once two are inside, and with one
/// inside its only tick is that number). `None` when no whole number
/// lies inside `span`.
pub(crate) fn whole_tick_count(span: Span) -> Option<usize> {
    let inside = span.hi.floor() - span.lo.ceil() + 1.0;
    (inside >= 1.0).then(|| (inside as usize).min(10))
}

/// A tick label without float noise or needless zeros: "5" rather than
/// "5.0", "0.25", "0.001"; scientific notation outside 1e-3..1e5.
/// Values smaller than a billionth of the axis `width` print as "0".
pub(crate) fn tick_label(value: f64, width: f64) -> String {
    let magnitude = value.abs();
    if !value.is_finite() || magnitude <= 1e-9 * width.abs() || magnitude == 0.0 {
        return "0".to_owned();
    }
    if !(1e-3..1e5).contains(&magnitude) {
        let text = format!("{value:.3e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        return format!("{}e{exponent}", trim_zeros(mantissa));
    }
    let decimals = (5.0 - magnitude.log10().floor()).clamp(0.0, 9.0) as usize;
    trim_zeros(&format!("{value:.decimals$}")).to_owned()
}

/// "2.500" -> "2.5", "3.000" -> "3"; integers are left alone.
fn trim_zeros(number: &str) -> &str {
    if !number.contains('.') {
        return number;
    }
    number.trim_end_matches('0').trim_end_matches('.')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_pad_and_equalise() {
        let span = bounds([3.0, f64::NAN, -1.0, 1.0]).expect("finite values");
        assert_eq!(span, Span { lo: -1.0, hi: 3.0 });
        let p = padded(span);
        assert!((p.lo + 1.2).abs() < 1e-12 && (p.hi - 3.2).abs() < 1e-12);
        let single = padded(Span { lo: 0.0, hi: 0.0 });
        assert!(single.lo < 0.0 && single.hi > 0.0);
        let log = padded_log(Span { lo: 2.0, hi: 3.0 });
        assert!(
            (log.hi / log.lo).log10() >= 1.0 - 1e-12,
            "at least one decade"
        );
        let (x, y) = equal_aspect(
            Span { lo: 0.0, hi: 10.0 },
            Span { lo: 0.0, hi: 2.0 },
            (500, 400),
        );
        assert!(
            (x.width() / 500.0 - y.width() / 400.0).abs() < 1e-12,
            "same units per pixel"
        );
        assert!((x.width() - 10.0).abs() < 1e-12 && (y.lo + y.hi - 2.0).abs() < 1e-12);
    }

    #[test]
    fn whole_ticks_never_ask_for_more_labels_than_whole_numbers() {
        let span = |lo, hi| Span { lo, hi };
        assert_eq!(whole_tick_count(span(0.8, 5.2)), Some(5));
        assert_eq!(whole_tick_count(span(0.95, 1.05)), Some(1));
        assert_eq!(whole_tick_count(span(1.0, 2.0)), Some(2));
        assert_eq!(whole_tick_count(span(-4.0, 300.0)), Some(10));
        assert_eq!(whole_tick_count(span(1.1, 1.9)), None);
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(5.0, 10.0), "5");
        assert_eq!(tick_label(-2.5, 10.0), "-2.5");
        assert_eq!(tick_label(0.1 + 0.2, 1.0), "0.3");
        assert_eq!(tick_label(0.01, 10.0), "0.01");
        assert_eq!(tick_label(1e-17, 1.0), "0");
        assert_eq!(tick_label(250_000.0, 1e6), "2.5e5");
        assert_eq!(tick_label(1e-4, 1.0), "1e-4");
        assert_eq!(tick_label(120.0, 300.0), "120");
    }
}
