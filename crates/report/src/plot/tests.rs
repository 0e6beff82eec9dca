//! Tests of the figure module: every function writes a non-empty SVG and a
//! PNG of the right size; bad data gives errors or is skipped, never a
//! panic; ranges, arrows and the SVG raster embedding check exactly.

use super::*;
use image::GrayImage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A fresh, empty directory for one test's figures, removed on drop.
struct ScratchDir(PathBuf);

impl ScratchDir {
    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn scratch_dir(test: &str) -> ScratchDir {
    let dir = tempfile::Builder::new()
        .prefix(&format!("tactrace-plot-{test}-"))
        .tempdir()
        .expect("temp dir is writable")
        .keep();
    ScratchDir(dir)
}

/// Checks both files exist, are non-empty and the PNG decodes at `size`.
fn check_outputs(paths: &[PathBuf], stem: &Path, size: (u32, u32)) {
    assert_eq!(paths.len(), 2);
    assert_eq!(paths[0], stem.with_extension("svg"));
    assert_eq!(paths[1], stem.with_extension("png"));
    let svg = std::fs::read_to_string(&paths[0]).expect("svg written");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let png = image::open(&paths[1]).expect("png decodes");
    assert_eq!((png.width(), png.height()), size);
}

fn series(name: &str, points: Vec<(f64, f64)>, style: Style) -> Series {
    Series {
        name: name.to_owned(),
        points,
        style,
    }
}

/// 1000 predicted-vs-true points with Gaussian-like noise of 0.3.
fn scatter(seed: u64) -> Vec<(f64, f64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..1000)
        .map(|_| {
            let truth = rng.random_range(-5.0..5.0);
            let noise: f64 = (0..4).map(|_| rng.random_range(-0.3..0.3)).sum();
            (truth, truth + noise)
        })
        .collect()
}

fn predicted_vs_true(seed: u64) -> Vec<Series> {
    vec![
        series("prediction", scatter(seed), Style::Points),
        series("ideal", vec![(-5.0, -5.0), (5.0, 5.0)], Style::Dashed),
    ]
}

/// A hexagonal grid of 127 pins (7 rings) centred in a 256 px frame.
fn hex_pins() -> Vec<[f64; 2]> {
    let mut pins = Vec::new();
    for q in -6i32..=6 {
        for r in -6i32..=6 {
            if (q + r).abs() <= 6 {
                let x = 128.0 + 17.0 * (f64::from(q) + 0.5 * f64::from(r));
                let y = 128.0 + 17.0 * 0.75f64.sqrt() * f64::from(r);
                pins.push([x, y]);
            }
        }
    }
    pins
}

/// A displacement field pushing pins away from a contact at (150, 110).
fn radial_field(pins: &[[f64; 2]]) -> Vec<[f64; 2]> {
    pins.iter()
        .map(|p| {
            let (dx, dy) = (p[0] - 150.0, p[1] - 110.0);
            let d2 = dx * dx + dy * dy + 400.0;
            [300.0 * dx / d2, 300.0 * dy / d2]
        })
        .collect()
}

/// A black frame with a white disc at every pin.
fn synthetic_frame(pins: &[[f64; 2]]) -> GrayImage {
    GrayImage::from_fn(256, 256, |x, y| {
        let near = pins
            .iter()
            .any(|p| (p[0] - f64::from(x)).hypot(p[1] - f64::from(y)) < 4.0);
        image::Luma([if near { 255 } else { 0 }])
    })
}

#[test]
fn chart_writes_scatter_with_dashed_reference() {
    let dir = scratch_dir("scatter");
    let stem = dir.join("pred_vs_true");
    let mut axes = Axes::new("position r", "true r (mm)", "predicted r (mm)");
    axes.size = (640, 480);
    let paths = chart(&stem, &axes, &predicted_vs_true(7)).expect("chart");
    check_outputs(&paths, &stem, (640, 480));
    let svg = std::fs::read_to_string(&paths[0]).expect("svg");
    assert!(
        svg.matches("<circle").count() >= 1000,
        "one marker per point"
    );
    // The dashed y = x line is split into many short polylines.
    assert!(svg.matches("<polyline").count() > 10);
    assert!(svg.contains("prediction") && svg.contains("ideal"));
}

