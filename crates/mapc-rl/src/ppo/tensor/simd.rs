//! Element-wise loops run with AVX-512 or AVX2 where the CPU has them. The compiler targets the baseline x86-64
//! (4 floats a vector register); with AVX2 the same loop takes 8 at a time, with AVX-512 16. Only the width
//! differs: each lane does the same IEEE operations in the same order (Rust never fuses a multiply and an add on
//! its own), so all give the same bits, on every machine (a test checks it).

/// `fn NAME(ARGS) = BODY;` defines `NAME`, which calls `BODY(ARGS)` compiled with AVX-512 (else AVX2) enabled
/// when the CPU has it, and as compiled otherwise. `BODY` must be `#[inline(always)]`, so that it is compiled
/// inside each copy.
macro_rules! wide_fn {
    ($(#[$m:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) = $body:ident;) => {
        $(#[$m])*
        $vis fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn with_avx512($($arg: $ty),*) {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU has AVX-512F, checked just above.
                    return unsafe { with_avx512($($arg),*) };
                }
                #[target_feature(enable = "avx2")]
                fn with_avx2($($arg: $ty),*) {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has AVX2, checked just above.
                    return unsafe { with_avx2($($arg),*) };
                }
            }
            $body($($arg),*)
        }
    };
}

pub(super) use wide_fn;
