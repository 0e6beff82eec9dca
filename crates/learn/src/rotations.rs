//! Turned copies of the training taps ([`Rotations`]): a sensor whose pin
//! layout has n-fold symmetry about its centre (the 331-pin TacTip: a
//! hexagonal number of pins on rings, n = 6) sees a contact turned by
//! `k 360/n` deg as the same field of displacements turned by that angle
//! and carried to the pins the turn lands on. A turn by `phi` of pin `i`
//! at `q_i` (about the layout's centre) lands on the pin `j` nearest
//! `R(phi) q_i`, and the copy's displacement at `j` is `R(phi) d_i`; an
//! edge's angle moves by `angle_sign * phi` (the sign is the dataset's:
//! the image's y axis points down, so on the 331-pin edge set a turn by
//! `+phi` in image coordinates lowers the labelled angle), its signed
//! distance from the centre does not move. Only circular targets move;
//! every other target must be one a turn leaves alone.
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::targets::{wrap_deg, ModelTarget};
use serde::{Deserialize, Serialize};

/// The largest order of symmetry accepted (a turn of 30 deg).
pub const MAX_ORDER: usize = 12;

/// How far a turned pin may land from the nearest pin of the layout, as a
/// fraction of the layout's median nearest-neighbour spacing: beyond it
/// the layout is not symmetric under the turn and the fit is refused.
pub const MATCH_TOLERANCE: f64 = 0.4;

/// Training on every tap and its copies turned by `k 360/order` deg,
/// `k = 1..order` ([`crate::ModelConfig::rotations`]); predictions see the
/// tap alone, or with `at_prediction` the mean over the tap and its turned
/// copies, each prediction turned back (`crate::turned_views`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotations {
    /// The layout's order of symmetry n: each tap gains n - 1 turned
    /// copies (2..=[`MAX_ORDER`]).
    pub order: usize,
    /// How a circular target moves when the frame turns by `phi` in image
    /// coordinates (x right, y down): by `angle_sign * phi`, +1 or -1.
    pub angle_sign: i8,
    /// Predict every tap and its copies under the same turns, turn each
    /// prediction back and average them (the nets' columns, a circular
    /// target's sine and cosine as a vector): an ensemble of `order`
    /// views. False (the default, not written): the tap alone.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub at_prediction: bool,
}

impl Rotations {
    /// Check the order and the sign.
    pub fn validate(&self) -> Result<(), LearnError> {
        if !(2..=MAX_ORDER).contains(&self.order) {
            return Err(rotations_err(format!(
                "order {} must lie in [2, {MAX_ORDER}]",
                self.order
            )));
        }
        if self.angle_sign.abs() != 1 {
            return Err(rotations_err(format!(
                "angle_sign {} must be 1 or -1",
                self.angle_sign
            )));
        }
        Ok(())
    }
}

/// One turn of the layout: where each pin lands, the rotation and the
/// move of every circular target (deg).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Turn {
    /// `lands[i]`: the pin that pin `i` lands on.
    lands: Vec<usize>,
    cos: f64,
    sin: f64,
    angle_shift_deg: f64,
}

impl Turn {
    /// The turn by `deg` of the layout `pins` (px), refused when a pin
    /// lands farther than `tolerance` px from every pin or two pins land on
    /// one.
    fn new(
        pins: &[[f64; 2]],
        deg: f64,
        angle_sign: i8,
        tolerance: f64,
    ) -> Result<Self, LearnError> {
        let centre = centre(pins);
        let (sin, cos) = deg.to_radians().sin_cos();
        let mut lands = Vec::with_capacity(pins.len());
        let mut taken = vec![false; pins.len()];
        for p in pins {
            let (x, y) = (p[0] - centre[0], p[1] - centre[1]);
            let turned = [centre[0] + cos * x - sin * y, centre[1] + sin * x + cos * y];
            let (j, dist) = nearest(pins, turned);
            if dist > tolerance || taken[j] {
                return Err(rotations_err(format!(
                    "the pin layout is not symmetric under a turn of {deg} deg: a pin lands \
                     {dist:.2} px from the nearest pin (tolerance {tolerance:.2} px){}",
                    if taken[j] {
                        ", on a pin already taken"
                    } else {
                        ""
                    }
                )));
            }
            taken[j] = true;
            lands.push(j);
        }
        Ok(Self {
            lands,
            cos,
            sin,
            angle_shift_deg: f64::from(angle_sign) * deg,
        })
    }

    /// The turned copy of one displacement vector (`P` x values, then `P`
    /// y values) into `out`.
    pub(crate) fn displacements(&self, d: &[f32], out: &mut [f32]) {
        let n = self.lands.len();
        for (i, &j) in self.lands.iter().enumerate() {
            let (x, y) = (f64::from(d[i]), f64::from(d[n + i]));
            out[j] = (self.cos * x - self.sin * y) as f32;
            out[n + j] = (self.sin * x + self.cos * y) as f32;
        }
    }

