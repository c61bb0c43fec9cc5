//! An incompressible pressure solver with the structure of divergence-free SPH (Bender &
//! Koschier, "Divergence-free smoothed particle hydrodynamics", SCA 2015; TVCG 2017), over the
//! [`layout`](super::layout). Pure, no ECS.
//!
//! **Experimental, not the default.** Measured: the Martin & Moyce dam-break front within 6–15%
//! of the experiment (as WCSPH), momentum conserved to rounding, a steady hydrostatic pressure
//! profile in a resting layer; not yet met: a still free surface (surface particles keep moving at
//! about 0.07 m/s) and the dam break's impact on a wall (about 1.4 s in, the sloshing throws
//! particles at 30 m/s).
//! Select it with [`PressureSolver::Dfsph`](crate::fluid::PressureSolver::Dfsph) to try it.
//!
//! One sub-step, in the order both drivers ([`systems`](super::systems) and
//! [`slices`](super::slices)) call it:
//! 1. [`Dfsph::prepare`]: from the sorted snapshot, each particle's fluid neighbours with their
//!    volume-weighted kernel gradients `gᵢⱼ = s V ∇Wᵢⱼ` and Laplacian weights (cached: every
//!    solver iteration reuses them), the summed wall gradient, and the density `ρ̂ᵢ = ρᵢ/ρ₀` by
//!    summation over fluid and wall particles.
//! 2. [`Dfsph::solve_divergence`]: the stiffness `κᵛ` that cancels the density change rate
//!    `Dρ̂ᵢ/Dt = Σⱼ gᵢⱼ·(vᵢ − vⱼ) + 2 g_wall,ᵢ·vᵢ` of the current velocities.
//! 3. The caller adds non-pressure accelerations ([`Dfsph::non_pressure_acceleration`]: gravity,
//!    viscosity, the walls' hydrostatic head) and its own external forces, picks the step
//!    ([`Dfsph::stable_time_step`]: the flow's CFL `C Δx / v_max`, the force and viscous limits),
//!    and stores the accelerations with [`Dfsph::set_acceleration`].
//! 4. [`Dfsph::solve_density`]: predicts `v* = v + dt a`, then the stiffness `κ` that brings the
//!    predicted density `ρ̂ᵢ + dt Dρ̂ᵢ/Dt` back to one.
//! 5. The caller moves each particle with its solved velocity ([`Dfsph::velocity`]).
//!
//! Both solves change velocities by the symmetric pressure force
//! `Δvᵢ = −dt (Σⱼ (κᵢ + κⱼ) gᵢⱼ + 2κᵢ g_wall,ᵢ)` (momentum is conserved pair by pair; walls
//! mirror the fluid's pressure and velocity, Akinci et al. 2012, with the hydrostatic head of
//! Adami et al. 2012). Unlike Bender & Koschier, who iterate Jacobi on the operator this force
//! implies, the pressure equations are solved by conjugate gradients on the compact SPH Laplacian
//! (Brookshaw 1985; Morris et al. 1997) `Σⱼ wᵢⱼ (κᵢ − κⱼ)`, as incompressible SPH does (Cummins &
//! Rudman 1999; Shao & Lo 2003): measured here, plain Jacobi on the DFSPH operator diverges in 2D,
//! relaxed Jacobi needed 30–80 iterations per sub-step and left the pressure ringing, while the
//! Laplacian solve converges in 10–20 and gives a steady hydrostatic profile. Free-surface
//! particles (summed density under [`SURFACE_DENSITY`]) and the air missing from the
//! neighbourhoods of particles away from walls are held at zero pressure, walls are mirrored, and
//! no particle is pulled (negative stiffness is cut to zero). The stiffness is a
//! pressure per rest density (`p = ρ₀ κ`, m²/s²), so it warm-starts the next sub-step.
//!
//! Wall particles lie on the fluid's rest lattice and count with the fluid's particle volume in
//! the density sum, so a particle at a wall has rest density at rest. Kernel gradients carry the
//! lattice correction [`SphConstants::gradient_scale`], which makes the discrete gradient of a
//! linear field exact at rest, so hydrostatic pressure rises at `ρ₀g`.
//!
//! Sums over particles are taken in f64 chunk by chunk of fixed size ([`CHUNK`]), so the
//! iteration count, and with it every result, is the same on any number of threads.
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin).

