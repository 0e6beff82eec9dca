//! The tap depth, the slide response and the rim of a user's sensor
//! found from its labelled taps (docs/calibration.md, "Tap depth, slide
//! response and rim").
//!
//! How deep a labelled tap presses the dome differs between collections:
//! a depth column may be an offset from a nominal depth (the shared
//! 127-pin set) or the absolute depth of each tap (the shared 331-pin
//! set, 3-5 mm, where the mean pin displacement triples over that range),
//! and the simulator's depth scale is its own (its compliance and
//! mechanics were fitted on another sensor). The depth is modelled as
//! `tap_depth_mm + depth_per_offset * dz`; this fit sets both
//! from the taps, parametrised by the depths at the smallest and largest
//! labelled `dz`, with a
//! scale of the skin's slide response (eq. S7: the stick gain and the
//! slip limit together, so the skin's lag behind a slide scales by it)
//! and a scale of the rim clamp's reach (eq. S8a: how far out from the
//! pole the pins still move; on the 331-pin set the outer rings move
//! twice as far as the built-in clamp lets them), with the edge offset
//! refined by the same misfit (the convention's cosine finds it on
//! fields of the wrong depth: depth and edge position both set how much
//! of the dome is pressed), and, when the taps' labelled angles go
//! round enough of the circle to tell it from the edge offset, the pivot
//! offset (eq. L3: the dome centre's offset from the point the labelled
//! pose turns about, which moves the edge by `pivot_x sin(yaw) + pivot_y
//! cos(yaw)`; a rig other than the one the sensor's own was found on has
//! its own, and over the full circle a wrong one is a position error of
//! up to its length that changes with the angle).
//! Unlike the label convention ([`crate::fit_convention`]), these set how
//! far the pins move, so they are judged by the RMS misfit of the fields
//! (each tap with its slide): a coarse grid of the two depths, then
//! Nelder-Mead over the depths, the logs of the two scales and the edge
//! offset (kept within [`EDGE_REACH_MM`] of the sensor's own). The
//! sensor's own values are kept unless the fit lowers the misfit by
//! [`DepthSearch::min_gain`], and when the taps' `dz` does not vary (no
//! depth column) the fit is not run. Pure, like [`crate::fit_joint`].
//!
//! With [`DepthSearch::labelled_depth`] every tap presses to its labelled
//! `dz` (`tap_depth_mm` 0, `depth_per_offset` 1: a depth column that is
//! the absolute depth) and the field's gain `g` is fitted in the depth
//! law's place: the gel flow's layer thickness divided by `g` and the
//! lift gain multiplied by it (eqs. S6, S8), so the pins move `g` times
//! as far for the same contact patch (docs/calibration.md, "The labelled
//! depth").
use crate::fit::FitSample;
use crate::fit_convention::scores;
use crate::nelder_mead::minimise;
use crate::{SensorError, TacTipConfig, TacTipModel};
use serde::{Deserialize, Serialize};

/// How to search for the depth and slide response.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthSearch {
    /// Step of the coarse grid of depths, mm (from one step to the
    /// model's deepest resolved indentation).
    pub grid_step_mm: f64,
    /// Nelder-Mead steps refining the best grid point.
    pub iterations: usize,
    /// Relative fall of the RMS misfit below the sensor's own needed to
    /// change it (0.05: 5 %).
    pub min_gain: f64,
    /// Threads the taps are simulated on.
    pub threads: usize,
    /// Press each tap to its labelled `dz` and fit the field's gain
    /// instead of the depth law (see the module header).
    pub labelled_depth: bool,
}

impl Default for DepthSearch {
    /// 1 mm grid, 100 refining steps, 5 % gain, one thread, the depth
    /// law fitted.
    fn default() -> Self {
        Self {
            grid_step_mm: 1.0,
            iterations: 100,
            min_gain: 0.05,
            threads: 1,
            labelled_depth: false,
        }
    }
}

