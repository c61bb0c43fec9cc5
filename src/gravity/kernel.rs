//! Pure point-mass sums, the inner loop of gravity: the softened acceleration and potential at a
//! point from a list of masses, on the widest SIMD the CPU has (AVX-512, AVX2, or the baseline),
//! picked once at run time.
//!
//! Every path computes the same thing in the same order, so the results are identical bit for
//! bit on every path and every x86 CPU (and on any other target):
//! - the masses are summed on [`LANES`] partial sums (mass `i` goes to lane `i % LANES`), which
//!   are added in one fixed tree at the end; the compiler never reorders a float sum, so each
//!   path vectorises the same lanes;
//! - the reciprocal square root is a bit-trick estimate refined by two Newton steps ([`rsqrt`]),
//!   plain IEEE multiplies and subtractions, instead of the CPU's approximate `rsqrt`
//!   instructions, which differ between vendors;
//! - no fused multiply-add: Rust does not contract `a * b + c`.

use bevy::math::Vec2;

/// Partial sums per point: 16, one AVX-512 register of `f32`, two of AVX2, four of SSE.
pub const LANES: usize = 16;

/// `1/√s` for finite normal `s > 0`, to within 5·10⁻⁷ relative (4 ulp): a bit-trick first
/// guess, then two Newton steps `y ← y (a − b s y²)` whose coefficients are chosen so that
/// each step's error swings equally above and below zero (the same idea as Moroz et al.,
/// "Fast calculation of inverse square root with the use of magic constant", 2018; our
/// constants come from a minimax over every `f32` in [1, 4), where the error repeats every two
/// binades): 6.5·10⁻⁴ after the first step, 3·10⁻⁷ plus rounding after the second. Twelve
/// multiplies and subtractions that vectorise, against a square root and a division that take
/// 10–20 cycles each per register.
#[inline(always)]
pub fn rsqrt(s: f32) -> f32 {
    let y = f32::from_bits(0x5f20_0000 - (s.to_bits() >> 1));
    let y = y * (1.681_913_9 - 0.703_951_95 * s * y * y);
    y * (1.500_000_4 - 0.500_000_06 * s * y * y)
}

/// Acceleration (per unit `G`, m/s² per (m³/(kg·s²))) and potential at `p` from the masses at
/// `(x[i], y[i])` of mass `m[i]`, softened by `eps_sq` (Plummer: `d/(d² + ε²)^{3/2}`), leaving out
/// any mass exactly at `p`. The slices may differ in length; the shortest counts.
pub fn sum_point_masses(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, checked just above.
            return unsafe { sum_avx512(p, x, y, m, eps_sq) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { sum_avx2(p, x, y, m, eps_sq) };
        }
    }
    sum_lanes(p, x, y, m, eps_sq)
}

