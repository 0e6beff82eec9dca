//! The report's figures, built from the generic [`crate::plot`] module.
use crate::error::Result;
use crate::plot::{chart, grid, pins_figure, Axes, Series, Style};
use std::path::{Path, PathBuf};
use tactrace_geometry::Contour;
use tactrace_learn::TrainingHistory;

/// Predictions of a model beside the truth (r mm, theta deg), for Fig. 4.4.
pub struct Predicted<'a> {
    pub truth: &'a [[f64; 2]],
    pub predictions: &'a [[f64; 2]],
    /// The mean absolute errors shown on the panels: position (mm), angle
    /// (deg), as the command that made the predictions reports them.
    pub mae: [f64; 2],
}

/// The title of a model's figures on a dataset: its kind, the model
/// folder's name and the dataset folder's name ("PDenNN pdennn on val").
pub fn model_on_data_title(kind: tactrace_learn::ModelKind, model: &Path, data: &Path) -> String {
    format!(
        "{} {} on {}",
        kind.name(),
        short_name(model),
        short_name(data)
    )
}

/// A folder's last component, cut to 24 characters so titles fit.
fn short_name(path: &Path) -> String {
    let name = path
        .file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy();
    if name.chars().count() <= 24 {
        return name.into_owned();
    }
    let head: String = name.chars().take(23).collect();
    format!("{head}\u{2026}")
}

fn axes(title: &str, x: &str, y: &str) -> Axes {
    Axes::new(title, x, y)
}

/// Fig. 4.5: loss and total energy per epoch for every network, log y.
pub fn training_curves(stem: &Path, history: &TrainingHistory) -> Result<Vec<PathBuf>> {
    let names: Vec<String> = history
        .epochs
        .first()
        .map(|e| e.nets.iter().map(|n| n.name.clone()).collect())
        .unwrap_or_default();
    let series_of = |pick: &dyn Fn(&tactrace_learn::NetEpoch) -> f64| -> Vec<Series> {
        names
            .iter()
            .enumerate()
            .map(|(k, name)| Series {
                name: name.clone(),
                points: history
                    .epochs
                    .iter()
                    .map(|e| (e.epoch as f64 + 1.0, pick(&e.nets[k])))
                    .collect(),
                style: Style::Line,
            })
            .collect()
    };
    let per_epoch = |title: &str, y: &str| Axes {
        log_y: true,
        whole_x: true,
        ..axes(title, "epoch", y)
    };
    let (loss, energy) = (
        per_epoch("Loss per epoch", "loss"),
        per_epoch("Total energy per epoch", "energy"),
    );
    let panels = vec![
        (loss, series_of(&|n| n.loss)),
        (energy, series_of(&|n| n.energy)),
    ];
    grid(stem, 2, &panels, (1200, 480)).map_err(Into::into)
}

/// Fig. 4.4: predicted against true position and angle, each panel titled
/// `name` and its mean absolute error.
pub fn predicted_vs_true(stem: &Path, name: &str, v: &Predicted) -> Result<Vec<PathBuf>> {
    let panel = |k: usize, what: &str, unit: &str| {
        let pts: Vec<(f64, f64)> = v
            .truth
            .iter()
            .zip(v.predictions)
            .map(|(t, p)| (t[k], p[k]))
            .collect();
        let lo = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        let hi = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
        let a = axes(
            &format!("{name}: {what}, MAE {:.3} {unit}", v.mae[k]),
            &format!("true {what} ({unit})"),
            &format!("predicted {what} ({unit})"),
        );
        (
            a,
            vec![
                Series {
                    name: "prediction".into(),
                    points: pts,
                    style: Style::Points,
                },
                Series {
                    name: "ideal".into(),
                    points: vec![(lo, lo), (hi, hi)],
                    style: Style::Dashed,
                },
            ],
        )
    };
    grid(
        stem,
        2,
        &[panel(0, "position r", "mm"), panel(1, "angle theta", "deg")],
        (1200, 480),
    )
    .map_err(Into::into)
}

/// One target's predictions for [`predicted_vs_true_targets`]: its name,
/// unit, `(true, predicted)` points and mean absolute error (wrapped for a
/// circular target, as `validate` reports it).
pub struct TargetPanel {
    pub name: String,
    pub unit: String,
    pub points: Vec<(f64, f64)>,
    pub mae: f64,
}

/// Fig. 4.4 for any targets: one panel a target, predicted against true,
/// titled `name`, the target and its mean absolute error; three panels a
/// row.
pub fn predicted_vs_true_targets(
    stem: &Path,
    name: &str,
    targets: &[TargetPanel],
) -> Result<Vec<PathBuf>> {
    let panels: Vec<_> = targets
        .iter()
        .map(|t| {
            let lo = t.points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let hi = t
                .points
                .iter()
                .map(|p| p.0)
                .fold(f64::NEG_INFINITY, f64::max);
            let a = axes(
                &format!("{name}: {}, MAE {:.3} {}", t.name, t.mae, t.unit),
                &format!("true {} ({})", t.name, t.unit),
                &format!("predicted {} ({})", t.name, t.unit),
            );
            let series = vec![
                Series {
                    name: "prediction".into(),
                    points: t.points.clone(),
                    style: Style::Points,
                },
                Series {
                    name: "ideal".into(),
                    points: vec![(lo, lo), (hi, hi)],
                    style: Style::Dashed,
                },
            ];
            (a, series)
        })
        .collect();
    let cols = targets.len().clamp(1, 3);
    let rows = targets.len().div_ceil(cols).max(1) as u32;
    grid(stem, cols, &panels, (600 * cols as u32, 480 * rows)).map_err(Into::into)
}

