//! Weakly compressible SPH (Monaghan 1994, 2005), the reference pressure solver, over the
//! [`layout`](super::layout):
//! - density by summation ([`density_and_neighbors_at`]);
//! - Tait equation of state `p = B((ρ/ρ₀)^γ − 1)`, `B = ρ₀c₀²/γ`, clamped at zero so the free
//!   surface (where summation under-counts) feels no tension;
//! - the symmetric pressure force `aᵢ = −Σⱼ m (pᵢ/ρᵢ² + pⱼ/ρⱼ² + Πᵢⱼ) ∇W`, which conserves momentum
//!   pair by pair, with Monaghan's artificial viscosity `Πᵢⱼ` and the Lo & Shao (2002) laminar
//!   viscosity term for a kinematic viscosity `ν`;
//! - walls as fixed boundary particles whose pressure is extrapolated from the fluid with the
//!   hydrostatic correction of Adami, Hu & Adams (2012); they take part in pressure and laminar
//!   viscosity, not in the artificial viscosity (which would act as wall friction);
//! - explicit sub-steps bounded by the acoustic CFL, force and viscous limits
//!   ([`stable_time_step`]).
//!
//! [`Wcsph`] runs these in the stages of a sub-step ([`step`](super::step)).

use super::config::SphConstants;
use super::density::{density_and_neighbors_at, with_kernels};
use super::integrate::advance_particle;
use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, LANES, NeighborList, WallState, Walls};
use super::parallel::{Parallel, for_each_slot};
use super::step::{ForcesWrite, Particles, PressureStages, Shared, for_each_particle};
use super::viscosity::Laminar;
use bevy::math::{Vec2, Vec4};

/// The weakly compressible solver's own state: each particle's fluid neighbours by sorted slot,
/// from the density stage, which the force stage reuses.
#[derive(Debug, Clone, Default)]
pub struct Wcsph {
    lists: Vec<NeighborList>,
}

impl PressureStages for Wcsph {
    const FORCES_WRITE: ForcesWrite = ForcesWrite {
        pressure: true,
        velocity: false,
    };

    /// Summed density and the equation of state by sorted slot, stored in the snapshot for the
    /// force stage (with each particle's fluid neighbours), then the wall particles' pressure
    /// extrapolated from the fluid.
    fn density(&mut self, s: &mut Shared, _particles: &Particles, parallel: &impl Parallel) {
        let c = s.constants;
        let n = s.snapshot.len();
        self.lists.resize(n, NeighborList::default());
        let (snapshot, walls, lists) = (&s.snapshot, &mut s.walls, &mut self.lists);
        with_kernels!(c.kernel, c.support, |w, _g| {
            let fixed = &*walls;
            for_each_slot(lists, parallel, |slot, list| {
                let x = snapshot.points.get(slot);
                // The number density times the particle's own mass (Solenthaler & Pajarola).
                let ratio = snapshot.rest_ratio[slot];
                let rho = ratio * density_and_neighbors_at(&w, &c, x, snapshot, fixed, list);
                snapshot.set_pressure(slot, rho, liquid_pressure(&c, rho, ratio));
                0.0
            });
            walls.update_pressure(|states, points| {
                for_each_slot(states, parallel, |slot, state| {
                    *state = wall_state_at(&w, &c, points.get(slot), snapshot);
                    0.0
                });
            });
        });
    }

    /// Pressure, viscosity and gravity by sorted slot, then each particle's acceleration,
    /// density and pressure.
    fn forces(&mut self, s: &mut Shared, particles: &mut Particles, parallel: &impl Parallel) {
        let c = s.constants;
        let n = s.snapshot.len();
        s.accelerations.resize(n, Vec2::ZERO);
        let (snapshot, walls, lists) = (&s.snapshot, &s.walls, &self.lists);
        with_kernels!(c.kernel, c.support, |_w, g| {
            for_each_slot(&mut s.accelerations, parallel, |slot, a| {
                *a = acceleration_at(&g, &c, slot, &lists[slot], snapshot, walls);
                0.0
            });
        });
        let (slot_of, accelerations) = (snapshot.grid().slot_of(), &s.accelerations);
        for_each_particle(particles, parallel, |i, particle| {
            let slot = slot_of[i] as usize;
            *particle.acceleration = accelerations[slot];
            *particle.density = snapshot.pressure.get(slot).0;
            *particle.pressure = liquid_pressure(&c, *particle.density, snapshot.rest_ratio[slot]);
            0
        });
    }

