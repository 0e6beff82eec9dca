//! A linear correction of the simulated pin field, fitted on a few real
//! taps (`tactrace calibrate`, docs/calibration.md): for the displacement d
//! of every pin from its rest position, stacked as the 2P values of a
//! dataset row (all x, then all y, pins in rest order),
//!
//! d' = d + W d + b,
//!
//! and the pins are moved to rest + d'. A tap without contact (d = 0)
//! stays at the rest pins exactly: the correction describes how the real
//! skin answers a contact, not a bias of the empty frame.
use crate::SensorError;

/// W (2P x 2P, row-major: row = output coordinate) and b (2P), px.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldCorrection {
    pins: usize,
    w: Vec<f32>,
    b: Vec<f32>,
}

impl FieldCorrection {
    /// A correction for `pins` pins; errors when W or b has another size or
    /// a non-finite value.
    pub fn new(pins: usize, w: Vec<f32>, b: Vec<f32>) -> Result<Self, SensorError> {
        let d = 2 * pins;
        if w.len() != d * d || b.len() != d {
            return Err(SensorError::Correction {
                reason: format!(
                    "W has {} values and b {} for {pins} pins (need {} and {d})",
                    w.len(),
                    b.len(),
                    d * d
                ),
            });
        }
        if w.iter().chain(&b).any(|v| !v.is_finite()) {
            return Err(SensorError::Correction {
                reason: "a non-finite value".into(),
            });
        }
        Ok(Self { pins, w, b })
    }

    /// Pins it corrects.
    pub fn pins(&self) -> usize {
        self.pins
    }

    /// `pins` (px, rest order) corrected around `rest`.
    pub fn apply(&self, rest: &[[f64; 2]], pins: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let p = self.pins;
        if pins.len() != p || rest.len() != p || pins == rest {
            return pins.to_vec();
        }
        let d: Vec<f64> = (0..2 * p)
            .map(|k| pins[k % p][k / p] - rest[k % p][k / p])
            .collect();
        let corrected = |k: usize| {
            let row = &self.w[k * 2 * p..(k + 1) * 2 * p];
            let wd: f64 = row.iter().zip(&d).map(|(w, x)| f64::from(*w) * x).sum();
            d[k] + wd + f64::from(self.b[k])
        };
        (0..p)
            .map(|i| [rest[i][0] + corrected(i), rest[i][1] + corrected(p + i)])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_and_rest_are_kept_and_a_known_map_is_applied() {
        let rest = vec![[10.0, 20.0], [30.0, 40.0]];
        let pins = vec![[11.0, 20.5], [29.0, 42.0]];
        let zero = FieldCorrection::new(2, vec![0.0; 16], vec![0.0; 4]).unwrap();
        assert_eq!(zero.apply(&rest, &pins), pins);
        // W doubles every coordinate's displacement (d' = 2 d) and b adds 1.
        let mut w = vec![0.0; 16];
        for k in 0..4 {
            w[k * 4 + k] = 1.0;
        }
        let c = FieldCorrection::new(2, w, vec![1.0; 4]).unwrap();
        assert_eq!(c.apply(&rest, &rest), rest, "no contact stays at rest");
        let got = c.apply(&rest, &pins);
        assert_eq!(got, vec![[13.0, 22.0], [29.0, 45.0]]);
        assert!(FieldCorrection::new(2, vec![0.0; 15], vec![0.0; 4]).is_err());
        assert!(FieldCorrection::new(2, vec![f32::NAN; 16], vec![0.0; 4]).is_err());
    }
}
