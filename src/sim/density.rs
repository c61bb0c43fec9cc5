//! Summation density and what every pass over neighbours shares: the kernel dispatch
//! ([`with_kernels`]), each particle's density and fluid neighbour list, the mean neighbour
//! count, and the largest length of a set of vectors (speeds, accelerations).

use super::config::SphConstants;
use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, LANES, NEIGHBOR_LIST_CAPACITY, NeighborList, Walls};
use bevy::math::{Vec2, Vec4};

/// Runs `$body` with `$w` bound to the density kernel and `$g` to the gradient kernel of
/// `$kind`, monomorphised per kernel so the neighbour loops have no dynamic dispatch.
macro_rules! with_kernels {
    ($kind:expr, $support:expr, |$w:ident, $g:ident| $body:expr) => {{
        use $crate::sim::kernels as k;
        match $kind {
            k::KernelKind::WendlandC2 => {
                let $w = k::WendlandC2::new($support);
                let $g = $w;
                $body
            }
            k::KernelKind::CubicSpline => {
                let $w = k::CubicSpline::new($support);
                let $g = $w;
                $body
            }
            k::KernelKind::Muller => {
                let $w = k::Poly6::new($support);
                let $g = k::Spiky::new($support);
                $body
            }
        }
    }};
}
pub(crate) use with_kernels;

/// Summed density at `x` (kg/m³): fluid particles (the one at `x` itself included) and wall
/// particles, summed lane by lane in a fixed order so the result does not depend on threads.
/// Also records the fluid neighbours inside the support, in candidate order, in `list`.
#[inline]
pub fn density_and_neighbors_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    x: Vec2,
    fluid: &FluidSnapshot,
    walls: &Walls,
    list: &mut NeighborList,
) -> f32 {
    let support_sq = Vec4::splat(c.support_sq);
    let tiny = Vec4::splat(1e-12 * c.support_sq);
    let mut sum = Vec4::ZERO;
    let mut len = 0usize;
    fluid.points.for_each_batch(x, |start, _, _, r2| {
        // No branch on the support: the kernels are zero beyond it.
        sum += kernel.value_sq_x4(r2);
        let inside = (r2.cmplt(support_sq) & r2.cmpgt(tiny)).bitmask() as usize;
        // Write all four slots, the inside ones first, and advance by how many are inside.
        if len <= NEIGHBOR_LIST_CAPACITY {
            let start = start as u32;
            let [a, b, c, d] = COMPACT[inside];
            list.slots[len..len + LANES].copy_from_slice(&[
                start + a,
                start + b,
                start + c,
                start + d,
            ]);
        }
        len += inside.count_ones() as usize;
    });
    walls
        .points
        .for_each_batch(x, |_, _, _, r2| sum += kernel.value_sq_x4(r2));
    list.len = if len <= NEIGHBOR_LIST_CAPACITY {
        // Pad the last lane batch with the padding slot after the last particle (far away).
        list.slots[len..len + LANES].fill(fluid.len() as u32);
        len as u32
    } else {
        u32::MAX
    };
    c.mass * sum.element_sum()
}

/// For each 4-bit lane mask, the lanes in the order "set lanes first": compaction by table.
const COMPACT: [[u32; LANES]; 16] = {
    let mut table = [[0u32; LANES]; 16];
    let mut mask = 0;
    while mask < 16 {
        let (mut next, mut lane) = (0, 0);
        while lane < LANES {
            if mask & (1 << lane) != 0 {
                table[mask][next] = lane as u32;
                next += 1;
            }
            lane += 1;
        }
        lane = 0;
        while lane < LANES {
            if mask & (1 << lane) == 0 {
                table[mask][next] = lane as u32;
                next += 1;
            }
            lane += 1;
        }
        mask += 1;
    }
    table
};

/// Mean number of particles, fluid and wall, within the kernel support of each fluid particle
/// (the particle itself included), over the snapshot's positions.
pub fn mean_neighbors(c: &SphConstants, fluid: &FluidSnapshot, walls: &Walls) -> f64 {
    if fluid.is_empty() {
        return 0.0;
    }
    let mut total = 0usize;
    for slot in 0..fluid.len() {
        let x = fluid.points.get(slot);
        for points in [&fluid.points, &walls.points] {
            points.for_each_batch(x, |_, _, _, r2| {
                total += r2.cmplt(Vec4::splat(c.support_sq)).bitmask().count_ones() as usize;
            });
        }
    }
    total as f64 / fluid.len() as f64
}

/// The largest length among `vectors` (the fastest speed, the largest acceleration).
pub(crate) fn max_length(vectors: &[Vec2]) -> f32 {
    vectors
        .iter()
        .fold(0.0f32, |m, a| m.max(a.length_squared()))
        .sqrt()
}