/// Fig. 5.3: the trajectory, with the true contour dashed on top of it.
pub fn trajectory(
    stem: &Path,
    title: &str,
    contour: &Contour,
    traj: &[(f64, f64)],
) -> Result<Vec<PathBuf>> {
    let mut a = axes(title, "x (mm)", "y (mm)");
    a.equal_aspect = true;
    chart(
        stem,
        &a,
        &[
            Series {
                name: "trajectory".into(),
                points: traj.to_vec(),
                style: Style::Line,
            },
            contour_series(contour),
        ],
    )
    .map_err(Into::into)
}

/// The true contour as a closed dashed line.
pub fn contour_series(contour: &Contour) -> Series {
    let mut pts: Vec<(f64, f64)> = contour.resample(600).iter().map(|p| (p.x, p.y)).collect();
    if let Some(&first) = pts.first() {
        pts.push(first);
    }
    Series {
        name: "true contour".into(),
        points: pts,
        style: Style::Dashed,
    }
}

/// Fig. 5.4: L2 error along the contour with its mean, against the arc
/// length (mm) from the contour's first point; `curve` is
/// [`tactrace_servo::l2_curve`] of `contour`.
pub fn error_curve(
    stem: &Path,
    title: &str,
    contour: &Contour,
    curve: &[f64],
) -> Result<Vec<PathBuf>> {
    let mean = curve.iter().sum::<f64>() / curve.len().max(1) as f64;
    let arc = tactrace_servo::l2_curve_arc_mm(contour, curve.len());
    let pts = arc.iter().zip(curve).map(|(s, d)| (*s, *d)).collect();
    chart(
        stem,
        &Axes {
            y_from_zero: true,
            ..axes(title, "arc length along the contour (mm)", "L2 error (mm)")
        },
        &[
            Series {
                name: "L2 error".into(),
                points: pts,
                style: Style::Line,
            },
            Series {
                name: format!("mean {mean:.2} mm"),
                points: vec![(0.0, mean), (contour.perimeter(), mean)],
                style: Style::Dashed,
            },
        ],
    )
    .map_err(Into::into)
}

/// Fig. 4.1: a camera frame, the pins extracted from it and their
/// displacement arrows from the undeformed frame's pins (`arrow_scale` x).
pub fn frame_pins_displacements(
    stem: &Path,
    frame: &image::GrayImage,
    extractor: &tactrace_vision::PinExtractor,
    arrow_scale: f64,
) -> Result<Vec<PathBuf>> {
    let tracked = extractor.extract(frame)?;
    let reference = extractor.tracker.reference();
    pins_figure(stem, frame, reference, &tracked.pins, arrow_scale).map_err(Into::into)
}

/// One generation of a tuning run, as the convergence figure shows it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenerationCost {
    /// Simulated runs evaluated so far.
    pub evaluations: usize,
    /// Best cost of this generation.
    pub generation_best: f64,
    /// Best cost so far.
    pub best_so_far: f64,
}

/// A search's convergence: each generation's best and the best so far
/// against the number of evaluations (named `x_label`: the tuning's
/// simulated runs, the transfer fit's candidates), log y; the evaluations
/// listed in `failed` (their x: diverged, invalid, no score) are marked
/// as their own series along the top of the chart.
pub fn convergence(
    stem: &Path,
    (title, x_label): (&str, &str),
    history: &[GenerationCost],
    failed: &[usize],
) -> Result<Vec<PathBuf>> {
    let series = |name: &str, style: Style, f: fn(&GenerationCost) -> f64| Series {
        name: name.into(),
        points: history
            .iter()
            .map(|g| (g.evaluations as f64, f(g)))
            .collect(),
        style,
    };
    let mut all = vec![
        series("generation best", Style::Points, |g| g.generation_best),
        series("best so far", Style::Line, |g| g.best_so_far),
    ];
    if !failed.is_empty() {
        let top = history
            .iter()
            .map(|g| g.generation_best)
            .filter(|c| c.is_finite() && *c > 0.0)
            .fold(f64::NAN, f64::max);
        let top = if top.is_finite() { top * 1.5 } else { 1.0 };
        all.push(Series {
            name: format!("failed ({}): no score", failed.len()),
            points: failed.iter().map(|&x| (x as f64, top)).collect(),
            style: Style::Points,
        });
    }
    chart(
        stem,
        &Axes {
            log_y: true,
            ..axes(title, x_label, "cost")
        },
        &all,
    )
    .map_err(Into::into)
}
