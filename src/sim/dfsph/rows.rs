//! The cached neighbour rows of [`Dfsph`](super::Dfsph) and the two sums the pressure solves
//! run over them in every iteration: the density rate of a velocity field ([`Row::rate`]) and
//! the push of a stiffness field ([`Row::push`]). Pure, no ECS.
//!
//! Each particle's row is stored as its neighbours' slots and, apart, their gradients as `x, y`
//! pairs, padded to whole blocks of [`BLOCK`] with entries that add exactly nothing (the particle
//! itself at zero gradient). A block's four gradients are one AVX2 register of eight `f32`, and so
//! are its four neighbours' velocities, loaded as four 64-bit pairs: the sums are two fused
//! multiply-adds per block of four. (Gathers, `vgatherdps`, measured slower on an AMD EPYC than
//! the loads they replace: 0.43x against 0.55x real time for the 2,500-particle dam break.) The
//! path is picked at run time ([`Simd`]); every path sums entry `k` of a block on lanes `2k` and
//! `2k + 1` and adds the lanes in one fixed tree ([`sum_lanes`]), so the results are identical bit
//! for bit on every FMA path (AVX2, on AVX-512 CPUs too, and 64-bit ARM), for any thread count.

use crate::sim::simd::{Simd, mul_add};
use bevy::math::Vec2;

/// Neighbours per block: their gradients fill one AVX2 register of `f32`.
pub(super) const BLOCK: usize = 4;

/// Lanes of the partial sums: `x, y` of each neighbour of a block.
const LANES: usize = 2 * BLOCK;

/// Every particle's row of `stride` entries (a multiple of [`BLOCK`]), by sorted slot.
#[derive(Debug, Clone, Default)]
pub(super) struct Rows {
    /// Entries per particle.
    stride: usize,
    /// Particles.
    len: usize,
    /// Sorted slot of each neighbour (always below `len`).
    slot: Vec<u32>,
    /// `s V ∇Wᵢⱼ` of each neighbour, 1/m.
    gradient: Vec<Vec2>,
}

/// The rows of a run of particles, to fill in a parallel pass.
pub(super) struct RowsMut<'a> {
    stride: usize,
    len: usize,
    slot: &'a mut [u32],
    gradient: &'a mut [Vec2],
}

/// One particle's row, padded to whole blocks.
#[derive(Clone, Copy)]
pub(super) struct Row<'a> {
    /// Particles: every slot is below it.
    len: usize,
    slot: &'a [u32],
    gradient: &'a [Vec2],
}

impl Rows {
    /// Entries per particle.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Rows of `stride` entries (rounded up to whole blocks) for `len` particles. Entries are
    /// read only once written; until then every slot is in range (zero after a change of shape,
    /// or a slot of the same particles).
    pub fn resize(&mut self, len: usize, stride: usize) {
        let stride = stride.next_multiple_of(BLOCK);
        if (self.len, self.stride) == (len, stride) {
            return;
        }
        (self.len, self.stride) = (len, stride);
        let entries = len * stride;
        self.slot.clear();
        self.slot.resize(entries, 0);
        self.gradient.resize(entries, Vec2::ZERO);
    }

    /// The rows of `slots` particles at a time, in slot order.
    pub fn chunks_mut(&mut self, slots: usize) -> impl Iterator<Item = RowsMut<'_>> {
        let (stride, len) = (self.stride, self.len);
        let entries = slots * stride;
        self.slot
            .chunks_mut(entries)
            .zip(self.gradient.chunks_mut(entries))
            .map(move |(slot, gradient)| RowsMut {
                stride,
                len,
                slot,
                gradient,
            })
    }

    /// The row of the particle at `slot` with `count` neighbours, padded to whole blocks.
    #[inline(always)]
    pub fn row(&self, slot: usize, count: u32) -> Row<'_> {
        let start = slot * self.stride;
        let end = start + (count as usize).next_multiple_of(BLOCK);
        Row {
            len: self.len,
            slot: &self.slot[start..end],
            gradient: &self.gradient[start..end],
        }
    }

    /// The `count` neighbours of the particle at `slot`: each one's slot and gradient.
    #[cfg(test)]
    pub fn neighbors(&self, slot: usize, count: u32) -> impl Iterator<Item = (usize, Vec2)> + '_ {
        let range = slot * self.stride..slot * self.stride + count as usize;
        self.slot[range.clone()]
            .iter()
            .zip(&self.gradient[range])
            .map(|(&j, &g)| (j as usize, g))
    }
}

