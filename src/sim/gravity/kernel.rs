//! Pure point-mass sums, the inner loop of gravity: the softened acceleration and potential at a
//! point from a list of masses ([`sum_point_masses`]) or of tree nodes with their quadrupole
//! moments ([`sum_quadrupoles`]), on the widest SIMD the CPU has (AVX-512, AVX2, or the
//! baseline), picked at run time.
//!
//! Every path computes the same thing in the same order, so the results are identical bit for
//! bit on every FMA path (x86 with AVX-512F and FMA, or AVX2 and FMA; any 64-bit ARM):
//! - the masses are summed on [`LANES`] partial sums (mass `i` goes to lane `i % LANES`), which
//!   are added in one fixed tree at the end; the compiler never reorders a float sum, so each
//!   path vectorises the same lanes;
//! - the reciprocal square root is a bit-trick estimate refined by two Newton steps ([`rsqrt`]),
//!   plain IEEE arithmetic, instead of the CPU's approximate `rsqrt` instructions, which differ
//!   between vendors;
//! - the same products are fused (`mul_add`, one rounding) on every FMA path.
//!
//! Other x86 CPUs take the baseline path, which rounds those products twice (see the crate's
//! shared SIMD rule in `src/simd.rs`): reproducible on that kind of CPU, not bit for bit against
//! an FMA CPU.

use crate::sim::simd::{Simd, mul_add, simd};
use bevy::math::Vec2;

/// Partial sums per point: 16, one AVX-512 register of `f32`, two of AVX2, four of SSE.
pub const LANES: usize = 16;

/// `1/√s` for finite normal `s > 0`, to within 5·10⁻⁷ relative (4 ulp): a bit-trick first
/// guess, then two Newton steps `y ← y (a − b s y²)` whose coefficients are chosen so that
/// each step's error swings equally above and below zero (the same idea as Moroz et al.,
/// "Fast calculation of inverse square root with the use of magic constant", 2018; our
/// constants come from a minimax over every `f32` in [1, 4), where the error repeats every two
/// binades): 6.5·10⁻⁴ after the first step, 3·10⁻⁷ plus rounding after the second. Ten
/// multiplies, subtractions and fused multiply-adds that vectorise, against a square root and a
/// division that take 10–20 cycles each per register. `FUSED`: see the module.
#[inline(always)]
pub fn rsqrt<const FUSED: bool>(s: f32) -> f32 {
    // `wrapping_sub` never wraps here (the shifted bits are below 2³⁰), and unlike `-` it has
    // no overflow check in debug builds, which would stop the loop vectorising.
    let y = f32::from_bits(0x5f20_0000u32.wrapping_sub(s.to_bits() >> 1));
    let t = 0.703_951_95 * s * y;
    let y = y * mul_add::<FUSED>(-t, y, 1.681_913_9);
    let t = 0.500_000_06 * s * y;
    y * mul_add::<FUSED>(-t, y, 1.500_000_4)
}

/// Acceleration (per unit `G`, m/s² per (m³/(kg·s²))) and potential at `p` from the masses at
/// `(x[i], y[i])` of mass `m[i]`, softened by `eps_sq` (Plummer: `d/(d² + ε²)^{3/2}`), leaving out
/// any mass exactly at `p`. The slices may differ in length; the shortest counts.
pub fn sum_point_masses(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    match simd() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX-512F and FMA (`simd` checked).
        Simd::Avx512 => unsafe { masses_avx512(p, x, y, m, eps_sq) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 and FMA (`simd` checked).
        Simd::Avx2 => unsafe { masses_avx2(p, x, y, m, eps_sq) },
        Simd::Fused => sum_masses::<true>(p, x, y, m, eps_sq),
        Simd::Baseline => sum_masses::<false>(p, x, y, m, eps_sq),
    }
}

/// Tree nodes as sources with their quadrupole moments, structure of arrays: centre of mass
/// (`x`, `y`), mass `m`, and the moment per unit mass `Q/m` (`xx`, `yy`, `xy`), where
/// `Q = Σ mᵢ (3 sᵢsᵢᵀ − |sᵢ|² I)` for the bodies at `sᵢ` from the centre. Per unit mass it
/// scales as the node's width squared, so it stays in range at any mass.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Quadrupoles {
    /// Centre of mass, x, m.
    pub x: Vec<f32>,
    /// Centre of mass, y, m.
    pub y: Vec<f32>,
    /// Mass, kg.
    pub m: Vec<f32>,
    /// `Qxx/m`, m².
    pub xx: Vec<f32>,
    /// `Qyy/m`, m².
    pub yy: Vec<f32>,
    /// `Qxy/m`, m².
    pub xy: Vec<f32>,
}

