//! The label convention of a user's sensor found from its labelled taps
//! (docs/calibration.md, "The label convention"): which way the labelled
//! angle turns the simulated edge (its sign), where its zero lies (the
//! angle offset, over the whole circle), which way the labelled position
//! moves the edge (its sign) and where its zero lies (the edge offset).
//!
//! A local fit cannot find these: the misfit of a wrong sign or an offset
//! half a turn away is a valley of its own. So every discrete convention
//! (angle sign x position sign) is scanned over the whole circle of angle
//! offsets, its best offset refined with the edge offset by Nelder-Mead,
//! and the conventions compared by the mean cosine between the simulated
//! and the measured fields (eqs. S4-S8a, each tap with its labelled
//! slide): the cosine judges where and which way the skin moves, not how
//! far, so a simulator whose mechanics are not yet this sensor's (taps
//! too deep or too shallow) still ranks the conventions right, where the
//! RMS misfit prefers an edge moved away from the dome (no field at all).
//! The conventions are scanned on the taps without their slides (a slide
//! turned the wrong way hides the edge's pattern); the slide's sign and
//! angle offset are then scanned round the circle under the convention
//! found. The object's side needs no scan: the object on the other side
//! with the angle offset turned by 180 deg and the position's sign and
//! offset negated is the same tap. Pure, like [`crate::fit_joint`].
use crate::fit::{misfit_sums, FitSample};
use crate::nelder_mead::minimise;
use crate::{wrap_deg, EdgeTap, SensorError, TacTipConfig, TacTipModel};
use serde::{Deserialize, Serialize};

/// How to search for the convention.
#[derive(Debug, Clone, PartialEq)]
pub struct ConventionSearch {
    /// Step of the angle-offset scan round the circle, degrees.
    pub angle_step_deg: f64,
    /// Nelder-Mead steps refining each convention's best scanned offset.
    pub iterations: usize,
    /// Threads the taps are simulated on.
    pub threads: usize,
}

impl Default for ConventionSearch {
    /// 15 deg steps, 60 refining steps, one thread.
    fn default() -> Self {
        Self {
            angle_step_deg: 15.0,
            iterations: 60,
            threads: 1,
        }
    }
}

/// One label convention and how well the simulator, set to it, matches
/// the measured taps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConventionScore {
    /// Sign of the model angle per degree of labelled angle (+1 or -1).
    pub angle_sign: f64,
    /// Sign of the model edge position per mm of labelled position.
    pub edge_sign: f64,
    /// The angle offset (deg) and edge offset (mm) of the convention.
    pub angle_offset_deg: f64,
    pub edge_offset_mm: f64,
    /// The slide's sign and angle offset (deg, eq. S7d) under it.
    pub shear_sign: f64,
    pub shear_angle_offset_deg: f64,
    /// Per-coordinate RMS pin misfit over the taps, px.
    pub rms_px: f64,
    /// Mean per-tap cosine between the simulated and measured fields:
    /// the score the conventions are ranked by (1 = same directions).
    pub cosine: f64,
}

impl ConventionScore {
    /// The signs as "+/-" for angle then position, e.g. "-+".
    pub fn signs(&self) -> String {
        let sign = |v: f64| if v < 0.0 { '-' } else { '+' };
        format!("{}{}", sign(self.angle_sign), sign(self.edge_sign))
    }
}

/// What [`fit_convention`] found: the configuration to use, and the
/// evidence (the sensor's own convention and every convention's best).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConventionFit {
    /// True when the given configuration's own convention was kept (no
    /// other convention matched the taps better, or the best is its own
    /// within one scan step): the configuration is then unchanged.
    pub kept_own: bool,
    /// The given configuration's convention and misfit.
    pub own: ConventionScore,
    /// The convention used (scored on the taps with their slides when it
    /// is not the sensor's own and some tap slid).
    pub chosen: ConventionScore,
    /// Each discrete convention's best after refining, best first.
    pub candidates: Vec<ConventionScore>,
    /// Taps it was judged on.
    pub taps: usize,
}

