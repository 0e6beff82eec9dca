//! A smooth displacement field over the reference pin layout, fitted to the
//! pins matched so far: a least-squares affine map plus a Gaussian-weighted
//! (Nadaraya-Watson) average of the residuals. The tracker uses it to predict
//! where every pin has moved before matching, and to fill in missing pins.

use nalgebra::{Matrix3, Vector3};

mod sums;

use sums::add_run;

/// Weights below this are dropped in the exact field (the field as it was
/// before the cut; see `Kernel::new`).
pub const EXACT_TOLERANCE: f64 = 1e-4;

/// Gaussian kernel weights between reference pins for one width, kept
/// where they reach a tolerance, source pin by source pin as runs of
/// consecutive target pins (near-linear in the pin count once the kept
/// radius is smaller than the layout).
pub struct Kernel {
    n: usize,
    /// Per source pin `j`, its runs are `runs[starts[j]..starts[j + 1]]`.
    starts: Vec<u32>,
    runs: Vec<Run>,
    /// The runs' weights, one after the other.
    weights: Vec<f64>,
    /// The weight sums of every pin when every pin is matched, for one
    /// prior ([`Kernel::with_prior`]).
    totals: Option<Totals>,
}

/// Per target pin `i`, `prior + sum_j w_ij` over every source pin `j` in
/// pin order: the denominators of [`smooth_field`] when every pin is
/// matched, the same in every such frame.
struct Totals {
    prior: f64,
    sums: Vec<f64>,
}

/// Consecutive target pins `first..first + len` of one source pin, their
/// weights at `weights[at..at + len]` (short gaps inside hold zeros).
#[derive(Clone, Copy)]
struct Run {
    first: u32,
    len: u32,
    at: u32,
}

/// Dropped weights between two kept ones that are stored as zeros rather
/// than ending the run (a zero weight adds an exact zero to a finite sum).
const GAP: usize = 3;

/// Below this many pins every source's kept weights are one run, the
/// dropped ones between them stored as zeros (at most `n^2` weights: 16129
/// for 127 pins): the sums run over a few long runs, vectorised, rather
/// than one short run per row of the layout, to the same values bit for bit.
pub const ONE_RUN_MAX_PINS: usize = 200;

impl Kernel {
    /// Weights `exp(-|r_i - r_j|^2 / (2 sigma^2))`, dropped below
    /// `tolerance` (the tracker's exact field drops them below
    /// [`EXACT_TOLERANCE`]).
    /// Below [`ONE_RUN_MAX_PINS`] pins each source's weights are one run.
    pub fn new(reference: &[[f64; 2]], sigma: f64, tolerance: f64) -> Self {
        let n = reference.len();
        let gap = if n < ONE_RUN_MAX_PINS { n } else { GAP };
        Self::with_gap(reference, sigma, tolerance, gap)
    }

    /// [`Kernel::new`] with runs broken where more than `gap` weights in a
    /// row are dropped.
    fn with_gap(reference: &[[f64; 2]], sigma: f64, tolerance: f64, gap: usize) -> Self {
        let n = reference.len();
        let scale = -0.5 / (sigma * sigma);
        let (mut starts, mut runs, mut weights) = (vec![0u32], Vec::new(), Vec::new());
        let mut row = vec![0.0; n];
        for b in reference {
            for (w, a) in row.iter_mut().zip(reference) {
                let d2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
                let v = (scale * d2).exp();
                *w = if v >= tolerance { v } else { 0.0 };
            }
            let mut i = 0;
            while let Some(lo) = row[i..].iter().position(|w| *w > 0.0).map(|k| i + k) {
                let mut hi = lo + 1; // one past the last kept weight of the run
                let mut k = hi;
                while k < n && k - hi <= gap {
                    if row[k] > 0.0 {
                        hi = k + 1;
                    }
                    k += 1;
                }
                runs.push(Run {
                    first: lo as u32,
                    len: (hi - lo) as u32,
                    at: weights.len() as u32,
                });
                weights.extend_from_slice(&row[lo..hi]);
                i = hi;
                if i >= n {
                    break;
                }
            }
            starts.push(runs.len() as u32);
        }
        Self {
            n,
            starts,
            runs,
            weights,
            totals: None,
        }
    }