    fn step_limit(&self, s: &Shared, max_acceleration: f32) -> f32 {
        let limits = (s.constants).with_largest_viscosity(s.snapshot.max_viscosity);
        stable_time_step(&limits, s.snapshot.max_speed, max_acceleration)
    }

    /// Symplectic Euler with the particles' accelerations, walls and solids.
    fn integrate(
        &mut self,
        s: &mut Shared,
        particles: &mut Particles,
        dt: f32,
        parallel: &impl Parallel,
    ) -> u64 {
        let (c, walls) = (s.constants, &s.walls);
        for_each_particle(particles, parallel, |_, p| {
            let (x, v, a) = (p.position, p.velocity, *p.acceleration);
            u64::from(!advance_particle(&c, walls, x, v, a, dt))
        })
    }

    /// Minus the pressure and laminar force each solid's boundary particles put on the fluid in
    /// the force stage (the pairs of [`acceleration_at`]), over `dt`.
    fn solid_impulses(&mut self, s: &mut Shared, dt: f32) {
        if s.walls.solids.is_empty() {
            return;
        }
        let c = s.constants;
        let (snapshot, walls) = (&s.snapshot, &s.walls);
        let centers: Vec<Vec2> = walls.solids.iter().map(|b| b.world_center()).collect();
        let mut sums = vec![(Vec2::ZERO, 0.0f32); centers.len()];
        let eta_sq = 0.01 * c.smoothing_length * c.smoothing_length;
        with_kernels!(c.kernel, c.support, |_w, g| {
            walls.for_each_solid_pair(&c, snapshot, |k, x, wall, i, r, r2| {
                let laminar = Laminar::at(snapshot, c.kinematic_viscosity, i).own();
                let [_, _, vx, vy] = snapshot.kinematics[i];
                let (rho_i, term_i) = snapshot.pressure.get(i);
                let d = &walls.data;
                let v = Vec2::new(vx - d.vx[wall], vy - d.vy[wall]);
                let viscous = laminar * r2 / ((r2 + eta_sq) * (rho_i + d.density[wall]));
                let slope = g.push_slope(r2.sqrt());
                let pair = slope * (viscous * v - (term_i + d.pressure_term[wall]) * r);
                let force = -c.mass * c.mass * snapshot.rest_ratio[i] * pair;
                sums[k].0 += force;
                sums[k].1 += (x - centers[k]).perp_dot(force);
            });
        });
        for (solid, (force, torque)) in s.walls.solids.iter_mut().zip(sums) {
            solid.end_substep(dt, force * dt, torque * dt);
        }
    }
}

/// Tait equation of state plus the background pressure, clamped at zero: pressure (Pa) at
/// `density` (kg/m³).
#[inline]
pub fn pressure_from_density(c: &SphConstants, density: f32) -> f32 {
    let ratio = density / c.rest_density;
    let powered = if c.eos_exponent == 7.0 {
        let r2 = ratio * ratio;
        r2 * r2 * r2 * ratio
    } else if c.eos_exponent == 1.0 {
        ratio
    } else {
        ratio.powf(c.eos_exponent)
    };
    (c.stiffness * (powered - 1.0) + c.background_pressure).max(0.0)
}

/// [`pressure_from_density`] for a liquid `ratio` times as dense as the base one: its own Tait
/// law, `ρ₀ᵢ = ratio ρ₀` and a stiffness `ratio` times the base liquid's (`ρ₀ᵢ c₀²/γ`).
#[inline]
pub fn liquid_pressure(c: &SphConstants, density: f32, ratio: f32) -> f32 {
    ratio * pressure_from_density(c, density / ratio)
}

/// Inverse of [`pressure_from_density`] for non-negative pressure, kg/m³.
#[inline]
pub fn density_from_pressure(c: &SphConstants, pressure: f32) -> f32 {
    let excess = (pressure.max(0.0) - c.background_pressure) / c.stiffness;
    c.rest_density * (1.0 + excess).max(0.0).powf(1.0 / c.eos_exponent)
}

