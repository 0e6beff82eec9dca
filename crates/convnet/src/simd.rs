//! Runtime choice of a kernel's build: the same portable Rust body
//! compiled three times (AVX-512F, AVX2, baseline), the widest the
//! processor has picked at each call (the detection is cached by the
//! standard library). The bodies use no fused multiply-adds, so every
//! build gives the same numbers bit for bit; only the vector width
//! changes (tests compare each dispatched kernel with its portable body).

/// `dispatched! { pub fn name(a: A, b: B) => body; }` defines `name`,
/// which calls the `#[inline(always)]` function `body` (same arguments,
/// returning `()`) in the widest build this processor runs.
macro_rules! dispatched {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) => $body:path;) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512($($arg: $ty),*) {
                    $body($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                fn avx2($($arg: $ty),*) {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the processor has AVX-512F (checked just above).
                    return unsafe { avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2 (checked just above).
                    return unsafe { avx2($($arg),*) };
                }
            }
            $body($($arg),*)
        }
    };
}

pub(crate) use dispatched;