impl RowsMut<'_> {
    /// Sets entry `k` of the `row`-th particle of the run to neighbour `slot` with `gradient`.
    ///
    /// # Panics
    /// If `slot` is not a particle: the sums gather by slot without bounds checks.
    #[inline]
    pub fn set(&mut self, row: usize, k: usize, slot: usize, gradient: Vec2) {
        assert!(slot < self.len, "neighbour slot {slot} of {}", self.len);
        let at = row * self.stride + k;
        self.slot[at] = slot as u32;
        self.gradient[at] = gradient;
    }

    /// Pads the `row`-th particle's row of `count` entries (at most the stride) to whole blocks
    /// with `own` slot (the particle itself) at zero gradient, which adds nothing to any sum.
    pub fn pad(&mut self, row: usize, count: usize, own: usize) {
        for k in count..count.next_multiple_of(BLOCK) {
            self.set(row, k, own, Vec2::ZERO);
        }
    }
}

impl<'a> Row<'a> {
    /// The row's blocks: each one's [`BLOCK`] neighbour slots and gradients (padding included,
    /// the particle itself at zero gradient).
    #[inline(always)]
    pub fn blocks(self) -> impl Iterator<Item = (&'a [u32], &'a [Vec2])> {
        self.slot
            .chunks_exact(BLOCK)
            .zip(self.gradient.chunks_exact(BLOCK))
    }

    /// `Σⱼ gᵢⱼ·(uᵢ − uⱼ)` over the row: the density change rate (1/s) of a velocity field `u`
    /// (m/s, by slot, at least one per particle) at a particle moving at `ui`.
    #[inline(always)]
    pub fn rate(self, simd: Simd, u: &[Vec2], ui: Vec2) -> f32 {
        assert!(u.len() >= self.len);
        match simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU has AVX2 and FMA (`simd` checked; AVX-512 CPUs have them), every
            // slot is below `len` (`RowsMut::set`), and `u` holds at least `len` velocities.
            Simd::Avx512 | Simd::Avx2 => unsafe { rate_avx2(self, u, ui) },
            Simd::Fused => rate_lanes::<true>(self, u, ui),
            Simd::Baseline => rate_lanes::<false>(self, u, ui),
        }
    }

    /// `Σⱼ (xᵢ + xⱼ) gᵢⱼ` over the row: the pressure acceleration (m/s² for a stiffness in
    /// m²/s²) of a stiffness field `x` (by slot, at least one per particle) on a particle whose
    /// own stiffness is `xi`.
    #[inline(always)]
    pub fn push(self, simd: Simd, x: &[f32], xi: f32) -> Vec2 {
        assert!(x.len() >= self.len);
        match simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `rate`, with `x` holding at least `len` values.
            Simd::Avx512 | Simd::Avx2 => unsafe { push_avx2(self, x, xi) },
            Simd::Fused => push_lanes::<true>(self, x, xi),
            Simd::Baseline => push_lanes::<false>(self, x, xi),
        }
    }
}

/// The lanes `[x₀ y₀ x₁ y₁ x₂ y₂ x₃ y₃]` added in one fixed tree: `x = (0+4)+(2+6)` and
/// `y = (1+5)+(3+7)`, the order an AVX2 register's halves, then quarters add in.
#[inline(always)]
fn sum_pairs(a: [f32; LANES]) -> Vec2 {
    Vec2::new((a[0] + a[4]) + (a[2] + a[6]), (a[1] + a[5]) + (a[3] + a[7]))
}

/// All lanes in [`sum_pairs`]' tree, then `x + y`.
#[inline(always)]
fn sum_lanes(a: [f32; LANES]) -> f32 {
    let pairs = sum_pairs(a);
    pairs.x + pairs.y
}

