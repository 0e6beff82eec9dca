//! Mirror copies of the training taps ([`Reflections`]): a pin layout on a
//! hexagonal lattice (the 127-pin TacTip: six rings about a centre pin)
//! is carried onto itself by a mirror across any of its six lattice axes
//! through the centre, so a contact mirrored across such an axis is seen
//! as the same field of displacements mirrored and carried to the pins
//! the mirror lands on. With `M` the reflection across the line through
//! the layout's centre `c` at `axis_deg` (image coordinates, x right, y
//! down),
//!
//! `M = [[cos 2a, sin 2a], [sin 2a, -cos 2a]]`,
//!
//! pin `i` at `q_i` lands on the pin `j` nearest `c + M (q_i - c)`, and
//! the copy's displacement at `j` is `M d_i`. A target the mirror leaves
//! alone (a surface's depth) is kept; one it reverses (a surface angle
//! tilted across the mirror line) is negated: which ones, the dataset
//! says, checked by predicting mirrored taps with a model fitted without
//! the copies ([`mirrored_inputs`]). A circular angle would move to
//! `2a' - theta`, which is not supported: such targets are refused.
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::rotations::{centre, median_spacing, nearest, MATCH_TOLERANCE};
use crate::targets::{encoded_columns, ModelTarget};
use serde::{Deserialize, Serialize};

/// Training on every tap and its mirror copy across one lattice axis
/// ([`crate::ModelConfig::reflections`]); predictions see the tap alone,
/// or with `at_prediction` the mean of the tap's and its mirror copy's
/// predictions, the copy's mirrored back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reflections {
    /// The mirror line's direction through the layout's centre, deg from
    /// the image's +x axis towards +y (down), in [0, 180).
    pub axis_deg: f64,
    /// The targets the mirror negates (names as the model's targets, none
    /// circular); every other target is kept.
    #[serde(default)]
    pub negate: Vec<String>,
    /// Predict every tap and its mirror copy, mirror the copy's
    /// prediction back and average the two. False (the default, not
    /// written): the tap alone.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub at_prediction: bool,
}

impl Reflections {
    /// Check the axis and that no target is named twice.
    pub fn validate(&self) -> Result<(), LearnError> {
        if !(self.axis_deg.is_finite() && (0.0..180.0).contains(&self.axis_deg)) {
            return Err(reflections_err(format!(
                "axis_deg {} must lie in [0, 180)",
                self.axis_deg
            )));
        }
        for (k, name) in self.negate.iter().enumerate() {
            if self.negate[..k].contains(name) {
                return Err(reflections_err(format!(
                    "target `{name}` is named twice in negate"
                )));
            }
        }
        Ok(())
    }

    /// The sign of every target of `outputs` under the mirror (-1 for
    /// the negated ones, else 1); error for a name that is not one of
    /// `outputs`, or when one of `outputs` is circular.
    fn signs(&self, outputs: &[ModelTarget]) -> Result<Vec<f32>, LearnError> {
        for name in &self.negate {
            if !outputs.iter().any(|o| &o.name == name) {
                let names: Vec<&str> = outputs.iter().map(|o| o.name.as_str()).collect();
                return Err(reflections_err(format!(
                    "target `{name}` is not one of the model's ({})",
                    names.join(", ")
                )));
            }
        }
        if let Some(t) = outputs.iter().find(|o| o.circular) {
            return Err(reflections_err(format!(
                "target `{}` is circular: a mirror moves it to 2a - theta, not supported",
                t.name
            )));
        }
        Ok(outputs
            .iter()
            .map(|o| {
                if self.negate.contains(&o.name) {
                    -1.0
                } else {
                    1.0
                }
            })
            .collect())
    }
}

/// The mirror of a layout: where each pin lands and the reflection.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Mirror {
    /// `lands[i]`: the pin that pin `i` lands on.
    lands: Vec<usize>,
    /// `cos 2a`, `sin 2a` of the reflection matrix.
    cos2: f64,
    sin2: f64,
}