    /// The kernel holding its weight sums for `prior` when every pin is
    /// matched, so that [`smooth_field`] with that prior sums only the
    /// residuals then: the same additions in the same order (source pin by
    /// source pin, from `prior`), so the same denominators bit for bit.
    pub fn with_prior(mut self, prior: f64) -> Self {
        let mut sums = vec![prior; self.n];
        for j in 0..self.n {
            for (first, w) in self.source(j) {
                for (s, w) in sums[first..first + w.len()].iter_mut().zip(w) {
                    *s += w;
                }
            }
        }
        self.totals = Some(Totals { prior, sums });
        self
    }

    /// The weight sums of every pin matched, when held for `prior`.
    fn totals_for(&self, prior: f64) -> Option<&[f64]> {
        let t = self.totals.as_ref()?;
        (t.prior.to_bits() == prior.to_bits()).then_some(t.sums.as_slice())
    }

    /// Number of weights kept (zeros inside runs included).
    #[cfg(test)]
    fn kept(&self) -> usize {
        self.weights.len()
    }

    /// The runs of source pin `j`: (first target pin, weights).
    fn source(&self, j: usize) -> impl Iterator<Item = (usize, &[f64])> {
        let runs = &self.runs[self.starts[j] as usize..self.starts[j + 1] as usize];
        runs.iter().map(|r| {
            let at = r.at as usize;
            (r.first as usize, &self.weights[at..at + r.len as usize])
        })
    }

    /// Weight of pin `j`'s residual at pin `i`.
    #[cfg(test)]
    fn at(&self, i: usize, j: usize) -> f64 {
        self.source(j)
            .find(|(first, w)| (*first..first + w.len()).contains(&i))
            .map_or(0.0, |(first, w)| w[i - first])
    }
}

/// Observed displacements: `Some(d)` for a matched pin, `None` otherwise.
pub type Observations = [Option<[f64; 2]>];

/// Displacement of every reference pin under the field fitted to the
/// observations; `prior` (in matched-pin units) pulls the local correction
/// towards the affine part where few neighbours are matched.
///
/// The local part at pin i is `sum_j w_ij res_j / (prior + sum_j w_ij)`
/// over the matched pins j with `w_ij > 0`, summed in pin order. The sums
/// run source by source over each run of its kept weights at once
/// (vectorised); a zero weight inside a run adds an exact zero, which changes no sum (the sums start
/// at +0 or `prior` and so never hold -0), so the result is the same, bit
/// for bit, as the pin-by-pin sum (checked in the tests). When every pin
/// is matched the denominators are the kernel's own sums for `prior`
/// where it holds them ([`Kernel::with_prior`]), the same values.
pub fn smooth_field(
    reference: &[[f64; 2]],
    observed: &Observations,
    kernel: &Kernel,
    prior: f64,
) -> Vec<[f64; 2]> {
    let affine = fit_affine(reference, observed);
    // Residuals of the matched pins only, in pin order (room for all).
    let mut residual: Vec<(usize, [f64; 2])> = Vec::with_capacity(reference.len());
    residual.extend(
        reference
            .iter()
            .zip(observed)
            .enumerate()
            .filter_map(|(j, (r, o))| {
                o.map(|d| {
                    let a = affine.apply(*r);
                    (j, [d[0] - a[0], d[1] - a[1]])
                })
            }),
    );
    let n = reference.len();
    let (mut sx, mut sy) = (vec![0.0; n], vec![0.0; n]);
    let totals = kernel
        .totals_for(prior)
        .filter(|_| kernel.n == n && residual.len() == n);
    let mut sw = totals.map_or_else(|| vec![prior; n], <[f64]>::to_vec);
    if kernel.n == n {
        let finite = residual
            .iter()
            .all(|(_, r)| r[0].is_finite() && r[1].is_finite());
        for &(j, r) in &residual {
            for (first, w) in kernel.source(j) {
                let end = first + w.len();
                let (x, y, s) = (
                    &mut sx[first..end],
                    &mut sy[first..end],
                    &mut sw[first..end],
                );
                if finite && totals.is_some() {
                    add_run::<false>(w, r, x, y, s);
                } else if finite {
                    add_run::<true>(w, r, x, y, s);
                } else {
                    // 0 * inf would not add zero: skip the zeros of the run.
                    // (Held totals added the zeros: exact, the same sums.)
                    for (k, &wk) in w.iter().enumerate().filter(|(_, w)| **w > 0.0) {
                        (x[k], y[k]) = (x[k] + wk * r[0], y[k] + wk * r[1]);
                        if totals.is_none() {
                            s[k] += wk;
                        }
                    }
                }
            }
        }
    }
    reference
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let base = affine.apply(*r);
            let local = if sw[i] > 0.0 {
                [sx[i] / sw[i], sy[i] / sw[i]]
            } else {
                [0.0, 0.0]
            };
            [base[0] + local[0], base[1] + local[1]]
        })
        .collect()
}