    /// The turned copy's targets: circular ones moved and wrapped.
    fn targets(&self, outputs: &[ModelTarget], y: &[f32], out: &mut Vec<f32>) {
        for (t, &v) in outputs.iter().zip(y) {
            out.push(if t.circular {
                wrap_deg(f64::from(v) + self.angle_shift_deg) as f32
            } else {
                v
            });
        }
    }

    /// One prediction of the turned copy, as the nets' unscaled columns
    /// (`encoded`, targets as `outputs` name them), turned back: a
    /// circular target's sine and cosine of `theta'` become those of
    /// `theta' - angle_shift` (a rotation of the pair by `-angle_shift`),
    /// every other column is kept.
    pub(crate) fn turn_back(&self, outputs: &[ModelTarget], encoded: &mut [f64]) {
        let (ss, cs) = self.angle_shift_deg.to_radians().sin_cos();
        let mut k = 0;
        for t in outputs {
            if t.circular {
                let (s, c) = (encoded[k], encoded[k + 1]);
                encoded[k] = s * cs - c * ss;
                encoded[k + 1] = c * cs + s * ss;
            }
            k += t.width();
        }
    }
}

/// The turns `rot` adds over the layout `pins` (px, in input order):
/// `k 360/order` deg for `k = 1..order`.
pub(crate) fn turns(rot: &Rotations, pins: &[[f64; 2]]) -> Result<Vec<Turn>, LearnError> {
    rot.validate()?;
    let tolerance = MATCH_TOLERANCE * median_spacing(pins)?;
    (1..rot.order)
        .map(|k| {
            Turn::new(
                pins,
                360.0 * k as f64 / rot.order as f64,
                rot.angle_sign,
                tolerance,
            )
        })
        .collect()
}

/// `data` (displacements laid out against `pins`, px; targets as
/// `outputs` name them, in their units) followed by its copies under
/// every turn `rot` adds, turn by turn: what a model with
/// [`crate::ModelConfig::rotations`] is fitted on.
pub fn turned_copies(
    data: &Dataset,
    outputs: &[ModelTarget],
    rot: &Rotations,
    pins: &[[f64; 2]],
) -> Result<Dataset, LearnError> {
    if 2 * pins.len() != data.dim_x {
        return Err(LearnError::DimensionMismatch {
            expected: 2 * pins.len(),
            got: data.dim_x,
        });
    }
    if outputs.len() != data.dim_y {
        return Err(LearnError::Shape {
            what: "targets per sample",
            expected: outputs.len(),
            got: data.dim_y,
        });
    }
    with_turned_copies(data, outputs, &turns(rot, pins)?)
}

/// `data` followed by its copy under every turn of `turns`, in that
/// order (targets as `outputs` name them, before encoding).
fn with_turned_copies(
    data: &Dataset,
    outputs: &[ModelTarget],
    turns: &[Turn],
) -> Result<Dataset, LearnError> {
    let copies = turns.len() + 1;
    let mut x = Vec::with_capacity(copies * data.x.len());
    let mut y = Vec::with_capacity(copies * data.y.len());
    x.extend_from_slice(&data.x);
    y.extend_from_slice(&data.y);
    let mut row = vec![0.0f32; data.dim_x];
    for turn in turns {
        for i in 0..data.n {
            turn.displacements(data.x_row(i), &mut row);
            x.extend_from_slice(&row);
            turn.targets(outputs, data.y_row(i), &mut y);
        }
    }
    Dataset::new(x, y, copies * data.n, data.dim_x, data.dim_y)
}

/// The mean of the pins (the centre of a layout symmetric about it).
pub(crate) fn centre(pins: &[[f64; 2]]) -> [f64; 2] {
    let n = pins.len().max(1) as f64;
    let (sx, sy) = pins
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p[0], b + p[1]));
    [sx / n, sy / n]
}

/// The pin nearest `at` and its distance.
pub(crate) fn nearest(pins: &[[f64; 2]], at: [f64; 2]) -> (usize, f64) {
    pins.iter()
        .map(|p| (p[0] - at[0]).hypot(p[1] - at[1]))
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |best, (j, d)| if d < best.1 { (j, d) } else { best },
        )
}

/// The median over the pins of the distance to their nearest neighbour.
pub(crate) fn median_spacing(pins: &[[f64; 2]]) -> Result<f64, LearnError> {
    if pins.len() < 2 {
        return Err(rotations_err(
            "a layout of fewer than two pins has no spacing".into(),
        ));
    }
    let mut d: Vec<f64> = pins
        .iter()
        .enumerate()
        .map(|(i, p)| {
            pins.iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    d.sort_by(f64::total_cmp);
    Ok(d[d.len() / 2])
}

fn rotations_err(reason: String) -> LearnError {
    LearnError::Config {
        field: "rotations",
        reason,
    }
}
