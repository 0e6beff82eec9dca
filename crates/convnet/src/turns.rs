//! Turned training frames ([`FrameTurns`]): a TacTip whose pins sit on
//! rings that carry onto themselves under a turn of `360/n` deg about the
//! dome's centre (the 331-pin TacTip: n = 6) sees a contact turned by
//! `k 360/n` deg as the same frame turned by that angle. Each training
//! frame is joined by its `n - 1` copies turned by `phi_k = k 360/n` deg
//! (bilinear resampling about the centre `c`): the copy's pixel at `p`
//! is the frame's value at `c + R(-phi_k) (p - c)`, so a pin at `q` lands
//! at `c + R(phi_k) (q - c)`, `R(phi) = [[cos, -sin], [sin, cos]]` in
//! image coordinates (x right, y down), as the pins' turned copies of
//! `tactrace_learn`'s `rotations` turn them. A circular target's angle
//! moves by `angle_sign phi_k`: its encoded sine and cosine turn as a
//! vector, `(sin(a + d), cos(a + d)) = (sin a cos d + cos a sin d, cos a
//! cos d - sin a sin d)`. Two targets named a vector ([`TurnedVector`],
//! a surface's two tilts) turn as one: `v' = R(vector_sign phi_k) v`
//! (a small-angle reading of the tilts: a turn about the dome's axis
//! turns the surface's normal, whose sideways part the two tilts are to
//! first order). Every other target is left as it is (the caller keeps to
//! targets a turn leaves alone, such as the edge's signed distance from
//! the centre or a surface's depth). Predictions never see a copy.
use crate::data::{Frames, Targets};
use crate::error::{config_error, ConvError};
use crate::model::ConvModel;
use serde::{Deserialize, Serialize};

/// The largest order of symmetry accepted (a turn of 30 deg).
pub const MAX_TURN_ORDER: usize = 12;

/// Training on every frame and its copies turned by `k 360/order` deg
/// about `centre`, `k = 1..order` ([`crate::ConvConfig::rotations`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameTurns {
    /// The pattern's order of symmetry n: each frame gains n - 1 turned
    /// copies (2..=[`MAX_TURN_ORDER`]).
    pub order: usize,
    /// How a circular target moves when the frame turns by `phi` in image
    /// coordinates (x right, y down): by `angle_sign * phi`, +1 or -1.
    pub angle_sign: i8,
    /// The centre of the turn `[x, y]`, px of the model's input frame
    /// (pixel centres at integers); `None`, the default, is the frame's
    /// centre `[(width - 1) / 2, (height - 1) / 2]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<[f64; 2]>,
    /// Predict with the mean of every turned view of a frame too
    /// ([`ConvModel::predict_batch_turned`]): each view's encoded angles
    /// turned back, so an angle is the circular mean of the views'. Off
    /// (false), the default, is left out of the JSON.
    #[serde(default, skip_serializing_if = "is_false")]
    pub at_prediction: bool,
    /// Pairs of targets that turn as a vector with the frame (none, the
    /// default, is left out of the JSON).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vectors: Vec<TurnedVector>,
}

/// Two targets, by name, that turn as a vector `(a, b)` when the frame
/// turns: by `sign * phi` for a turn of the frame by `phi` in image
/// coordinates, `(a, b) -> (a cos - b sin, a sin + b cos)`. The 331-pin
/// surface's tilts: `targets = ["pose_4", "pose_5"]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurnedVector {
    /// The names of the two components, `[a, b]`.
    pub targets: [String; 2],
    /// +1 or -1: how the vector turns with the frame.
    pub sign: i8,
}

/// Two encoded target columns `[a, b]` of a [`TurnedVector`] and its
/// sign, as the caller resolved its names ([`crate::Targets::with_vectors`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VectorColumns {
    /// The columns of `a` and `b`.
    pub columns: [usize; 2],
    /// +1 or -1, the [`TurnedVector`]'s.
    pub sign: i8,
}