impl ConventionFit {
    /// One line for the user: the convention used and the evidence (the
    /// field cosines of the taps without their slides, then the slide's
    /// sign and offset with the cosine of the taps with them).
    pub fn describe(&self) -> String {
        let c = &self.chosen;
        let what = if self.kept_own {
            "the sensor's own kept"
        } else {
            "estimated from the taps"
        };
        let others: Vec<String> = self
            .candidates
            .iter()
            .map(|k| format!("{} {:.3}", k.signs(), k.cosine))
            .collect();
        let slid = if self.kept_own {
            String::new()
        } else {
            format!("; with slides {:.3}, RMS {:.3} px", c.cosine, c.rms_px)
        };
        format!(
            "label convention ({what}, {} taps): angle sign {:+}, position sign {:+}, \
             angle offset {:.1} deg, edge offset {:.2} mm, slide sign {:+} turned {:.1} deg; \
             field cosine without slides: the sensor's own {:.3}, best of each sign pair \
             (angle, position) {}{slid}",
            self.taps,
            c.angle_sign,
            c.edge_sign,
            c.angle_offset_deg,
            c.edge_offset_mm,
            c.shear_sign,
            c.shear_angle_offset_deg,
            self.own.cosine,
            others.join(", "),
        )
    }

    /// `cfg` set to the chosen convention (the magnitudes of its scales
    /// kept); `cfg` itself when its own convention was kept.
    pub fn apply(&self, cfg: &TacTipConfig) -> TacTipConfig {
        if self.kept_own {
            return cfg.clone();
        }
        with_convention(cfg, &self.chosen)
    }
}

