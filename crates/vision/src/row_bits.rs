//! The vector compares of the binary-frame path of the blob detector
//! (report ch. 4.1): a row's pixels above a grey level as bit masks and
//! labels (`runs.rs` reads the runs from the masks and walks borders on
//! the labels), and whether any pixel lies in a span of grey levels (the
//! binary-frame test, `binary.rs`). 32 pixels a compare where the processor
//! has AVX2, 16 (SSE2, part of the x86_64 baseline) elsewhere on x86_64,
//! one at a time otherwise and for the tail: the same bits either way.

/// Bit `x % 64` of `masks[x / 64]` set, and `labels[x]` 1 (else 0), where
/// `row[x] > lvl` (`lvl` < 255; `row` and `labels` of the same length, at
/// most 64 bits a mask; the bits past the row cleared): whole 64-pixel
/// words by vector compares ([`vector_masks`]), the tail one at a time.
pub(crate) fn row_mask(row: &[u8], lvl: u8, labels: &mut [i8], masks: &mut [u64]) {
    let n = row.len().min(labels.len()).min(64 * masks.len());
    masks.fill(0);
    let done = vector_masks(&row[..n], lvl, &mut labels[..n], masks);
    for x in done..n {
        let white = row[x] > lvl;
        labels[x] = i8::from(white);
        masks[x / 64] |= u64::from(white) << (x % 64);
    }
}

/// [`row_mask`] of the first `64 * (row.len() / 64)` pixels (returned):
/// with AVX2 where the processor has it, else SSE2; none elsewhere.
fn vector_masks(row: &[u8], lvl: u8, labels: &mut [i8], masks: &mut [u64]) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { masks_avx2(row, lvl, labels, masks) };
        }
        masks_sse2(row, lvl, labels, masks)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (row, lvl, labels, masks);
        0
    }
}

/// [`vector_masks`] by four 16-pixel SSE2 compares a word: `v > lvl` where
/// `max(v, lvl + 1) == v`.
#[cfg(target_arch = "x86_64")]
fn masks_sse2(row: &[u8], lvl: u8, labels: &mut [i8], masks: &mut [u64]) -> usize {
    use std::arch::x86_64::{
        _mm_and_si128, _mm_cmpeq_epi8, _mm_loadu_si128, _mm_max_epu8, _mm_movemask_epi8,
        _mm_set1_epi8, _mm_storeu_si128,
    };
    let words = (row.len().min(labels.len()) / 64).min(masks.len());
    let (src, dst) = (row.as_ptr(), labels.as_mut_ptr());
    for (w, mask) in masks.iter_mut().enumerate().take(words) {
        let mut bits = 0u64;
        for q in 0..4 {
            let at = 64 * w + 16 * q;
            // SAFETY: SSE2 is in the x86_64 baseline, so these intrinsics
            // exist on every x86_64 CPU; at + 16 <= 64 (w + 1) <= the
            // lengths of `row` and `labels`, so the 16 bytes loaded and
            // stored are in bounds (no alignment needed).
            let hits = unsafe {
                let v = _mm_loadu_si128(src.add(at).cast());
                let hit = _mm_cmpeq_epi8(_mm_max_epu8(v, _mm_set1_epi8((lvl + 1) as i8)), v);
                _mm_storeu_si128(dst.add(at).cast(), _mm_and_si128(hit, _mm_set1_epi8(1)));
                _mm_movemask_epi8(hit)
            };
            bits |= u64::from(hits as u16) << (16 * q);
        }
        *mask = bits;
    }
    64 * words
}