impl Quadrupoles {
    /// No sources.
    pub fn clear(&mut self) {
        for v in self.columns() {
            v.clear();
        }
    }

    /// Adds a node at centre `c` of mass `m` and moment per unit mass
    /// `q = [Qxx, Qyy, Qxy] / m`.
    pub fn push(&mut self, c: Vec2, m: f32, q: [f32; 3]) {
        for (v, value) in self
            .columns()
            .into_iter()
            .zip([c.x, c.y, m, q[0], q[1], q[2]])
        {
            v.push(value);
        }
    }

    /// Pads with zero masses (which add exactly nothing) up to whole SIMD chunks.
    pub fn pad(&mut self) {
        let padded = self.x.len().div_ceil(LANES) * LANES;
        for v in self.columns() {
            v.resize(padded, 0.0);
        }
    }

    /// Whether there is no source.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    fn columns(&mut self) -> [&mut Vec<f32>; 6] {
        [
            &mut self.x,
            &mut self.y,
            &mut self.m,
            &mut self.xx,
            &mut self.yy,
            &mut self.xy,
        ]
    }
}

/// Acceleration (per unit `G`) and potential at `p` from `nodes`, each a point mass plus its
/// quadrupole term: `a = m d/r³ − Q d/r⁵ + (5/2)(dᵀQd) d/r⁷` and `φ = −m/r − (dᵀQd)/(2r⁵)` for
/// `d` from `p` to the centre, softened by putting `r² = |d|² + ε²` (not the exact expansion of
/// a Plummer potential, which adds an `ε² tr Q` term: the two agree while `ε` is small next to
/// the distance, as it is for a node far enough to be accepted). Computed as
/// `a = (m/r²) (n (1 + 5/2 nᵀQ'n) − Q'n)` with `n = d/r` and `Q' = Q/(m r²)`, which has the
/// point mass's range. Sources of zero mass (padding) or exactly at `p` are left out.
pub fn sum_quadrupoles(p: Vec2, nodes: &Quadrupoles, eps_sq: f32) -> (Vec2, f32) {
    match simd() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX-512F and FMA (`simd` checked).
        Simd::Avx512 => unsafe { quadrupoles_avx512(p, nodes, eps_sq) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 and FMA (`simd` checked).
        Simd::Avx2 => unsafe { quadrupoles_avx2(p, nodes, eps_sq) },
        Simd::Fused => sum_nodes::<true>(p, nodes, eps_sq),
        Simd::Baseline => sum_nodes::<false>(p, nodes, eps_sq),
    }
}

/// The acceleration and potential per unit `G` at `p` from one node at `c` of mass `m` and
/// moment per unit mass `q`, as one source of [`sum_quadrupoles`] (for single-point queries).
pub fn quadrupole_at(p: Vec2, c: Vec2, m: f32, q: [f32; 3], eps_sq: f32) -> (Vec2, f32) {
    let d = c - p;
    let (ax, ay, phi) = if simd() == Simd::Baseline {
        quadrupole::<false>(d.x, d.y, m, q, eps_sq)
    } else {
        quadrupole::<true>(d.x, d.y, m, q, eps_sq)
    };
    (Vec2::new(ax, ay), -phi)
}