/// One depth law and slide response, and how well they match the taps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthScore {
    /// Indentation depth at `dz = 0`, mm (`calibration.tap_depth_mm`).
    pub tap_depth_mm: f64,
    /// Depth change per unit of the labelled `dz` (`calibration.depth_per_offset`).
    pub depth_per_offset: f64,
    /// The slide response's scale against the given sensor's (stick gain
    /// and slip limit both multiplied by it).
    pub slide_scale: f64,
    /// The rim clamp's reach against the given sensor's
    /// (`mechanics.rim_clamp_mm` multiplied by it).
    pub rim_scale: f64,
    /// Added to the labelled edge position, mm (`calibration.edge_offset_mm`).
    pub edge_offset_mm: f64,
    /// The pivot offset, sensor frame, mm (`calibration.pivot_x_mm`,
    /// `pivot_y_mm`, eq. L3); absent in files written before it was
    /// fitted.
    #[serde(default)]
    pub pivot_mm: Option<[f64; 2]>,
    /// The field's gain against the given sensor's (layer thickness
    /// divided by it, lift gain multiplied), when fitted
    /// ([`DepthSearch::labelled_depth`]); absent otherwise.
    #[serde(default)]
    pub field_gain: Option<f64>,
    /// Per-coordinate RMS pin misfit over the taps, px.
    pub rms_px: f64,
    /// Mean per-tap cosine between the simulated and measured fields.
    pub cosine: f64,
}

/// How far (mm) the fit may move the edge offset from the sensor's own.
pub const EDGE_REACH_MM: f64 = 4.0;

/// How far (mm) the fit may move each pivot component from the sensor's own.
pub const PIVOT_REACH_MM: f64 = 4.0;

/// The pivot offset is fitted only when the mean resultant length of the
/// taps' labelled angles is below this: over a narrow arc (the 127-pin
/// set's +-45 deg gives 0.90) the pivot trades against the edge and angle
/// offsets, over the circle (near 0) it is a distinct sinusoid in the
/// angle.
pub const PIVOT_MAX_RESULTANT: f64 = 0.5;

impl DepthScore {
    /// The indentation depth (mm) at the labelled `dz`.
    pub fn depth_at(&self, dz: f64) -> f64 {
        self.tap_depth_mm + self.depth_per_offset * dz
    }
}

/// What [`fit_depth`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthFit {
    /// True when the sensor's own depth law and slide response were kept.
    pub kept_own: bool,
    /// The sensor's own, scored on the taps.
    pub own: DepthScore,
    /// The one used (`own` when kept).
    pub chosen: DepthScore,
    /// The smallest and largest labelled `dz` of the taps.
    pub dz_range: [f64; 2],
    /// Taps it was judged on.
    pub taps: usize,
}

impl DepthFit {
    /// One line for the user.
    pub fn describe(&self) -> String {
        let c = &self.chosen;
        let [lo, hi] = self.dz_range;
        let depths = if hi > lo {
            format!(
                "{:.2} mm at dz {lo:.2}, {:.2} mm at dz {hi:.2}",
                c.depth_at(lo),
                c.depth_at(hi)
            )
        } else {
            format!("{:.2} mm", c.depth_at(lo))
        };
        let mut pivot = match c.pivot_mm {
            Some([x, y]) => format!(", pivot ({x:.2}, {y:.2}) mm"),
            None => String::new(),
        };
        if let Some(g) = c.field_gain {
            pivot.push_str(&format!(", field gain x{g:.2}"));
        }
        let what = if self.kept_own {
            "the sensor's own kept"
        } else {
            "fitted to the taps"
        };
        format!(
            "tap depth, slide response and rim ({what}, {} taps): depth {depths}, \
             slide response x{:.2}, rim clamp's reach x{:.2}, edge offset {:.2} mm{pivot}; \
             field RMS {:.3} px (cosine {:.3}), the sensor's own {:.3} px ({:.3})",
            self.taps,
            c.slide_scale,
            c.rim_scale,
            c.edge_offset_mm,
            c.rms_px,
            c.cosine,
            self.own.rms_px,
            self.own.cosine
        )
    }