/// The encoded columns a turn moves: the circular targets' sine columns
/// (cosine next) and the vectors' pairs.
#[derive(Debug, Clone, Copy, Default)]
pub struct TurnedColumns<'a> {
    /// Each circular target's sine column.
    pub angles: &'a [usize],
    /// Each vector's two columns and sign.
    pub vectors: &'a [VectorColumns],
}

fn is_false(v: &bool) -> bool {
    !*v
}

impl FrameTurns {
    /// Check the order, the sign and the centre.
    pub fn validate(&self) -> Result<(), ConvError> {
        if !(2..=MAX_TURN_ORDER).contains(&self.order) {
            return Err(config_error(
                "rotations.order",
                format!("{} is not in 2..={MAX_TURN_ORDER}", self.order),
            ));
        }
        if self.angle_sign.abs() != 1 {
            return Err(config_error(
                "rotations.angle_sign",
                format!("{} is not 1 or -1", self.angle_sign),
            ));
        }
        for v in &self.vectors {
            if v.sign.abs() != 1 {
                return Err(config_error(
                    "rotations.vectors.sign",
                    format!("{} is not 1 or -1", v.sign),
                ));
            }
            if v.targets[0] == v.targets[1] {
                return Err(config_error(
                    "rotations.vectors.targets",
                    format!("a vector of {} and itself", v.targets[0]),
                ));
            }
        }
        if let Some(c) = self.centre {
            if !c.iter().all(|v| v.is_finite()) {
                return Err(config_error(
                    "rotations.centre",
                    format!("[{}, {}] is not two finite numbers", c[0], c[1]),
                ));
            }
        }
        Ok(())
    }

    /// The centre of the turn for frames of `(height, width)` px.
    pub fn centre_for(&self, (h, w): (usize, usize)) -> [f64; 2] {
        self.centre
            .unwrap_or([(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0])
    }

    /// The turn of copy `k` (0 = the frame itself), deg in image
    /// coordinates.
    pub fn turn_deg(&self, k: usize) -> f64 {
        360.0 * k as f64 / self.order as f64
    }
}

/// `frame` (`(height, width)` grey px, row-major) turned by `deg` about
/// `centre` (`[x, y]` px) into `out`, by bilinear interpolation; a sample
/// that falls outside the frame takes the nearest edge pixel (outside
/// the dome's mask, so dark like it).
pub fn turn_frame(
    frame: &[u8],
    (h, w): (usize, usize),
    centre: [f64; 2],
    deg: f64,
    out: &mut [u8],
) {
    let (sin, cos) = deg.to_radians().sin_cos();
    let at = |x: isize, y: isize| -> f64 {
        let x = x.clamp(0, w as isize - 1) as usize;
        let y = y.clamp(0, h as isize - 1) as usize;
        f64::from(frame[y * w + x])
    };
    for (py, row) in out.chunks_exact_mut(w).enumerate().take(h) {
        let dy = py as f64 - centre[1];
        for (px, o) in row.iter_mut().enumerate() {
            let dx = px as f64 - centre[0];
            // R(-phi) (p - c) + c: where the pixel came from.
            let sx = centre[0] + cos * dx + sin * dy;
            let sy = centre[1] - sin * dx + cos * dy;
            let (x0, y0) = (sx.floor(), sy.floor());
            let (fx, fy) = (sx - x0, sy - y0);
            let (x0, y0) = (x0 as isize, y0 as isize);
            let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
            let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
            *o = (top * (1.0 - fy) + bottom * fy).round().clamp(0.0, 255.0) as u8;
        }
    }
}

/// One target row's encoded angles turned by `deg`: each `(sin, cos)`
/// pair starting at a column of `angles` turns as a vector.
pub fn turn_angles(row: &mut [f64], angles: &[usize], deg: f64) {
    let (sd, cd) = deg.to_radians().sin_cos();
    for &j in angles {
        let (s, c) = (row[j], row[j + 1]);
        row[j] = s * cd + c * sd;
        row[j + 1] = c * cd - s * sd;
    }
}

/// One target row's vector `(row[a], row[b])` turned by `deg`:
/// `(a cos - b sin, a sin + b cos)`.
pub fn turn_vector(row: &mut [f64], [a, b]: [usize; 2], deg: f64) {
    let (sd, cd) = deg.to_radians().sin_cos();
    let (x, y) = (row[a], row[b]);
    row[a] = x * cd - y * sd;
    row[b] = x * sd + y * cd;
}

/// One target row as a turn of the frame by `phi` deg moves it: the
/// angles by `angle_sign phi`, each vector by its `sign phi`.
fn turn_row(row: &mut [f64], columns: TurnedColumns, angle_sign: i8, phi: f64) {
    turn_angles(row, columns.angles, f64::from(angle_sign) * phi);
    for v in columns.vectors {
        turn_vector(row, v.columns, f64::from(v.sign) * phi);
    }
}

impl ConvModel {
    /// Whether it predicts with the mean of a frame's turned views
    /// ([`FrameTurns::at_prediction`]); `None` for a model fitted without
    /// `rotations`, which has no views to average.
    pub fn turned_views(&self) -> Option<bool> {
        self.config.rotations.as_ref().map(|t| t.at_prediction)
    }