/// Find the label convention of the measured `samples` (pins in the
/// order of `rest_px`), starting from `cfg`'s mechanics; see the module
/// header. Errors when `cfg` and `rest_px` make no model.
pub fn fit_convention(
    cfg: &TacTipConfig,
    rest_px: &[[f64; 2]],
    samples: &[FitSample],
    search: &ConventionSearch,
) -> Result<ConventionFit, SensorError> {
    let model = TacTipModel::with_rest_pins(cfg.clone(), rest_px.to_vec())?;
    let still: Vec<FitSample> = samples
        .iter()
        .map(|s| FitSample {
            tap: EdgeTap {
                shear: None,
                ..s.tap
            },
            disp: s.disp.clone(),
        })
        .collect();
    let misfit_on = |c: &ConventionScore, samples: &[FitSample]| -> [f64; 2] {
        let cfg = with_convention(cfg, c);
        match TacTipModel::with_rest_pins(cfg, rest_px.to_vec()) {
            Ok(m) => scores(&m, samples, search.threads),
            Err(_) => [f64::INFINITY, -1.0],
        }
    };
    let misfit = |c: &ConventionScore| misfit_on(c, &still);
    let k = &cfg.calibration;
    let [rms_px, cosine] = scores(&model, &still, search.threads);
    let own = ConventionScore {
        angle_sign: k.angle_scale.signum(),
        edge_sign: k.edge_scale.signum(),
        angle_offset_deg: k.angle_offset_deg,
        edge_offset_mm: k.edge_offset_mm,
        shear_sign: k.shear_sign,
        shear_angle_offset_deg: k.shear_angle_offset_deg,
        rms_px,
        cosine,
    };
    let mut candidates: Vec<ConventionScore> = [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
        .into_iter()
        .map(|(a, e)| best_of_class(&own, (a, e), search, &misfit))
        .collect();
    candidates.sort_by(|a, b| b.cosine.total_cmp(&a.cosine));
    let best = candidates[0];
    let same_class = best.angle_sign == own.angle_sign && best.edge_sign == own.edge_sign;
    let near =
        wrap_deg(best.angle_offset_deg - own.angle_offset_deg).abs() <= search.angle_step_deg;
    let kept_own = own.cosine >= best.cosine || (same_class && near);
    let slid = samples.iter().any(|s| s.tap.shear.is_some());
    let chosen = match (kept_own, slid) {
        (true, _) => own,
        (false, false) => best,
        (false, true) => best_slide(best, search, &|c| misfit_on(c, samples)),
    };
    Ok(ConventionFit {
        kept_own,
        own,
        chosen,
        candidates,
        taps: samples.len(),
    })
}

/// The best convention with signs (`angle_sign`, `edge_sign`): the scan
/// of angle offsets round the circle (edge offset `edge0`), then the best
/// refined with the edge offset (kept within [`EDGE_REACH_MM`] of `edge0`).
fn best_of_class(
    own: &ConventionScore,
    (angle_sign, edge_sign): (f64, f64),
    search: &ConventionSearch,
    misfit: &dyn Fn(&ConventionScore) -> [f64; 2],
) -> ConventionScore {
    let edge0 = own.edge_offset_mm;
    let step = search.angle_step_deg.clamp(1.0, 90.0);
    let steps = (360.0 / step).round() as usize;
    let at = |a: f64, e: f64| {
        let mut c = ConventionScore {
            angle_sign,
            edge_sign,
            angle_offset_deg: wrap_deg(a),
            edge_offset_mm: e,
            rms_px: f64::INFINITY,
            cosine: -1.0,
            ..*own
        };
        if (e - edge0).abs() <= EDGE_REACH_MM {
            [c.rms_px, c.cosine] = misfit(&c);
        }
        c
    };
    let mut best = at(0.0, edge0);
    for i in 1..steps {
        let c = at(-180.0 + step * i as f64, edge0);
        if c.cosine > best.cosine {
            best = c;
        }
    }
    let objective = |x: &[f64]| 1.0 - at(x[0], x[1]).cosine;
    let x0 = [best.angle_offset_deg, best.edge_offset_mm];
    let (x, _) = minimise(&objective, &x0, &[step / 3.0, 1.0], search.iterations);
    let refined = at(x[0], x[1]);
    if refined.cosine > best.cosine {
        best = refined;
    }
    best
}

/// `conv` with the slide's sign and angle offset that match the taps
/// best (by `misfit`, on the taps with their slides): each sign scanned
/// round the circle, the best refined.
fn best_slide(
    conv: ConventionScore,
    search: &ConventionSearch,
    misfit: &dyn Fn(&ConventionScore) -> [f64; 2],
) -> ConventionScore {
    let step = search.angle_step_deg.clamp(1.0, 90.0);
    let steps = (360.0 / step).round() as usize;
    let at = |sign: f64, psi: f64| {
        let mut c = ConventionScore {
            shear_sign: sign,
            shear_angle_offset_deg: wrap_deg(psi),
            ..conv
        };
        [c.rms_px, c.cosine] = misfit(&c);
        c
    };
    let mut best = at(conv.shear_sign, conv.shear_angle_offset_deg);
    for sign in [1.0, -1.0] {
        for i in 0..steps {
            let c = at(sign, -180.0 + step * i as f64);
            if c.cosine > best.cosine {
                best = c;
            }
        }
    }
    let sign = best.shear_sign;
    let objective = |x: &[f64]| 1.0 - at(sign, x[0]).cosine;
    let (x, _) = minimise(
        &objective,
        &[best.shear_angle_offset_deg],
        &[step / 3.0],
        search.iterations / 2,
    );
    let refined = at(sign, x[0]);
    if refined.cosine > best.cosine {
        best = refined;
    }
    // The same slide with the turn within +-90 deg: a half turn is the
    // other sign.
    if best.shear_angle_offset_deg.abs() > 90.0 {
        best.shear_sign = -best.shear_sign;
        best.shear_angle_offset_deg = wrap_deg(best.shear_angle_offset_deg + 180.0);
    }
    best
}

/// How far (mm) the refinement may move the edge offset from the
/// sensor's own.
pub const EDGE_REACH_MM: f64 = 6.0;

/// `cfg` with the convention `c`: the scales' signs and the offsets.
fn with_convention(cfg: &TacTipConfig, c: &ConventionScore) -> TacTipConfig {
    let mut out = cfg.clone();
    let k = &mut out.calibration;
    k.angle_scale = c.angle_sign * k.angle_scale.abs();
    k.edge_scale = c.edge_sign * k.edge_scale.abs();
    k.angle_offset_deg = c.angle_offset_deg;
    k.edge_offset_mm = c.edge_offset_mm;
    k.shear_sign = c.shear_sign;
    k.shear_angle_offset_deg = c.shear_angle_offset_deg;
    out
}

/// [per-coordinate RMS pin misfit (px), mean per-tap cosine] of `model`
/// over the samples, the taps split over `threads`.
pub(crate) fn scores(model: &TacTipModel, samples: &[FitSample], threads: usize) -> [f64; 2] {
    let chunk = samples.len().div_ceil(threads.max(1)).max(1);
    let sums = std::thread::scope(|scope| {
        let handles: Vec<_> = samples
            .chunks(chunk)
            .map(|part| scope.spawn(move || misfit_sums(model, part)))
            .collect();
        handles.into_iter().fold([0.0; 3], |acc, h| match h.join() {
            Ok(s) => [acc[0] + s[0], acc[1] + s[1], acc[2] + s[2]],
            Err(_) => [f64::INFINITY, acc[1], acc[2]],
        })
    });
    [
        (sums[0] / sums[1].max(1.0)).sqrt(),
        sums[2] / samples.len().max(1) as f64,
    ]
}
