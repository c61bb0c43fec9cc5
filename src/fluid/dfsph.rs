//! **Experimental, not the default yet**: a resting layer does not settle (velocities of
//! 0.1–0.4 m/s remain and the bottom row's pressure spikes); see the crate README. Select it with
//! [`PressureSolver::Dfsph`](crate::fluid::PressureSolver::Dfsph) to try it.
//!
//! Divergence-free SPH (Bender & Koschier, "Divergence-free smoothed particle hydrodynamics",
//! SCA 2015; "Divergence-free SPH for incompressible and viscous fluids", TVCG 2017), over the
//! [`layout`](super::layout). Pure, no ECS.
//!
//! One sub-step, in the order both drivers ([`systems`](super::systems) and
//! [`slices`](super::slices)) call it:
//! 1. [`Dfsph::prepare`]: from the sorted snapshot, each particle's fluid neighbours with their
//!    volume-weighted kernel gradients `gᵢⱼ = s V ∇Wᵢⱼ` (cached: every solver iteration reuses
//!    them), the summed wall gradient, density `ρ̂ᵢ = ρᵢ/ρ₀` by summation over fluid and wall
//!    particles, and the DFSPH factor `1/αᵢ`.
//! 2. [`Dfsph::solve_divergence`]: Jacobi iterations on the stiffness `κᵛ` until the mean density
//!    change over a step, `dt Dρ̂/Dt` with `Dρ̂ᵢ/Dt = Σⱼ gᵢⱼ·(vᵢ − vⱼ) + g_wall,ᵢ·vᵢ`, is below
//!    the tolerance.
//! 3. The caller adds non-pressure accelerations ([`Dfsph::non_pressure_acceleration`]: gravity,
//!    viscosity) and its own external forces, picks the step ([`Dfsph::stable_time_step`]: the
//!    flow's CFL `C Δx / v_max`, the force and viscous limits), and stores the accelerations with
//!    [`Dfsph::set_acceleration`].
//! 4. [`Dfsph::solve_density`]: predicts `v* = v + dt a`, then Jacobi iterations on the stiffness
//!    `κ` until the mean predicted compression `ρ̂ᵢ + dt Dρ̂ᵢ/Dt − 1` is below the tolerance.
//! 5. The caller moves each particle with its solved velocity ([`Dfsph::velocity`]).
//!
//! Each iteration sets `Δκᵢ = (source)/(dtᵏ αᵢ)` with
//! `αᵢ = Gᵢ·(Gᵢ + g_wall,ᵢ) + Σⱼ |gᵢⱼ|²`, `Gᵢ = Σⱼ gᵢⱼ + g_wall,ᵢ`, and changes velocities by
//! `Δvᵢ = −dt (Σⱼ (Δκᵢ + Δκⱼ) gᵢⱼ + 2Δκᵢ g_wall,ᵢ)`: the symmetric pressure force (momentum is
//! conserved pair by pair) with wall particles mirroring the fluid's pressure (Akinci et al.
//! 2012), so `αᵢ` is exactly how much `Δκᵢ` alone changes particle `i`'s density. The stiffness
//! is a pressure per rest density (`p = ρ₀ κ`, m²/s²), so it warm-starts the next sub-step
//! whatever its length. The stiffness stays non-negative (a projected Jacobi iteration): a free
//! surface feels no tension, and an overshooting warm start is taken back.
//!
//! Wall particles lie on the fluid's rest lattice and count with the fluid's particle volume in
//! the density sum, so a particle at a wall has rest density at rest (the boundary contribution
//! of Akinci et al. with the lattice volume). Kernel gradients carry the lattice correction
//! [`SphConstants::gradient_scale`], which makes the discrete gradient of a linear field exact at
//! rest, so hydrostatic pressure rises at `ρ₀g`.
//!
//! Convergence sums are taken in fixed point over slots, so the iteration count, and with it
//! every result, is the same on any number of threads.
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin).

use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, SlotVectors, Walls};
use super::parallel::{Parallel, chunk_size};
use super::solver::{SphConstants, with_kernels};
use bevy::math::{Vec2, Vec4};