    /// Switch the mean over turned views at prediction on or off
    /// ([`FrameTurns::at_prediction`]; training is not affected); refused
    /// for a model fitted without `rotations`.
    pub fn set_turned_views(&mut self, on: bool) -> Result<(), ConvError> {
        match self.config.rotations.as_mut() {
            Some(t) => {
                t.at_prediction = on;
                Ok(())
            }
            None => Err(config_error(
                "rotations.at_prediction",
                "the model was not fitted with rotations: it has no turned views",
            )),
        }
    }

    /// [`ConvModel::predict_batch`] (`count x N`, encoded and unscaled),
    /// or, when its `rotations` say `at_prediction`, the mean over the frames'
    /// `order` turned views, each view's angles (the sine columns
    /// `columns.angles`, cosine next) turned back by `-angle_sign phi_k`
    /// and its vectors by `-sign phi_k` first.
    pub fn predict_batch_turned(
        &self,
        frames: &Frames,
        columns: TurnedColumns,
    ) -> Result<Vec<f64>, ConvError> {
        let mut sum = self.predict_batch(frames)?;
        let Some(turns) = self.config.rotations.as_ref().filter(|t| t.at_prediction) else {
            return Ok(sum);
        };
        let (size, n, dim) = (frames.size(), frames.count(), self.outputs());
        let hw = size.0 * size.1;
        let centre = turns.centre_for(size);
        let mut pixels = vec![0u8; n * hw];
        for k in 1..turns.order {
            let deg = turns.turn_deg(k);
            for (i, out) in pixels.chunks_exact_mut(hw).enumerate() {
                turn_frame(frames.frame(i), size, centre, deg, out);
            }
            let mut view = self.predict_batch(&Frames::new(&pixels, n, size.0, size.1)?)?;
            for row in view.chunks_exact_mut(dim.max(1)) {
                turn_row(row, columns, turns.angle_sign, -deg);
            }
            sum.iter_mut().zip(&view).for_each(|(s, v)| *s += v);
        }
        let order = turns.order as f64;
        sum.iter_mut().for_each(|s| *s /= order);
        Ok(sum)
    }
}

/// Training frames and their turned copies, owned: copy `k` of frame `i`
/// is row `k count + i`.
pub(crate) struct TurnedSet {
    pixels: Vec<u8>,
    values: Vec<f64>,
    count: usize,
    size: (usize, usize),
    dim: usize,
}

impl TurnedSet {
    /// `frames` and `targets` followed by their copies under every turn
    /// of `turns`; pixels only: pins the frames carry are left out (their
    /// turn needs the pin layout; a model that reads them refuses turns,
    /// [`crate::ConvConfig::validate`]).
    pub fn of(frames: &Frames, targets: &Targets, turns: &FrameTurns) -> Result<Self, ConvError> {
        turns.validate()?;
        let (n, size, dim) = (frames.count(), frames.size(), targets.dim());
        let hw = size.0 * size.1;
        let centre = turns.centre_for(size);
        let mut pixels = vec![0u8; turns.order * n * hw];
        let mut values = Vec::with_capacity(turns.order * n * dim);
        for k in 0..turns.order {
            let deg = turns.turn_deg(k);
            let columns = targets.columns();
            let block = &mut pixels[k * n * hw..(k + 1) * n * hw];
            for (i, out) in block.chunks_exact_mut(hw).enumerate() {
                if k == 0 {
                    out.copy_from_slice(frames.frame(i));
                } else {
                    turn_frame(frames.frame(i), size, centre, deg, out);
                }
                let start = values.len();
                values.extend_from_slice(targets.row(i));
                turn_row(&mut values[start..], columns, turns.angle_sign, deg);
            }
        }
        Ok(Self {
            pixels,
            values,
            count: turns.order * n,
            size,
            dim,
        })
    }