/// The SIMD path in use on this CPU, for benchmark lines: `avx512`, `avx2` or `baseline`.
pub fn simd_path() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return "avx512";
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            return "avx2";
        }
    }
    "baseline"
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn sum_avx512(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    sum_lanes(p, x, y, m, eps_sq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sum_avx2(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    sum_lanes(p, x, y, m, eps_sq)
}

/// Accumulators of one point's sum, one per lane.
struct Lanes {
    ax: [f32; LANES],
    ay: [f32; LANES],
    phi: [f32; LANES],
}

impl Lanes {
    /// Adds `LANES` masses, one per lane (the compiler turns this into whole-register SIMD).
    #[inline(always)]
    fn add(&mut self, p: Vec2, x: &[f32; LANES], y: &[f32; LANES], m: &[f32; LANES], eps: f32) {
        for j in 0..LANES {
            let dx = x[j] - p.x;
            let dy = y[j] - p.y;
            let r2 = dx * dx + dy * dy;
            let inv_r = if r2 > 0.0 { rsqrt(r2 + eps) } else { 0.0 };
            // Mass first: a zero mass (padding) contributes exactly zero at any distance.
            let m_inv_r = m[j] * inv_r;
            let k = m_inv_r * inv_r * inv_r;
            self.ax[j] += dx * k;
            self.ay[j] += dy * k;
            self.phi[j] -= m_inv_r;
        }
    }

    /// The lanes added in one fixed pairwise tree.
    #[inline(always)]
    fn total(&self) -> (Vec2, f32) {
        (
            Vec2::new(pairwise(self.ax), pairwise(self.ay)),
            pairwise(self.phi),
        )
    }
}

#[inline(always)]
fn pairwise(mut v: [f32; LANES]) -> f32 {
    let mut width = LANES / 2;
    while width > 0 {
        for j in 0..width {
            v[j] += v[j + width];
        }
        width /= 2;
    }
    v[0]
}

#[inline(always)]
fn sum_lanes(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    let n = x.len().min(y.len()).min(m.len());
    let (x, y, m) = (&x[..n], &y[..n], &m[..n]);
    let mut lanes = Lanes {
        ax: [0.0; LANES],
        ay: [0.0; LANES],
        phi: [0.0; LANES],
    };
    let whole = n / LANES * LANES;
    for ((x, y), m) in x[..whole]
        .chunks_exact(LANES)
        .zip(y[..whole].chunks_exact(LANES))
        .zip(m[..whole].chunks_exact(LANES))
    {
        let chunk = |s: &[f32]| -> [f32; LANES] { s.try_into().expect("a whole chunk") };
        lanes.add(p, &chunk(x), &chunk(y), &chunk(m), eps_sq);
    }
    if whole < n {
        // The rest in the same lanes, padded with zero masses at `p` (left out exactly).
        let (mut tx, mut ty, mut tm) = ([p.x; LANES], [p.y; LANES], [0.0; LANES]);
        let rest = n - whole;
        tx[..rest].copy_from_slice(&x[whole..]);
        ty[..rest].copy_from_slice(&y[whole..]);
        tm[..rest].copy_from_slice(&m[whole..]);
        lanes.add(p, &tx, &ty, &tm, eps_sq);
    }
    lanes.total()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rsqrt_is_within_five_parts_in_ten_million_over_many_decades() {
        let mut worst = 0.0f64;
        let mut s = 1.0e-30f32;
        while s < 1.0e30 {
            for k in 0..97 {
                let v = s * (1.0 + k as f32 / 97.0);
                let exact = 1.0 / (v as f64).sqrt();
                worst = worst.max(((rsqrt(v) as f64 - exact) / exact).abs());
            }
            s *= 10.0;
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
    }

    #[test]
    fn every_path_gives_the_same_bits_and_matches_the_plain_sum() {
        let n = 1_000 + 7;
        let x: Vec<f32> = (0..n)
            .map(|i| (i as f32 * 0.618).fract() * 4.0 - 2.0)
            .collect();
        let y: Vec<f32> = (0..n)
            .map(|i| (i as f32 * 0.377).fract() * 4.0 - 2.0)
            .collect();
        let m: Vec<f32> = (0..n).map(|i| 0.5 + (i % 5) as f32 * 0.25).collect();
        for p in [
            Vec2::new(0.1, -0.2),
            Vec2::new(x[3], y[3]),
            Vec2::new(9.0, 9.0),
        ] {
            for eps_sq in [0.0, 1e-4] {
                let reference = sum_lanes(p, &x, &y, &m, eps_sq);
                assert_eq!(sum_point_masses(p, &x, &y, &m, eps_sq), reference);
                #[cfg(target_arch = "x86_64")]
                {
                    if std::arch::is_x86_feature_detected!("avx2") {
                        assert_eq!(unsafe { sum_avx2(p, &x, &y, &m, eps_sq) }, reference);
                    }
                    if std::arch::is_x86_feature_detected!("avx512f") {
                        assert_eq!(unsafe { sum_avx512(p, &x, &y, &m, eps_sq) }, reference);
                    }
                }
                // Against a plain f64 sum.
                let (mut ax, mut ay, mut phi) = (0.0f64, 0.0f64, 0.0f64);
                for i in 0..n {
                    let (dx, dy) = ((x[i] - p.x) as f64, (y[i] - p.y) as f64);
                    let r2 = dx * dx + dy * dy;
                    if r2 > 0.0 {
                        let inv = 1.0 / (r2 + eps_sq as f64).sqrt();
                        ax += m[i] as f64 * dx * inv * inv * inv;
                        ay += m[i] as f64 * dy * inv * inv * inv;
                        phi -= m[i] as f64 * inv;
                    }
                }
                let (a, potential) = reference;
                let a_err = ((a.x as f64 - ax).powi(2) + (a.y as f64 - ay).powi(2)).sqrt();
                assert!(
                    a_err <= 1e-4 * (ax * ax + ay * ay).sqrt(),
                    "{a} vs {ax} {ay}"
                );
                assert!((potential as f64 - phi).abs() <= 1e-5 * phi.abs());
            }
        }
    }

    #[test]
    fn the_point_itself_and_padding_add_nothing() {
        let p = Vec2::new(1.0, 2.0);
        assert_eq!(
            sum_point_masses(p, &[1.0], &[2.0], &[5.0], 0.0),
            (Vec2::ZERO, 0.0)
        );
        assert_eq!(sum_point_masses(p, &[], &[], &[], 0.0), (Vec2::ZERO, 0.0));
        let one = sum_point_masses(p, &[2.0], &[2.0], &[1.0], 0.0);
        let padded = sum_point_masses(p, &[2.0, 0.0, 7.0], &[2.0, 0.0, 3.0], &[1.0, 0.0, 0.0], 0.0);
        assert_eq!(one, padded);
        assert!((one.0.x - 1.0).abs() < 1e-6 && (one.1 + 1.0).abs() < 1e-6);
    }
}
