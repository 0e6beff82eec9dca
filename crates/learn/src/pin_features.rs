//! What a pose model's nets see of a tap ([`PinFeatures`]): the pins'
//! displacements as read, or beside them the local gradient of the
//! displacement field at every pin, the strain and rotation of the skin
//! under it, which a straight edge pressed at an angle shapes more
//! directly than the whole field's shear.
//!
//! The gradient at pin `i` (rest position `p_i`, displacement `d_i`) is the
//! 2 x 2 matrix `G_i` of least squares over its [`NEIGHBOURS`] nearest
//! pins `j` in the reference layout:
//! `G_i = argmin sum_j |(d_j - d_i) - G (p_j - p_i)|^2`, that is
//! `G_i = (sum_j (d_j - d_i) dp_j^T) (sum_j dp_j dp_j^T)^-1`, `dp_j = p_j - p_i`.
//! Its trace is the divergence (areal strain), `G_yx - G_xy` the curl
//! (twice the local rotation), its symmetric part the strain tensor.
//! Linear in the displacements, so the gradients of a rigid shift are 0
//! and those of an affine field `d = A p + b` are `A` exactly.
use crate::error::LearnError;
use serde::{Deserialize, Serialize};

/// Nearest pins over which each pin's gradient is fitted (a pin's ring of
/// six on the hexagonal and ring lattices).
pub const NEIGHBOURS: usize = 6;

/// The inputs of a pose model's nets, a typed option of
/// [`crate::ModelConfig`] recorded in the model file so prediction uses
/// the features training used.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PinFeatures {
    /// The displacements as read: `2P` inputs, x then y (the default).
    #[default]
    Displacements,
    /// The displacements, then every pin's gradient `G_i`: `6P` inputs
    /// (`x, y`, then `G_xx`, `G_xy`, `G_yx`, `G_yy` over the pins each).
    WithGradients,
}

impl PinFeatures {
    /// Whether it is the default (not written into configurations).
    pub fn is_displacements(&self) -> bool {
        *self == PinFeatures::Displacements
    }
}

/// Per pin, its neighbours and each neighbour's weights `w_jk` in
/// `G_i[c][a] = sum_k w_k[a] ((d_k)_c - (d_i)_c)`: the rows of the
/// least-squares pseudo-inverse `(dP^T dP)^-1 dP^T`.
#[derive(Debug, Clone, PartialEq)]
struct Stencil {
    neighbours: Vec<usize>,
    weights: Vec<[f64; 2]>,
}

/// The map from a displacement vector to a model's net inputs, built from
/// the training data's reference pins; serialised as those pins.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "FeatureMapFile", into = "FeatureMapFile")]
pub struct FeatureMap {
    kind: PinFeatures,
    reference_pins: Vec<[f64; 2]>,
    stencils: Vec<Stencil>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FeatureMapFile {
    kind: PinFeatures,
    reference_pins: Vec<[f64; 2]>,
}

impl TryFrom<FeatureMapFile> for FeatureMap {
    type Error = LearnError;
    fn try_from(f: FeatureMapFile) -> Result<Self, LearnError> {
        FeatureMap::new(f.kind, &f.reference_pins)
    }
}

impl From<FeatureMap> for FeatureMapFile {
    fn from(m: FeatureMap) -> Self {
        FeatureMapFile {
            kind: m.kind,
            reference_pins: m.reference_pins,
        }
    }
}

impl FeatureMap {
    /// The map of `kind` over the rest layout `reference_pins` (px, in
    /// input order); an error when there are too few pins or a pin's
    /// neighbours are collinear (no gradient).
    pub fn new(kind: PinFeatures, reference_pins: &[[f64; 2]]) -> Result<Self, LearnError> {
        let stencils = match kind {
            PinFeatures::Displacements => Vec::new(),
            PinFeatures::WithGradients => stencils(reference_pins)?,
        };
        Ok(FeatureMap {
            kind,
            reference_pins: reference_pins.to_vec(),
            stencils,
        })
    }

    /// Which features.
    pub fn kind(&self) -> PinFeatures {
        self.kind
    }