impl Mirror {
    /// The mirror of `pins` (px) across the line at `axis_deg` through
    /// their centre, refused when a pin lands farther than
    /// [`MATCH_TOLERANCE`] spacings from every pin or two land on one.
    pub(crate) fn new(pins: &[[f64; 2]], axis_deg: f64) -> Result<Self, LearnError> {
        let tolerance = MATCH_TOLERANCE * median_spacing(pins)?;
        let c = centre(pins);
        let (sin2, cos2) = (2.0 * axis_deg).to_radians().sin_cos();
        let mut lands = Vec::with_capacity(pins.len());
        let mut taken = vec![false; pins.len()];
        for p in pins {
            let (x, y) = (p[0] - c[0], p[1] - c[1]);
            let to = [c[0] + cos2 * x + sin2 * y, c[1] + sin2 * x - cos2 * y];
            let (j, dist) = nearest(pins, to);
            if dist > tolerance || taken[j] {
                return Err(reflections_err(format!(
                    "the pin layout is not symmetric under a mirror at {axis_deg} deg: a pin \
                     lands {dist:.2} px from the nearest pin (tolerance {tolerance:.2} px){}",
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
        Ok(Self { lands, cos2, sin2 })
    }

    /// The mirror copy of one displacement vector (`P` x values, then `P`
    /// y values) into `out`.
    pub(crate) fn displacements(&self, d: &[f32], out: &mut [f32]) {
        let n = self.lands.len();
        for (i, &j) in self.lands.iter().enumerate() {
            let (x, y) = (f64::from(d[i]), f64::from(d[n + i]));
            out[j] = (self.cos2 * x + self.sin2 * y) as f32;
            out[n + j] = (self.sin2 * x - self.cos2 * y) as f32;
        }
    }
}

/// Where each pin of `pins` (px) lands under the mirror across the line
/// at `axis_deg` through their centre (`lands[i]`: the pin `i` lands
/// on); error for a layout the mirror does not carry onto itself.
pub fn mirror_pins(pins: &[[f64; 2]], axis_deg: f64) -> Result<Vec<usize>, LearnError> {
    Ok(Mirror::new(pins, axis_deg)?.lands)
}

/// The inputs of `data` mirrored across the line at `axis_deg` through
/// the centre of `pins`, the targets as read: what a model fitted without
/// the copies predicts to tell which targets the mirror negates.
pub fn mirrored_inputs(
    data: &Dataset,
    pins: &[[f64; 2]],
    axis_deg: f64,
) -> Result<Dataset, LearnError> {
    check_layout(data, pins)?;
    let mirror = Mirror::new(pins, axis_deg)?;
    let mut x = vec![0.0f32; data.x.len()];
    for (i, out) in x.chunks_mut(data.dim_x).enumerate() {
        mirror.displacements(data.x_row(i), out);
    }
    Dataset::new(x, data.y.clone(), data.n, data.dim_x, data.dim_y)
}

/// `data` (displacements laid out against `pins`, px; targets as
/// `outputs` name them) followed by its mirror copies, the targets of
/// `refl.negate` negated: what a model with
/// [`crate::ModelConfig::reflections`] is fitted on.
pub fn mirrored_copies(
    data: &Dataset,
    outputs: &[ModelTarget],
    refl: &Reflections,
    pins: &[[f64; 2]],
) -> Result<Dataset, LearnError> {
    refl.validate()?;
    if outputs.len() != data.dim_y {
        return Err(LearnError::Shape {
            what: "targets per sample",
            expected: outputs.len(),
            got: data.dim_y,
        });
    }
    let signs = refl.signs(outputs)?;
    let copies = mirrored_inputs(data, pins, refl.axis_deg)?;
    let mut x = data.x.clone();
    x.extend_from_slice(&copies.x);
    let mut y = data.y.clone();
    for i in 0..data.n {
        y.extend(data.y_row(i).iter().zip(&signs).map(|(v, s)| v * s));
    }
    Dataset::new(x, y, 2 * data.n, data.dim_x, data.dim_y)
}

/// The layout a model with reflections was fitted over and its mirror:
/// what averaging the tap with its mirror copy needs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MirrorViews {
    /// The reference pins (px, in input order).
    pins: Vec<[f64; 2]>,
    mirror: Mirror,
    /// The encoded columns the mirror negates.
    negated: Vec<usize>,
}

impl MirrorViews {
    /// The mirror of `refl` over `pins` for a model of `outputs`.
    pub(crate) fn new(
        refl: &Reflections,
        outputs: &[ModelTarget],
        pins: &[[f64; 2]],
    ) -> Result<Self, LearnError> {
        refl.validate()?;
        let signs = refl.signs(outputs)?;
        let columns = encoded_columns(outputs);
        let negated = signs
            .iter()
            .zip(&columns)
            .filter(|(s, _)| **s < 0.0)
            .flat_map(|(_, c)| c.iter().copied())
            .collect();
        Ok(Self {
            pins: pins.to_vec(),
            mirror: Mirror::new(pins, refl.axis_deg)?,
            negated,
        })
    }

    /// The reference pins the mirror was found over.
    pub(crate) fn pins(&self) -> &[[f64; 2]] {
        &self.pins
    }

    /// `(f(d) + S f(M d)) / 2`: the mean of `predict`'s columns of the tap
    /// `d` and of its mirror copy, the copy's negated columns (`S`)
    /// negated back.
    pub(crate) fn average(
        &self,
        d: &[f32],
        mut predict: impl FnMut(&[f32]) -> Result<Vec<f64>, LearnError>,
    ) -> Result<Vec<f64>, LearnError> {
        let mut sum = predict(d)?;
        let mut view = vec![0.0f32; d.len()];
        self.mirror.displacements(d, &mut view);
        let mut copy = predict(&view)?;
        for &k in &self.negated {
            copy[k] = -copy[k];
        }
        sum.iter_mut()
            .zip(&copy)
            .for_each(|(s, v)| *s = 0.5 * (*s + v));
        Ok(sum)
    }
}

/// `data`'s inputs are two values a pin of `pins`.
fn check_layout(data: &Dataset, pins: &[[f64; 2]]) -> Result<(), LearnError> {
    if 2 * pins.len() != data.dim_x {
        return Err(LearnError::DimensionMismatch {
            expected: 2 * pins.len(),
            got: data.dim_x,
        });
    }
    Ok(())
}

fn reflections_err(reason: String) -> LearnError {
    LearnError::Config {
        field: "reflections",
        reason,
    }
}

/// `train` with its mirror copies by `cfg.reflections` over
/// `reference_pins`; `None` without reflections.
pub(crate) fn mirrored_training_data(
    cfg: &crate::ModelConfig,
    outputs: &[ModelTarget],
    train: &Dataset,
    reference_pins: Option<&[[f64; 2]]>,
) -> Result<Option<Dataset>, LearnError> {
    let Some(refl) = &cfg.reflections else {
        return Ok(None);
    };
    mirrored_copies(train, outputs, refl, needs_pins(reference_pins)?).map(Some)
}

/// The mirror views of a model of `outputs` with `cfg.reflections`
/// fitted over `reference_pins`; `None` without reflections.
pub(crate) fn mirror_views(
    cfg: &crate::ModelConfig,
    outputs: &[ModelTarget],
    reference_pins: Option<&[[f64; 2]]>,
) -> Result<Option<MirrorViews>, LearnError> {
    let Some(refl) = &cfg.reflections else {
        return Ok(None);
    };
    MirrorViews::new(refl, outputs, needs_pins(reference_pins)?).map(Some)
}

fn needs_pins(reference_pins: Option<&[[f64; 2]]>) -> Result<&[[f64; 2]], LearnError> {
    reference_pins
        .ok_or_else(|| reflections_err("mirror copies of the taps need the reference pins".into()))
}

/// The mirror views of a model file with `config.reflections` over its
/// recorded `pins` (a model of `outputs`, `input_dim` inputs); the reason
/// the file is corrupt otherwise.
pub(crate) fn load_mirror(
    config: &crate::ModelConfig,
    outputs: &[ModelTarget],
    pins: Option<&[[f64; 2]]>,
    input_dim: usize,
) -> Result<Option<MirrorViews>, String> {
    match (&config.reflections, pins) {
        (Some(refl), Some(pins)) if 2 * pins.len() == input_dim => {
            MirrorViews::new(refl, outputs, pins)
                .map(Some)
                .map_err(|e| format!("reflection_pins: {e}"))
        }
        (Some(_), Some(pins)) => Err(format!(
            "{} reflection_pins, but the model takes {input_dim} inputs",
            pins.len()
        )),
        (Some(_), None) => Err("reflections without reflection_pins".into()),
        (None, Some(_)) => Err("reflection_pins without reflections".into()),
        (None, None) => Ok(None),
    }
}
