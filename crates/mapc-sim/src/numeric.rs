//! Floating-point helpers every model and the step share: SUMO's zero threshold, and `floor`, `ceil`, `min` and
//! `max` without the baseline x86-64 target's library calls and NaN fix-ups (the same bits for every input the
//! simulator produces).

/// Below this a quantity counts as zero (SUMO's `NUMERICAL_EPS`).
pub const NUMERICAL_EPS: f64 = 0.001;

/// Whether the target rounds to an integer in one instruction: x86-64 with SSE4.1 (`roundsd`; x86-64-v2 and later,
/// the level `.cargo/config.toml` builds for) and AArch64 (`frintm`).
const NATIVE_ROUNDING: bool = cfg!(any(
    target_arch = "aarch64",
    all(target_arch = "x86_64", target_feature = "sse4.1")
));

/// Whether this processor runs what the build uses: an x86-64 build for x86-64-v2 (`.cargo/config.toml`) needs
/// its instructions (SSE4.1 and the rest of the level); `Err` says what is missing and how to build for this
/// processor. The binary and the Python module check it first: otherwise the first such instruction would kill
/// the process.
#[cfg(all(target_arch = "x86_64", target_feature = "sse4.1"))]
pub fn check_cpu() -> Result<(), String> {
    cpu_lacks(|feature| match feature {
        "sse3" => std::arch::is_x86_feature_detected!("sse3"),
        "ssse3" => std::arch::is_x86_feature_detected!("ssse3"),
        "sse4.1" => std::arch::is_x86_feature_detected!("sse4.1"),
        "sse4.2" => std::arch::is_x86_feature_detected!("sse4.2"),
        "cmpxchg16b" => std::arch::is_x86_feature_detected!("cmpxchg16b"),
        _ => std::arch::is_x86_feature_detected!("popcnt"),
    })
}

/// [`check_cpu`] where the build asks nothing beyond its target's baseline.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse4.1")))]
pub fn check_cpu() -> Result<(), String> {
    Ok(())
}

/// x86-64-v2's instructions beyond the baseline that this build may use (but LAHF and SAHF, which every processor
/// with the others has).
#[cfg_attr(
    not(all(target_arch = "x86_64", target_feature = "sse4.1")),
    allow(dead_code)
)]
const X86_64_V2: [&str; 6] = ["sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "cmpxchg16b"];

/// [`check_cpu`]'s verdict given which features the processor has.
#[cfg_attr(
    not(all(target_arch = "x86_64", target_feature = "sse4.1")),
    allow(dead_code)
)]
fn cpu_lacks(has: impl Fn(&str) -> bool) -> Result<(), String> {
    let missing: Vec<&str> = X86_64_V2.into_iter().filter(|f| !has(f)).collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(format!(
        "this build of mapc uses x86-64-v2 instructions this processor lacks ({}); build it for this processor \
         with RUSTFLAGS=\"-C target-cpu=native\"",
        missing.join(", ")
    ))
}

/// `x.floor()`, bit for bit: the instruction where the target has one ([`NATIVE_ROUNDING`]), else
/// [`floor_by_truncation`] instead of the baseline x86-64 target's library call.
#[inline(always)]
pub(crate) fn floor_exact(x: f64) -> f64 {
    if NATIVE_ROUNDING {
        x.floor()
    } else {
        floor_by_truncation(x)
    }
}

/// `x.ceil()`, bit for bit (as [`floor_exact`]).
#[inline(always)]
pub(crate) fn ceil_exact(x: f64) -> f64 {
    if NATIVE_ROUNDING {
        x.ceil()
    } else {
        ceil_by_truncation(x)
    }
}

/// `x.floor()`, bit for bit, without a library call: below 2^52 in magnitude, truncation through an integer is
/// exact and only needs a correction of one for negative non-integers; zeros are their own floor; NaN, infinities
/// and large values take the library path.
#[inline(always)]
fn floor_by_truncation(x: f64) -> f64 {
    if x == 0.0 {
        x
    } else if x.abs() < 4_503_599_627_370_496.0 {
        let t = truncate(x);
        if t > x { t - 1.0 } else { t }
    } else {
        library_floor(x)
    }
}

/// `x.ceil()`, bit for bit, without a library call (as [`floor_by_truncation`]); the sign is copied from `x` so
/// that a negative number above -1 gives -0, as the library's.
#[inline(always)]
fn ceil_by_truncation(x: f64) -> f64 {
    if x == 0.0 {
        x
    } else if x.abs() < 4_503_599_627_370_496.0 {
        let t = truncate(x);
        (if t < x { t + 1.0 } else { t }).copysign(x)
    } else {
        library_ceil(x)
    }
}

/// `x` truncated towards zero, for `|x| < 2^52` (so neither NaN nor out of `i64`'s range): one conversion each
/// way. `x as i64` would add the saturation and NaN fix-ups (five more instructions) that the caller's range test
/// already rules out; the optimizer does not carry that test over to the conversion.
#[inline(always)]
fn truncate(x: f64) -> f64 {
    debug_assert!(x.abs() < 4_503_599_627_370_496.0);
    // SAFETY: the callers test |x| < 2^52 first: x is finite and its truncation fits an i64
    (unsafe { x.to_int_unchecked::<i64>() }) as f64
}

/// `exact().floor()`, bit for bit, given `approx`, a value of the same expression computed with fewer divisions
/// (multiplications by reciprocals of parameters, whose own divisions wait for no data): its floor unless it lies
/// within a tolerance of an integer, far above the few ulps by which the two can differ, where `exact` decides.
/// The divisions then leave the chain of dependent operations in all but rare cases.
#[inline(always)]
pub(crate) fn floor_near(approx: f64, exact: impl FnOnce() -> f64) -> f64 {
    let f = floor_exact(approx);
    let tol = FLOOR_NEAR_TOLERANCE * (1.0 + approx.abs());
    if approx - f > tol && (f + 1.0) - approx > tol && approx.abs() < 1e12 {
        f
    } else {
        floor_exact(exact())
    }
}

/// Relative distance to an integer below which [`floor_near`] computes the exact expression.
const FLOOR_NEAR_TOLERANCE: f64 = 1e-9;

// The rare paths out of line: inlined, the library calls are speculated (executed before the test that selects
// them) wherever the optimizer hoists the arithmetic around them.
#[cold]
#[inline(never)]
fn library_floor(x: f64) -> f64 {
    x.floor()
}

#[cold]
#[inline(never)]
fn library_ceil(x: f64) -> f64 {
    x.ceil()
}

/// `f64::min` / `f64::max` as one compare-and-select, without the NaN fix-up sequence the baseline x86-64 target
/// emits around `minsd`/`maxsd` (seven instructions; -8 % of the simulator's instructions). The same value as the
/// library's for every input the simulator produces: the left operand is never NaN (debug builds check it); of
/// two zeros of different signs either may come back, as with the library's.
pub(crate) trait FastMinMax {
    fn fmin(self, other: f64) -> f64;
    fn fmax(self, other: f64) -> f64;
}

impl FastMinMax for f64 {
    #[inline(always)]
    fn fmin(self, other: f64) -> f64 {
        debug_assert!(!self.is_nan(), "fmin on NaN");
        if other < self { other } else { self }
    }
    #[inline(always)]
    fn fmax(self, other: f64) -> f64 {
        debug_assert!(!self.is_nan(), "fmax on NaN");
        if other > self { other } else { self }
    }
}

#[cfg(test)]
#[path = "numeric_tests.rs"]
mod tests;