/// [`smooth_field`]'s displacement at the pins with no observation, and
/// the observed displacement at the others: what the tracker's last stage
/// needs (its field only fills the missing pins). At a missing pin `i` the
/// sums run over its own kernel weights (the kernel is symmetric, `w_ij =
/// w_ji` bit for bit, as `(a - b)^2 = (b - a)^2`), over the matched pins in
/// pin order and skipping zero weights, so each value is
/// [`smooth_field`]'s, bit for bit (checked in the tests), for a fraction
/// of the work when few pins are missing; with none missing, the
/// observations as they are.
pub fn fill_missing(
    reference: &[[f64; 2]],
    observed: &Observations,
    kernel: &Kernel,
    prior: f64,
) -> Vec<[f64; 2]> {
    if observed.len() == reference.len() && observed.iter().all(Option::is_some) {
        // No pin to fill: every value is its observation (no affine fit).
        return observed.iter().flatten().copied().collect();
    }
    let affine = fit_affine(reference, observed);
    let residual: Vec<Option<[f64; 2]>> = reference
        .iter()
        .zip(observed)
        .map(|(r, o)| {
            o.map(|d| {
                let a = affine.apply(*r);
                [d[0] - a[0], d[1] - a[1]]
            })
        })
        .collect();
    let symmetric = kernel.n == reference.len();
    reference
        .iter()
        .zip(observed)
        .enumerate()
        .map(|(i, (r, o))| {
            if let Some(d) = o {
                return *d;
            }
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, prior);
            for (first, w) in kernel.source(i).filter(|_| symmetric) {
                for (res, &wk) in residual[first..first + w.len()].iter().zip(w) {
                    if let (Some(res), true) = (res, wk > 0.0) {
                        (sx, sy, sw) = (sx + wk * res[0], sy + wk * res[1], sw + wk);
                    }
                }
            }
            let base = affine.apply(*r);
            let local = if sw > 0.0 {
                [sx / sw, sy / sw]
            } else {
                [0.0, 0.0]
            };
            [base[0] + local[0], base[1] + local[1]]
        })
        .collect()
}

#[cfg(test)]
/// Kernel-weighted sums (x, y, weight) of the matched residuals
/// `(pin, residual)` at one pin, `weights` indexed by source pin, the
/// weight starting at `prior` (pins with zero weight are skipped).
fn weighted_sums(
    weights: impl Iterator<Item = f64> + Clone,
    residual: &[(usize, [f64; 2])],
    prior: f64,
) -> [f64; 3] {
    let weights: Vec<f64> = weights.collect();
    let (mut sx, mut sy, mut sw) = (0.0, 0.0, prior);
    for &(j, r) in residual {
        let w = weights[j];
        if w > 0.0 {
            sx += w * r[0];
            sy += w * r[1];
            sw += w;
        }
    }
    [sx, sy, sw]
}

/// Displacement d(r) = origin-centred affine map of the reference position.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    centre: [f64; 2],
    x: Vector3<f64>,
    y: Vector3<f64>,
}

impl Affine {
    fn zero() -> Self {
        Self {
            centre: [0.0; 2],
            x: Vector3::zeros(),
            y: Vector3::zeros(),
        }
    }

    pub fn apply(&self, r: [f64; 2]) -> [f64; 2] {
        let v = Vector3::new(r[0] - self.centre[0], r[1] - self.centre[1], 1.0);
        [self.x.dot(&v), self.y.dot(&v)]
    }
}