use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, SlotVectors, Walls};
use super::parallel::Parallel;
use super::solver::{SphConstants, with_kernels};
use bevy::math::{Vec2, Vec4};

/// Slots per parallel task, fixed (not from the thread count) so that sums over slots add up in
/// the same order on any number of threads. A fluid of up to this many particles runs each pass
/// on the calling thread: at 2,500 particles a pass is tens of microseconds, about the cost of
/// waking a second thread.
pub const CHUNK: usize = 2048;

/// Fewest particles whose passes run in parallel (measured with the `bench` example: at 2,500
/// particles the ECS path, on Bevy's task pool, ran 3.6 times slower than on one thread).
pub const PARALLEL_SLOTS: usize = 8192;

/// Walls mirror the fluid next to them: its pressure (Akinci et al. 2012, with the hydrostatic
/// head of Adami et al. 2012) and its velocity towards them, so a wall particle counts twice its
/// one-sided share.
const WALL_MIRROR: f32 = 2.0;

/// Particles with less than this fraction of rest density from summation are at the free
/// surface: they are held at zero pressure.
pub const SURFACE_DENSITY: f32 = 0.97;

/// One cached fluid neighbour of a particle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Neighbor {
    /// Sorted slot of the neighbour.
    slot: u32,
    /// `s V ∇Wᵢⱼ`, 1/m.
    gradient: Vec2,
    /// `−2 (rᵢⱼ·gᵢⱼ)/(r² + η²)`, 1/m²: the pair's weight in the SPH Laplacian.
    weight: f32,
}

/// Per-particle values of the current sub-step, by sorted slot.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct SlotState {
    /// Cached fluid neighbours.
    count: u32,
    /// `ρ/ρ₀`.
    density: f32,
    /// `1/Σⱼ wᵢⱼ`, the inverse diagonal of the Laplacian, m² (zero for a particle without
    /// neighbours): the preconditioner of the pressure solves.
    factor: f32,
    /// `Σ_b s V ∇W_ib` over wall particles, 1/m.
    wall_gradient: Vec2,
    /// `Σ_b V (r·∇W)/(r² + η²)` over wall particles (dimensionless, negative), for wall friction.
    wall_viscosity: f32,
    /// `−Σ_b (g·(x_b − xᵢ)) s V ∇W_ib`, m/s²: the hydrostatic head of the walls' mirrored
    /// pressure (Adami et al. 2012), which a pressed particle feels on top of its own.
    wall_head: Vec2,
    /// Laplacian weight of the neighbours a particle away from walls lacks (air), held at zero
    /// pressure, 1/m²: the free surface as a boundary condition even where no surface particle
    /// marks it. Without it a detached sheet of fluid is a pure Neumann problem, whose solve
    /// diverged (measured: stiffness of 10⁶ m²/s² after 100 iterations in the demo's dam break).
    air: f32,
}

impl SlotState {
    /// Whether the particle takes part in the pressure solves (is not at the free surface).
    #[inline]
    fn active(&self) -> bool {
        self.factor > 0.0 && self.density >= SURFACE_DENSITY
    }
}

/// Scratch of the conjugate-gradient solves, by sorted slot.
#[derive(Debug, Clone, Default)]
struct Scratch {
    b: Vec<f32>,
    best: Vec<f32>,
    r: Vec<f32>,
    p: Vec<f32>,
    q: Vec<f32>,
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
    cg: Scratch,
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