    /// `cfg` with the chosen depth law and slide response; `cfg` itself
    /// when its own were kept.
    pub fn apply(&self, cfg: &TacTipConfig) -> TacTipConfig {
        if self.kept_own {
            return cfg.clone();
        }
        with_depth(cfg, &self.chosen)
    }
}

/// `cfg` with the depth law and slide scale of `d`.
fn with_depth(cfg: &TacTipConfig, d: &DepthScore) -> TacTipConfig {
    let mut out = cfg.clone();
    out.calibration.tap_depth_mm = d.tap_depth_mm;
    out.calibration.depth_per_offset = d.depth_per_offset;
    out.mechanics.stick_gain *= d.slide_scale;
    out.mechanics.shear_limit_mm *= d.slide_scale;
    out.mechanics.rim_clamp_mm *= d.rim_scale;
    out.calibration.edge_offset_mm = d.edge_offset_mm;
    if let Some([x, y]) = d.pivot_mm {
        out.calibration.pivot_x_mm = x;
        out.calibration.pivot_y_mm = y;
    }
    if let Some(g) = d.field_gain {
        out.mechanics.layer_thickness_mm /= g;
        out.mechanics.lift_gain *= g;
    }
    out
}

/// Field gains the labelled-depth search starts from (its coarse grid).
const GAIN_GRID: [f64; 5] = [0.5, 0.7, 1.0, 1.4, 2.0];

/// Mean resultant length of the taps' labelled angles: 1 when they are
/// all one angle, near 0 when they go round the circle evenly.
fn angle_resultant(samples: &[FitSample]) -> f64 {
    let (s, c) = samples.iter().fold((0.0, 0.0), |(s, c), x| {
        let (a, b) = x.tap.theta_deg.to_radians().sin_cos();
        (s + a, c + b)
    });
    s.hypot(c) / samples.len().max(1) as f64
}

/// Fit the depth law and slide response of the measured `samples` (pins
/// in the order of `rest_px`, each tap with its labelled `dz` and slide)
/// from `cfg`; see the module header. Errors when `cfg` and `rest_px`
/// make no model.
pub fn fit_depth(
    cfg: &TacTipConfig,
    rest_px: &[[f64; 2]],
    samples: &[FitSample],
    search: &DepthSearch,
) -> Result<DepthFit, SensorError> {
    TacTipModel::with_rest_pins(cfg.clone(), rest_px.to_vec())?;
    let problem = DepthProblem::new(cfg, rest_px, samples, search);
    let own = problem.own_score()?;
    let fit = |kept_own: bool, chosen: DepthScore| DepthFit {
        kept_own,
        own,
        chosen,
        dz_range: [problem.lo, problem.hi],
        taps: samples.len(),
    };
    if !problem.varies() {
        // No depth column (or one depth for every tap): the fit is not
        // run, the sensor's own kept (a lone depth trades against the
        // field correction, which a synthetic sensor showed).
        return Ok(fit(true, own));
    }
    let best = problem.coarse_best(own);
    let refined = problem.refine(best.0);
    let chosen = if refined.rms_px < best.1.rms_px {
        refined
    } else {
        best.1
    };
    let kept_own = chosen.rms_px >= own.rms_px * (1.0 - search.min_gain);
    Ok(fit(kept_own, if kept_own { own } else { chosen }))
}

/// The taps' smallest and largest labelled `dz` (both 0 without taps).
fn dz_range(samples: &[FitSample]) -> (f64, f64) {
    let (lo, hi) = samples
        .iter()
        .map(|s| s.tap.dz_mm)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo.is_finite() {
        (lo, hi)
    } else {
        (0.0, 0.0)
    }
}

