//! The detection noise of a sensor's pins, estimated from its taps
//! (docs/calibration.md, "Pin jitter fitted from the taps").
//!
//! A tap's displacement field is smooth over the dome: a pin's
//! displacement is well predicted by a quadratic fitted to its nearest
//! neighbours' (a stencil: `d_i ~ sum_j w_ij d_j`, exact for any
//! quadratic field). Detection noise is not smooth: with independent
//! noise of variance `sigma^2` per pin and axis, the residual
//! `e_i = d_i - sum_j w_ij d_j` has variance `sigma^2 (1 + sum_j w_ij^2)`
//! (the stencil's gain). So the residual divided by its gain, its
//! variance over the taps taken about its own mean (which drops anything
//! fixed to the pin, such as the reference frame's own detection error)
//! and the median over the pins (robust to the few pins where the field
//! bends sharply, at the contact's edge or the rim), is an estimate of
//! `sigma^2`: the field's *roughness* ([`roughness`]).
//!
//! The real frames' roughness is then compared with the simulator's at a
//! grid of render jitters (rendered, binarised and read as the twin does,
//! so the detector's own quantisation is counted on both sides), and the
//! jitter whose simulated roughness equals the real one is the fit
//! ([`fit_jitter`], interpolated in variance: `q(s)^2 ~ q(0)^2 + c s^2`).
use crate::error::{CalibError, Result};
use crate::fields::Fields;
use crate::stats::median;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Neighbours of each pin the quadratic stencil is fitted to.
pub const STENCIL_NEIGHBOURS: usize = 12;

/// Render jitters (px) at which the simulator's roughness is measured.
pub const JITTER_GRID: [f64; 10] = [0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0];

/// One pin's stencil: its neighbours and their weights, and its gain
/// `1 + sum w^2`.
#[derive(Debug, Clone)]
struct PinStencil {
    pin: usize,
    neighbours: Vec<(usize, f64)>,
    gain: f64,
}

/// The quadratic stencils of a rest layout's pins (pins whose neighbours
/// do not fix a quadratic are left out).
#[derive(Debug, Clone)]
pub struct Stencil {
    pins: usize,
    stencils: Vec<PinStencil>,
}

impl Stencil {
    /// The stencils of the rest pins `rest` (px), each pin's quadratic
    /// fitted to its [`STENCIL_NEIGHBOURS`] nearest others.
    pub fn new(rest: &[[f64; 2]]) -> Result<Stencil> {
        if rest.len() <= STENCIL_NEIGHBOURS {
            return Err(CalibError::Dimension {
                what: "pins for the noise stencil".into(),
                expected: STENCIL_NEIGHBOURS + 1,
                found: rest.len(),
            });
        }
        let stencils: Vec<PinStencil> = (0..rest.len())
            .filter_map(|i| pin_stencil(rest, i))
            .collect();
        if stencils.is_empty() {
            return Err(CalibError::Param(
                "no pin's neighbours fix a quadratic: the rest pins are on a line".into(),
            ));
        }
        Ok(Stencil {
            pins: rest.len(),
            stencils,
        })
    }

    /// Pins with a stencil.
    pub fn len(&self) -> usize {
        self.stencils.len()
    }

    /// Whether no pin has a stencil (never, for a stencil [`Stencil::new`] made).
    pub fn is_empty(&self) -> bool {
        self.stencils.is_empty()
    }
}

/// Pin `i`'s stencil: the weights that give the value at pin `i` of the
/// least-squares quadratic through its nearest neighbours' values.
fn pin_stencil(rest: &[[f64; 2]], i: usize) -> Option<PinStencil> {
    let [x0, y0] = rest[i];
    let mut by_distance: Vec<(f64, usize)> = rest
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .map(|(j, p)| ((p[0] - x0).hypot(p[1] - y0), j))
        .collect();
    by_distance.sort_by(|a, b| a.0.total_cmp(&b.0));
    by_distance.truncate(STENCIL_NEIGHBOURS);
    // Coordinates in units of the farthest neighbour's distance (conditioning).
    let scale = by_distance.last()?.0.max(f64::EPSILON);
    let a = DMatrix::from_fn(by_distance.len(), 6, |row, col| {
        let p = rest[by_distance[row].1];
        let (u, v) = ((p[0] - x0) / scale, (p[1] - y0) / scale);
        [1.0, u, v, u * u, u * v, v * v][col]
    });
    let normal = a.transpose() * &a;
    let inverse = normal.try_inverse()?;
    // The value at the pin is the constant term: row 0 of (A^T A)^-1 A^T.
    let e0 = DVector::from_column_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let w = a * (inverse * e0);
    if w.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let gain = 1.0 + w.iter().map(|v| v * v).sum::<f64>();
    let neighbours = by_distance.iter().map(|d| d.1).zip(w.iter().copied());
    Some(PinStencil {
        pin: i,
        neighbours: neighbours.collect(),
        gain,
    })
}

