//! Issue 20: the PNG of a line chart drew segments below the x axis,
//! through the tick labels, where the SVG was clean. These tests render
//! jagged curves to PNG and check that no pixel of a series' colour lies
//! outside the plotting area.

use super::chart::{builder, titled};
use super::font::ensure_font;
use super::palette::colour;
use super::{chart, Axes, Series, Style};
use plotters::prelude::*;
use std::path::Path;

/// The plotting area (x0, y0, x1, y1), in pixels, of a one-panel chart of
/// `axes`: the same layout [`chart`] draws.
fn plotting_area(axes: &Axes) -> (i32, i32, i32, i32) {
    assert!(ensure_font());
    let mut buffer = vec![0u8; axes.size.0 as usize * axes.size.1 as usize * 3];
    let root = BitMapBackend::with_buffer(&mut buffer, axes.size).into_drawing_area();
    let area = titled(&root, &axes.title).expect("title");
    let probe = builder(&area)
        .build_cartesian_2d(0.0..1.0, 0.0..1.0)
        .expect("layout");
    let (x, y) = probe.plotting_area().get_pixel_range();
    (x.start, y.start, x.end, y.end)
}

/// Pixels of `rgb` in the PNG at `path` farther than `slack` pixels
/// outside `area`.
fn stray_pixels(path: &Path, rgb: RGBColor, area: (i32, i32, i32, i32), slack: i32) -> usize {
    let png = image::open(path).expect("png decodes").to_rgb8();
    png.enumerate_pixels()
        .filter(|(_, _, p)| p.0 == [rgb.0, rgb.1, rgb.2])
        .filter(|(x, y, _)| {
            let (x, y) = (*x as i32, *y as i32);
            x < area.0 - slack || x >= area.2 + slack || y < area.1 - slack || y >= area.3 + slack
        })
        .count()
}

/// A curve that jumps between 0 and a high value at every sample, the
/// shape of a real L2 error curve (1000 points on 640 pixels).
fn jagged(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let wobble = ((k * 7919) % 13) as f64 / 13.0;
            let y = if k % 2 == 0 { 0.0 } else { 0.2 + wobble };
            (k as f64, y)
        })
        .collect()
}

#[test]
fn png_lines_stay_inside_the_plotting_area() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, style) in [("line", Style::Line), ("linepoints", Style::LinePoints)] {
        let axes = Axes {
            y_from_zero: true,
            ..Axes::new("jagged", "arc length (mm)", "L2 error (mm)")
        };
        let data = [Series {
            name: String::new(),
            points: jagged(1000),
            style,
        }];
        let stem = dir.path().join(name);
        let paths = chart(&stem, &axes, &data).expect("chart");
        // Half a line width (1 px) and a marker radius may reach past the
        // frame where data touches it; nothing may reach the tick labels.
        let stray = stray_pixels(&paths[1], colour(0), plotting_area(&axes), 4);
        assert_eq!(stray, 0, "{name}: {stray} line pixels outside the plot");
    }
}

/// Issue 20: Fig. 5.4 and a follow run's l2_error were plotted against
/// "contour point" 0-1000; they now run along the contour's arc length in
/// mm, and their PNG stays inside the plot like any other chart.
#[test]
fn error_curve_runs_along_the_arc_length_in_mm() {
    let circle: Vec<_> = (0..400)
        .map(|k| {
            let t = k as f64 / 400.0 * std::f64::consts::TAU;
            tactrace_geometry::Vec2::new(53.0 * t.cos(), 53.0 * t.sin())
        })
        .collect();
    let contour = tactrace_geometry::Contour::new(circle).expect("contour");
    let curve: Vec<f64> = jagged(1000).into_iter().map(|p| p.1).collect();
    let dir = tempfile::tempdir().expect("temp dir");
    let stem = dir.path().join("l2_error");
    let paths = crate::figures::error_curve(&stem, "disk", &contour, &curve).expect("error curve");
    let svg = std::fs::read_to_string(&paths[0]).expect("svg");
    assert!(svg.contains("arc length along the contour (mm)"), "x label");
    assert!(!svg.contains("contour point"));
    // The perimeter is 333 mm: ticks reach 300, never the old 1000.
    let ticks: Vec<&str> = svg.lines().map(str::trim).collect();
    assert!(
        ticks.contains(&"300") && !ticks.contains(&"1000"),
        "x ticks"
    );
    let axes = Axes {
        y_from_zero: true,
        ..Axes::new("disk", "arc length along the contour (mm)", "L2 error (mm)")
    };
    for series in 0..2 {
        let stray = stray_pixels(&paths[1], colour(series), plotting_area(&axes), 4);
        assert_eq!(stray, 0, "series {series}: pixels outside the plot");
    }
}