/// [`vector_masks`] by two 32-pixel AVX2 compares a word, as
/// [`masks_sse2`].
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn masks_avx2(row: &[u8], lvl: u8, labels: &mut [i8], masks: &mut [u64]) -> usize {
    use std::arch::x86_64::{
        _mm256_and_si256, _mm256_cmpeq_epi8, _mm256_loadu_si256, _mm256_max_epu8,
        _mm256_movemask_epi8, _mm256_set1_epi8, _mm256_storeu_si256,
    };
    let words = (row.len().min(labels.len()) / 64).min(masks.len());
    let (src, dst) = (row.as_ptr(), labels.as_mut_ptr());
    let (above, one) = (_mm256_set1_epi8((lvl + 1) as i8), _mm256_set1_epi8(1));
    for (w, mask) in masks.iter_mut().enumerate().take(words) {
        let mut bits = 0u64;
        for q in 0..2 {
            let at = 64 * w + 32 * q;
            // SAFETY: at + 32 <= 64 (w + 1) <= the lengths of `row` and
            // `labels`, so the 32 bytes loaded and stored are in bounds
            // (no alignment needed).
            let hits = unsafe {
                let v = _mm256_loadu_si256(src.add(at).cast());
                let hit = _mm256_cmpeq_epi8(_mm256_max_epu8(v, above), v);
                _mm256_storeu_si256(dst.add(at).cast(), _mm256_and_si256(hit, one));
                _mm256_movemask_epi8(hit)
            };
            bits |= u64::from(hits as u32) << (32 * q);
        }
        *mask = bits;
    }
    64 * words
}

/// Whether any value of `pixels` has `v - base < span` (wrapping in u8;
/// `span` >= 1): 64 values a step by vector compares (AVX2 where the
/// processor has it, else SSE2; on x86_64), the rest one at a time.
pub(crate) fn any_in_span(pixels: &[u8], base: u8, span: u8) -> bool {
    #[cfg(target_arch = "x86_64")]
    let (found, done) = if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above).
        unsafe { span_avx2(pixels, base, span) }
    } else {
        span_sse2(pixels, base, span)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (found, done) = (false, 0);
    found || pixels[done..].iter().any(|&v| v.wrapping_sub(base) < span)
}

/// [`any_in_span`] over the whole 64-value blocks of `pixels` by SSE2
/// compares, `v - base <= span - 1` where the saturating `(v - base) -
/// (span - 1)` is zero; stops at the first block that has one. Returns
/// whether one did and how many values the blocks covered.
#[cfg(target_arch = "x86_64")]
fn span_sse2(pixels: &[u8], base: u8, span: u8) -> (bool, usize) {
    use std::arch::x86_64::{
        _mm_cmpeq_epi8, _mm_loadu_si128, _mm_movemask_epi8, _mm_or_si128, _mm_set1_epi8,
        _mm_setzero_si128, _mm_sub_epi8, _mm_subs_epu8,
    };
    let blocks = pixels.chunks_exact(64);
    let done = pixels.len() - blocks.remainder().len();
    for block in blocks {
        // SAFETY: SSE2 is in the x86_64 baseline, so these intrinsics exist
        // on every x86_64 CPU; `block` holds 64 bytes, so the four 16-byte
        // loads at 0, 16, 32 and 48 are in bounds (no alignment needed).
        let any = unsafe {
            let (b, top) = (_mm_set1_epi8(base as i8), _mm_set1_epi8((span - 1) as i8));
            let inside = |at: usize| {
                let d = _mm_sub_epi8(_mm_loadu_si128(block.as_ptr().add(at).cast()), b);
                _mm_cmpeq_epi8(_mm_subs_epu8(d, top), _mm_setzero_si128())
            };
            let any = _mm_or_si128(
                _mm_or_si128(inside(0), inside(16)),
                _mm_or_si128(inside(32), inside(48)),
            );
            _mm_movemask_epi8(any) != 0
        };
        if any {
            return (true, done);
        }
    }
    (false, done)
}