/// One fit's fixed parts: the sensor, its rest pins, the taps and their
/// `dz` range, the search, and whether the pivot is fitted.
struct DepthProblem<'a> {
    cfg: &'a TacTipConfig,
    rest_px: &'a [[f64; 2]],
    samples: &'a [FitSample],
    search: &'a DepthSearch,
    lo: f64,
    hi: f64,
    /// The sensor's own pivot offset, mm.
    own_pivot: [f64; 2],
    /// Whether the taps' angles go round enough of the circle to fit the
    /// pivot ([`PIVOT_MAX_RESULTANT`]).
    fit_pivot: bool,
}

impl<'a> DepthProblem<'a> {
    fn new(
        cfg: &'a TacTipConfig,
        rest_px: &'a [[f64; 2]],
        samples: &'a [FitSample],
        search: &'a DepthSearch,
    ) -> Self {
        let (lo, hi) = dz_range(samples);
        let k = &cfg.calibration;
        Self {
            cfg,
            rest_px,
            samples,
            search,
            lo,
            hi,
            own_pivot: [k.pivot_x_mm, k.pivot_y_mm],
            fit_pivot: angle_resultant(samples) < PIVOT_MAX_RESULTANT,
        }
    }

    /// Whether the taps' labelled `dz` varies (else the fit is not run).
    fn varies(&self) -> bool {
        self.hi - self.lo > 1e-6
    }

    /// Parameters in the simplex before the three of the slide, rim and
    /// edge: the two depths, or the log field gain with the labelled depth.
    fn head(&self) -> usize {
        if self.search.labelled_depth {
            1
        } else {
            2
        }
    }

    /// The sensor's own depth law and slide response, scored on the taps.
    fn own_score(&self) -> Result<DepthScore, SensorError> {
        let k = &self.cfg.calibration;
        let model = TacTipModel::with_rest_pins(self.cfg.clone(), self.rest_px.to_vec())?;
        let [rms_px, cosine] = scores(&model, self.samples, self.search.threads);
        Ok(DepthScore {
            tap_depth_mm: k.tap_depth_mm,
            depth_per_offset: k.depth_per_offset,
            slide_scale: 1.0,
            rim_scale: 1.0,
            edge_offset_mm: k.edge_offset_mm,
            pivot_mm: self.fit_pivot.then_some(self.own_pivot),
            field_gain: None,
            rms_px,
            cosine,
        })
    }

    /// The candidate pressing `depth_lo` at the smallest `dz` and
    /// `depth_hi` at the largest, with `x = [ln slide scale, ln rim scale,
    /// edge offset, pivot x, pivot y, ln field gain]` (the gain read only
    /// with the labelled depth), scored on the taps; unscored (RMS
    /// infinite) outside the search's bounds.
    fn score(&self, depth_lo: f64, depth_hi: f64, x: [f64; 6]) -> DepthScore {
        let [ln_slide, ln_rim, edge, px, py, ln_gain] = x;
        let k = &self.cfg.calibration;
        let per = if self.varies() {
            (depth_hi - depth_lo) / (self.hi - self.lo)
        } else {
            k.depth_per_offset
        };
        let mut d = DepthScore {
            tap_depth_mm: depth_lo - per * self.lo,
            depth_per_offset: per,
            slide_scale: ln_slide.exp(),
            rim_scale: ln_rim.exp(),
            edge_offset_mm: edge,
            pivot_mm: self.fit_pivot.then_some([px, py]),
            field_gain: self.search.labelled_depth.then_some(ln_gain.exp()),
            rms_px: f64::INFINITY,
            cosine: -1.0,
        };
        let deepest = self.cfg.mechanics.max_depth_mm;
        let inside = |v: f64| v > 0.0 && v <= deepest;
        let near = (edge - k.edge_offset_mm).abs() <= EDGE_REACH_MM
            && (px - self.own_pivot[0]).abs() <= PIVOT_REACH_MM
            && (py - self.own_pivot[1]).abs() <= PIVOT_REACH_MM;
        if !inside(depth_lo)
            || !inside(depth_hi)
            || ln_slide.abs() > 3.0
            || ln_rim.abs() > 2.0
            || ln_gain.abs() > 2.0
            || !near
        {
            return d;
        }
        let cfg = with_depth(self.cfg, &d);
        if let Ok(m) = TacTipModel::with_rest_pins(cfg, self.rest_px.to_vec()) {
            [d.rms_px, d.cosine] = scores(&m, self.samples, self.search.threads);
        }
        d
    }

