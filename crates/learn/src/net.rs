//! Weights, biases and the feed-forward pass shared by the dendritic network
//! and its backprop twin, in the report's notation (ch. 3.3): `W(l)` is
//! `d(l-1) x d(l)` (stored in column panels, or transposed when narrow), and
//! `s(l) = W(l)^T phi(s(l-1)) + b(l)` with `phi` the identity on the input,
//! the sigmoid on hidden layers, and a linear output `y = s(N)`.
use crate::error::LearnError;
use crate::kernels::{
    affine_cols, affine_panels, back_cols, back_panels, from_panels, madd, rank1_cols,
    rank1_panels, rank1_then_affine_panels, sigmoid, to_panels,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Uniform};

/// Layers narrower than this store `W(l)` transposed (`d(l) x d(l-1)`), so
/// their products are contiguous dots instead of short strided rows; wider
/// layers store it in column panels (see [`crate::kernels::panels`]), so the
/// sweeps over it keep a panel's partial sums in registers and read memory
/// contiguously.
const NARROW: usize = 16;

fn is_narrow(d_out: usize) -> bool {
    d_out < NARROW
}

/// Row-major `rows x cols` to row-major `cols x rows`.
fn transpose(w: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    (0..cols * rows)
        .map(|k| w[(k % rows) * cols + k / rows])
        .collect()
}

/// The parameters of a fully connected network with sizes `d(0..=N)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Layers {
    pub(crate) sizes: Vec<usize>,
    /// `w[l - 1]` is `W(l)`: `d(l-1) x d(l)` in column panels, or its
    /// row-major transpose for narrow layers (see [`NARROW`]).
    pub(crate) w: Vec<Vec<f32>>,
    /// `b[l - 1]` is `b(l)`.
    pub(crate) b: Vec<Vec<f32>>,
}

/// Layer sizes for people: `254 -> 1000 -> 1`.
pub(crate) fn sizes_text(sizes: &[usize]) -> String {
    let parts: Vec<String> = sizes.iter().map(usize::to_string).collect();
    if parts.is_empty() {
        "(no layers)".into()
    } else {
        parts.join(" -> ")
    }
}