/// Slots a parallel task takes at least. Below `2 ×` this a pass runs on the calling thread:
/// at 2,500 particles a pass is tens of microseconds, the cost of waking a second thread.
pub const MIN_SLOTS_PER_TASK: usize = 2048;

/// Jacobi relaxation: the plain update (1.0) diverges in 2D (measured: the resting layer blows
/// up in its first tick); 0.6 converges.
const RELAXATION: f32 = 0.6;

/// Weight of the wall term in the pressure force: walls mirror the fluid particle's pressure
/// (with 1.0 the floor would pull the bottom row down by `κᵢ g_wall`).
const WALL_MIRROR: f32 = 2.0;

/// Fixed-point scale of the convergence sums (exact, so independent of the summation order).
const FIXED_POINT: f64 = (1u64 << 32) as f64;

/// One cached fluid neighbour of a particle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Neighbor {
    /// Sorted slot of the neighbour.
    slot: u32,
    /// `s V ∇Wᵢⱼ`, 1/m.
    gradient: Vec2,
}

/// Per-particle values of the current sub-step, by sorted slot.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct SlotState {
    /// Cached fluid neighbours.
    count: u32,
    /// `ρ/ρ₀`.
    density: f32,
    /// `1/αᵢ`, m² (zero for a particle without neighbours).
    factor: f32,
    /// `Σ_b s V ∇W_ib` over wall particles, 1/m.
    wall_gradient: Vec2,
    /// `Σ_b V (r·∇W)/(r² + η²)` over wall particles (dimensionless, negative), for wall friction.
    wall_viscosity: f32,
}

/// What the last sub-step's solves did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DfsphReport {
    /// Jacobi iterations of the density solve.
    pub density_iterations: u32,
    /// Jacobi iterations of the divergence solve.
    pub divergence_iterations: u32,
    /// Mean predicted compression left after the density solve, fraction.
    pub density_error: f32,
    /// Mean density change per step left after the divergence solve, fraction.
    pub divergence_error: f32,
}

/// The divergence-free solver's state for one sub-step, by sorted slot (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Dfsph {
    stride: usize,
    rows: Vec<Neighbor>,
    state: Vec<SlotState>,
    velocity: Vec<Vec2>,
    acceleration: SlotVectors,
    kappa: Vec<f32>,
    kappa_divergence: Vec<f32>,
    step: Vec<f32>,
    /// What the last sub-step did.
    pub report: DfsphReport,
}

impl Dfsph {
    /// Number of particles in the current sub-step.
    pub fn len(&self) -> usize {
        self.state.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.state.is_empty()
    }

    /// Step 1: caches neighbours and gradients, sums densities, computes the factors, and takes
    /// the velocities from the snapshot. `warm_start(slot)` gives each particle's stiffness
    /// `[κ, κᵛ]` from the last sub-step (m²/s²).
    pub fn prepare(
        &mut self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &Walls,
        warm_start: impl Fn(usize) -> Vec2 + Sync,
        parallel: &impl Parallel,
    ) {
        let n = fluid.len();
        self.state.clear();
        self.state.resize(n, SlotState::default());
        self.velocity.clear();
        self.velocity.extend(
            fluid.kinematics[..n]
                .iter()
                .map(|&[_, _, vx, vy]| Vec2::new(vx, vy)),
        );
        self.acceleration.reset(n);
        self.kappa.resize(n, 0.0);
        self.kappa_divergence.resize(n, 0.0);
        self.step.resize(n, 0.0);
        let warm = c.dfsph.warm_start;
        for slot in 0..n {
            let k = if warm { warm_start(slot) } else { Vec2::ZERO };
            self.kappa[slot] = k.x.max(0.0);
            self.kappa_divergence[slot] = k.y.max(0.0);
        }
        // Room for a compressed neighbourhood; a particle with more doubles it and tries again.
        let ratio = c.support / c.spacing;
        let mut stride = ((core::f32::consts::PI * ratio * ratio * 1.5) as usize + 8)
            .next_multiple_of(4)
            .max(self.stride);
        loop {
            self.rows.clear();
            self.rows.resize(n * stride, Neighbor::default());
            let overflow = with_kernels!(c.kernel, c.support, |w, g| {
                self.gather_neighbors(&w, &g, c, fluid, walls, stride, parallel)
            });
            if !overflow {
                break;
            }
            stride *= 2;
        }
        self.stride = stride;
        self.report = DfsphReport::default();
    }