    /// The candidate at the simplex point `x`: its [`Self::head`] first,
    /// then the slide, rim and edge, then the pivot when it is fitted.
    fn at(&self, x: &[f64]) -> DepthScore {
        let rest = &x[self.head()..];
        let pivot = if self.fit_pivot {
            [rest[3], rest[4]]
        } else {
            self.own_pivot
        };
        let (a, b, ln_gain) = if self.search.labelled_depth {
            (self.lo, self.hi, x[0])
        } else {
            (x[0], x[1], 0.0)
        };
        self.score(
            a,
            b,
            [rest[0], rest[1], rest[2], pivot[0], pivot[1], ln_gain],
        )
    }

    /// The coarse starts: a grid of the two depths, or with the labelled
    /// depth of the field's gain (its first [`Self::head`] values count).
    fn starts(&self) -> Vec<[f64; 2]> {
        if self.search.labelled_depth {
            return GAIN_GRID.iter().map(|g| [g.ln(), 0.0]).collect();
        }
        let step = self.grid_step();
        let deepest = self.cfg.mechanics.max_depth_mm;
        let grid: Vec<f64> = (1..)
            .map(|i| step * f64::from(i))
            .take_while(|&v| v <= deepest)
            .collect();
        grid.iter()
            .flat_map(|&a| grid.iter().map(move |&b| [a, b]))
            .collect()
    }

    fn grid_step(&self) -> f64 {
        self.search.grid_step_mm.max(0.1)
    }

    /// The slide, rim and edge of the sensor's own, as the simplex holds them.
    fn own_tail(&self) -> [f64; 3] {
        [0.0, 0.0, self.cfg.calibration.edge_offset_mm]
    }

    /// The best coarse start and its score: the sensor's own law (the
    /// gain 1 with the labelled depth) unless a start beats it.
    fn coarse_best(&self, own: DepthScore) -> ([f64; 2], DepthScore) {
        let k = &self.cfg.calibration;
        let own_start = if self.search.labelled_depth {
            [0.0; 2]
        } else {
            [
                k.tap_depth_mm + k.depth_per_offset * self.lo,
                k.tap_depth_mm + k.depth_per_offset * self.hi,
            ]
        };
        let mut best = (own_start, own);
        for start in &self.starts() {
            let x: Vec<f64> = start[..self.head()]
                .iter()
                .chain(&self.own_tail())
                .chain(&self.own_pivot)
                .copied()
                .collect();
            let d = self.at(&x);
            if d.rms_px < best.1.rms_px {
                best = (*start, d);
            }
        }
        best
    }

    /// Nelder-Mead from the coarse start `start` (the pivot moved only
    /// when it is fitted): the candidate it ends at.
    fn refine(&self, start: [f64; 2]) -> DepthScore {
        let head = self.head();
        let objective = |x: &[f64]| self.at(x).rms_px;
        let mut x0: Vec<f64> = start[..head]
            .iter()
            .chain(&self.own_tail())
            .copied()
            .collect();
        let first_step = if self.search.labelled_depth {
            0.2
        } else {
            self.grid_step() / 2.0
        };
        let mut first = vec![first_step; head];
        first.extend([0.3, 0.3, 0.5]);
        if self.fit_pivot {
            x0.extend(self.own_pivot);
            first.extend([0.5, 0.5]);
        }
        let (x, _) = minimise(&objective, &x0, &first, self.search.iterations);
        self.at(&x)
    }
}
