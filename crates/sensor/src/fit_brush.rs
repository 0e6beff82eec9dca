//! Fit of the brush slip law (eqs. B1-B3) to measured fields, frame by
//! frame with each frame's labelled slide (docs/sensor-model.md, "Brush
//! law"). Pure, like [`crate::fit_slip`]. The contact without slip
//! (eqs. S4-S6) and the indentation along each slide's path do not depend
//! on the brush parameters, so they are computed once per frame.
use crate::contact::{ContactField, PathContact};
use crate::fit::{compare, displacement, FitSample};
use crate::nelder_mead::minimise;
use crate::{SensorError, SlipLaw, TacTipConfig, TacTipModel};
use tactrace_geometry::Vec2;

/// The brush parameters [`fit_brush`] moves, in its vector's order.
pub const BRUSH_PARAMS: [&str; 4] = [
    "mechanics.brush_slip_ratio",
    "mechanics.brush_local_gain",
    "mechanics.brush_skin_gain",
    "mechanics.slip_profile_mm",
];

/// Outcome of [`fit_brush`]: the fitted configuration (slip law set to
/// the brush) and the per-coordinate RMS misfit (px) before and after.
#[derive(Debug, Clone)]
pub struct BrushFit {
    pub config: TacTipConfig,
    pub rms_start_px: f64,
    pub rms_px: f64,
    pub frames: usize,
}

fn to_vec(cfg: &TacTipConfig) -> Vec<f64> {
    let m = &cfg.mechanics;
    vec![
        m.brush_slip_ratio,
        m.brush_local_gain,
        m.brush_skin_gain,
        m.slip_profile_mm,
    ]
}

fn with_vec(cfg: &TacTipConfig, x: &[f64]) -> Option<TacTipConfig> {
    let ok = (0.0..20.0).contains(&x[0])
        && (-5.0..5.0).contains(&x[1])
        && (-5.0..5.0).contains(&x[2])
        && (5.0..300.0).contains(&x[3]);
    ok.then(|| {
        let mut c = cfg.clone();
        let m = &mut c.mechanics;
        m.slip_law = SlipLaw::Brush;
        (m.brush_slip_ratio, m.brush_local_gain) = (x[0], x[1]);
        (m.brush_skin_gain, m.slip_profile_mm) = (x[2], x[3]);
        c
    })
}

/// Per-frame state that the brush parameters do not change.
struct Frame<'a> {
    sample: &'a FitSample,
    field: ContactField,
    path: Option<PathContact>,
}

/// Fit zeta, g_l, g_w and S_T (eqs. B2, B3, S7c) to the samples from
/// `cfg` (its other parameters held); `rest_px` are the rest pins the
/// displacements are measured from. `rounds` restarts of `iterations`
/// Nelder-Mead steps, with halving first steps; `threads` share the frames.
pub fn fit_brush(
    cfg: &TacTipConfig,
    rest_px: Vec<[f64; 2]>,
    samples: &[FitSample],
    (rounds, iterations, threads): (usize, usize, usize),
) -> Result<BrushFit, SensorError> {
    let mut start = cfg.clone();
    start.mechanics.slip_law = SlipLaw::Brush;
    let model = TacTipModel::with_rest_pins(start.clone(), rest_px)?;
    let side = start.calibration.object_side;
    let sd = move |p: Vec2| side * p.y;
    let frames: Vec<Frame> = samples
        .iter()
        .map(|s| Frame {
            sample: s,
            field: model.edge_contact(&s.tap),
            path: s
                .tap
                .sensor_shear(&model)
                .map(|sh| model.path_contact(&sd, s.tap.tip_pose(&model), sh)),
        })
        .collect();
    let threads = threads.max(1);
    let chunk = frames.len().div_ceil(threads).max(1);
    let objective = |x: &[f64]| -> f64 {
        let Some(c) = with_vec(&start, x) else {
            return f64::INFINITY;
        };
        std::thread::scope(|s| {
            let jobs: Vec<_> = frames
                .chunks(chunk)
                .map(|part| s.spawn(|| sum_squares(&model, &c, part)))
                .collect();
            jobs.into_iter().map(|j| j.join().unwrap_or(f64::NAN)).sum()
        })
    };
    let count: usize = samples
        .iter()
        .map(|s| s.disp.iter().flatten().count())
        .sum();
    let rms = |sse: f64| (sse / (2 * count.max(1)) as f64).sqrt();
    let mut x = to_vec(&start);
    let first = objective(&x);
    let step = [0.2, 0.3, 0.3, 10.0];
    for round in 0..rounds {
        let s: Vec<f64> = step.iter().map(|v| v * 0.5f64.powi(round as i32)).collect();
        x = minimise(&objective, &x, &s, iterations).0;
    }
    let best = objective(&x);
    Ok(BrushFit {
        config: with_vec(&start, &x).unwrap_or(start),
        rms_start_px: rms(first),
        rms_px: rms(best),
        frames: samples.len(),
    })
}

/// Sum of squared pin differences (px^2) with the brush law of `cfg`.
fn sum_squares(model: &TacTipModel, cfg: &TacTipConfig, frames: &[Frame]) -> f64 {
    frames
        .iter()
        .map(|f| {
            let slip = f.path.as_ref().map(|p| model.brush_slip(p, &cfg.mechanics));
            let pins = model.compose_slip(&f.field, slip.as_deref());
            compare(&displacement(model, &pins), &f.sample.disp)[0]
        })
        .sum()
}
