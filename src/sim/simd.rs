//! Which SIMD path the hot loops take on this CPU, picked at run time, and the one fused
//! multiply-add rule they share: gravity's point-mass sums ([`gravity`](crate::gravity)) and the
//! fluid's pressure-solve rows ([`fluid`](crate::fluid)). Pure, no ECS.
//!
//! Every path computes the same operations in the same order, so results are identical bit for
//! bit on every FMA path (x86 with AVX2 and FMA, AVX-512 among them, and any 64-bit ARM). Other
//! x86 CPUs (without AVX2 or FMA: before 2013, some AMD CPUs up to 2015, some low-end Atoms,
//! Celerons and Pentiums) take the baseline, which rounds products twice instead of calling a slow
//! software `fmaf`: a run there is reproducible on that kind of CPU (for any thread count), not
//! bit for bit against an FMA CPU.

/// The code path of the SIMD loops on this CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Simd {
    /// x86 with AVX-512F and FMA: 16 lanes in one register.
    #[cfg(target_arch = "x86_64")]
    Avx512,
    /// x86 with AVX2 and FMA: 8 lanes in one register.
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// A target whose baseline has fused multiply-add (64-bit ARM: NEON).
    Fused,
    /// Anything else: the compiler's baseline SIMD, products rounded twice.
    Baseline,
}

/// The widest path this CPU runs (the feature checks are cached by the standard library).
#[inline]
pub(crate) fn simd() -> Simd {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("fma") && has!("avx512f") {
            return Simd::Avx512;
        }
        if has!("fma") && has!("avx2") {
            return Simd::Avx2;
        }
    }
    if cfg!(target_arch = "aarch64") {
        Simd::Fused
    } else {
        Simd::Baseline
    }
}

/// The path the SIMD loops take on this CPU, for benchmark lines: `avx512+fma`, `avx2+fma`,
/// `fma` (64-bit ARM) or `baseline`.
pub fn simd_path() -> &'static str {
    match simd() {
        #[cfg(target_arch = "x86_64")]
        Simd::Avx512 => "avx512+fma",
        #[cfg(target_arch = "x86_64")]
        Simd::Avx2 => "avx2+fma",
        Simd::Fused => "fma",
        Simd::Baseline => "baseline",
    }
}

/// `a b + c`: fused (one rounding) on the FMA paths, two roundings on the baseline.
#[inline(always)]
pub(crate) fn mul_add<const FUSED: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FUSED { a.mul_add(b, c) } else { a * b + c }
}