    #[expect(clippy::too_many_arguments, reason = "one pass, spelled out")]
    fn gather_neighbors<W: RadialKernel, G: RadialKernel>(
        &mut self,
        w: &W,
        g: &G,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &Walls,
        stride: usize,
        parallel: &impl Parallel,
    ) -> bool {
        let n = self.state.len();
        let chunk = slots_per_task(n, parallel);
        let scaled_volume = c.gradient_scale * c.volume;
        let support_sq = Vec4::splat(c.support_sq);
        let tiny = Vec4::splat(1e-12 * c.support_sq);
        let eta_sq = 0.01 * c.smoothing_length * c.smoothing_length;
        let mut jobs: Vec<_> = self
            .state
            .chunks_mut(chunk)
            .zip(self.rows.chunks_mut(chunk * stride))
            .enumerate()
            .map(|(k, (state, rows))| (k * chunk, state, rows, false))
            .collect();
        parallel.for_each(&mut jobs, |(start, states, rows, overflow)| {
            for (k, state) in states.iter_mut().enumerate() {
                let x = fluid.points.get(*start + k);
                let row = &mut rows[k * stride..(k + 1) * stride];
                let mut len = 0usize;
                let mut density = Vec4::ZERO;
                let mut gradient_sum = Vec2::ZERO;
                let mut squares = 0.0f32;
                fluid.points.for_each_batch(x, |first, dx, dy, r2| {
                    density += w.value_sq_x4(r2);
                    let inside = r2.cmplt(support_sq) & r2.cmpgt(tiny);
                    let mask = inside.bitmask();
                    if mask == 0 {
                        return;
                    }
                    let slope = g.derivative_over_r_x4(r2.min(support_sq).sqrt());
                    // ∇ᵢWᵢⱼ = slope (xᵢ − xⱼ) = −slope (dx, dy).
                    let gx = (-scaled_volume * slope * dx).to_array();
                    let gy = (-scaled_volume * slope * dy).to_array();
                    for lane in 0..4 {
                        if mask & (1 << lane) == 0 {
                            continue;
                        }
                        let gradient = Vec2::new(gx[lane], gy[lane]);
                        gradient_sum += gradient;
                        squares += gradient.length_squared();
                        if len < stride {
                            row[len] = Neighbor {
                                slot: (first + lane) as u32,
                                gradient,
                            };
                        }
                        len += 1;
                    }
                });
                let mut wall_gradient = Vec2::ZERO;
                let mut wall_viscosity = 0.0f32;
                walls.points.for_each_batch(x, |_, dx, dy, r2| {
                    density += w.value_sq_x4(r2);
                    let inside = r2.cmplt(support_sq) & r2.cmpgt(tiny);
                    let mask = inside.bitmask();
                    if mask == 0 {
                        return;
                    }
                    let r2 = r2.min(support_sq);
                    let slope = g.derivative_over_r_x4(r2.sqrt());
                    let gx = (-scaled_volume * slope * dx).to_array();
                    let gy = (-scaled_volume * slope * dy).to_array();
                    let friction = (c.volume * slope * r2 / (r2 + Vec4::splat(eta_sq))).to_array();
                    for lane in 0..4 {
                        if mask & (1 << lane) != 0 {
                            wall_gradient += Vec2::new(gx[lane], gy[lane]);
                            wall_viscosity += friction[lane];
                        }
                    }
                });
                if len > stride {
                    *overflow = true;
                }
                let total = gradient_sum + wall_gradient;
                let mirrored = total + (WALL_MIRROR - 1.0) * wall_gradient;
                let alpha = mirrored.length_squared() + squares;
                *state = SlotState {
                    count: len.min(stride) as u32,
                    density: c.volume * density.element_sum(),
                    factor: if alpha > 1e-6 / c.support_sq {
                        1.0 / alpha
                    } else {
                        0.0
                    },
                    wall_gradient,
                    wall_viscosity,
                };
            }
        });
        jobs.iter().any(|job| job.3)
    }

