//! The prediction path of a pose model (report ch. 4.2: standardise,
//! project onto the principal components, feed each net forward), laid out
//! once per model for speed:
//! - standardisation and projection are folded into one affine map per
//!   distinct projection (`u = A v + c`, in f64), and nets with the same
//!   PCA (the PDenNN's two nets are fitted on the same data) share it;
//! - with AVX-512 (detected at run time; `predict/avx512.rs`) rows are fed
//!   forward in blocks of [`BLOCK`], so every weight loaded feeds a block
//!   of rows (a single row is bound by reading the weights); elsewhere one
//!   row at a time through the training kernels, with fused multiply-adds
//!   where the CPU has AVX2 + FMA;
//! - no allocation per row;
//! - an ensemble's members each add their outputs, averaged before the
//!   targets are unscaled.
//!
//! The numbers are those of the plain path to rounding: f64 up to the
//! projection, f32 in the nets as before (`tests/predict.rs` checks
//! 1e-5 of the targets' spread).

use crate::kernels::sigmoid;
use crate::pose_model::PoseModel;

#[cfg(target_arch = "x86_64")]
mod avx512;

/// Rows fed forward together.
pub(crate) const BLOCK: usize = 8;

/// Columns of the projection the AVX-512 path keeps in registers at a
/// time (five vectors of eight f64).
pub(crate) const PROJECTION_COLUMNS: usize = 40;

/// `a` (`k x dim`, row-major) transposed to `dim x kp`, each row's `k`
/// values followed by zeros up to `kp`, the next multiple of
/// [`PROJECTION_COLUMNS`].
fn transposed_padded(a: &[f64], k: usize, dim: usize) -> Vec<f64> {
    let kp = k.next_multiple_of(PROJECTION_COLUMNS);
    let mut at = vec![0.0; dim * kp];
    for (j, row) in a.chunks_exact(dim).enumerate() {
        for (i, &v) in row.iter().enumerate() {
            at[i * kp + j] = v;
        }
    }
    at
}

/// How a net's inputs come from a displacement vector.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum InputMap {
    /// The standardised displacements: `(v - mean) / std`.
    Standardised { mean: Vec<f64>, std: Vec<f64> },
    /// Standardisation and PCA folded: `u = A v + c`, `A` row-major
    /// `k x dim`; `at` is `A` transposed, `dim` rows of its `k` columns
    /// zero-padded to a multiple of [`PROJECTION_COLUMNS`] (the layout
    /// the AVX-512 path reads).
    Projected {
        a: Vec<f64>,
        c: Vec<f64>,
        at: Vec<f64>,
    },
}

impl InputMap {
    pub fn width(&self) -> usize {
        match self {
            Self::Standardised { mean, .. } => mean.len(),
            Self::Projected { c, .. } => c.len(),
        }
    }
}

/// A pose model's prediction path (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Predictor {
    dim: usize,
    maps: Vec<InputMap>,
    /// Per net, the index of its input map.
    net_map: Vec<usize>,
}

impl Predictor {
    /// The path of `model`.
    pub fn new(model: &PoseModel) -> Self {
        let (mean, std) = (model.standardiser.mean(), model.standardiser.std());
        let mut maps: Vec<InputMap> = Vec::new();
        let mut net_map = Vec::new();
        for net in &model.nets {
            let map = match &net.pca {
                None => InputMap::Standardised {
                    mean: mean.to_vec(),
                    std: std.to_vec(),
                },
                Some(p) => {
                    let dim = p.dim();
                    let mut a = Vec::with_capacity(p.n_components() * dim);
                    let mut c = Vec::with_capacity(p.n_components());
                    let rows = p.components().chunks_exact(dim).zip(p.scales());
                    for (w, &scale) in rows {
                        let mut offset = 0.0;
                        for i in 0..dim {
                            let ai = scale * w[i] / std[i];
                            a.push(ai);
                            offset -= ai * mean[i] + scale * w[i] * p.mean()[i];
                        }
                        c.push(offset);
                    }
                    let at = transposed_padded(&a, c.len(), dim);
                    InputMap::Projected { a, c, at }
                }
            };
            let k = maps.iter().position(|m| *m == map).unwrap_or_else(|| {
                maps.push(map);
                maps.len() - 1
            });
            net_map.push(k);
        }
        Self {
            dim: model.input_dim(),
            maps,
            net_map,
        }
    }