/// Pressure and density of the wall particle at `x` (Adami et al. 2012): the kernel-weighted
/// fluid pressure around it plus the hydrostatic head `ρ g·(x_w − x_f)` between fluid and wall.
/// A wall particle with no fluid near it gets zero pressure.
#[inline]
pub fn wall_state_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    x: Vec2,
    fluid: &FluidSnapshot,
) -> WallState {
    let (mut weight, mut pressure) = (Vec4::ZERO, Vec4::ZERO);
    let (mut head_x, mut head_y) = (Vec4::ZERO, Vec4::ZERO);
    fluid.points.for_each_batch(x, |start, dx, dy, r2| {
        let w = kernel.value_sq_x4(r2); // zero outside the support and in masked lanes
        let (_, [_, _, rho, term]) = fluid.gather([start, start + 1, start + 2, start + 3]);
        weight += w;
        pressure += term * rho * rho * w;
        // x_w − x_f = −(dx, dy).
        head_x -= rho * w * dx;
        head_y -= rho * w * dy;
    });
    let weight = weight.element_sum();
    if weight <= 0.0 {
        return WallState {
            density: c.rest_density,
            pressure: 0.0,
        };
    }
    let head = Vec2::new(head_x.element_sum(), head_y.element_sum());
    let p = ((pressure.element_sum() + c.gravity.dot(head)) / weight).max(0.0);
    WallState {
        density: density_from_pressure(c, p),
        pressure: p,
    }
}

/// Acceleration (m/s²) of the particle at sorted `slot` (its density summed into the snapshot
/// this sub-step): pressure, artificial and laminar viscosity from fluid and wall neighbours,
/// plus gravity.
///
/// Fluid neighbours come from `list` (filled by
/// [`density_and_neighbors_at`](super::density::density_and_neighbors_at) this sub-step), or
/// from the grid if it overflowed; wall neighbours always come from the wall grid, and add
/// pressure and laminar viscosity (no-slip) but no artificial viscosity. Lanes are
/// evaluated four at a time and those outside the support masked, so there is no branch per
/// neighbour.
#[inline]
pub fn acceleration_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    slot: usize,
    list: &NeighborList,
    fluid: &FluidSnapshot,
    walls: &Walls,
) -> Vec2 {
    let [x, y, vx, vy] = fluid.kinematics[slot];
    let (x, v, rho) = (
        Vec2::new(x, y),
        Vec2::new(vx, vy),
        fluid.pressure.get(slot).0,
    );
    let p = liquid_pressure(c, rho, fluid.rest_ratio[slot]);
    let pair = PairTerms::new(c, v, rho, p);
    let laminar = Laminar::at(fluid, c.kinematic_viscosity, slot);
    let mut sum = (Vec4::ZERO, Vec4::ZERO);
    match list.padded_slots() {
        Some(slots) => {
            for batch in slots.chunks_exact(LANES) {
                let lanes = [0, 1, 2, 3].map(|lane| batch[lane] as usize);
                let ([px, py], neighbor) = fluid.gather(lanes);
                let (dx, dy) = (px - Vec4::splat(x.x), py - Vec4::splat(x.y));
                let mass = Vec4::from_array(lanes.map(|j| fluid.rest_ratio[j]));
                let nu = laminar.lanes(|nu| Vec4::from_array(lanes.map(|j| nu[j])));
                pair.accumulate(kernel, (dx, dy, mass, nu), neighbor, &mut sum);
            }
        }
        None => fluid.points.for_each_batch(x, |start, dx, dy, _| {
            let (_, neighbor) = fluid.gather([start, start + 1, start + 2, start + 3]);
            let mass = Vec4::from_slice(&fluid.rest_ratio[start..start + LANES]);
            let nu = laminar.lanes(|nu| Vec4::from_slice(&nu[start..start + LANES]));
            pair.accumulate(kernel, (dx, dy, mass, nu), neighbor, &mut sum);
        }),
    }
    // Artificial viscosity is a numerical damping of the fluid's own noise; against a wall it
    // would act as friction (measured: a dam-break front slowing by a fifth, where experiments
    // show none), so walls only take the physical laminar term, with the particle's own `ν`.
    let wall_pair = PairTerms {
        artificial: Vec4::ZERO,
        ..pair
    };
    let own = Vec4::splat(laminar.own());
    walls.points.for_each_batch(x, |start, dx, dy, _| {
        let lanes = walls.data.lanes(start);
        wall_pair.accumulate(kernel, (dx, dy, Vec4::ONE, own), lanes, &mut sum);
    });
    c.mass * Vec2::new(sum.0.element_sum(), sum.1.element_sum()) + c.gravity
}

