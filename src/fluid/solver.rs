//! What both pressure solvers share: the constants derived from
//! [`SphParams`](crate::fluid::SphParams), kernel dispatch, summation density, the particle
//! integrator and collision safety net. Pure, no ECS: the systems in
//! [`systems`](super::systems) and the slice solver in [`slices`](super::slices) both call these
//! functions, so the two paths compute the same numbers. The pressure solvers are
//! [`wcsph`](super::wcsph) and [`dfsph`](super::dfsph), over the data in
//! [`layout`](super::layout).
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin).

use super::boundary::{Obstacle, Tank};
use super::kernels::{KernelKind, RadialKernel};
use super::layout::{FluidSnapshot, LANES, NEIGHBOR_LIST_CAPACITY, NeighborList, Walls};
use super::params::{DfsphSettings, PressureSolver};
use bevy::math::{Vec2, Vec4};

/// Everything the sub-step maths needs, derived once from validated
/// [`SphParams`](crate::fluid::SphParams) by
/// [`SphParams::constants`](crate::fluid::SphParams::constants).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphConstants {
    /// Kernel choice.
    pub kernel: KernelKind,
    /// Initial particle spacing, m.
    pub spacing: f32,
    /// Kernel support radius `H`, m.
    pub support: f32,
    /// `H²`, m².
    pub support_sq: f32,
    /// Smoothing length `h = H/2`, m (the length in the time-step limits and viscosity terms).
    pub smoothing_length: f32,
    /// Mass of every particle, kg per metre of depth.
    pub mass: f32,
    /// Rest density `ρ₀`, kg/m³.
    pub rest_density: f32,
    /// Speed of sound `c₀`, m/s.
    pub speed_of_sound: f32,
    /// Tait exponent `γ`.
    pub eos_exponent: f32,
    /// Tait stiffness `B = ρ₀c₀²/γ`, Pa.
    pub stiffness: f32,
    /// Background pressure added to the equation of state, Pa.
    pub background_pressure: f32,
    /// Monaghan artificial viscosity `α`.
    pub artificial_viscosity: f32,
    /// Kinematic viscosity `ν`, m²/s.
    pub kinematic_viscosity: f32,
    /// Gravity, m/s².
    pub gravity: Vec2,
    /// Courant number of the acoustic time-step limit.
    pub cfl_number: f32,
    /// Speeds are capped here, m/s: beyond `c₀` the weakly compressible model is meaningless.
    pub speed_limit: f32,
    /// Restitution of the collision safety net, 0..1.
    pub wall_restitution: f32,
    /// The tank, if any.
    pub tank: Option<Tank>,
    /// Layers of boundary particles behind each wall.
    pub wall_layers: u32,
    /// Sub-steps allowed per tick.
    pub max_substeps: u32,
    /// Which pressure solver runs.
    pub solver: PressureSolver,
    /// The settings of [`PressureSolver::Dfsph`].
    pub dfsph: DfsphSettings,
    /// Volume of a particle, `m/ρ₀`, m² (per metre of depth).
    pub volume: f32,
    /// Factor on the kernel gradient in the DFSPH solver that makes the discrete gradient
    /// of a linear field exact on the rest lattice (about 1.05 at 2.5 spacings), so hydrostatic
    /// pressure comes out at `ρ₀g` per metre instead of a few percent high.
    pub gradient_scale: f32,
}

/// Runs `$body` with `$w` bound to the density kernel and `$g` to the gradient kernel of
/// `$kind`, monomorphised per kernel so the neighbour loops have no dynamic dispatch.
macro_rules! with_kernels {
    ($kind:expr, $support:expr, |$w:ident, $g:ident| $body:expr) => {{
        use $crate::fluid::kernels as k;
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

/// Advances one particle by `dt` (symplectic Euler: velocity first, then position with the new
/// velocity), caps its speed, and keeps it inside the tank and out of obstacles. Returns `false`
/// (and leaves the particle where it was, at rest) if the result would not be finite.
#[inline]
pub fn advance_particle(
    c: &SphConstants,
    obstacles: &[Obstacle],
    position: &mut Vec2,
    velocity: &mut Vec2,
    acceleration: Vec2,
    dt: f32,
) -> bool {
    let v = *velocity + acceleration * dt;
    move_particle(c, obstacles, position, velocity, v, dt)
}

/// Gives one particle the velocity `v` (capped at the speed limit) and moves it by `v dt`, keeping
/// it inside the tank and out of obstacles. Returns `false` (and leaves the particle where it
/// was, at rest) if the result would not be finite.
#[inline]
pub fn move_particle(
    c: &SphConstants,
    obstacles: &[Obstacle],
    position: &mut Vec2,
    velocity: &mut Vec2,
    mut v: Vec2,
    dt: f32,
) -> bool {
    let speed_sq = v.length_squared();
    if speed_sq > c.speed_limit * c.speed_limit {
        v *= c.speed_limit / speed_sq.sqrt();
    }
    let mut x = *position + v * dt;
    for obstacle in obstacles {
        obstacle.push_out(&mut x, &mut v, c.wall_restitution);
    }
    if let Some(tank) = &c.tank {
        tank.confine(&mut x, &mut v, c.wall_restitution);
    }
    if x.is_finite() && v.is_finite() {
        *position = x;
        *velocity = v;
        true
    } else {
        *velocity = Vec2::ZERO;
        false
    }
}

/// The largest length among `vectors` (the fastest speed, the largest acceleration).
pub(crate) fn max_length(vectors: &[Vec2]) -> f32 {
    vectors
        .iter()
        .fold(0.0f32, |m, a| m.max(a.length_squared()))
        .sqrt()
}