/// The roughness of `fields` (N taps of the stencil's pins, all x then
/// all y), px: the estimate of the per-axis detection noise's standard
/// deviation described in the module docs (the square root of the
/// median over pins and axes of the gain-scaled residual variance about
/// each pin's mean). Needs at least two taps.
pub fn roughness(fields: &Fields, stencil: &Stencil) -> Result<f64> {
    let p = stencil.pins;
    if fields.dim() != 2 * p {
        return Err(CalibError::Dimension {
            what: "field coordinates for the noise stencil".into(),
            expected: 2 * p,
            found: fields.dim(),
        });
    }
    if fields.len() < 2 {
        return Err(CalibError::TooFewTaps {
            got: fields.len(),
            needed: 2,
            recommended: crate::RECOMMENDED_TAPS,
        });
    }
    let m = fields.matrix();
    let mut variances = Vec::with_capacity(2 * stencil.len());
    for axis in 0..2 {
        for s in &stencil.stencils {
            let residual: Vec<f64> = (0..m.nrows())
                .map(|t| {
                    let smooth: f64 = s
                        .neighbours
                        .iter()
                        .map(|&(j, w)| w * m[(t, axis * p + j)])
                        .sum();
                    m[(t, axis * p + s.pin)] - smooth
                })
                .collect();
            variances.push(centred_variance(&residual) / s.gain);
        }
    }
    // A stencil has pins (`Stencil::new`), so there are variances.
    Ok(median(&variances).map_or(f64::NAN, f64::sqrt))
}

/// The variance of `x` about its own mean (divided by n - 1).
fn centred_variance(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
}

/// The simulator's roughness at one render jitter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JitterPoint {
    /// Render jitter, px per axis.
    pub jitter_px: f64,
    /// Roughness of the rendered and read taps, px.
    pub roughness_px: f64,
}

/// The fitted pin jitter and its evidence (recorded in a sensor file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JitterFit {
    /// The render jitter whose roughness equals the real taps', px.
    pub pin_jitter_px: f64,
    /// Roughness of the real taps, px.
    pub real_roughness_px: f64,
    /// Taps both were measured on.
    pub taps: usize,
    /// The simulator's roughness over [`JITTER_GRID`].
    pub curve: Vec<JitterPoint>,
    /// The real roughness is above the whole curve: the jitter is the
    /// grid's largest, a lower bound.
    pub beyond_grid: bool,
}

/// The jitter whose simulated roughness (`curve`, jitters ascending)
/// equals `real_roughness_px`: 0 when the real taps are no rougher than
/// the simulator's noiseless renders, else interpolated linearly in
/// variance between the two grid points about it (the curve made
/// non-decreasing first); above the whole curve, its largest jitter.
pub fn fit_jitter(real_roughness_px: f64, curve: &[JitterPoint], taps: usize) -> Result<JitterFit> {
    if curve.is_empty() || !real_roughness_px.is_finite() {
        return Err(CalibError::Param(
            "the jitter fit needs a finite real roughness and a curve".into(),
        ));
    }
    if curve.windows(2).any(|w| w[1].jitter_px <= w[0].jitter_px) {
        return Err(CalibError::Param(
            "the jitter curve's jitters must rise".into(),
        ));
    }
    let mut top = f64::NEG_INFINITY;
    let rising: Vec<(f64, f64)> = curve
        .iter()
        .map(|p| {
            top = top.max(p.roughness_px);
            (p.jitter_px, top)
        })
        .collect();
    let q = real_roughness_px;
    let (px, beyond_grid) = if q <= rising[0].1 {
        (rising[0].0, false)
    } else if let Some(w) = rising.windows(2).find(|w| q <= w[1].1) {
        let ((s0, q0), (s1, q1)) = (w[0], w[1]);
        let t = (q * q - q0 * q0) / (q1 * q1 - q0 * q0);
        ((s0 * s0 + t * (s1 * s1 - s0 * s0)).sqrt(), false)
    } else {
        (rising[rising.len() - 1].0, true)
    };
    Ok(JitterFit {
        pin_jitter_px: px,
        real_roughness_px,
        taps,
        curve: curve.to_vec(),
        beyond_grid,
    })
}

impl JitterFit {
    /// What was found, in a line.
    pub fn describe(&self) -> String {
        let at = |s: f64| {
            self.curve
                .iter()
                .find(|p| p.jitter_px == s)
                .map_or(f64::NAN, |p| p.roughness_px)
        };
        format!(
            "pin jitter fitted on {} taps: {}{:.3} px (real roughness {:.3} px; simulated {:.3} px \
             at 0, {:.3} at 0.2, {:.3} at 0.4)",
            self.taps,
            if self.beyond_grid { "at least " } else { "" },
            self.pin_jitter_px,
            self.real_roughness_px,
            at(0.0),
            at(0.2),
            at(0.4)
        )
    }
}