/// What one particle brings to each of its pair interactions, splatted across lanes.
struct PairTerms {
    support_sq: Vec4,
    tiny: Vec4,
    eta_sq: Vec4,
    own_term: Vec4,
    rho: Vec4,
    vx: Vec4,
    vy: Vec4,
    /// `2 α c₀ h`: Monaghan's `Π = −α c₀ h μ / ρ̄` with `μ = (v·r)/(r²+η²)` for approaching
    /// pairs and `ρ̄ = (ρᵢ+ρⱼ)/2`.
    artificial: Vec4,
}

impl PairTerms {
    #[inline]
    fn new(c: &SphConstants, v: Vec2, rho: f32, p: f32) -> Self {
        let h = c.smoothing_length;
        Self {
            support_sq: Vec4::splat(c.support_sq),
            tiny: Vec4::splat(1e-12 * c.support_sq),
            eta_sq: Vec4::splat(0.01 * h * h),
            own_term: Vec4::splat(p / (rho * rho)),
            rho: Vec4::splat(rho),
            vx: Vec4::splat(v.x),
            vy: Vec4::splat(v.y),
            artificial: Vec4::splat(2.0 * c.artificial_viscosity * c.speed_of_sound * h),
        }
    }

    /// Adds, per lane, the pressure and viscosity terms (per unit mass) of four neighbours at
    /// offsets `(dx, dy)` with `[vx, vy, density, pressure term]`, masses `mass` (over the
    /// base liquid's) and the pairs' `4ν` (Lo & Shao's laminar term `4ν (r·∇W)/((ρᵢ+ρⱼ)(r²+η²))
    /// vᵢⱼ`); lanes outside the support (or at the particle itself) add nothing.
    #[inline(always)]
    fn accumulate<K: RadialKernel>(
        &self,
        kernel: &K,
        (dx, dy, mass, laminar): (Vec4, Vec4, Vec4, Vec4),
        [vx_j, vy_j, rho_j, term_j]: [Vec4; 4],
        sum: &mut (Vec4, Vec4),
    ) {
        let r2 = dx * dx + dy * dy;
        let inside = r2.cmplt(self.support_sq) & r2.cmpgt(self.tiny);
        let r2 = r2.min(self.support_sq); // finite in masked lanes
        let (rx, ry) = (-dx, -dy); // rᵢⱼ = xᵢ − xⱼ
        let (vx, vy) = (self.vx - vx_j, self.vy - vy_j);
        let slope = kernel.push_slope_x4(r2.sqrt()); // ∇W = slope · r
        let inv = Vec4::ONE / ((r2 + self.eta_sq) * (self.rho + rho_j));
        let approach = (vx * rx + vy * ry).min(Vec4::ZERO);
        let scalar = self.own_term + term_j - self.artificial * approach * inv;
        let viscous = laminar * r2 * inv;
        let slope = slope * mass;
        let fx = slope * (viscous * vx - scalar * rx);
        let fy = slope * (viscous * vy - scalar * ry);
        sum.0 += Vec4::select(inside, fx, Vec4::ZERO);
        sum.1 += Vec4::select(inside, fy, Vec4::ZERO);
    }
}

/// The largest stable time step (s) for the given fastest speed (m/s) and largest acceleration
/// (m/s²): the acoustic CFL limit `C h/(c₀ + v)`, the force limit `¼√(h/a)` and the viscous
/// limit `⅛ h²/ν` (Monaghan 1992; Morris et al. 1997).
pub fn stable_time_step(c: &SphConstants, max_speed: f32, max_acceleration: f32) -> f32 {
    let h = c.smoothing_length;
    let mut dt = c.cfl_number * h / (c.speed_of_sound + max_speed);
    if max_acceleration > 0.0 {
        dt = dt.min(0.25 * (h / max_acceleration).sqrt());
    }
    if c.kinematic_viscosity > 0.0 {
        dt = dt.min(0.125 * h * h / c.kinematic_viscosity);
    }
    dt
}