/// [`Row::rate`] on plain lanes: entry `k` of a block on lanes `2k` (x) and `2k + 1` (y).
fn rate_lanes<const FUSED: bool>(row: Row, u: &[Vec2], ui: Vec2) -> f32 {
    let mut acc = [0.0f32; LANES];
    for (slots, gradients) in row
        .slot
        .chunks_exact(BLOCK)
        .zip(row.gradient.chunks_exact(BLOCK))
    {
        for k in 0..BLOCK {
            let (g, du) = (gradients[k], ui - u[slots[k] as usize]);
            acc[2 * k] = mul_add::<FUSED>(g.x, du.x, acc[2 * k]);
            acc[2 * k + 1] = mul_add::<FUSED>(g.y, du.y, acc[2 * k + 1]);
        }
    }
    sum_lanes(acc)
}

/// [`Row::push`] on plain lanes: entry `k` of a block on lanes `2k` (x) and `2k + 1` (y).
fn push_lanes<const FUSED: bool>(row: Row, x: &[f32], xi: f32) -> Vec2 {
    let mut acc = [0.0f32; LANES];
    for (slots, gradients) in row
        .slot
        .chunks_exact(BLOCK)
        .zip(row.gradient.chunks_exact(BLOCK))
    {
        for k in 0..BLOCK {
            let (g, weight) = (gradients[k], xi + x[slots[k] as usize]);
            acc[2 * k] = mul_add::<FUSED>(weight, g.x, acc[2 * k]);
            acc[2 * k + 1] = mul_add::<FUSED>(weight, g.y, acc[2 * k + 1]);
        }
    }
    sum_pairs(acc)
}

/// The lanes of an AVX2 register added in [`sum_pairs`]' tree: `x` in lane 0, `y` in lane 1.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn sum_register(v: std::arch::x86_64::__m256) -> std::arch::x86_64::__m128 {
    use std::arch::x86_64::*;
    // [0+4, 1+5, 2+6, 3+7], then [(0+4)+(2+6), (1+5)+(3+7), ..].
    let halves = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
    _mm_add_ps(halves, _mm_movehl_ps(halves, halves))
}

/// [`Row::rate`] on AVX2: a block's four velocities as four 64-bit loads, against its four
/// gradients in one register.
///
/// # Safety
/// The CPU has AVX2 and FMA; every slot of `row` indexes `u`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rate_avx2(row: Row, u: &[Vec2], ui: Vec2) -> f32 {
    use std::arch::x86_64::*;
    let velocities = u.as_ptr().cast::<f64>();
    let own = _mm256_setr_ps(ui.x, ui.y, ui.x, ui.y, ui.x, ui.y, ui.x, ui.y);
    let mut acc = _mm256_setzero_ps();
    for b in (0..row.slot.len()).step_by(BLOCK) {
        // SAFETY: `b + BLOCK` is within the row (whole blocks); each slot indexes `u` (the
        // caller's promise), whose `Vec2`s are pairs of `f32`, read as one `f64` each.
        unsafe {
            let slot = |k: usize| velocities.add(*row.slot.get_unchecked(b + k) as usize);
            let low = _mm_loadh_pd(_mm_load_sd(slot(0)), slot(1));
            let high = _mm_loadh_pd(_mm_load_sd(slot(2)), slot(3));
            let uj = _mm256_castpd_ps(_mm256_set_m128d(high, low));
            let g = _mm256_loadu_ps(row.gradient.as_ptr().add(b).cast());
            acc = _mm256_fmadd_ps(g, _mm256_sub_ps(own, uj), acc);
        }
    }
    let pairs = sum_register(acc);
    _mm_cvtss_f32(_mm_add_ss(pairs, _mm_movehdup_ps(pairs)))
}