    /// Step 2: makes the velocity field divergence-free for a step of `dt` seconds (the last
    /// sub-step's length). Returns the iterations taken.
    pub fn solve_divergence(&mut self, c: &SphConstants, dt: f32, parallel: &impl Parallel) -> u32 {
        let settings = c.dfsph;
        if self.is_empty() || dt <= 0.0 || settings.max_divergence_iterations == 0 {
            return 0;
        }
        // Warm start: half the last sub-step's divergence stiffness (it scales with the step).
        for (step, kappa) in self.step.iter_mut().zip(&mut self.kappa_divergence) {
            *step = 0.5 * *kappa;
            *kappa = 0.0;
        }
        if settings.warm_start {
            self.apply_pressure(dt, Target::Divergence, parallel);
        }
        let mut iterations = 0;
        loop {
            let error = self.divergence_source(dt, parallel);
            self.report.divergence_error = error;
            if (error <= settings.divergence_tolerance && iterations >= 1)
                || iterations >= settings.max_divergence_iterations
            {
                break;
            }
            self.apply_pressure(dt, Target::Divergence, parallel);
            iterations += 1;
        }
        self.report.divergence_iterations = iterations;
        iterations
    }

    /// Step 4: predicts velocities with the stored accelerations and solves for the pressure
    /// that keeps the density at rest after a step of `dt` seconds. Returns the iterations.
    pub fn solve_density(&mut self, c: &SphConstants, dt: f32, parallel: &impl Parallel) -> u32 {
        if self.is_empty() || dt <= 0.0 {
            return 0;
        }
        let settings = c.dfsph;
        for (slot, v) in self.velocity.iter_mut().enumerate() {
            *v += dt * self.acceleration.get(slot);
        }
        for (step, kappa) in self.step.iter_mut().zip(&mut self.kappa) {
            *step = *kappa;
            *kappa = 0.0;
        }
        if settings.warm_start {
            self.apply_pressure(dt, Target::Density, parallel);
        }
        let mut iterations = 0;
        loop {
            let error = self.density_source(dt, parallel);
            self.report.density_error = error;
            if (error <= settings.density_tolerance && iterations >= 2)
                || iterations >= settings.max_density_iterations
            {
                break;
            }
            self.apply_pressure(dt, Target::Density, parallel);
            iterations += 1;
        }
        self.report.density_iterations = iterations;
        iterations
    }

    /// Computes each particle's stiffness increment for the divergence solve into `step` and
    /// returns the mean remaining density change per step (fraction).
    fn divergence_source(&mut self, dt: f32, parallel: &impl Parallel) -> f32 {
        let (rows, state, velocity, kappa) = (
            &self.rows,
            &self.state,
            &self.velocity,
            &self.kappa_divergence,
        );
        let stride = self.stride;
        let total = for_each_slot(&mut self.step, parallel, |slot, step| {
            let s = state[slot];
            let vi = velocity[slot];
            let row = &rows[slot * stride..slot * stride + s.count as usize];
            let mut rate = s.wall_gradient.dot(vi);
            for neighbor in row {
                rate += neighbor.gradient.dot(vi - velocity[neighbor.slot as usize]);
            }
            *step = (RELAXATION * rate * s.factor / dt).max(-kappa[slot]);
            fixed_point(residual(rate * dt, kappa[slot]))
        });
        mean(total, self.state.len())
    }

    /// Computes each particle's stiffness increment for the density solve into `step` and
    /// returns the mean predicted compression (fraction).
    fn density_source(&mut self, dt: f32, parallel: &impl Parallel) -> f32 {
        let (rows, state, velocity, kappa) = (&self.rows, &self.state, &self.velocity, &self.kappa);
        let stride = self.stride;
        let total = for_each_slot(&mut self.step, parallel, |slot, step| {
            let s = state[slot];
            let vi = velocity[slot];
            let row = &rows[slot * stride..slot * stride + s.count as usize];
            let mut rate = s.wall_gradient.dot(vi);
            for neighbor in row {
                rate += neighbor.gradient.dot(vi - velocity[neighbor.slot as usize]);
            }
            let compression = s.density + dt * rate - 1.0;
            *step = (RELAXATION * compression * s.factor / (dt * dt)).max(-kappa[slot]);
            fixed_point(residual(compression, kappa[slot]))
        });
        mean(total, self.state.len())
    }

