//! The smooth field's weighted sums over one run of a source pin's kernel
//! weights (`field.rs`): four target pins a step in AVX registers where the
//! processor has AVX, one at a time elsewhere, to the same values bit for
//! bit (each lane multiplies, then adds, as the plain loop does). The
//! weights' own sums can be left out (`WEIGHTS` false) where the kernel
//! holds them already (every pin matched: `Kernel::with_prior`).

/// Adds one source's residual `r`, weighted by a run of its weights `w`,
/// to the sums (x, y, weight) of the run's target pins: four pins a step
/// where the processor has AVX ([`add_run_avx`]), else as
/// [`add_run_plain`]; the same products and sums, rounded the same, so the
/// same values bit for bit (a multiply then an add, never fused). Without
/// `WEIGHTS` the weight sums `s` are left as they are (`s` may be empty).
pub(super) fn add_run<const WEIGHTS: bool>(
    w: &[f64],
    r: [f64; 2],
    x: &mut [f64],
    y: &mut [f64],
    s: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above).
        unsafe { add_run_avx::<WEIGHTS>(w, r, x, y, s) };
        return;
    }
    add_run_plain::<WEIGHTS>(w, r, x, y, s);
}

/// The length of a run's slices: `w`, `x` and `y` (and `s` with `WEIGHTS`).
fn run_len<const WEIGHTS: bool>(w: &[f64], x: &[f64], y: &[f64], s: &[f64]) -> usize {
    let len = w.len().min(x.len()).min(y.len());
    if WEIGHTS {
        len.min(s.len())
    } else {
        len
    }
}

/// [`add_run`] one pin at a time.
fn add_run_plain<const WEIGHTS: bool>(
    w: &[f64],
    r: [f64; 2],
    x: &mut [f64],
    y: &mut [f64],
    s: &mut [f64],
) {
    let len = run_len::<WEIGHTS>(w, x, y, s);
    let (w, x, y) = (&w[..len], &mut x[..len], &mut y[..len]);
    let s = if WEIGHTS { &mut s[..len] } else { &mut s[..0] };
    for k in 0..len {
        x[k] += w[k] * r[0];
        y[k] += w[k] * r[1];
        if WEIGHTS {
            s[k] += w[k];
        }
    }
}

/// [`add_run`] four pins a step in AVX registers (a multiply, then an add:
/// each lane rounds as [`add_run_plain`] does), the rest one at a time.
///
/// # Safety
/// The processor must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn add_run_avx<const WEIGHTS: bool>(
    w: &[f64],
    r: [f64; 2],
    x: &mut [f64],
    y: &mut [f64],
    s: &mut [f64],
) {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_storeu_pd,
    };
    let len = run_len::<WEIGHTS>(w, x, y, s);
    let (w, x, y) = (&w[..len], &mut x[..len], &mut y[..len]);
    let s = if WEIGHTS { &mut s[..len] } else { &mut s[..0] };
    let (rx, ry) = (_mm256_set1_pd(r[0]), _mm256_set1_pd(r[1]));
    let whole = len / 4 * 4;
    let mut k = 0;
    while k < whole {
        // SAFETY: k + 4 <= len, the length of `w`, `x`, `y` (and of `s`
        // with WEIGHTS), so every load and store is in bounds (no
        // alignment needed).
        unsafe {
            let wk = _mm256_loadu_pd(w.as_ptr().add(k));
            let (px, py) = (x.as_mut_ptr().add(k), y.as_mut_ptr().add(k));
            _mm256_storeu_pd(
                px,
                _mm256_add_pd(_mm256_loadu_pd(px), _mm256_mul_pd(wk, rx)),
            );
            _mm256_storeu_pd(
                py,
                _mm256_add_pd(_mm256_loadu_pd(py), _mm256_mul_pd(wk, ry)),
            );
            if WEIGHTS {
                let ps = s.as_mut_ptr().add(k);
                _mm256_storeu_pd(ps, _mm256_add_pd(_mm256_loadu_pd(ps), wk));
            }
        }
        k += 4;
    }
    let rest = if WEIGHTS { whole } else { 0 };
    add_run_plain::<WEIGHTS>(
        &w[whole..],
        r,
        &mut x[whole..],
        &mut y[whole..],
        &mut s[rest..],
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sums of a run four pins a step (AVX, where the processor has
    /// it) are those of one pin at a time, bit for bit, for runs of every
    /// length up to 23, signed residuals and sums of any sign and size;
    /// without the weights, the same x and y sums and the weight sums left
    /// as they were.
    #[test]
    fn run_sums_by_four_equal_one_at_a_time_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for len in 0..24 {
            let value = |rng: &mut rand_chacha::ChaCha8Rng| {
                rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-8..8))
            };
            let w: Vec<f64> = (0..len).map(|_| rng.random_range(0.0..1.0)).collect();
            let r = [value(&mut rng), value(&mut rng)];
            let start: Vec<f64> = (0..3 * len).map(|_| value(&mut rng)).collect();
            let (mut a, mut b) = (start.clone(), start);
            let (ax, rest) = a.split_at_mut(len);
            let (ay, az) = rest.split_at_mut(len);
            add_run::<true>(&w, r, ax, ay, az);
            let (bx, rest) = b.split_at_mut(len);
            let (by, bz) = rest.split_at_mut(len);
            add_run_plain::<true>(&w, r, bx, by, bz);
            let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "length {len}");
            // Without the weights: x and y as with them, s untouched.
            let mut c: Vec<f64> = (0..3 * len).map(|_| value(&mut rng)).collect();
            let mut d = c.clone();
            let (cx, rest) = c.split_at_mut(len);
            let (cy, cz) = rest.split_at_mut(len);
            add_run::<false>(&w, r, cx, cy, cz);
            let (dx, rest) = d.split_at_mut(len);
            let (dy, dz) = rest.split_at_mut(len);
            let untouched = bits(dz);
            add_run_plain::<true>(&w, r, dx, dy, dz);
            assert_eq!(bits(&c[..2 * len]), bits(&d[..2 * len]), "length {len}");
            assert_eq!(bits(&c[2 * len..]), untouched, "length {len}: s untouched");
        }
    }
}