    /// Displacement-vector length taken (2 x pins).
    pub fn input_dim(&self) -> usize {
        2 * self.reference_pins.len()
    }

    /// Feature-vector length given.
    pub fn output_dim(&self) -> usize {
        match self.kind {
            PinFeatures::Displacements => self.input_dim(),
            PinFeatures::WithGradients => 6 * self.reference_pins.len(),
        }
    }

    /// Append the features of one displacement vector (x then y,
    /// [`Self::input_dim`] values) to `out`.
    pub fn extend(&self, displacement: &[f32], out: &mut Vec<f32>) {
        out.extend_from_slice(displacement);
        if self.kind == PinFeatures::Displacements {
            return;
        }
        let p = self.reference_pins.len();
        let (dx, dy) = displacement.split_at(p);
        let start = out.len();
        out.resize(start + 4 * p, 0.0);
        for (i, s) in self.stencils.iter().enumerate() {
            let mut g = [0.0f64; 4];
            for (&k, w) in s.neighbours.iter().zip(&s.weights) {
                let (ux, uy) = ((dx[k] - dx[i]) as f64, (dy[k] - dy[i]) as f64);
                g[0] += w[0] * ux;
                g[1] += w[1] * ux;
                g[2] += w[0] * uy;
                g[3] += w[1] * uy;
            }
            for (c, v) in g.into_iter().enumerate() {
                out[start + c * p + i] = v as f32;
            }
        }
    }

    /// The features of every row of `rows` (row-major, [`Self::input_dim`]
    /// a row).
    pub fn rows(&self, rows: &[f32]) -> Vec<f32> {
        let dim = self.input_dim();
        let mut out = Vec::with_capacity(rows.len() / dim * self.output_dim());
        for row in rows.chunks(dim) {
            self.extend(row, &mut out);
        }
        out
    }
}

/// Every pin's least-squares stencil over its [`NEIGHBOURS`] nearest pins
/// (ties broken by input order).
fn stencils(pins: &[[f64; 2]]) -> Result<Vec<Stencil>, LearnError> {
    if pins.len() <= NEIGHBOURS {
        return Err(LearnError::Config {
            field: "pin_features",
            reason: format!(
                "gradients need more than {NEIGHBOURS} reference pins, got {}",
                pins.len()
            ),
        });
    }
    pins.iter()
        .enumerate()
        .map(|(i, p)| {
            let mut order: Vec<usize> = (0..pins.len()).filter(|&j| j != i).collect();
            order.sort_by(|&a, &b| dist2(p, &pins[a]).total_cmp(&dist2(p, &pins[b])));
            order.truncate(NEIGHBOURS);
            let offsets: Vec<[f64; 2]> = order
                .iter()
                .map(|&j| [pins[j][0] - p[0], pins[j][1] - p[1]])
                .collect();
            let weights = pseudo_inverse_rows(&offsets).ok_or_else(|| LearnError::Config {
                field: "pin_features",
                reason: format!("the neighbours of reference pin {i} are collinear"),
            })?;
            Ok(Stencil {
                neighbours: order,
                weights,
            })
        })
        .collect()
}

fn dist2(a: &[f64; 2], b: &[f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// The columns of `(dP^T dP)^-1 dP^T` for the offsets `dP` (one row
/// each), as one `[a_x, a_y]` pair an offset; `None` when `dP^T dP` is
/// singular (collinear offsets).
fn pseudo_inverse_rows(offsets: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for o in offsets {
        sxx += o[0] * o[0];
        sxy += o[0] * o[1];
        syy += o[1] * o[1];
    }
    let det = sxx * syy - sxy * sxy;
    if det.abs() <= 1e-9 * (sxx * syy).max(f64::MIN_POSITIVE) {
        return None;
    }
    let inv = [[syy / det, -sxy / det], [-sxy / det, sxx / det]];
    Some(
        offsets
            .iter()
            .map(|o| {
                [
                    inv[0][0] * o[0] + inv[0][1] * o[1],
                    inv[1][0] * o[0] + inv[1][1] * o[1],
                ]
            })
            .collect(),
    )
}