#[test]
fn chart_is_fast() {
    let dir = scratch_dir("timing");
    let axes = Axes::new("timing", "x", "y");
    chart(&dir.join("warm"), &axes, &predicted_vs_true(1)).expect("warm-up");
    let start = Instant::now();
    chart(&dir.join("timed"), &axes, &predicted_vs_true(2)).expect("chart");
    let elapsed = start.elapsed().as_secs_f64();
    // 50 ms is the target on an idle machine; allow for shared cores.
    assert!(elapsed < 0.25, "one chart (svg + png) took {elapsed:.3} s");
}

#[test]
fn chart_log_y_skips_non_positive_values() {
    let dir = scratch_dir("log");
    let stem = dir.join("loss");
    let mut axes = Axes::new("Loss per epoch", "epoch", "loss");
    axes.log_y = true;
    let loss: Vec<(f64, f64)> = (1..=50)
        .map(|e| (f64::from(e), 10.0 / f64::from(e * e)))
        .collect();
    let mut with_zero = loss.clone();
    with_zero.push((51.0, 0.0));
    with_zero.push((52.0, -1.0));
    let data = [
        series("dendritic", with_zero, Style::Line),
        series("backprop", loss, Style::Dashed),
    ];
    check_outputs(
        &chart(&stem, &axes, &data).expect("log chart"),
        &stem,
        (640, 480),
    );
    let only_negative = [series("bad", vec![(1.0, -1.0), (2.0, 0.0)], Style::Line)];
    let err = chart(&dir.join("neg"), &axes, &only_negative).expect_err("no positive data");
    assert!(matches!(err, PlotError::NoData { .. }));
}

#[test]
fn chart_skips_nan_and_rejects_empty_data() {
    let dir = scratch_dir("nan");
    let axes = Axes::new("nan", "x", "y");
    let mixed = [series(
        "mixed",
        vec![
            (0.0, 0.0),
            (f64::NAN, 1.0),
            (1.0, f64::INFINITY),
            (2.0, 1.0),
        ],
        Style::LinePoints,
    )];
    let stem = dir.join("mixed");
    check_outputs(
        &chart(&stem, &axes, &mixed).expect("finite points remain"),
        &stem,
        (640, 480),
    );
    for data in [
        vec![],
        vec![series("empty", vec![], Style::Line)],
        vec![series("nan", vec![(f64::NAN, 0.0)], Style::Points)],
    ] {
        let err = chart(&dir.join("none"), &axes, &data).expect_err("nothing to draw");
        assert!(matches!(err, PlotError::NoData { .. }), "{err}");
    }
}

#[test]
fn chart_equal_aspect_trajectory() {
    let dir = scratch_dir("trajectory");
    let stem = dir.join("disk");
    let mut axes = Axes::new("disk", "x (mm)", "y (mm)");
    axes.equal_aspect = true;
    axes.size = (700, 500);
    let circle = |r: f64, n: usize| -> Vec<(f64, f64)> {
        (0..=n)
            .map(|k| (k as f64 / n as f64 * std::f64::consts::TAU).sin_cos())
            .map(|(s, c)| (r * c, r * s))
            .collect()
    };
    let data = [
        series("true contour", circle(53.0, 400), Style::Dashed),
        series("trajectory", circle(54.0, 60), Style::LinePoints),
    ];
    check_outputs(
        &chart(&stem, &axes, &data).expect("trajectory"),
        &stem,
        (700, 500),
    );
}

#[test]
fn grid_draws_panels_and_tolerates_an_empty_one() {
    let dir = scratch_dir("grid");
    let stem = dir.join("shapes");
    let panel = |title: &str, seed: u64| {
        (
            Axes::new(title, "true (mm)", "predicted (mm)"),
            predicted_vs_true(seed),
        )
    };
    let empty = (
        Axes::new("teardrop", "x", "y"),
        vec![series("nan", vec![(f64::NAN, 1.0)], Style::Line)],
    );
    let panels = vec![
        panel("disk", 1),
        panel("flower", 2),
        panel("trine", 3),
        empty,
    ];
    check_outputs(
        &grid(&stem, 2, &panels, (1000, 800)).expect("grid"),
        &stem,
        (1000, 800),
    );
    let svg = std::fs::read_to_string(stem.with_extension("svg")).expect("svg");
    assert!(svg.contains("no data") && svg.contains("teardrop"));
    let err = grid(&dir.join("zero"), 0, &panels, (800, 600)).expect_err("no columns");
    assert!(matches!(err, PlotError::InvalidInput { .. }));
    let err = grid(&dir.join("none"), 2, &[], (800, 600)).expect_err("no panels");
    assert!(matches!(err, PlotError::NoData { .. }));
}

