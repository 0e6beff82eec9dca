//! Contours from CSV text: the way to follow an object that is not one of
//! the report's four.
//!
//! Format: one `x,y` point per line in millimetres (`,`, `;` or whitespace
//! separate the two numbers); an optional header as the first data line;
//! blank lines and `#` comments (whole-line or trailing) are skipped. The
//! outline must be closed: either the last point repeats the first, or the
//! gap between them is no longer than 1.5 times the longest given segment
//! or 1 mm, whichever is larger (a polygon given by its corners closes
//! implicitly; a dense outline with a missing stretch does not). The caller
//! reads the file; this module only parses text.
use crate::validate::dedup_closed;
use crate::{Contour, GeometryError, Vec2};

/// Gaps up to this many longest-segment lengths count as closed.
const CLOSING_GAP_SEGMENTS: f64 = 1.5;
/// Gaps up to this length (mm) always count as closed.
const CLOSING_GAP_MM: f64 = 1.0;

/// Parse CSV text of `x,y` lines (mm; optional header; blank lines and `#`
/// comments skipped). The outline must be closed: the last point repeats
/// the first, or the gap is at most max(1.5 longest segments, 1 mm).
///
/// Errors carry 1-based line numbers for bad lines.
pub fn parse_contour_csv(text: &str) -> Result<Contour, GeometryError> {
    let points = parse_points(text)?;
    let closed = dedup_closed(points.clone());
    if closed.len() < 3 {
        return Err(GeometryError::TooFewPoints {
            points: closed.len(),
            min: 3,
        });
    }
    if points.first() != points.last() {
        check_closing_gap(&closed)?;
    }
    Contour::new(closed)
}

/// The points of every data line, in order.
fn parse_points(text: &str) -> Result<Vec<Vec2>, GeometryError> {
    let mut points = Vec::new();
    let mut seen_data_line = false;
    for (index, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let first = !seen_data_line;
        seen_data_line = true;
        match parse_line(line, index + 1) {
            Ok(p) => points.push(p),
            Err(_) if first && looks_like_header(line) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(points)
}

/// A header has a field that is not a number at all (so `nan,1` is data, and an error).
fn looks_like_header(line: &str) -> bool {
    fields(line).any(|f| f.parse::<f64>().is_err())
}

fn fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c == ',' || c == ';' || c.is_whitespace())
        .filter(|f| !f.is_empty())
}

fn parse_line(line: &str, number: usize) -> Result<Vec2, GeometryError> {
    let bad = |reason: String| GeometryError::BadLine {
        line: number,
        reason,
    };
    let values: Vec<&str> = fields(line).collect();
    if values.len() != 2 {
        return Err(bad(format!(
            "expected two numbers `x,y` in mm, found {} fields in `{line}`",
            values.len()
        )));
    }
    let mut xy = [0.0; 2];
    for (slot, field) in xy.iter_mut().zip(&values) {
        let value: f64 = field
            .parse()
            .map_err(|_| bad(format!("`{field}` is not a number")))?;
        if !value.is_finite() {
            return Err(bad(format!("`{field}` is not a finite number")));
        }
        *slot = value;
    }
    Ok(Vec2::new(xy[0], xy[1]))
}

/// Error when the first and last points are too far apart to be one outline.
fn check_closing_gap(points: &[Vec2]) -> Result<(), GeometryError> {
    let gap = match (points.first(), points.last()) {
        (Some(a), Some(b)) => (a - b).norm(),
        _ => return Ok(()),
    };
    let longest = points
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .fold(0.0, f64::max);
    let tolerance_mm = (CLOSING_GAP_SEGMENTS * longest).max(CLOSING_GAP_MM);
    if gap > tolerance_mm {
        return Err(GeometryError::NotClosed {
            gap_mm: gap,
            tolerance_mm,
        });
    }
    Ok(())
}