    /// Applies the increments in `step` to the velocities and adds them to the target's
    /// stiffness.
    fn apply_pressure(&mut self, dt: f32, target: Target, parallel: &impl Parallel) {
        let (rows, state, step) = (&self.rows, &self.state, &self.step);
        let stride = self.stride;
        let kappa = match target {
            Target::Density => &mut self.kappa,
            Target::Divergence => &mut self.kappa_divergence,
        };
        let n = state.len();
        let chunk = slots_per_task(n, parallel);
        let mut jobs: Vec<_> = self
            .velocity
            .chunks_mut(chunk)
            .zip(kappa.chunks_mut(chunk))
            .enumerate()
            .map(|(k, (v, kappa))| (k * chunk, v, kappa))
            .collect();
        parallel.for_each(&mut jobs, |(start, velocities, kappas)| {
            for (k, (v, kappa)) in velocities.iter_mut().zip(kappas.iter_mut()).enumerate() {
                let slot = *start + k;
                let s = state[slot];
                let own = step[slot];
                let row = &rows[slot * stride..slot * stride + s.count as usize];
                let mut push = WALL_MIRROR * own * s.wall_gradient;
                for neighbor in row {
                    push += (own + step[neighbor.slot as usize]) * neighbor.gradient;
                }
                *v -= dt * push;
                *kappa += own;
            }
        });
    }

    /// Gravity plus laminar (Lo & Shao 2002) and artificial (Monaghan) viscosity at sorted
    /// `slot`, m/s², from the cached neighbours and the divergence-free velocities. Walls add
    /// laminar friction only, as in [`wcsph`](super::wcsph).
    pub fn non_pressure_acceleration(
        &self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        slot: usize,
    ) -> Vec2 {
        let s = self.state[slot];
        let (xi, vi) = (fluid.points.get(slot), self.velocity[slot]);
        let rho_i = s.density * c.rest_density;
        let h = c.smoothing_length;
        let eta_sq = 0.01 * h * h;
        // m ∇W = ρ₀ g / s.
        let to_mass_gradient = c.rest_density / c.gradient_scale;
        let laminar = 4.0 * c.kinematic_viscosity;
        let artificial = 2.0 * c.artificial_viscosity * c.speed_of_sound * h;
        let row = &self.rows[slot * self.stride..slot * self.stride + s.count as usize];
        let mut a = Vec2::ZERO;
        for neighbor in row {
            let j = neighbor.slot as usize;
            let r = xi - fluid.points.get(j);
            let v = vi - self.velocity[j];
            let mass_gradient = to_mass_gradient * neighbor.gradient;
            let r2 = r.length_squared();
            let inv = 1.0 / ((r2 + eta_sq) * (rho_i + self.state[j].density * c.rest_density));
            let approach = v.dot(r).min(0.0);
            a += (laminar * inv * r.dot(mass_gradient)) * v
                + (artificial * approach * inv) * mass_gradient;
        }
        let wall = laminar * c.rest_density / (rho_i + c.rest_density) * s.wall_viscosity;
        a + wall * vi + c.gravity
    }

    /// The largest stable step (s) for the fastest particle after the divergence solve and the
    /// largest acceleration `max_acceleration` (m/s²): the flow's CFL limit `C Δx / v_max`, the
    /// force limit `¼√(h/a)`, the viscous limit `⅛h²/ν` for the laminar viscosity plus the
    /// artificial one (`ν ≈ α c₀ h / 8` in 2D), and the settings' longest step.
    pub fn stable_time_step(&self, c: &SphConstants, max_acceleration: f32) -> f32 {
        let max_speed = self
            .velocity
            .iter()
            .fold(0.0f32, |m, v| m.max(v.length_squared()))
            .sqrt();
        stable_time_step(c, max_speed, max_acceleration)
    }