    /// Multiply-adds of one prediction: each distinct projection's
    /// (f64) and every layer's (f32).
    pub fn multiply_adds(&self, model: &PoseModel) -> (usize, usize) {
        let f64_ops = self
            .maps
            .iter()
            .map(|m| match m {
                InputMap::Projected { a, .. } => a.len(),
                InputMap::Standardised { .. } => 0,
            })
            .sum();
        let f32_ops = model
            .nets
            .iter()
            .flat_map(|n| n.layers.sizes().windows(2).map(|w| w[0] * w[1]))
            .sum();
        (f64_ops, f32_ops)
    }

    /// Predicts every row of `flat` (rows of the model's input length,
    /// checked finite by the caller) into `out`.
    pub fn predict_rows(&self, model: &PoseModel, flat: &[f32], out: &mut Vec<[f64; 2]>) {
        #[cfg(target_arch = "x86_64")]
        {
            if avx512::available() {
                // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked above).
                return unsafe { avx512::rows(self, model, flat, out) };
            }
            if crate::net::has_fma() {
                // SAFETY: the CPU has AVX2 and FMA (checked by `has_fma`).
                return unsafe { rows_fma(self, model, flat, out) };
            }
        }
        rows::<false>(self, model, flat, out);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn rows_fma(p: &Predictor, model: &PoseModel, flat: &[f32], out: &mut Vec<[f64; 2]>) {
    rows::<true>(p, model, flat, out);
}

/// Working rows of a block of up to `rows` (at most [`BLOCK`]) rows,
/// kept between blocks.
pub(crate) struct Scratch {
    /// The block's inputs, f64, `rows x dim`.
    pub x: Vec<f64>,
    /// Each input map's values, f32, `rows x width`.
    pub maps: Vec<Vec<f32>>,
    /// Two activation buffers a layer reads from and writes to.
    pub act: [Vec<f32>; 2],
}

impl Scratch {
    /// Buffers for blocks of `rows` rows: one for a single prediction (a
    /// block's worth is 80 KB to zero for the report's nets, more than
    /// the prediction costs).
    pub fn new(p: &Predictor, model: &PoseModel, rows: usize) -> Self {
        let widest = model
            .nets
            .iter()
            .flat_map(|n| n.layers.sizes().iter().copied())
            .max()
            .unwrap_or(0);
        Self {
            x: vec![0.0; rows * p.dim],
            maps: p.maps.iter().map(|m| vec![0.0; rows * m.width()]).collect(),
            act: [vec![0.0; rows * widest], vec![0.0; rows * widest]],
        }
    }
}

/// One row at a time through the plain kernels of training (fused when
/// `F`).
#[inline(always)]
fn rows<const F: bool>(p: &Predictor, model: &PoseModel, flat: &[f32], out: &mut Vec<[f64; 2]>) {
    let mut s = Scratch::new(p, model, 1);
    for row in flat.chunks_exact(p.dim) {
        for (x, &v) in s.x.iter_mut().zip(row) {
            *x = f64::from(v);
        }
        for (map, values) in p.maps.iter().zip(&mut s.maps) {
            input_map::<F>(map, &s.x[..p.dim], values);
        }
        let mut scaled = [0.0f64; 2];
        for (net, &m) in model.nets.iter().zip(&p.net_map) {
            let layers = &net.layers;
            let depth = layers.depth();
            let [a, b] = &mut s.act;
            let d0 = layers.sizes()[0];
            a[..d0].copy_from_slice(&s.maps[m][..d0]);
            for l in 1..=depth {
                let (d_in, d_out) = (layers.sizes()[l - 1], layers.sizes()[l]);
                layers.affine::<F>(l, &a[..d_in], &mut b[..d_out]);
                if l < depth {
                    sigmoid::<F>(&b[..d_out], &mut a[..d_out]);
                } else {
                    a[..d_out].copy_from_slice(&b[..d_out]);
                }
            }
            for (k, &col) in net.targets.iter().enumerate() {
                scaled[col] += f64::from(a[k]);
            }
        }
        out.push(p.unscale(model, &scaled));
    }
}

impl Predictor {
    /// The input length.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The input maps and, per net, the index of its map.
    pub(crate) fn maps(&self) -> (&[InputMap], &[usize]) {
        (&self.maps, &self.net_map)
    }

    /// `[r mm, theta deg]` from the sums of the nets' scaled outputs
    /// (one net a column, or one a column per ensemble member: averaged).
    pub(crate) fn unscale(&self, model: &PoseModel, scaled: &[f64; 2]) -> [f64; 2] {
        let mut scaled = *scaled;
        model.average_members(&mut scaled);
        let mut pose = [0.0f64; 2];
        model.targets.inverse_into(&scaled, &mut pose);
        pose
    }
}

/// One row's input map: `x` (`dim` values) into `values`.
#[inline(always)]
fn input_map<const F: bool>(map: &InputMap, x: &[f64], values: &mut [f32]) {
    match map {
        InputMap::Standardised { mean, std } => {
            for (((v, &x), m), s) in values.iter_mut().zip(x).zip(mean).zip(std) {
                *v = ((x - m) / s) as f32;
            }
        }
        InputMap::Projected { a, c, .. } => {
            for ((v, aj), &cj) in values.iter_mut().zip(a.chunks_exact(x.len())).zip(c) {
                *v = (dot64::<F>(aj, x) + cj) as f32;
            }
        }
    }
}

/// `a . x` in f64 with eight independent accumulators.
#[inline(always)]
fn dot64<const F: bool>(a: &[f64], x: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let (ca, cx) = (a.chunks_exact(8), x.chunks_exact(8));
    let mut tail = 0.0;
    for (&u, &v) in ca.remainder().iter().zip(cx.remainder()) {
        tail = madd64::<F>(u, v, tail);
    }
    for (u, v) in ca.zip(cx) {
        for t in 0..8 {
            acc[t] = madd64::<F>(u[t], v[t], acc[t]);
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// `a * b + c` in f64, fused when `F` (as [`madd`]).
#[inline(always)]
fn madd64<const F: bool>(a: f64, b: f64, c: f64) -> f64 {
    if F {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// The crate's test data (its integration tests' `mod support`).
#[cfg(test)]
#[path = "../tests/it/support/mod.rs"]
mod test_support;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{ModelConfig, ModelKind, Preset};
    use crate::dataset::Dataset;
    use crate::net::States;
    use test_support as support;

    /// The prediction as it was computed before the fast path: one row,
    /// f64 standardisation and PCA, then each net's plain (unfused)
    /// feed-forward pass in f32.
    fn plain_predict(model: &PoseModel, row: &[f32]) -> [f64; 2] {
        let mut z = vec![0.0f64; model.input_dim()];
        model.standardiser.transform_into(row, &mut z);
        let mut scaled = [0.0f64; 2];
        for net in &model.nets {
            let input: Vec<f32> = match &net.pca {
                Some(p) => p.transform(&z),
                None => z.clone(),
            }
            .into_iter()
            .map(|v| v as f32)
            .collect();
            let mut st = States::new(net.layers.sizes());
            net.layers.forward::<false>(&input, &mut st);
            for (k, &col) in net.targets.iter().enumerate() {
                scaled[col] += f64::from(st.s[net.layers.depth()][k]);
            }
        }
        model.average_members(&mut scaled);
        let mut pose = [0.0f64; 2];
        model.targets.inverse_into(&scaled, &mut pose);
        pose
    }

    /// A model of `kind` fitted for `epochs` on `n` random rows of `dim`
    /// correlated values (pin-displacement-like), with hidden sizes `hidden`.
    fn model(kind: ModelKind, dim: usize, hidden: &[usize], seed: u64) -> (PoseModel, Dataset) {
        let n = 120;
        let (x, y) = support::correlated_rows(n, dim, seed);
        let data = Dataset::new(x, y, n, dim, 2).expect("data");
        let mut cfg = ModelConfig::preset(kind, Preset::Default);
        cfg.set_epochs(2);
        for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
            .into_iter()
            .flatten()
        {
            net.hidden = hidden.to_vec();
            if let Some(k) = net.n_components.as_mut() {
                *k = (*k).min(dim / 2);
            }
        }
        let (m, _) = PoseModel::fit(&cfg, &data, &mut |_| {}).expect("fit");
        (m, data)
    }

    /// Each target's spread (std) over the plain predictions of `rows`.
    fn spread(m: &PoseModel, rows: &[f32]) -> [f64; 2] {
        let plain: Vec<[f64; 2]> = rows
            .chunks_exact(m.input_dim())
            .map(|r| plain_predict(m, r))
            .collect();
        let n = plain.len() as f64;
        std::array::from_fn(|k| {
            let mean = plain.iter().map(|p| p[k]).sum::<f64>() / n;
            (plain.iter().map(|p| (p[k] - mean).powi(2)).sum::<f64>() / n).sqrt()
        })
    }

    /// Largest difference from the plain path over `rows`, in units of
    /// each target's spread `s`, of both the block path and one row at a
    /// time.
    fn worst_difference(m: &PoseModel, rows: &[f32], s: [f64; 2]) -> f64 {
        let fast = m.predict_rows(rows).expect("rows");
        let dim = m.input_dim();
        let plain: Vec<[f64; 2]> = rows
            .chunks_exact(dim)
            .map(|r| plain_predict(m, r))
            .collect();
        let mut worst = 0.0f64;
        for (i, (f, p)) in fast.iter().zip(&plain).enumerate() {
            let one = m.predict(&rows[i * dim..(i + 1) * dim]).expect("one");
            for k in 0..2 {
                worst = worst.max((f[k] - p[k]).abs() / s[k]);
                worst = worst.max((one[k] - p[k]).abs() / s[k]);
            }
        }
        worst
    }

    /// Every model kind, odd and default layer sizes, blocks of rows full
    /// and short: the fast path gives the plain path's predictions within
    /// 1e-5 of the targets' spread.
    #[test]
    fn fast_predictions_equal_the_plain_path_within_1e_5() {
        let cases: [(ModelKind, usize, &[usize]); 6] = [
            (ModelKind::PDenNN, 254, &[1000]),
            (ModelKind::PcaDenNN, 254, &[1000]),
            (ModelKind::DisDenNN, 254, &[500]),
            (ModelKind::Mlp, 40, &[37]),
            (ModelKind::PDenNN, 30, &[45, 9]),
            (ModelKind::DisDenNN, 19, &[3]),
        ];
        for (seed, (kind, dim, hidden)) in cases.into_iter().enumerate() {
            let (m, data) = model(kind, dim, hidden, seed as u64);
            let s = spread(&m, &data.x);
            for rows in [1, 7, 8, 9, 21] {
                let worst = worst_difference(&m, &data.x[..rows * dim], s);
                eprintln!("{kind:?} {dim} {hidden:?}, {rows} rows: {worst:e}");
                assert!(
                    worst < 1e-5,
                    "{kind:?} {dim} {hidden:?}, {rows} rows: {worst:e}"
                );
            }
        }
    }
}