impl Layers {
    /// Uniform weights in `+-1/sqrt(d(l-1))` (keeps hidden pre-activations
    /// of unit-scale inputs near the sigmoid's linear range), zero biases.
    pub fn new(sizes: &[usize], seed: u64) -> Result<Self, LearnError> {
        if sizes.len() < 2 || sizes.contains(&0) {
            return Err(LearnError::Config {
                field: "sizes",
                reason: format!(
                    "{}: need at least an input and an output layer, all non-empty",
                    sizes_text(sizes)
                ),
            });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut w = Vec::new();
        for pair in sizes.windows(2) {
            let bound = 1.0 / (pair[0] as f32).sqrt();
            let dist = Uniform::new_inclusive(-bound, bound).map_err(|e| LearnError::Config {
                field: "sizes",
                reason: e.to_string(),
            })?;
            let canonical: Vec<f32> = (0..pair[0] * pair[1])
                .map(|_| dist.sample(&mut rng))
                .collect();
            w.push(to_storage(canonical, pair[0], pair[1]));
        }
        let b = sizes[1..].iter().map(|&d| vec![0.0; d]).collect();
        Ok(Layers {
            sizes: sizes.to_vec(),
            w,
            b,
        })
    }

    /// Rebuild from stored parts, checking every shape.
    pub(crate) fn from_parts(
        sizes: Vec<usize>,
        w: Vec<Vec<f32>>,
        b: Vec<Vec<f32>>,
    ) -> Result<Self, LearnError> {
        let n = sizes.len().saturating_sub(1);
        let shapes_ok = n >= 1
            && !sizes.contains(&0)
            && w.len() == n
            && b.len() == n
            && (0..n).all(|l| w[l].len() == sizes[l] * sizes[l + 1] && b[l].len() == sizes[l + 1]);
        if !shapes_ok {
            return Err(LearnError::Corrupt {
                reason: format!("weights do not match layer sizes {}", sizes_text(&sizes)),
            });
        }
        let w = w
            .into_iter()
            .enumerate()
            .map(|(l, m)| to_storage(m, sizes[l], sizes[l + 1]))
            .collect();
        Ok(Layers { sizes, w, b })
    }

    /// `W(l)` (`l` in `1..=N`) as row-major `d(l-1) x d(l)`, the report's
    /// orientation, whatever the internal storage.
    pub fn weight(&self, l: usize) -> Vec<f32> {
        let (rows, cols) = (self.sizes[l - 1], self.sizes[l]);
        if is_narrow(cols) {
            transpose(&self.w[l - 1], cols, rows)
        } else {
            from_panels(&self.w[l - 1], rows, cols)
        }
    }

    /// `b(l)` for `l` in `1..=N`.
    pub fn bias(&self, l: usize) -> &[f32] {
        &self.b[l - 1]
    }

    /// Number of weight layers `N`.
    pub fn depth(&self) -> usize {
        self.sizes.len() - 1
    }

    /// Layer sizes `d(0..=N)`.
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// Whether every weight and bias is finite.
    pub fn is_finite(&self) -> bool {
        self.w
            .iter()
            .chain(&self.b)
            .all(|v| v.iter().all(|a| a.is_finite()))
    }

    /// `out = W(l)^T a + b(l)` for layer `l` in `1..=N`.
    #[inline(always)]
    pub(crate) fn affine<const FMA: bool>(&self, l: usize, a: &[f32], out: &mut [f32]) {
        if is_narrow(self.sizes[l]) {
            affine_cols::<FMA>(&self.w[l - 1], a, &self.b[l - 1], out);
        } else {
            affine_panels::<FMA>(&self.w[l - 1], a, &self.b[l - 1], out);
        }
    }

    /// `g = W(l) e` (the error sent down from layer `l` to layer `l - 1`).
    #[inline(always)]
    pub(crate) fn back<const FMA: bool>(&self, l: usize, e: &[f32], g: &mut [f32]) {
        if is_narrow(self.sizes[l]) {
            back_cols::<FMA>(&self.w[l - 1], e, g);
        } else {
            back_panels::<FMA>(&self.w[l - 1], e, g);
        }
    }

    /// `W(l) += u v^T`, `b(l) += g v`.
    #[inline(always)]
    pub(crate) fn rank1<const FMA: bool>(&mut self, l: usize, u: &[f32], (v, g): (&[f32], f32)) {
        if is_narrow(self.sizes[l]) {
            rank1_cols::<FMA>(&mut self.w[l - 1], u, v);
        } else {
            rank1_panels::<FMA>(&mut self.w[l - 1], u, v);
        }
        let bias = self.b[l - 1].iter_mut().zip(v);
        bias.for_each(|(b, &v)| *b = madd::<FMA>(g, v, *b));
    }

    /// `W(1) += u v^T`, `b(1) += g v`, then the next sample's first-layer
    /// drive `out = W(1)^T next + b(1)`, fused into one sweep when `W(1)` is
    /// wide (the same numbers as doing both in turn).
    #[inline(always)]
    pub(crate) fn rank1_then_drive<const FMA: bool>(
        &mut self,
        u: &[f32],
        v: (&[f32], f32),
        next: &[f32],
        out: &mut [f32],
    ) {
        if is_narrow(self.sizes[1]) {
            self.rank1::<FMA>(1, u, v);
            self.affine::<FMA>(1, next, out);
        } else {
            rank1_then_affine_panels::<FMA>(&mut self.w[0], u, v, next, &mut self.b[0], out);
        }
    }

    /// Layers `2..=N` of the feed-forward pass, given the first layer's
    /// drive `s(1)` already in `st.s[1]` and the input in `st.phi[0]`.
    #[inline(always)]
    pub(crate) fn forward_from_drive<const FMA: bool>(&self, st: &mut States) {
        let n = self.depth();
        for l in 1..=n {
            let (lower, upper) = st.phi.split_at_mut(l);
            if l > 1 {
                self.affine::<FMA>(l, &lower[l - 1], &mut st.s[l]);
            }
            if l < n {
                sigmoid::<FMA>(&st.s[l], &mut upper[0]);
            }
        }
    }

    /// Feed-forward prediction of one sample into `out`; wrong lengths are
    /// errors.
    pub fn predict(&self, x: &[f32], out: &mut [f32]) -> Result<(), LearnError> {
        let mut st = States::new(&self.sizes);
        self.predict_with(x, out, &mut st)
    }

    /// As [`Self::predict`], reusing working vectors.
    pub(crate) fn predict_with(
        &self,
        x: &[f32],
        out: &mut [f32],
        st: &mut States,
    ) -> Result<(), LearnError> {
        let (d_in, d_out) = (self.sizes[0], self.sizes[self.depth()]);
        if x.len() != d_in {
            return Err(LearnError::DimensionMismatch {
                expected: d_in,
                got: x.len(),
            });
        }
        if out.len() != d_out {
            return Err(LearnError::Shape {
                what: "output",
                expected: d_out,
                got: out.len(),
            });
        }
        self.forward::<false>(x, st);
        out.copy_from_slice(&st.s[self.depth()]);
        Ok(())
    }

    /// Whether `W(l)` is stored in panels (wide layer) rather than
    /// transposed.
    pub(crate) fn is_row_major(&self, l: usize) -> bool {
        !is_narrow(self.sizes[l])
    }

    /// The feed-forward pass: fills `st.s[l]` for every layer and `st.phi[l]`
    /// for the input and hidden layers (the free phase's exact fixed point).
    #[inline(always)]
    pub(crate) fn forward<const FMA: bool>(&self, x: &[f32], st: &mut States) {
        st.phi[0].copy_from_slice(x);
        st.s[0].copy_from_slice(x);
        let n = self.depth();
        for l in 1..=n {
            let (lower, upper) = st.phi.split_at_mut(l);
            self.affine::<FMA>(l, &lower[l - 1], &mut st.s[l]);
            if l < n {
                sigmoid::<FMA>(&st.s[l], &mut upper[0]);
            }
        }
    }
}

fn to_storage(canonical: Vec<f32>, rows: usize, cols: usize) -> Vec<f32> {
    if is_narrow(cols) {
        transpose(&canonical, rows, cols)
    } else {
        to_panels(&canonical, rows, cols)
    }
}

/// Per-layer working vectors, allocated once per network so the training
/// loop never allocates.
#[derive(Debug, Clone)]
pub(crate) struct States {
    /// Somatic potentials `s(l)`, `s(0) = x`.
    pub s: Vec<Vec<f32>>,
    /// `phi(s(l))` for `l < N` (`phi(s(0)) = x`).
    pub phi: Vec<Vec<f32>>,
    /// Errors `e(l) = s(l) - (W(l)^T phi(s(l-1)) + b(l))`, `e(0)` unused.
    pub e: Vec<Vec<f32>>,
    /// Scratch of each layer's size.
    pub tmp: Vec<Vec<f32>>,
    /// Constant first-layer drive `W(1)^T x + b(1)` (computed once a sample).
    pub drive: Vec<f32>,
    /// Nudged output.
    pub nudged: Vec<f32>,
    /// Extra scratch of the first hidden layer's size.
    pub scratch: Vec<f32>,
    /// `k x k` matrix and `k` right-hand side of the output-error system.
    pub system: Vec<f64>,
    /// The deep clamped phase's per-layer slopes and output Jacobians
    /// (`crate::deep_clamp`), sized on first use.
    pub deep: Vec<Vec<f32>>,
}

impl States {
    pub fn new(sizes: &[usize]) -> Self {
        let per_layer = || sizes.iter().map(|&d| vec![0.0f32; d]).collect::<Vec<_>>();
        States {
            s: per_layer(),
            phi: per_layer(),
            e: per_layer(),
            tmp: per_layer(),
            drive: vec![0.0; sizes.get(1).copied().unwrap_or(0)],
            nudged: vec![0.0; sizes.last().copied().unwrap_or(0)],
            scratch: vec![0.0; sizes.get(1).copied().unwrap_or(0)],
            system: vec![0.0; sizes.last().map_or(0, |k| k * k + k)],
            deep: Vec::new(),
        }
    }
}

/// Whether the running CPU has AVX2 and FMA (checked once, cached by std).
#[inline]
pub(crate) fn has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