    /// Step 1: caches neighbours and gradients, sums densities, computes the preconditioner, and takes
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
        self.cg.b.resize(n, 0.0);
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
        let chunk = CHUNK;
        let scaled_volume = c.gradient_scale * c.volume;
        let full_weight = lattice_weight(g, c);
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
        run_jobs(parallel, n, &mut jobs, |(start, states, rows, overflow)| {
            for (k, state) in states.iter_mut().enumerate() {
                let x = fluid.points.get(*start + k);
                let row = &mut rows[k * stride..(k + 1) * stride];
                let mut len = 0usize;
                let mut density = Vec4::ZERO;
                let mut diagonal = 0.0f32;
                fluid.points.for_each_batch(x, |first, dx, dy, r2| {
                    density += w.value_sq_x4(r2);
                    let inside = r2.cmplt(support_sq) & r2.cmpgt(tiny);
                    let mask = inside.bitmask();
                    if mask == 0 {
                        return;
                    }
                    let r2 = r2.min(support_sq);
                    let slope = g.derivative_over_r_x4(r2.sqrt());
                    // ∇ᵢWᵢⱼ = slope (xᵢ − xⱼ) = −slope (dx, dy).
                    let gx = (-scaled_volume * slope * dx).to_array();
                    let gy = (-scaled_volume * slope * dy).to_array();
                    let weights =
                        (-2.0 * scaled_volume * slope * r2 / (r2 + Vec4::splat(eta_sq))).to_array();
                    for lane in 0..4 {
                        if mask & (1 << lane) == 0 {
                            continue;
                        }
                        diagonal += weights[lane];
                        if len < stride {
                            row[len] = Neighbor {
                                slot: (first + lane) as u32,
                                gradient: Vec2::new(gx[lane], gy[lane]),
                                weight: weights[lane],
                            };
                        }
                        len += 1;
                    }
                });
                let mut wall_gradient = Vec2::ZERO;
                let mut wall_viscosity = 0.0f32;
                let mut wall_head = Vec2::ZERO;
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
                    let head =
                        (Vec4::splat(c.gravity.x) * dx + Vec4::splat(c.gravity.y) * dy).to_array();
                    for lane in 0..4 {
                        if mask & (1 << lane) != 0 {
                            let gradient = Vec2::new(gx[lane], gy[lane]);
                            wall_gradient += gradient;
                            wall_viscosity += friction[lane];
                            wall_head -= head[lane] * gradient;
                        }
                    }
                });
                if len > stride {
                    *overflow = true;
                }
                // What a particle away from walls lacks of a full lattice is air. Next to walls
                // none is counted: measured, counting it there (walls as fluid) made the demo's
                // dam break blow up within 0.1 s, for a reason not found yet.
                let near_wall = wall_viscosity < 0.0;
                let air = if near_wall {
                    0.0
                } else {
                    (full_weight - diagonal).max(0.0)
                };
                *state = SlotState {
                    count: len.min(stride) as u32,
                    density: c.volume * density.element_sum(),
                    factor: if diagonal > 1e-3 / c.support_sq {
                        1.0 / (diagonal + air)
                    } else {
                        0.0
                    },
                    wall_gradient,
                    wall_viscosity,
                    wall_head,
                    air,
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
        // `dt D P κᵛ = Dv`: the pressure that cancels the density change rate.
        self.fill_source(|rate, _| rate / dt, parallel);
        let warm = settings.warm_start;
        let (iterations, error) = self.conjugate_gradient(
            dt,
            Target::Divergence,
            warm,
            settings.divergence_tolerance,
            1,
            settings.max_divergence_iterations,
            parallel,
        );
        self.apply_pressure(dt, Target::Divergence, parallel);
        self.report.divergence_iterations = iterations;
        self.report.divergence_error = error;
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
        // `dt² D P κ = ρ̂ + dt Dv* − 1`: the pressure that removes the predicted compression.
        self.fill_source(
            |rate, density| (density + dt * rate - 1.0) / (dt * dt),
            parallel,
        );
        let (iterations, error) = self.conjugate_gradient(
            dt,
            Target::Density,
            settings.warm_start,
            settings.density_tolerance,
            1,
            settings.max_density_iterations,
            parallel,
        );
        self.apply_pressure(dt, Target::Density, parallel);
        self.report.density_iterations = iterations;
        self.report.density_error = error;
        iterations
    }

    /// Sets the right-hand side `b` of the active particles from their density change rate
    /// `Dρ̂/Dt` (with the current velocities) and density: `source(rate, ρ̂)`; zero elsewhere.
    fn fill_source(&mut self, source: impl Fn(f32, f32) -> f32 + Sync, parallel: &impl Parallel) {
        let (rows, state, velocity) = (&self.rows, &self.state, &self.velocity);
        let stride = self.stride;
        for_each_slot(&mut self.cg.b, parallel, |slot, b| {
            let s = state[slot];
            if !s.active() {
                *b = 0.0;
                return 0.0;
            }
            let vi = velocity[slot];
            let row = &rows[slot * stride..slot * stride + s.count as usize];
            // Walls mirror the particle's velocity towards them.
            let mut rate = WALL_MIRROR * s.wall_gradient.dot(vi);
            for neighbor in row {
                rate += neighbor.gradient.dot(vi - velocity[neighbor.slot as usize]);
            }
            *b = source(rate, s.density);
            0.0
        });
    }

    /// Solves `−∇²κ = b` (the SPH Laplacian, [`multiply`](Self::multiply)) over the active
    /// particles by conjugate gradients with the Laplacian's diagonal as (Jacobi)
    /// preconditioner, starting from the target's stiffness (warm) or zero, until the mean
    /// remaining density change `dt² |r|` is under `tolerance`. Returns the iterations and that
    /// error.
    #[expect(
        clippy::too_many_arguments,
        reason = "the solve's settings, spelled out"
    )]
    fn conjugate_gradient(
        &mut self,
        dt: f32,
        target: Target,
        warm: bool,
        tolerance: f32,
        min_iterations: u32,
        max_iterations: u32,
        parallel: &impl Parallel,
    ) -> (u32, f32) {
        let n = self.state.len();
        let scale = (dt * dt) as f64 / n as f64;
        let mut x = core::mem::take(match target {
            Target::Density => &mut self.kappa,
            Target::Divergence => &mut self.kappa_divergence,
        });
        for (k, s) in x.iter_mut().zip(&self.state) {
            if !warm || !s.active() {
                *k = 0.0;
            }
        }
        // r = b − A x, z = r/α, p = z.
        let mut q = core::mem::take(&mut self.cg.q);
        self.multiply(&x, &mut q, parallel);
        let (b, state) = (&self.cg.b, &self.state);
        let mut r = core::mem::take(&mut self.cg.r);
        r.resize(n, 0.0);
        let mut rz = for_each_slot(&mut r, parallel, |slot, r| {
            *r = b[slot] - q[slot];
            (*r as f64) * ((*r * state[slot].factor) as f64)
        });
        let mut direction = core::mem::take(&mut self.cg.p);
        direction.clear();
        direction.extend(r.iter().zip(state).map(|(r, s)| r * s.factor));
        let mut error = (r.iter().map(|r| r.abs() as f64).sum::<f64>() * scale) as f32;
        // The best iterate so far: where the system is nearly singular (a sheet of fluid whose
        // pressure nothing pins), the iterates can run off while the residual stalls.
        let mut best = core::mem::take(&mut self.cg.best);
        best.clear();
        best.extend_from_slice(&x);
        let mut best_error = error;
        let mut iterations = 0;
        while (error > tolerance || iterations < min_iterations) && iterations < max_iterations {
            let pq = self.multiply(&direction, &mut q, parallel);
            if pq <= 0.0 || !pq.is_finite() {
                break;
            }
            let step = (rz / pq) as f32;
            let state = &self.state;
            let mut jobs: Vec<_> = x
                .chunks_mut(CHUNK)
                .zip(r.chunks_mut(CHUNK))
                .enumerate()
                .map(|(k, (x, r))| (k * CHUNK, x, r, 0.0f64, 0.0f64))
                .collect();
            let (p_ref, q_ref) = (&direction, &q);
            run_jobs(parallel, n, &mut jobs, |(start, xs, rs, rz, abs)| {
                for (k, (x, r)) in xs.iter_mut().zip(rs.iter_mut()).enumerate() {
                    let slot = *start + k;
                    *x += step * p_ref[slot];
                    *r -= step * q_ref[slot];
                    *rz += (*r as f64) * ((*r * state[slot].factor) as f64);
                    *abs += r.abs() as f64;
                }
            });
            let rz_new: f64 = jobs.iter().map(|j| j.3).sum();
            error = (jobs.iter().map(|j| j.4).sum::<f64>() * scale) as f32;
            drop(jobs);
            let beta = if rz > 0.0 { (rz_new / rz) as f32 } else { 0.0 };
            rz = rz_new;
            for ((p, r), s) in direction.iter_mut().zip(&r).zip(&self.state) {
                *p = r * s.factor + beta * *p;
            }
            iterations += 1;
            if error < best_error {
                best.copy_from_slice(&x);
                best_error = error;
            } else if error.is_nan() || error >= 4.0 * best_error {
                // Running off: stop and keep the best.
                break;
            }
        }
        if error.is_nan() || error > best_error {
            core::mem::swap(&mut x, &mut best);
            error = best_error;
        }
        self.cg.best = best;
        // No tension: a particle the solve would pull is left at zero pressure.
        for k in &mut x {
            *k = k.max(0.0);
        }
        match target {
            Target::Density => self.kappa = x,
            Target::Divergence => self.kappa_divergence = x,
        }
        self.cg.q = q;
        self.cg.r = r;
        self.cg.p = direction;
        (iterations, error)
    }

    /// `out = −∇²x` on the active particles by the SPH Laplacian (Brookshaw 1985; Morris et al.
    /// 1997), `Σⱼ wᵢⱼ (xᵢ − xⱼ)`, with `x` held at zero at the free surface and mirrored at walls
    /// (no wall term); `out = x` on the others.
    /// Returns `x·out` (f64, chunk by chunk).
    fn multiply(&mut self, x: &[f32], out: &mut Vec<f32>, parallel: &impl Parallel) -> f64 {
        let n = self.state.len();
        let (rows, state) = (&self.rows, &self.state);
        let stride = self.stride;
        out.resize(n, 0.0);
        for_each_slot(out, parallel, |slot, out| {
            let s = state[slot];
            let own = x[slot];
            if !s.active() {
                *out = own;
                return (own as f64) * (own as f64);
            }
            let row = &rows[slot * stride..slot * stride + s.count as usize];
            let mut sum = s.air * own;
            for neighbor in row {
                sum += neighbor.weight * (own - x[neighbor.slot as usize]);
            }
            *out = sum;
            (own as f64) * (sum as f64)
        })
    }

    /// Changes the velocities by the target stiffness' pressure accelerations over `dt`.
    fn apply_pressure(&mut self, dt: f32, target: Target, parallel: &impl Parallel) {
        let (rows, state) = (&self.rows, &self.state);
        let stride = self.stride;
        let kappa = match target {
            Target::Density => &self.kappa,
            Target::Divergence => &self.kappa_divergence,
        };
        for_each_slot(&mut self.velocity, parallel, |slot, v| {
            *v -= dt * pressure_push(rows, stride, state[slot], slot, kappa);
            0.0
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
        // The walls' hydrostatic head acts on particles pressed against them (pressure in the
        // last sub-step), not on spray passing by.
        // Walls mirror the particle's pressure (Akinci et al. 2012) with the hydrostatic head
        // (Adami et al. 2012): the solves take the particle's own stiffness on the wall side
        // (`κᵢ g_wall`, which keeps their operator symmetric); the mirrored half and the head
        // follow here from the last sub-step's stiffness.
        let kappa = self.kappa[slot];
        let head = if kappa > 0.0 { s.wall_head } else { Vec2::ZERO };
        a + wall * vi + head + c.gravity
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

/// `Σⱼ wᵢⱼ` of an interior particle of the rest lattice: the Laplacian weight of a full
/// neighbourhood, 1/m².
fn lattice_weight<G: RadialKernel>(g: &G, c: &SphConstants) -> f32 {
    let reach = (c.support / c.spacing).ceil() as i32;
    let eta_sq = 0.01 * c.smoothing_length * c.smoothing_length;
    let mut sum = 0.0f32;
    for j in -reach..=reach {
        for i in -reach..=reach {
            let r2 = ((i * i + j * j) as f32) * c.spacing * c.spacing;
            if r2 > 0.0 && r2 < c.support_sq {
                let slope = g.derivative_over_r(r2.sqrt());
                sum += -2.0 * c.gradient_scale * c.volume * slope * r2 / (r2 + eta_sq);
            }
        }
    }
    sum
}

/// Which stiffness a pressure application adds to.
#[derive(Clone, Copy)]
enum Target {
    Density,
    Divergence,
}

/// `Σⱼ (xᵢ + xⱼ) gᵢⱼ + xᵢ g_wall,ᵢ`: the pressure acceleration of stiffness `x` on particle
/// `slot`, per unit stiffness gradient (walls take the particle's own stiffness).
#[inline]
fn pressure_push(rows: &[Neighbor], stride: usize, s: SlotState, slot: usize, x: &[f32]) -> Vec2 {
    let own = x[slot];
    let row = &rows[slot * stride..slot * stride + s.count as usize];
    let mut push = WALL_MIRROR * own * s.wall_gradient;
    for neighbor in row {
        push += (own + x[neighbor.slot as usize]) * neighbor.gradient;
    }
    push
}

/// Runs the jobs of a pass over `slots` particles: on `parallel` from [`PARALLEL_SLOTS`] on, on
/// the calling thread below (waking a pool's threads costs more than a small pass). The jobs are
/// the same either way, so are the sums.
fn run_jobs<T: Send>(
    parallel: &impl Parallel,
    slots: usize,
    jobs: &mut [T],
    work: impl Fn(&mut T) + Sync,
) {
    if slots < PARALLEL_SLOTS {
        jobs.iter_mut().for_each(work);
    } else {
        parallel.for_each(jobs, work);
    }
}

/// Runs `work(slot, &mut out[slot])` for every slot, in parallel chunks of [`CHUNK`] slots, and
/// returns the sum of what it returns, added chunk by chunk in slot order: the same on any
/// number of threads.
fn for_each_slot<T: Send>(
    out: &mut [T],
    parallel: &impl Parallel,
    work: impl Fn(usize, &mut T) -> f64 + Sync,
) -> f64 {
    let n = out.len();
    let mut jobs: Vec<_> = out
        .chunks_mut(CHUNK)
        .enumerate()
        .map(|(k, values)| (k * CHUNK, values, 0.0f64))
        .collect();
    run_jobs(parallel, n, &mut jobs, |(start, values, sum)| {
        for (k, value) in values.iter_mut().enumerate() {
            *sum += work(*start + k, value);
        }
    });
    jobs.iter().map(|job| job.2).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::parallel::Sequential;
    use crate::fluid::params::{PressureSolver, SphParams};

    /// Particles on a square lattice of `n × n`, spacing `dx`, and the solver prepared on them.
    fn lattice(
        n: usize,
        params: &SphParams,
        stiffness: impl Fn(Vec2) -> Vec2 + Sync,
    ) -> (SphConstants, FluidSnapshot, Dfsph) {
        let c = params.constants().unwrap();
        let dx = params.particle_spacing;
        let points: Vec<Vec2> = (0..n * n)
            .map(|k| Vec2::new((k % n) as f32 + 0.5, (k / n) as f32 + 0.5) * dx)
            .collect();
        let mut fluid = FluidSnapshot::default();
        fluid.rebuild(&c, &points, &vec![Vec2::ZERO; points.len()], &Sequential);
        let mut dfsph = Dfsph::default();
        let walls = Walls::default();
        let order = fluid.grid().order().to_vec();
        dfsph.prepare(
            &c,
            &fluid,
            &walls,
            |slot| stiffness(points[order[slot] as usize]),
            &Sequential,
        );
        (c, fluid, dfsph)
    }

    #[test]
    fn one_solve_from_rest_gives_hydrostatic_pressure() {
        use crate::fluid::boundary::Tank;
        let (w, d) = (0.2f32, 0.2f32);
        let mut p = params();
        p.tank = Some(Tank::new(w, 0.3));
        p.dfsph.density_tolerance = 1e-6;
        p.dfsph.max_density_iterations = 2000;
        let c = p.constants().unwrap();
        let dx = p.particle_spacing;
        let (nx, ny) = ((w / dx) as usize, (d / dx) as usize);
        let points: Vec<Vec2> = (0..nx * ny)
            .map(|k| Vec2::new((k % nx) as f32 + 0.5, (k / nx) as f32 + 0.5) * dx)
            .collect();
        let mut fluid = FluidSnapshot::default();
        fluid.rebuild(&c, &points, &vec![Vec2::ZERO; points.len()], &Sequential);
        let mut walls = Walls::default();
        walls.rebuild(&c, &[]);
        let mut dfsph = Dfsph::default();
        dfsph.prepare(&c, &fluid, &walls, |_| Vec2::ZERO, &Sequential);
        for slot in 0..fluid.len() {
            let a = dfsph.non_pressure_acceleration(&c, &fluid, slot);
            dfsph.set_acceleration(slot, a);
        }
        let dt = 0.004;
        let iterations = dfsph.solve_density(&c, dt, &Sequential);
        assert!(dfsph.report.density_error <= 1e-6, "{:?}", dfsph.report);
        // The free surface sits half a spacing above the top row.
        let surface = d - 0.5 * dx;
        for y in [0.015f32, 0.055, 0.105, 0.155] {
            let slot = (0..fluid.len())
                .min_by(|&a, &b| {
                    let q = |s: usize| (fluid.points.get(s) - Vec2::new(0.105, y)).length();
                    q(a).total_cmp(&q(b))
                })
                .unwrap();
            let (p, v) = (dfsph.pressure(&c, slot), dfsph.velocity(slot));
            let hydrostatic = 1000.0 * 9.81 * (surface - y);
            assert!(
                (p - hydrostatic).abs() < 0.1 * hydrostatic + 30.0 && v.length() < 0.005,
                "at y = {y} m after {iterations} iterations: p = {p} Pa (ρ₀g(d−y) = \
                 {hydrostatic} Pa), v = {v} m/s"
            );
        }
    }

    fn params() -> SphParams {
        SphParams {
            solver: PressureSolver::Dfsph,
            support_ratio: 2.5,
            particle_spacing: 0.01,
            tank: None,
            ..SphParams::water()
        }
    }

    #[test]
    fn interior_density_is_rest_density() {
        let (c, fluid, dfsph) = lattice(20, &params(), |_| Vec2::ZERO);
        let centre = (0..fluid.len())
            .min_by(|&a, &b| {
                let d = |s: usize| (fluid.points.get(s) - Vec2::splat(0.1)).length();
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        assert!((dfsph.density(&c, centre) / c.rest_density - 1.0).abs() < 1e-4);
    }

    #[test]
    fn pressure_of_a_linear_stiffness_field_is_its_gradient() {
        let slope = 3.0;
        let (_, fluid, mut dfsph) = lattice(20, &params(), |x| Vec2::new(slope * x.y, 0.0));
        dfsph.apply_pressure(1.0, Target::Density, &Sequential);
        let centre = (0..fluid.len())
            .min_by(|&a, &b| {
                let d = |s: usize| (fluid.points.get(s) - Vec2::splat(0.1)).length();
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let v = dfsph.velocity(centre);
        assert!(
            (v.y / -slope - 1.0).abs() < 0.01 && v.x.abs() < 1e-3,
            "pressure acceleration {v} for ∇κ = (0, {slope})"
        );
    }
}