    /// The frames, copies after the originals.
    pub fn frames(&self) -> Result<Frames<'_>, ConvError> {
        Frames::new(&self.pixels, self.count, self.size.0, self.size.1)
    }

    /// Their targets, with the columns a turn moves.
    pub fn targets<'a>(&'a self, columns: TurnedColumns<'a>) -> Result<Targets<'a>, ConvError> {
        Targets::new(&self.values, self.count, self.dim)?
            .with_angles(columns.angles)?
            .with_vectors(columns.vectors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIDE: usize = 33;

    /// A frame with a Gaussian spot (sigma 1.2 px) at `at`, dark elsewhere.
    fn spot_frame(at: [f64; 2]) -> Vec<u8> {
        let mut f = vec![0u8; SIDE * SIDE];
        for (i, v) in f.iter_mut().enumerate() {
            let (x, y) = ((i % SIDE) as f64, (i / SIDE) as f64);
            let d2 = (x - at[0]).powi(2) + (y - at[1]).powi(2);
            *v = (250.0 * (-d2 / (2.0 * 1.44)).exp()).round() as u8;
        }
        f
    }

    /// The intensity-weighted centroid of a frame.
    fn centroid(f: &[u8]) -> [f64; 2] {
        let (mut m, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for (i, &v) in f.iter().enumerate() {
            let v = f64::from(v);
            m += v;
            sx += v * (i % SIDE) as f64;
            sy += v * (i / SIDE) as f64;
        }
        [sx / m, sy / m]
    }

    /// Six turns about the spot frames' centre `[16, 16]`, angles and
    /// `vectors` turning by `+phi`.
    fn six_turns(vectors: Vec<TurnedVector>) -> FrameTurns {
        FrameTurns {
            order: 6,
            angle_sign: 1,
            centre: Some([16.0, 16.0]),
            at_prediction: false,
            vectors,
        }
    }

    #[test]
    fn each_copy_holds_the_turned_frame_and_its_turned_angle() {
        let centre = [16.0, 16.0];
        let turns = six_turns(Vec::new());
        // two frames: a spot at 9 px from the centre, at 20 and 75 deg
        // (image coordinates), each labelled with its angle's sine and
        // cosine after an unturned target 3.5 (as an edge's distance)
        let (mut pixels, mut values) = (Vec::new(), Vec::new());
        for a in [20.0f64, 75.0] {
            let (s, c) = a.to_radians().sin_cos();
            pixels.extend(spot_frame([centre[0] + 9.0 * c, centre[1] + 9.0 * s]));
            values.extend([3.5, s, c]);
        }
        let frames = Frames::new(&pixels, 2, SIDE, SIDE).unwrap();
        let angles = [1];
        let targets = Targets::new(&values, 2, 3)
            .unwrap()
            .with_angles(&angles)
            .unwrap();
        let set = TurnedSet::of(&frames, &targets, &turns).unwrap();
        let (tf, tt) = (
            set.frames().unwrap(),
            set.targets(targets.columns()).unwrap(),
        );
        assert_eq!(tf.count(), 12);
        for row in 0..12 {
            let c = centroid(tf.frame(row));
            let seen = (c[1] - centre[1]).atan2(c[0] - centre[0]).to_degrees();
            let t = tt.row(row);
            let label = t[1].atan2(t[2]).to_degrees();
            let diff = (seen - label + 540.0).rem_euclid(360.0) - 180.0;
            assert!(
                diff.abs() < 0.3,
                "copy {row}: spot at {seen} deg, label {label}"
            );
            assert!(((c[0] - centre[0]).hypot(c[1] - centre[1]) - 9.0).abs() < 0.1);
            assert_eq!(t[0], 3.5, "a target a turn leaves alone stays");
            assert!((t[1].hypot(t[2]) - 1.0).abs() < 1e-12);
        }
        assert_eq!(tf.frame(1), frames.frame(1), "copy 0 is the frame itself");
    }

    #[test]
    fn a_vector_turns_with_the_frame_and_depth_stays() {
        let centre = [16.0, 16.0];
        let turns = six_turns(vec![TurnedVector {
            targets: ["dx".into(), "dy".into()],
            sign: 1,
        }]);
        // a spot at offset (dx, dy) from the centre, labelled with a depth
        // and the offset as a vector (columns 1 and 2): in image
        // coordinates the spot turns by +phi, so the vector's sign is +1
        let (dx, dy) = (7.0, -4.0);
        let pixels = spot_frame([centre[0] + dx, centre[1] + dy]);
        let frames = Frames::new(&pixels, 1, SIDE, SIDE).unwrap();
        let values = [2.5, dx, dy];
        let vectors = [VectorColumns {
            columns: [1, 2],
            sign: 1,
        }];
        let targets = Targets::new(&values, 1, 3)
            .unwrap()
            .with_vectors(&vectors)
            .unwrap();
        let set = TurnedSet::of(&frames, &targets, &turns).unwrap();
        let (tf, tt) = (
            set.frames().unwrap(),
            set.targets(targets.columns()).unwrap(),
        );
        for row in 0..6 {
            let c = centroid(tf.frame(row));
            let t = tt.row(row);
            assert_eq!(t[0], 2.5, "copy {row}: the depth stays");
            assert!(
                (c[0] - centre[0] - t[1]).abs() < 0.1 && (c[1] - centre[1] - t[2]).abs() < 0.1,
                "copy {row}: spot at {c:?}, vector label ({}, {})",
                t[1],
                t[2]
            );
        }
    }

    #[test]
    fn a_vector_and_its_turn_back_cancel() {
        let mut row = [1.0, 0.3, -0.8, 0.6, 0.8];
        let columns = TurnedColumns {
            angles: &[3],
            vectors: &[VectorColumns {
                columns: [2, 1],
                sign: -1,
            }],
        };
        let before = row;
        turn_row(&mut row, columns, 1, 60.0);
        assert!((row[1] - before[1]).abs() > 0.1 && (row[3] - before[3]).abs() > 0.1);
        turn_row(&mut row, columns, 1, -60.0);
        for (a, b) in row.iter().zip(&before) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn the_copies_carry_no_pins() {
        let pixels = vec![0u8; SIDE * SIDE];
        let pins = [0.5f32, -0.5];
        let frames = Frames::new(&pixels, 1, SIDE, SIDE)
            .unwrap()
            .with_pins(&pins, 2)
            .unwrap();
        let values = [0.0, 1.0];
        let targets = Targets::new(&values, 1, 2).unwrap();
        let turns = FrameTurns {
            order: 6,
            angle_sign: -1,
            centre: None,
            at_prediction: false,
            vectors: Vec::new(),
        };
        let set = TurnedSet::of(&frames, &targets, &turns).unwrap();
        assert_eq!(set.frames().unwrap().pin_dim(), 0);
        assert_eq!(set.frames().unwrap().count(), 6);
    }
}