/// [`span_sse2`] by AVX2 compares, 32 values each.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn span_avx2(pixels: &[u8], base: u8, span: u8) -> (bool, usize) {
    use std::arch::x86_64::{
        _mm256_cmpeq_epi8, _mm256_loadu_si256, _mm256_movemask_epi8, _mm256_or_si256,
        _mm256_set1_epi8, _mm256_setzero_si256, _mm256_sub_epi8, _mm256_subs_epu8,
    };
    let blocks = pixels.chunks_exact(64);
    let done = pixels.len() - blocks.remainder().len();
    let (b, top) = (
        _mm256_set1_epi8(base as i8),
        _mm256_set1_epi8((span - 1) as i8),
    );
    for block in blocks {
        // SAFETY: `block` holds 64 bytes, so the two 32-byte loads at 0
        // and 32 are in bounds (no alignment needed).
        let inside = |at: usize| unsafe {
            let d = _mm256_sub_epi8(_mm256_loadu_si256(block.as_ptr().add(at).cast()), b);
            _mm256_cmpeq_epi8(_mm256_subs_epu8(d, top), _mm256_setzero_si256())
        };
        if _mm256_movemask_epi8(_mm256_or_si256(inside(0), inside(32))) != 0 {
            return (true, done);
        }
    }
    (false, done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random row of `n` values, mostly 0 and 255 with some grey.
    fn random_row(rng: &mut ChaCha8Rng, n: usize) -> Vec<u8> {
        (0..n)
            .map(|_| match rng.random_range(0..4) {
                0 => 0,
                1 => 255,
                _ => rng.random(),
            })
            .collect()
    }

    /// Each vector build of the masks and labels (SSE2 always, AVX2 where
    /// the processor has it) is the pixel-by-pixel definition.
    #[test]
    fn masks_of_every_build_are_the_pixels_above() {
        let mut rng = ChaCha8Rng::seed_from_u64(2114);
        for _ in 0..500 {
            let n = rng.random_range(0..300);
            let row = random_row(&mut rng, n);
            let lvl = rng.random_range(0..255u8);
            let mut want = vec![0u64; n.div_ceil(64)];
            let labels_want: Vec<i8> = row.iter().map(|&v| i8::from(v > lvl)).collect();
            for (x, &v) in row.iter().enumerate() {
                want[x / 64] |= u64::from(v > lvl) << (x % 64);
            }
            let (mut masks, mut labels) = (vec![u64::MAX; want.len()], vec![7i8; n]);
            row_mask(&row, lvl, &mut labels, &mut masks);
            assert_eq!((&masks, &labels), (&want, &labels_want));
            #[cfg(target_arch = "x86_64")]
            {
                let whole = 64 * (n / 64);
                let (mut masks, mut labels) = (vec![0u64; want.len()], vec![7i8; n]);
                assert_eq!(masks_sse2(&row, lvl, &mut labels, &mut masks), whole);
                assert_eq!(masks[..n / 64], want[..n / 64]);
                assert_eq!(labels[..whole], labels_want[..whole]);
                if std::arch::is_x86_feature_detected!("avx2") {
                    let (mut masks, mut labels) = (vec![0u64; want.len()], vec![7i8; n]);
                    // SAFETY: the processor has AVX2 (checked just above).
                    assert_eq!(
                        unsafe { masks_avx2(&row, lvl, &mut labels, &mut masks) },
                        whole
                    );
                    assert_eq!(masks[..n / 64], want[..n / 64]);
                    assert_eq!(labels[..whole], labels_want[..whole]);
                }
            }
        }
    }

    /// Each vector build of the span test is the value-by-value one.
    #[test]
    fn span_test_of_every_build_is_value_by_value() {
        let mut rng = ChaCha8Rng::seed_from_u64(2115);
        for _ in 0..2000 {
            let n = rng.random_range(0..400);
            let common: u8 = rng.random();
            let mut pixels = vec![common; n];
            if n > 0 && rng.random_bool(0.5) {
                let at = rng.random_range(0..n);
                pixels[at] = rng.random();
            }
            let (base, span) = (rng.random(), rng.random_range(1..=255u8));
            let want = pixels.iter().any(|&v| v.wrapping_sub(base) < span);
            assert_eq!(any_in_span(&pixels, base, span), want);
            #[cfg(target_arch = "x86_64")]
            {
                let tail =
                    |done: usize| pixels[done..].iter().any(|&v| v.wrapping_sub(base) < span);
                let (found, done) = span_sse2(&pixels, base, span);
                assert_eq!(found || tail(done), want);
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2 (checked just above).
                    let (found, done) = unsafe { span_avx2(&pixels, base, span) };
                    assert_eq!(found || tail(done), want);
                }
            }
        }
    }
}