#[test]
fn pins_figure_embeds_frame_in_svg() {
    let dir = scratch_dir("pins");
    let stem = dir.join("fig4_1");
    let reference = hex_pins();
    assert_eq!(reference.len(), 127);
    let field = radial_field(&reference);
    let pins: Vec<[f64; 2]> = reference
        .iter()
        .zip(&field)
        .map(|(r, d)| [r[0] + d[0], r[1] + d[1]])
        .collect();
    let frame = synthetic_frame(&pins);
    let paths = pins_figure(&stem, &frame, &reference, &pins, 3.0).expect("pins figure");
    check_outputs(&paths, &stem, (1320, 480));
    let svg = std::fs::read_to_string(&paths[0]).expect("svg");
    assert_eq!(
        svg.matches("<image").count(),
        2,
        "panels (a) and (b) show the frame"
    );
    assert!(!svg.contains("#010203"), "no placeholder left");
    let err = pins_figure(&dir.join("bad"), &frame, &reference, &pins[1..], 3.0)
        .expect_err("length mismatch");
    assert!(matches!(err, PlotError::InvalidInput { .. }));
    let err =
        pins_figure(&dir.join("bad"), &frame, &reference, &pins, f64::NAN).expect_err("nan scale");
    assert!(matches!(err, PlotError::InvalidInput { .. }));
}

#[test]
fn pins_figure_on_real_frame() {
    let Some(data) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let path = data.join("frames/init_0.png");
    let frame = image::open(&path).expect("the real reference frame reads");
    let dir = scratch_dir("real");
    let stem = dir.join("init_0");
    let reference = hex_pins();
    let paths =
        pins_figure(&stem, &frame.to_luma8(), &reference, &reference, 1.0).expect("real frame");
    check_outputs(&paths, &stem, (1320, 480));
}

#[test]
fn quiver_pair_compares_fields() {
    let dir = scratch_dir("quiver");
    let stem = dir.join("sim_vs_real");
    let pins = hex_pins();
    let simulated = radial_field(&pins);
    let real: Vec<[f64; 2]> = simulated
        .iter()
        .map(|d| [0.8 * d[0] + 0.2, 0.9 * d[1]])
        .collect();
    let paths = quiver_pair(
        &stem,
        ["simulated", "real"],
        &pins,
        [&simulated, &real],
        4.0,
    )
    .expect("quiver");
    check_outputs(&paths, &stem, (1100, 560));
    let err =
        quiver_pair(&stem, ["a", "b"], &pins, [&simulated, &real[1..]], 4.0).expect_err("length");
    assert!(matches!(err, PlotError::InvalidInput { .. }));
    let nan_pins = vec![[f64::NAN, 1.0]; 3];
    let err = quiver_pair(
        &stem,
        ["a", "b"],
        &nan_pins,
        [&[[0.0; 2]; 3], &[[0.0; 2]; 3]],
        1.0,
    )
    .expect_err("nan");
    assert!(matches!(err, PlotError::NoData { .. }));
}

#[test]
fn bad_size_and_unwritable_path_are_errors() {
    let axes = Axes {
        size: (10, 480),
        ..Axes::new("tiny", "x", "y")
    };
    let data = [series("a", vec![(0.0, 0.0), (1.0, 1.0)], Style::Line)];
    let dir = scratch_dir("errors");
    let err = chart(&dir.join("tiny"), &axes, &data).expect_err("too small");
    assert!(matches!(err, PlotError::InvalidSize { width: 10, .. }));
    let missing = dir.join("no/such/dir/fig");
    let err = chart(&missing, &Axes::new("t", "x", "y"), &data).expect_err("missing dir");
    match err {
        PlotError::Write { path, .. } => assert_eq!(path, missing.with_extension("svg")),
        other => panic!("expected a write error, got {other}"),
    }
}

#[test]
fn stem_keeps_its_dots() {
    let dir = scratch_dir("dots");
    let stem = dir.join("fig4.1");
    let data = [series("a", vec![(0.0, 1.0), (1.0, 2.0)], Style::Line)];
    let paths = chart(&stem, &Axes::new("", "x", "y"), &data).expect("chart");
    assert_eq!(paths[0], dir.join("fig4.1.svg"));
    assert_eq!(paths[1], dir.join("fig4.1.png"));
}