    /// Stores the acceleration (m/s²) of the particle at sorted `slot` for
    /// [`solve_density`](Self::solve_density); safe to call from parallel loops (one slot each).
    #[inline]
    pub fn set_acceleration(&self, slot: usize, acceleration: Vec2) {
        self.acceleration.set(slot, acceleration);
    }

    /// Velocity at sorted `slot`, m/s: divergence-free after step 2, solved after step 4.
    #[inline]
    pub fn velocity(&self, slot: usize) -> Vec2 {
        self.velocity[slot]
    }

    /// Summed density at sorted `slot`, kg/m³.
    #[inline]
    pub fn density(&self, c: &SphConstants, slot: usize) -> f32 {
        self.state[slot].density * c.rest_density
    }

    /// Stiffness `[κ, κᵛ]` at sorted `slot` (m²/s²), to warm-start the next sub-step.
    #[inline]
    pub fn stiffness(&self, slot: usize) -> Vec2 {
        Vec2::new(self.kappa[slot], self.kappa_divergence[slot])
    }

    /// Pressure at sorted `slot`, Pa: `ρ₀ (κ + κᵛ)`, both solves' pressures of this sub-step.
    #[inline]
    pub fn pressure(&self, c: &SphConstants, slot: usize) -> f32 {
        c.rest_density * (self.kappa[slot] + self.kappa_divergence[slot])
    }
}

/// The stable DFSPH step for a fastest speed (m/s) and largest acceleration (m/s²); see
/// [`Dfsph::stable_time_step`].
pub fn stable_time_step(c: &SphConstants, max_speed: f32, max_acceleration: f32) -> f32 {
    let h = c.smoothing_length;
    let mut dt = c.dfsph.max_time_step;
    if max_speed > 0.0 {
        dt = dt.min(c.dfsph.cfl_number * c.spacing / max_speed);
    }
    if max_acceleration > 0.0 {
        dt = dt.min(0.25 * (h / max_acceleration).sqrt());
    }
    let viscosity = c.kinematic_viscosity + c.artificial_viscosity * c.speed_of_sound * h / 8.0;
    if viscosity > 0.0 {
        dt = dt.min(0.125 * h * h / viscosity);
    }
    dt
}

/// Which stiffness a pressure application adds to.
#[derive(Clone, Copy)]
enum Target {
    Density,
    Divergence,
}

/// Slots per parallel task: a few tasks per thread, none under [`MIN_SLOTS_PER_TASK`].
fn slots_per_task(n: usize, parallel: &impl Parallel) -> usize {
    chunk_size(n, 4 * parallel.threads(), MIN_SLOTS_PER_TASK)
}

/// Runs `work(slot, &mut out[slot])` for every slot, in parallel chunks, and returns the sum of
/// what it returns (integers: the same whatever the chunking).
fn for_each_slot<T: Send>(
    out: &mut [T],
    parallel: &impl Parallel,
    work: impl Fn(usize, &mut T) -> u64 + Sync,
) -> u64 {
    let chunk = slots_per_task(out.len(), parallel);
    let mut jobs: Vec<_> = out
        .chunks_mut(chunk)
        .enumerate()
        .map(|(k, values)| (k * chunk, values, 0u64))
        .collect();
    parallel.for_each(&mut jobs, |(start, values, sum)| {
        for (k, value) in values.iter_mut().enumerate() {
            *sum += work(*start + k, value);
        }
    });
    jobs.iter().map(|job| job.2).sum()
}

/// The error of a particle whose density would change by `source` (fraction) while it has
/// stiffness `kappa`: compression always counts; expansion counts while the particle still has
/// pressure to give back (it is what an overshooting warm start leaves).
#[inline]
fn residual(source: f32, kappa: f32) -> f32 {
    if kappa > 0.0 { source.abs() } else { source }
}

/// A non-negative error in fixed point (negative values count as zero, huge ones are capped).
#[inline]
fn fixed_point(error: f32) -> u64 {
    (error.clamp(0.0, 1000.0) as f64 * FIXED_POINT) as u64
}

/// The mean of `n` fixed-point values summing to `total`.
fn mean(total: u64, n: usize) -> f32 {
    (total as f64 / FIXED_POINT / n.max(1) as f64) as f32
}