/// [`Row::push`] on AVX2: a block's four stiffnesses broadcast and blended into `x, x` pairs,
/// against its four gradients in one register.
///
/// # Safety
/// The CPU has AVX2 and FMA; every slot of `row` indexes `x`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn push_avx2(row: Row, x: &[f32], xi: f32) -> Vec2 {
    use std::arch::x86_64::*;
    let own = _mm256_set1_ps(xi);
    let mut acc = _mm256_setzero_ps();
    for b in (0..row.slot.len()).step_by(BLOCK) {
        // SAFETY: as in `rate_avx2`, each slot indexes `x`.
        unsafe {
            let slot = |k: usize| {
                _mm_broadcast_ss(&*x.as_ptr().add(*row.slot.get_unchecked(b + k) as usize))
            };
            let low = _mm_blend_ps::<0b1100>(slot(0), slot(1));
            let high = _mm_blend_ps::<0b1100>(slot(2), slot(3));
            let weight = _mm256_add_ps(own, _mm256_set_m128(high, low));
            let g = _mm256_loadu_ps(row.gradient.as_ptr().add(b).cast());
            acc = _mm256_fmadd_ps(weight, g, acc);
        }
    }
    let pairs = sum_register(acc);
    Vec2::new(_mm_cvtss_f32(pairs), _mm_cvtss_f32(_mm_movehdup_ps(pairs)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of 40 particles with 0 to 20 neighbours each, scattered slots and gradients.
    fn rows() -> (Rows, Vec<u32>) {
        let n = 40;
        let mut rows = Rows::default();
        rows.resize(n, 20);
        let mut counts = Vec::new();
        let mut chunk = rows.chunks_mut(n).next().unwrap();
        for i in 0..n {
            let count = (i * 7) % 21;
            for k in 0..count {
                let j = (i * 13 + k * 29) % n;
                let g = Vec2::new(((i + k) as f32 * 0.37).sin(), ((i * k) as f32 * 0.61).cos());
                chunk.set(i, k, j, 50.0 * g);
            }
            chunk.pad(i, count, i);
            counts.push(count as u32);
        }
        (rows, counts)
    }

    #[test]
    fn every_fma_path_gives_the_same_bits_and_the_sums() {
        let (rows, counts) = rows();
        let n = counts.len();
        let u: Vec<Vec2> = (0..n)
            .map(|i| Vec2::new((i as f32 * 0.3).sin(), (i as f32 * 0.7).cos()))
            .collect();
        let x: Vec<f32> = (0..n).map(|i| 10.0 + (i as f32 * 1.3).sin()).collect();
        let paths = [
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2,
            Simd::Fused,
        ];
        let available = |path: &Simd| match path {
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 | Simd::Avx512 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            _ => true,
        };
        for i in 0..n {
            let row = rows.row(i, counts[i]);
            let reference = (
                row.rate(Simd::Fused, &u, u[i]),
                row.push(Simd::Fused, &x, x[i]),
            );
            for path in paths.iter().filter(|p| available(p)) {
                assert_eq!(row.rate(*path, &u, u[i]), reference.0, "{path:?}");
                assert_eq!(row.push(*path, &x, x[i]), reference.1, "{path:?}");
            }
            // Against plain f64 sums over the neighbours alone.
            let (mut rate, mut push) = (0.0f64, [0.0f64; 2]);
            for (j, g) in rows.neighbors(i, counts[i]) {
                let du = u[i] - u[j];
                rate += g.x as f64 * du.x as f64 + g.y as f64 * du.y as f64;
                let w = x[i] as f64 + x[j] as f64;
                push[0] += w * g.x as f64;
                push[1] += w * g.y as f64;
            }
            assert!((reference.0 as f64 - rate).abs() < 1e-4 * (1.0 + rate.abs()));
            assert!((reference.1.x as f64 - push[0]).abs() < 1e-4 * (1.0 + push[0].abs()));
            assert!((reference.1.y as f64 - push[1]).abs() < 1e-4 * (1.0 + push[1].abs()));
        }
    }

    #[test]
    #[should_panic(expected = "neighbour slot")]
    fn a_slot_outside_the_particles_is_refused() {
        let mut rows = Rows::default();
        rows.resize(4, 8);
        rows.chunks_mut(4).next().unwrap().set(0, 0, 4, Vec2::ONE);
    }
}