/// Least-squares affine displacement; a pure translation when the matched
/// pins are fewer than three or collinear; zero when none is matched.
pub fn fit_affine(reference: &[[f64; 2]], observed: &Observations) -> Affine {
    // Sized for every pin up front: collecting the filter would regrow.
    let mut pairs: Vec<([f64; 2], [f64; 2])> = Vec::with_capacity(reference.len());
    pairs.extend(
        reference
            .iter()
            .zip(observed)
            .filter_map(|(r, o)| o.map(|d| (*r, d))),
    );
    if pairs.is_empty() {
        return Affine::zero();
    }
    let n = pairs.len() as f64;
    let centre = [
        pairs.iter().map(|p| p.0[0]).sum::<f64>() / n,
        pairs.iter().map(|p| p.0[1]).sum::<f64>() / n,
    ];
    let mean_d = [
        pairs.iter().map(|p| p.1[0]).sum::<f64>() / n,
        pairs.iter().map(|p| p.1[1]).sum::<f64>() / n,
    ];
    let translation = Affine {
        centre,
        x: Vector3::new(0.0, 0.0, mean_d[0]),
        y: Vector3::new(0.0, 0.0, mean_d[1]),
    };
    let mut normal = Matrix3::<f64>::zeros();
    let (mut bx, mut by) = (Vector3::zeros(), Vector3::zeros());
    for (r, d) in &pairs {
        let v = Vector3::new(r[0] - centre[0], r[1] - centre[1], 1.0);
        normal += v * v.transpose();
        bx += v * d[0];
        by += v * d[1];
    }
    let spread = normal[(0, 0)] + normal[(1, 1)];
    if pairs.len() < 3 || normal.determinant().abs() <= 1e-9 * spread * spread * n {
        return translation;
    }
    match normal.try_inverse() {
        Some(inv) => Affine {
            centre,
            x: inv * bx,
            y: inv * by,
        },
        None => translation,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn grid() -> Vec<[f64; 2]> {
        (0..7)
            .flat_map(|i| (0..7).map(move |j| [10.0 * f64::from(i), 10.0 * f64::from(j)]))
            .collect()
    }

    #[test]
    fn recovers_an_exact_affine_field_with_gaps() {
        let reference = grid();
        let truth = |r: [f64; 2]| {
            [
                0.1 * r[0] - 0.05 * r[1] + 3.0,
                0.02 * r[0] + 0.2 * r[1] - 1.0,
            ]
        };
        let observed: Vec<Option<[f64; 2]>> = reference
            .iter()
            .enumerate()
            .map(|(i, r)| (i % 5 != 0).then(|| truth(*r)))
            .collect();
        let field = smooth_field(
            &reference,
            &observed,
            &Kernel::new(&reference, 15.0, EXACT_TOLERANCE),
            0.1,
        );
        for (r, d) in reference.iter().zip(&field) {
            let t = truth(*r);
            assert!((d[0] - t[0]).abs() < 1e-9 && (d[1] - t[1]).abs() < 1e-9);
        }
    }

    /// The source-by-source (vectorised) sums equal the pin-by-pin ones
    /// bit for bit, on a jittered grid with random gaps and residuals.
    /// Each pin of `layout` moved by up to `jitter` in x and y.
    fn jittered(layout: &[[f64; 2]], jitter: f64, rng: &mut impl rand::Rng) -> Vec<[f64; 2]> {
        layout
            .iter()
            .map(|r| {
                [
                    r[0] + rng.random_range(-jitter..jitter),
                    r[1] + rng.random_range(-jitter..jitter),
                ]
            })
            .collect()
    }

    /// Each pin seen with probability `seen`, displaced by up to `reach`.
    fn observed_at_random(
        reference: &[[f64; 2]],
        seen: f64,
        reach: f64,
        rng: &mut impl rand::Rng,
    ) -> Vec<Option<[f64; 2]>> {
        reference
            .iter()
            .map(|_| {
                rng.random_bool(seen).then(|| {
                    [
                        rng.random_range(-reach..reach),
                        rng.random_range(-reach..reach),
                    ]
                })
            })
            .collect()
    }

    #[test]
    fn banded_sums_equal_pin_by_pin_sums() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        for _ in 0..50 {
            let reference = jittered(&grid(), 2.0, &mut rng);
            let observed = observed_at_random(&reference, 0.8, 9.0, &mut rng);
            let kernel = Kernel::new(&reference, rng.random_range(5.0..30.0), EXACT_TOLERANCE);
            let prior = rng.random_range(0.0..0.5);
            let got = smooth_field(&reference, &observed, &kernel, prior);
            let affine = fit_affine(&reference, &observed);
            let residual: Vec<(usize, [f64; 2])> = observed
                .iter()
                .enumerate()
                .filter_map(|(j, o)| {
                    o.map(|d| {
                        let a = affine.apply(reference[j]);
                        (j, [d[0] - a[0], d[1] - a[1]])
                    })
                })
                .collect();
            for (i, r) in reference.iter().enumerate() {
                let weights = (0..reference.len()).map(|j| kernel.at(i, j));
                let [sx, sy, sw] = weighted_sums(weights, &residual, prior);
                let local = if sw > 0.0 {
                    [sx / sw, sy / sw]
                } else {
                    [0.0, 0.0]
                };
                let base = affine.apply(*r);
                assert_eq!(got[i], [base[0] + local[0], base[1] + local[1]]);
            }
        }
    }

    /// A source's weights as one run (the default below
    /// [`ONE_RUN_MAX_PINS`] pins) give the field and the fill of short runs
    /// (a run broken after [`GAP`] dropped weights), bit for bit, on
    /// jittered grids with and without missing pins.
    #[test]
    fn one_run_a_source_gives_the_short_runs_field_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(127);
        let mut broken = 0;
        let bits =
            |v: Vec<[f64; 2]>| -> Vec<[u64; 2]> { v.iter().map(|p| p.map(f64::to_bits)).collect() };
        for _ in 0..40 {
            let reference = jittered(&grid(), 2.0, &mut rng);
            assert!(reference.len() < ONE_RUN_MAX_PINS);
            let observed = observed_at_random(&reference, 0.8, 9.0, &mut rng);
            let sigma = rng.random_range(3.0..30.0);
            let one = Kernel::new(&reference, sigma, EXACT_TOLERANCE);
            let short = Kernel::with_gap(&reference, sigma, EXACT_TOLERANCE, GAP);
            assert_eq!(one.runs.len(), reference.len(), "one run a source");
            broken += usize::from(short.runs.len() > one.runs.len());
            let prior = rng.random_range(0.0..0.5);
            assert_eq!(
                bits(smooth_field(&reference, &observed, &one, prior)),
                bits(smooth_field(&reference, &observed, &short, prior))
            );
            assert_eq!(
                bits(fill_missing(&reference, &observed, &one, prior)),
                bits(fill_missing(&reference, &observed, &short, prior))
            );
        }
        assert!(broken >= 10, "only {broken} kernels had short runs");
    }

    /// The fill at missing pins is the full field there, bit for bit, on
    /// jittered grids and on the 331-pin ring layout, with the exact and
    /// the cut kernels; observed pins keep their observation.
    #[test]
    fn fill_missing_is_the_field_at_missing_pins_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(331);
        for trial in 0..40 {
            let layout = if trial % 2 == 0 { grid() } else { rings() };
            let reference = jittered(&layout, 0.5, &mut rng);
            let observed = observed_at_random(&reference, 0.9, 3.0, &mut rng);
            let spacing = if trial % 2 == 0 { 10.0 } else { 5.0 };
            let tolerance = if trial % 4 < 2 { EXACT_TOLERANCE } else { 1e-2 };
            let sigma = spacing * rng.random_range(0.8..2.5);
            let kernel = Kernel::new(&reference, sigma, tolerance);
            let full = smooth_field(&reference, &observed, &kernel, 0.2);
            let fill = fill_missing(&reference, &observed, &kernel, 0.2);
            for (i, o) in observed.iter().enumerate() {
                let want = o.unwrap_or(full[i]);
                assert_eq!(
                    fill[i].map(f64::to_bits),
                    want.map(f64::to_bits),
                    "{trial} {i}"
                );
            }
        }
    }

    /// A kernel holding its weight sums for the prior gives the field of
    /// one that does not, bit for bit: every pin matched (the held sums
    /// used; residuals finite and not), pins missing (not used), another
    /// prior (not used); on jittered grids and the 331-pin rings, one run
    /// a source and short runs.
    #[test]
    fn held_weight_sums_give_the_same_field_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2021);
        let bits =
            |v: Vec<[f64; 2]>| -> Vec<[u64; 2]> { v.iter().map(|p| p.map(f64::to_bits)).collect() };
        for trial in 0..40 {
            let (layout, spacing) = if trial % 2 == 0 {
                (grid(), 10.0)
            } else {
                (rings(), 5.0)
            };
            let reference = jittered(&layout, 0.5, &mut rng);
            let seen = [1.0, 1.0, 0.9][trial % 3];
            let mut observed = observed_at_random(&reference, seen, 3.0, &mut rng);
            if trial % 5 == 4 {
                observed[trial % reference.len()] = Some([f64::INFINITY, 0.0]);
            }
            let sigma = spacing * rng.random_range(0.8..3.0);
            let tolerance = if trial % 4 < 2 { EXACT_TOLERANCE } else { 1e-2 };
            let plain = Kernel::new(&reference, sigma, tolerance);
            let prior = rng.random_range(0.0..0.5);
            let held = Kernel::new(&reference, sigma, tolerance).with_prior(prior);
            assert_eq!(
                held.totals_for(prior).map(<[f64]>::len),
                Some(reference.len())
            );
            assert!(held.totals_for(prior + 0.125).is_none());
            for p in [prior, prior + 0.125] {
                assert_eq!(
                    bits(smooth_field(&reference, &observed, &held, p)),
                    bits(smooth_field(&reference, &observed, &plain, p)),
                    "trial {trial}, prior {p}"
                );
            }
        }
    }

    #[test]
    fn degenerate_observations_fall_back_gracefully() {
        let reference = grid();
        let none = vec![None; reference.len()];
        let kernel = Kernel::new(&reference, 15.0, EXACT_TOLERANCE);
        assert!(smooth_field(&reference, &none, &kernel, 0.1)
            .iter()
            .all(|d| d == &[0.0, 0.0]));
        let mut one = none.clone();
        one[3] = Some([2.0, -1.0]);
        let field = smooth_field(&reference, &one, &kernel, 0.1);
        assert!(field
            .iter()
            .all(|d| (d[0] - 2.0).abs() < 1e-12 && (d[1] + 1.0).abs() < 1e-12));
    }

    /// 331 pins on 10 concentric rings of 6k pins (and the centre), about
    /// 5 px apart, as the 331-pin TacTip.
    pub(crate) fn rings() -> Vec<[f64; 2]> {
        let mut pins = vec![[64.0, 64.0]];
        for k in 1..=10 {
            let count = 6 * k;
            for m in 0..count {
                let a =
                    std::f64::consts::TAU * f64::from(m) / f64::from(count) + 0.1 * f64::from(k);
                let r = 5.0 * f64::from(k);
                pins.push([64.0 + r * a.cos(), 64.0 + r * a.sin()]);
            }
        }
        pins
    }

    /// The cut field is the exact one within the bound the dropped weights
    /// allow (per pin `2 e R / b`: `e` the dropped weight, `b` the kept one
    /// plus the prior, `R` the largest residual), on a 331-pin ring layout
    /// under a sheared, bumped field with a tenth of the pins unmatched; and
    /// the two widest kernels keep under 70 % of the exact kernel's weights.
    #[test]
    fn cut_field_is_the_exact_one_within_its_bound_on_331_rings() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let reference = rings();
        let spacing = 5.0;
        let observed: Vec<Option<[f64; 2]>> = reference
            .iter()
            .map(|r| {
                let (x, y) = (r[0] - 70.0, r[1] - 60.0);
                let bump = 4.0 * (-(x * x + y * y) / 300.0).exp();
                rng.random_bool(0.9).then(|| {
                    [
                        0.08 * r[1] + bump + rng.random_range(-0.5..0.5),
                        -0.03 * r[0] - bump + rng.random_range(-0.5..0.5),
                    ]
                })
            })
            .collect();
        let affine = fit_affine(&reference, &observed);
        let largest = reference
            .iter()
            .zip(&observed)
            .filter_map(|(r, o)| o.map(|d| (d, affine.apply(*r))))
            .flat_map(|(d, a)| [(d[0] - a[0]).abs(), (d[1] - a[1]).abs()])
            .fold(0.0, f64::max);
        let prior = 0.2;
        for sigma in [3.0, 2.0, 1.2] {
            let exact = Kernel::new(&reference, sigma * spacing, EXACT_TOLERANCE);
            let cut = Kernel::new(&reference, sigma * spacing, crate::tracker::CUT_TOLERANCE);
            assert!(
                (cut.kept() as f64) < 0.7 * exact.kept() as f64 || sigma < 2.0,
                "sigma {sigma}: {} of {} weights kept",
                cut.kept(),
                exact.kept()
            );
            let a = smooth_field(&reference, &observed, &exact, prior);
            let b = smooth_field(&reference, &observed, &cut, prior);
            let mut most = 0.0f64;
            for i in 0..reference.len() {
                let (mut kept, mut dropped) = (prior, 0.0);
                for (j, o) in observed.iter().enumerate() {
                    if o.is_some() {
                        kept += cut.at(i, j);
                        dropped += exact.at(i, j) - cut.at(i, j);
                    }
                }
                let bound = 2.0 * dropped * largest / kept + 1e-12;
                let d = (a[i][0] - b[i][0]).abs().max((a[i][1] - b[i][1]).abs());
                assert!(d <= bound, "sigma {sigma}, pin {i}: {d} px > bound {bound}");
                most = most.max(d);
            }
            // A hundredth of the spacing: far inside the narrowest gate
            // that follows a cut stage (0.6 spacings).
            assert!(most < 0.05, "sigma {sigma}: the cut moves a pin {most} px");
        }
    }
}
