//! The machine's fused multiply-add throughput, measured: the bound a
//! prediction's multiply-adds ([`crate::PoseModel::multiply_adds`]) cannot
//! beat, which `tactrace bench` sets its prediction time against. Chains
//! of independent multiply-adds in the widest vectors the CPU has (the
//! ones the prediction uses), so neither latency nor memory limits them.
//! Timings move with the machine's load: take the best of a few runs.

use crate::kernels::madd;
use std::time::Instant;

/// Independent accumulators: enough vectors in flight to cover the
/// multiply-add latency on two pipes.
const CHAINS: usize = 12;
/// f32 lanes of a 512-bit vector (also run as two 256-bit halves).
const LANES: usize = 16;

/// Multiply-adds per second, f32 and f64, as measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FmaPeak {
    pub f32_per_second: f64,
    pub f64_per_second: f64,
}

impl FmaPeak {
    /// Seconds `(f64, f32)` multiply-adds take at this peak.
    pub fn seconds(&self, (f64_ops, f32_ops): (usize, usize)) -> f64 {
        f64_ops as f64 / self.f64_per_second + f32_ops as f64 / self.f32_per_second
    }
}

/// Measures the peak over `rounds` runs of about a millisecond each,
/// keeping the fastest.
pub fn measure_fma_peak(rounds: usize) -> FmaPeak {
    let steps = 20_000;
    let best = |run: &dyn Fn(usize) -> f64| {
        (0..rounds.max(1))
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(run(steps));
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (l32, l64) = lanes();
    let ops = |lanes: usize| (steps * CHAINS * lanes) as f64;
    FmaPeak {
        f32_per_second: ops(l32) / best(&|n| f64::from(chains32(n))),
        f64_per_second: ops(l64) / best(&chains64),
    }
}

/// f32 and f64 lanes of the vectors the chains run in.
fn lanes() -> (usize, usize) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") && crate::net::has_fma() {
            return (16, 8);
        }
        if crate::net::has_fma() {
            return (8, 4);
        }
    }
    (LANES, LANES / 2)
}

/// `steps` rounds of [`CHAINS`] vectors of f32 multiply-adds (see [`lanes`]).
fn chains32(steps: usize) -> f32 {
    let (m, a) = std::hint::black_box((0.999_999, 1e-7));
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") && crate::net::has_fma() {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked just above).
            return unsafe { chains32_avx512(steps, m, a) };
        }
        if crate::net::has_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked by `has_fma`).
            return unsafe { chains32_avx2(steps, m, a) };
        }
    }
    chains::<false, f32, LANES>(steps, m, a)
}

/// `steps` rounds of [`CHAINS`] vectors of f64 multiply-adds.
fn chains64(steps: usize) -> f64 {
    let (m, a) = std::hint::black_box((0.999_999, 1e-7));
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") && crate::net::has_fma() {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked just above).
            return unsafe { chains64_avx512(steps, m, a) };
        }
        if crate::net::has_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked by `has_fma`).
            return unsafe { chains64_avx2(steps, m, a) };
        }
    }
    chains::<false, f64, { LANES / 2 }>(steps, m, a)
}

/// [`CHAINS`] chains of one vector type `$v`, `x = x m + a` by `$fma`,
/// `$set1` broadcasting a scalar; the sum of the lanes of `$store`d
/// results.
macro_rules! vector_chains {
    ($name:ident, $features:literal, $t:ty, $v:ty, $set1:ident, $fma:ident, $store:ident, $lanes:expr) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $name(steps: usize, m: f64, a: f64) -> $t {
            use std::arch::x86_64::*;
            let (mv, av): ($v, $v) = ($set1(m as $t), $set1(a as $t));
            let mut acc: [$v; CHAINS] = [$set1(1.0); CHAINS];
            for _ in 0..steps {
                for x in acc.iter_mut() {
                    *x = $fma(*x, mv, av);
                }
            }
            let mut lanes = [0.0 as $t; $lanes];
            let mut total = 0.0 as $t;
            for x in acc {
                // SAFETY: `lanes` holds one vector.
                unsafe { $store(lanes.as_mut_ptr(), x) };
                total += lanes.iter().sum::<$t>();
            }
            total
        }
    };
}

vector_chains!(
    chains32_avx512,
    "avx512f,avx2,fma",
    f32,
    __m512,
    _mm512_set1_ps,
    _mm512_fmadd_ps,
    _mm512_storeu_ps,
    16
);
vector_chains!(
    chains32_avx2,
    "avx2,fma",
    f32,
    __m256,
    _mm256_set1_ps,
    _mm256_fmadd_ps,
    _mm256_storeu_ps,
    8
);
vector_chains!(
    chains64_avx512,
    "avx512f,avx2,fma",
    f64,
    __m512d,
    _mm512_set1_pd,
    _mm512_fmadd_pd,
    _mm512_storeu_pd,
    8
);
vector_chains!(
    chains64_avx2,
    "avx2,fma",
    f64,
    __m256d,
    _mm256_set1_pd,
    _mm256_fmadd_pd,
    _mm256_storeu_pd,
    4
);

/// A number type the chains run in.
trait Lane: Copy + std::ops::Add<Output = Self> {
    fn from_f64(v: f64) -> Self;
    fn fused<const F: bool>(a: Self, b: Self, c: Self) -> Self;
}

impl Lane for f32 {
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn fused<const F: bool>(a: Self, b: Self, c: Self) -> Self {
        madd::<F>(a, b, c)
    }
}

impl Lane for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn fused<const F: bool>(a: Self, b: Self, c: Self) -> Self {
        if F {
            a.mul_add(b, c)
        } else {
            a * b + c
        }
    }
}

/// [`CHAINS`] x `N` independent chains `x = x m + a`, `steps` long; their
/// sum (so nothing is optimised away).
#[inline(always)]
fn chains<const F: bool, T: Lane, const N: usize>(steps: usize, m: f64, a: f64) -> T {
    let (m, a) = (T::from_f64(m), T::from_f64(a));
    let mut acc = [[T::from_f64(1.0); N]; CHAINS];
    for _ in 0..steps {
        for chain in &mut acc {
            for x in chain.iter_mut() {
                *x = T::fused::<F>(*x, m, a);
            }
        }
    }
    acc.iter()
        .flatten()
        .fold(T::from_f64(0.0), |total, &x| total + x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_is_a_positive_rate_and_sets_a_bound() {
        let peak = measure_fma_peak(1);
        assert!(
            peak.f32_per_second > 1e8 && peak.f64_per_second > 1e8,
            "{peak:?}"
        );
        let t = peak.seconds((1000, 2000));
        assert!(t > 0.0 && t.is_finite());
    }
}
