//! Averaging over turned views at prediction
//! ([`crate::Rotations::at_prediction`]). A model fitted on the turned
//! copies of its taps predicts a tap `d` and its copies under the same
//! turns, turns each prediction back and takes the mean:
//!
//! `y(d) = 1/n sum_{k=0}^{n-1} T_k^-1 f(R_k d)`
//!
//! with `R_k` the turn of the field by `k 360/n` deg (each pin carried to
//! the pin it lands on, its displacement turned; `R_0` the tap as read),
//! `T_k` the move of the targets (a circular target by
//! `angle_sign k 360/n` deg, the others kept) and `f` the model's
//! prediction as the nets' unscaled columns. A circular target's sine and
//! cosine are turned back and averaged as a vector, so its angle is the
//! circular mean of the views', each weighted by the length of its
//! vector, as an ensemble's members are averaged. For a map that is
//! equivariant under the turns, `f(R_k d) = T_k f(d)`, the mean is `f(d)`:
//! the views only average out what breaks the symmetry.
use crate::error::LearnError;
use crate::rotations::{turns, Rotations, Turn};
use crate::targets::ModelTarget;

/// The layout a model with [`crate::ModelConfig::rotations`] was fitted
/// over and its turns: what averaging over turned views needs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TurnedViews {
    /// The reference pins (px, in input order).
    pins: Vec<[f64; 2]>,
    turns: Vec<Turn>,
}

impl TurnedViews {
    /// The turns `rot` adds over `pins`, refused for a layout they do not
    /// carry onto itself.
    pub(crate) fn new(rot: &Rotations, pins: &[[f64; 2]]) -> Result<Self, LearnError> {
        Ok(Self {
            pins: pins.to_vec(),
            turns: turns(rot, pins)?,
        })
    }

    /// The reference pins the turns were found over.
    pub(crate) fn pins(&self) -> &[[f64; 2]] {
        &self.pins
    }

    /// The mean over `d` ([`Self::input_dim`] values) and its turned
    /// views of `predict`'s columns (targets as `outputs` name them),
    /// each view's turned back (the module's equation).
    pub(crate) fn average(
        &self,
        outputs: &[ModelTarget],
        d: &[f32],
        mut predict: impl FnMut(&[f32]) -> Result<Vec<f64>, LearnError>,
    ) -> Result<Vec<f64>, LearnError> {
        let mut sum = predict(d)?;
        let mut view = vec![0.0f32; d.len()];
        for turn in &self.turns {
            turn.displacements(d, &mut view);
            let mut columns = predict(&view)?;
            turn.turn_back(outputs, &mut columns);
            sum.iter_mut().zip(&columns).for_each(|(s, v)| *s += v);
        }
        let views = (self.turns.len() + 1) as f64;
        sum.iter_mut().for_each(|v| *v /= views);
        Ok(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::targets::{decode, wrap_deg, Unit};

    /// A hexagonal layout of `rings` rings about the origin: ring `k`
    /// walks the hexagon of corners `4 k (cos 60 j, sin 60 j)` in `k`
    /// steps a side.
    fn hex(rings: usize) -> Vec<[f64; 2]> {
        let corner = |k: usize, j: usize| {
            let (s, c) = (60.0 * j as f64).to_radians().sin_cos();
            [4.0 * k as f64 * c, 4.0 * k as f64 * s]
        };
        let mut pins = vec![[0.0, 0.0]];
        for k in 1..=rings {
            for j in 0..6 {
                let (a, b) = (corner(k, j), corner(k, j + 1));
                for step in 0..k {
                    let t = step as f64 / k as f64;
                    pins.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
                }
            }
        }
        pins
    }

    fn outputs() -> Vec<ModelTarget> {
        vec![
            ModelTarget::new("size", Unit::Mm),
            ModelTarget::circular("heading"),
        ]
    }

    const SIX: Rotations = Rotations {
        order: 6,
        angle_sign: -1,
        at_prediction: true,
    };

    /// An equivariant map: the length of the mean displacement (kept by a
    /// turn) and its heading in image axes, negated (`angle_sign` -1).
    fn equivariant(d: &[f32]) -> Result<Vec<f64>, LearnError> {
        let n = d.len() / 2;
        let sx: f64 = d[..n].iter().map(|&v| f64::from(v)).sum();
        let sy: f64 = d[n..].iter().map(|&v| f64::from(v)).sum();
        let heading = -sy.atan2(sx);
        Ok(vec![sx.hypot(sy), heading.sin(), heading.cos()])
    }

    /// A tap: pin `i` moves by a direction and length that vary over the
    /// pins, so no turn leaves it alone.
    fn tap(pins: &[[f64; 2]]) -> Vec<f32> {
        let n = pins.len();
        let mut d = vec![0.0f32; 2 * n];
        for (i, p) in pins.iter().enumerate() {
            d[i] = (0.3 + 0.05 * p[0] + 0.01 * p[1] * p[1]) as f32;
            d[n + i] = (-0.2 + 0.03 * p[1] - 0.02 * p[0]) as f32;
        }
        d
    }

    #[test]
    fn an_equivariant_map_averages_to_itself() {
        let pins = hex(3);
        let views = TurnedViews::new(&SIX, &pins).unwrap();
        let d = tap(&pins);
        let plain = equivariant(&d).unwrap();
        let mean = views.average(&outputs(), &d, equivariant).unwrap();
        for (a, b) in plain.iter().zip(&mean) {
            assert!((a - b).abs() < 1e-5, "{plain:?} vs {mean:?}");
        }
        let mut calls = 0;
        views
            .average(&outputs(), &d, |v| {
                calls += 1;
                equivariant(v)
            })
            .unwrap();
        assert_eq!(calls, 6, "the tap and its five turned views");
    }

    #[test]
    fn a_map_blind_to_the_turns_averages_its_angle_away() {
        // A map that gives every view the same heading, 40 deg: turned
        // back by 0, 60, ..., 300 deg the six unit vectors cancel, and
        // the position (kept by every turn) is unchanged.
        let pins = hex(2);
        let views = TurnedViews::new(&SIX, &pins).unwrap();
        let fixed = |_: &[f32]| {
            let a = 40f64.to_radians();
            Ok(vec![1.5, a.sin(), a.cos()])
        };
        let mean = views.average(&outputs(), &tap(&pins), fixed).unwrap();
        assert!((mean[0] - 1.5).abs() < 1e-12);
        assert!(mean[1].hypot(mean[2]) < 1e-12, "{mean:?}");
    }

    #[test]
    fn views_off_the_symmetry_are_pulled_to_their_circular_mean() {
        // Turn k's view predicts the true heading turned, plus an error
        // e_k; turned back, the views' headings are 100 + e_k, whose
        // circular mean (e_k symmetric about 0) is 100 deg, the wrap
        // crossed on the way.
        let pins = hex(2);
        let views = TurnedViews::new(&SIX, &pins).unwrap();
        let errors = [0.0, 8.0, -8.0, 3.0, -3.0, 0.0];
        let mut k = 0;
        let noisy = |_: &[f32]| {
            let heading = 100.0 - 60.0 * k as f64 + errors[k];
            k += 1;
            let a = heading.to_radians();
            Ok(vec![2.0, a.sin(), a.cos()])
        };
        let mean = views.average(&outputs(), &tap(&pins), noisy).unwrap();
        let values = decode(&outputs(), &mean);
        assert!((wrap_deg(values[1] - 100.0)).abs() < 1e-9, "{values:?}");
    }
}