/// One quadrupole source at `(dx, dy)` from the point: its acceleration per unit `G` and the
/// potential's magnitude (see [`sum_quadrupoles`] for the formula).
#[inline(always)]
fn quadrupole<const F: bool>(dx: f32, dy: f32, m: f32, q: [f32; 3], eps: f32) -> (f32, f32, f32) {
    let r2 = mul_add::<F>(dx, dx, dy * dy);
    let s = r2 + eps;
    // Padding (zero mass), the point itself and overflowing distances are left out.
    let inv = if r2 > 0.0 && m > 0.0 && s < f32::INFINITY {
        rsqrt::<F>(s)
    } else {
        0.0
    };
    let inv2 = inv * inv;
    let (nx, ny) = (dx * inv, dy * inv);
    // Q'n and nᵀQ'n, dimensionless (about (w/r)² for a node of width w).
    let qx = mul_add::<F>(q[0], nx, q[2] * ny) * inv2;
    let qy = mul_add::<F>(q[2], nx, q[1] * ny) * inv2;
    let nqn = mul_add::<F>(nx, qx, ny * qy);
    let m_inv = m * inv;
    let m_inv2 = m_inv * inv;
    let radial = mul_add::<F>(2.5, nqn, 1.0);
    (
        m_inv2 * mul_add::<F>(nx, radial, -qx),
        m_inv2 * mul_add::<F>(ny, radial, -qy),
        m_inv * mul_add::<F>(0.5, nqn, 1.0),
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn masses_avx512(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    sum_masses::<true>(p, x, y, m, eps_sq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn masses_avx2(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    sum_masses::<true>(p, x, y, m, eps_sq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn quadrupoles_avx512(p: Vec2, nodes: &Quadrupoles, eps_sq: f32) -> (Vec2, f32) {
    sum_nodes::<true>(p, nodes, eps_sq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn quadrupoles_avx2(p: Vec2, nodes: &Quadrupoles, eps_sq: f32) -> (Vec2, f32) {
    sum_nodes::<true>(p, nodes, eps_sq)
}

/// One chunk of sources, one per lane.
type Chunk = [f32; LANES];

/// Accumulators of one point's sum, one per lane.
struct Lanes {
    ax: Chunk,
    ay: Chunk,
    phi: Chunk,
}

impl Lanes {
    fn new() -> Self {
        Self {
            ax: [0.0; LANES],
            ay: [0.0; LANES],
            phi: [0.0; LANES],
        }
    }

    /// Adds `LANES` point masses, one per lane (the compiler turns this into whole-register
    /// SIMD).
    #[inline(always)]
    fn add_masses<const F: bool>(&mut self, p: Vec2, x: &Chunk, y: &Chunk, m: &Chunk, eps: f32) {
        for j in 0..LANES {
            let dx = x[j] - p.x;
            let dy = y[j] - p.y;
            let r2 = mul_add::<F>(dx, dx, dy * dy);
            let s = r2 + eps;
            // Beyond 10¹⁹ m the square overflows: such a mass counts as infinitely far.
            let inv_r = if r2 > 0.0 && s < f32::INFINITY {
                rsqrt::<F>(s)
            } else {
                0.0
            };
            // Mass first: a zero mass (padding) contributes exactly zero at any distance.
            let m_inv_r = m[j] * inv_r;
            let k = m_inv_r * inv_r * inv_r;
            self.ax[j] = mul_add::<F>(dx, k, self.ax[j]);
            self.ay[j] = mul_add::<F>(dy, k, self.ay[j]);
            self.phi[j] -= m_inv_r;
        }
    }

    /// Adds `LANES` quadrupole sources, one per lane.
    #[inline(always)]
    fn add_quadrupoles<const F: bool>(&mut self, p: Vec2, q: [&Chunk; 6], eps: f32) {
        let [x, y, m, xx, yy, xy] = q;
        for j in 0..LANES {
            let moment = [xx[j], yy[j], xy[j]];
            let (ax, ay, phi) = quadrupole::<F>(x[j] - p.x, y[j] - p.y, m[j], moment, eps);
            self.ax[j] += ax;
            self.ay[j] += ay;
            self.phi[j] -= phi;
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
fn pairwise(mut v: Chunk) -> f32 {
    let mut width = LANES / 2;
    while width > 0 {
        for j in 0..width {
            v[j] += v[j + width];
        }
        width /= 2;
    }
    v[0]
}

/// The chunk of `v` at `start` (which has `LANES` values from there on), borrowed.
#[inline(always)]
fn whole(v: &[f32], start: usize) -> &Chunk {
    v[start..start + LANES].try_into().expect("a whole chunk")
}

/// The values of `v` from `start` on (fewer than `LANES`), padded with `fill`.
#[inline(always)]
fn rest(v: &[f32], start: usize, fill: f32) -> Chunk {
    let mut padded = [fill; LANES];
    padded[..v.len() - start].copy_from_slice(&v[start..]);
    padded
}

#[inline(always)]
fn sum_masses<const F: bool>(p: Vec2, x: &[f32], y: &[f32], m: &[f32], eps_sq: f32) -> (Vec2, f32) {
    let n = x.len().min(y.len()).min(m.len());
    let (x, y, m) = (&x[..n], &y[..n], &m[..n]);
    let mut lanes = Lanes::new();
    let end = n / LANES * LANES;
    for k in (0..end).step_by(LANES) {
        lanes.add_masses::<F>(p, whole(x, k), whole(y, k), whole(m, k), eps_sq);
    }
    if end < n {
        // The rest in the same lanes, padded with zero masses at `p` (left out exactly).
        let (x, y, m) = (rest(x, end, p.x), rest(y, end, p.y), rest(m, end, 0.0));
        lanes.add_masses::<F>(p, &x, &y, &m, eps_sq);
    }
    lanes.total()
}

#[inline(always)]
fn sum_nodes<const F: bool>(p: Vec2, q: &Quadrupoles, eps_sq: f32) -> (Vec2, f32) {
    let columns = [&q.x, &q.y, &q.m, &q.xx, &q.yy, &q.xy];
    let n = columns.iter().map(|c| c.len()).min().unwrap_or(0);
    let [x, y, m, xx, yy, xy] = columns.map(|column| &column[..n]);
    let mut lanes = Lanes::new();
    let end = n / LANES * LANES;
    for k in (0..end).step_by(LANES) {
        let chunks = [x, y, m, xx, yy, xy].map(|column| whole(column, k));
        lanes.add_quadrupoles::<F>(p, chunks, eps_sq);
    }
    if end < n {
        // The rest padded with zero masses (left out exactly).
        let padded = [x, y, m, xx, yy, xy].map(|column| rest(column, end, 0.0));
        let [a, b, c, d, e, f] = &padded;
        lanes.add_quadrupoles::<F>(p, [a, b, c, d, e, f], eps_sq);
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
                for r in [rsqrt::<true>(v), rsqrt::<false>(v)] {
                    worst = worst.max(((r as f64 - exact) / exact).abs());
                }
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
                // Every FMA path gives the bits of the portable fused code.
                let reference = sum_masses::<true>(p, &x, &y, &m, eps_sq);
                if simd() != Simd::Baseline {
                    assert_eq!(sum_point_masses(p, &x, &y, &m, eps_sq), reference);
                }
                #[cfg(target_arch = "x86_64")]
                {
                    use std::arch::is_x86_feature_detected as has;
                    if has!("fma") && has!("avx2") {
                        // SAFETY: the CPU has AVX2 and FMA, checked just above.
                        assert_eq!(unsafe { masses_avx2(p, &x, &y, &m, eps_sq) }, reference);
                    }
                    if has!("fma") && has!("avx512f") {
                        // SAFETY: the CPU has AVX-512F and FMA, checked just above.
                        assert_eq!(unsafe { masses_avx512(p, &x, &y, &m, eps_sq) }, reference);
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
                // Both the fused and the baseline arithmetic match it.
                let baseline = sum_masses::<false>(p, &x, &y, &m, eps_sq);
                for (a, potential) in [reference, baseline] {
                    let a_err = ((a.x as f64 - ax).powi(2) + (a.y as f64 - ay).powi(2)).sqrt();
                    assert!(
                        a_err <= 1e-4 * (ax * ax + ay * ay).sqrt(),
                        "{a} vs {ax} {ay}"
                    );
                    assert!((potential as f64 - phi).abs() <= 1e-5 * phi.abs());
                }
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

    #[test]
    fn a_quadrupole_source_matches_its_bodies_far_away_better_than_a_point_mass() {
        // Four bodies about (0.3, -0.2); the moment from the definition.
        let c = Vec2::new(0.3, -0.2);
        let bodies = [
            (0.1, 0.05, 1.0),
            (-0.08, 0.02, 2.0),
            (0.02, -0.1, 1.5),
            (-0.04, 0.03, 0.5),
        ];
        let m_total: f32 = bodies.iter().map(|b| b.2).sum();
        let com = bodies
            .iter()
            .fold(Vec2::ZERO, |a, b| a + Vec2::new(b.0, b.1) * b.2)
            / m_total;
        let mut q = [0.0f32; 3];
        for &(sx, sy, m) in &bodies {
            let s = Vec2::new(sx, sy) - com;
            q[0] += m * (3.0 * s.x * s.x - s.length_squared());
            q[1] += m * (3.0 * s.y * s.y - s.length_squared());
            q[2] += m * 3.0 * s.x * s.y;
        }
        let x: Vec<f32> = bodies.iter().map(|b| c.x + b.0).collect();
        let y: Vec<f32> = bodies.iter().map(|b| c.y + b.1).collect();
        let m: Vec<f32> = bodies.iter().map(|b| b.2).collect();
        let mut source = Quadrupoles::default();
        source.push(c + com, m_total, q.map(|v| v / m_total));
        source.pad();
        for p in [
            Vec2::new(5.0, 1.0),
            Vec2::new(-4.0, -6.0),
            Vec2::new(0.3, 7.0),
        ] {
            let exact = sum_point_masses(p, &x, &y, &m, 0.0);
            let point = sum_point_masses(p, &[c.x + com.x], &[c.y + com.y], &[m_total], 0.0);
            let quad = sum_quadrupoles(p, &source, 0.0);
            let error = |a: (Vec2, f32)| (a.0 - exact.0).length() / exact.0.length();
            assert!(
                error(quad) < 0.2 * error(point),
                "{p}: {} vs {}",
                error(quad),
                error(point)
            );
            assert!((quad.1 - exact.1).abs() < 0.2 * (point.1 - exact.1).abs());
        }
        // Every path gives the same bits, and a zero moment is a point mass.
        let p = Vec2::new(1.0, 2.0);
        #[cfg(target_arch = "x86_64")]
        {
            let reference = sum_nodes::<true>(p, &source, 1e-3);
            use std::arch::is_x86_feature_detected as has;
            if has!("fma") && has!("avx2") {
                // SAFETY: the CPU has AVX2 and FMA, checked just above.
                assert_eq!(unsafe { quadrupoles_avx2(p, &source, 1e-3) }, reference);
            }
            if has!("fma") && has!("avx512f") {
                // SAFETY: the CPU has AVX-512F and FMA, checked just above.
                assert_eq!(unsafe { quadrupoles_avx512(p, &source, 1e-3) }, reference);
            }
        }
        let mut plain = Quadrupoles::default();
        plain.push(c, 2.0, [0.0; 3]);
        let (a, phi) = sum_quadrupoles(p, &plain, 0.0);
        let (b, psi) = sum_point_masses(p, &[c.x], &[c.y], &[2.0], 0.0);
        assert!((a - b).length() <= 1e-6 * b.length() && (phi - psi).abs() <= 1e-6 * psi.abs());
    }

    #[test]
    fn far_masses_and_heavy_nodes_stay_finite() {
        let p = Vec2::ZERO;
        // A mass beyond 10¹⁹ m (its square overflows) counts as infinitely far, next to padding.
        let (a, phi) = sum_point_masses(p, &[1.0e20, 0.0], &[0.0, 0.0], &[1.0, 0.0], 0.0);
        assert_eq!((a, phi), (Vec2::ZERO, 0.0));
        let mut far = Quadrupoles::default();
        far.push(Vec2::new(1.0e20, 0.0), 1.0, [0.1, -0.1, 0.0]);
        far.pad();
        assert_eq!(sum_quadrupoles(p, &far, 0.0), (Vec2::ZERO, 0.0));
        // A solar mass a million kilometres wide, 1 AU away: Q itself (2·10⁴⁸ kg·m²) would
        // overflow an f32; per unit mass it does not.
        let (m, w, r) = (2.0e30f32, 1.0e9f32, 1.5e11f32);
        let mut sun = Quadrupoles::default();
        sun.push(Vec2::new(r, 0.0), m, [w * w, -w * w, 0.0]);
        sun.pad();
        let (a, phi) = sum_quadrupoles(p, &sun, 0.0);
        let point = m / (r * r);
        assert!(a.is_finite() && phi.is_finite());
        assert!(
            (a.x / point - 1.0).abs() < 1e-3 && a.x > 0.0,
            "{a} vs {point}"
        );
    }
}
