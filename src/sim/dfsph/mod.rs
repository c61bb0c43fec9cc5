//! An incompressible pressure solver with the structure of divergence-free SPH (Bender &
//! Koschier, "Divergence-free smoothed particle hydrodynamics", SCA 2015; TVCG 2017), over the
//! [`layout`](super::layout). Pure, no ECS.
//!
//! One sub-step, in the order of [`step`](super::step), which both drivers call (the stage
//! methods are in [`stages`]):
//! 1. [`Dfsph::prepare`]: from the sorted snapshot, each particle's fluid neighbours with their
//!    volume-weighted kernel gradients `gᵢⱼ = s V ∇Wᵢⱼ` (cached: every solver iteration reuses
//!    them), the summed wall gradient, the density `ρ̂ᵢ = ρᵢ/ρ₀` by summation over fluid and
//!    wall particles, and the DFSPH factor `αᵢ = 1/(|Σⱼ gᵢⱼ + 2 g_wall,ᵢ|² + Σⱼ |gᵢⱼ|²)`. With
//!    the grid start, the coarse grid's cells and equations are built beside it from the
//!    positions ([`Dfsph::start_from_grid`] solves on them in step 4).
//! 2. [`Dfsph::solve_divergence`]: the stiffness `κᵛ` that cancels the density change rate
//!    `Dρ̂ᵢ/Dt = Σⱼ gᵢⱼ·(vᵢ − vⱼ) + 2 g_wall,ᵢ·vᵢ` of the current velocities (walls mirror the
//!    particle's velocity; particles with a deficient neighbourhood,
//!    [`DEFICIENT_NEIGHBORHOOD`], are left alone).
//! 3. The caller adds non-pressure accelerations ([`Dfsph::non_pressure_acceleration`]: gravity,
//!    viscosity, the walls' hydrostatic head) and its own external forces, picks the step
//!    ([`Dfsph::stable_time_step`]: the flow's CFL `C Δx / v_max`, with the speed the largest
//!    pressure can give ([`pressure_speed`]) counted in `v_max`, the force and viscous limits).
//! 4. [`Dfsph::predict`]: `v* = v + dt a` with every acceleration; with
//!    [`grid_start`](super::config::DfsphSettings::grid_start), [`Dfsph::start_from_grid`]: the
//!    starting stiffness from a pressure on a coarse grid; then [`Dfsph::solve_density`]: the
//!    stiffness `κ` that brings the predicted density `ρ̂ᵢ + dt Dρ̂ᵢ/Dt` back to one wherever it
//!    is compressed.
//! 5. The caller moves each particle with its solved velocity ([`Dfsph::velocity`]).
//!
//! Both solves change velocities by the symmetric pressure force
//! `Δvᵢ = −dt (Σⱼ (κᵢ + κⱼ) gᵢⱼ + 2κᵢ g_wall,ᵢ)`: momentum is conserved pair by pair, and a wall
//! particle mirrors the pressure of the fluid particle it pushes (Akinci et al. 2012, who count
//! it once: mirrored, the pressure at a wall is the hydrostatic one, not twice it). Mirroring
//! both the pressure and the velocity keeps the pressure equations symmetric (the push is the
//! transpose of the density rate); mirroring the pressure alone made the wall rows of a resting
//! layer bounce at 0.4 m/s under a 0.1% tolerance.
//!
//! The solves ([`solve`]) are a bound-constrained, Jacobi-preconditioned conjugate gradient
//! (MPRGP) on those symmetric equations with the stiffness kept non-negative (pressure pushes,
//! never pulls: a particle that is not compressed relaxes to zero pressure instead of holding
//! the last sub-step's). Under a fixed budget the density solve takes projected gradient steps
//! instead, half the cost of MPRGP's expanding iterations (see [`solve`]). They stop once the
//! mean error is under the settings' tolerance and the
//! largest under [`LARGEST_ERROR_RATIO`] times it, for the density solve also under
//! [`PRESSURE_ACCURACY`] of what the largest acceleration moves in a step (a smooth pressure
//! error hides from a density tolerance in deep water). The stiffness is a pressure per rest
//! density (`p = ρ₀ κ`, m²/s²), independent of the step, so it warm-starts the next sub-step:
//! the density solve from its SPH average ([`Dfsph::prepare`] smooths it, so that the stiffness
//! modes the equations cannot see do not pile up), the divergence solve from half of it, as
//! Bender & Koschier do. A compressed particle's excess density is relieved at most at
//! [`MAX_RELIEF_RATE`], so fluid spawned too densely expands instead of exploding.
//!
//! Wall particles lie on the fluid's rest lattice and count with the fluid's particle volume in
//! the density sum, so a particle at a wall has rest density at rest. Kernel gradients carry the
//! lattice correction [`SphConstants::gradient_scale`], which makes the discrete gradient of a
//! linear field exact at rest, so hydrostatic pressure rises at `ρ₀g`.
//!
//! Sums over particles are taken in f64 chunk by chunk of fixed size ([`CHUNK`]), so the
//! iteration count, and with it every result, is the same on any number of threads.
//!
//! Why the deep layers boiled before (the depth issue): the pressure force on a particle depends
//! on where its neighbours are, with a stiffness that grows with the pressure, and that part is
//! integrated explicitly. At rest the flow's CFL let steps grow to the longest allowed, past
//! `Δx/√(2κ)` at the floor of a deep layer, and the floor rows oscillated into a boil; the step
//! now counts that speed. And the old mean-error stop let a smooth pressure error that carries
//! a tenth of the weight hide at the floor rows.
//!

use super::clock::SubstepClock;
use super::config::SphConstants;
use super::density::{max_length, with_kernels};
use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, Walls};
use super::parallel::Parallel;
use super::viscosity::Laminar;
use crate::sim::simd::Simd;
use bevy::math::{Vec2, Vec4};
use rows::{BLOCK, Rows};
use solve::Target;

mod gather;
mod grid_start;
#[expect(
    unsafe_code,
    reason = "the AVX2 sums, each unsafe block with its SAFETY note"
)]
mod rows;
mod solids;
mod solve;
mod stages;

/// The density solve's largest error is held under this fraction of the displacement the
/// largest acceleration `a` makes over a step, `a dt²/Δx` as a density change. A pressure
/// error that pushes a whole column (a smooth error, the slowest for any solver) shows as a
/// density error only at the column's floor, of about `δa dt²/Δx`, and the mean hides it: this
/// keeps the pressure within about this fraction of the load it carries at any depth (a layer 100
/// particles deep read 0.90 of the hydrostatic slope under a mean tolerance alone, 1.00 with it).
pub const PRESSURE_ACCURACY: f32 = 0.01;

/// A particle with fewer neighbours (fluid and wall) than this fraction of a full rest
/// neighbourhood is deficient: the divergence solve leaves it alone (Bender & Koschier's
/// "particle deficiency", which keeps splashes and the free surface from being pinned).
pub const DEFICIENT_NEIGHBORHOOD: f32 = 0.6;

/// A particle whose pressure equation has a diagonal under this fraction of an interior
/// particle's of the rest lattice ([`lattice_diagonal`]) is pinned: no pressure of its own can
/// move it, and both solves leave it alone (a zero factor).
///
/// Such a particle is caught between walls whose gradients cancel, with a few far fluid
/// neighbours: a stone settling on the floor squeezes one in the closing gap. Its density stays
/// near the rest density while the solve raises its stiffness without bound (measured: 400 to
/// 3·10⁸ m²/s² as its diagonal fell to 0.06% of the lattice's), and the step, which counts the
/// speed the largest pressure can give, shrank with it to 10⁻⁷ s: the fluid froze (a 10 × 6 cm
/// stone of 2,500 kg/m³ on the floor of a 0.2 m layer at 5 mm, ticks of 100 Hz). From 0.01 the
/// fluid steps on; at 0.01 a row of particles a spacing apart, caught in a gap thinner than a
/// spacing, held that stone 3.5 mm above the floor for seconds (a film no real water keeps
/// under a stone); at 0.1 the row is pinned and the stone rests on the floor. The pressure
/// such a film carries comes instead from the water seeping into the contact (see the core's
/// `MovingSolid`): without it a crate lighter than water that reached the floor stayed there.
pub const PINNED_DIAGONAL: f32 = 0.1;

/// Walls mirror the pressure of the fluid particle they push (Akinci et al. 2012 take it once;
/// mirrored, a particle at a wall holds the hydrostatic pressure of its depth instead of twice
/// it, which matters where wall pressure is read).
const WALL_MIRROR: f32 = 2.0;

/// How much a wall particle weighs in the sums of a fluid particle of relative density
/// `density`: one, and beyond [`MIRRORED_FROM`] one plus the excess, so that a wall mirrors a
/// crushed particle's density as it mirrors its pressure.
///
/// Taken at the rest density, a wall weighs less than the fluid that presses a crushed particle
/// against it, and the solve relieves such a particle by driving it into the wall, where the
/// tank's safety net stops it. Measured on 3,000 particles spawned at four times the rest
/// density: the layer on the floor then kept up to nine times the rest density at no pressure,
/// a fifth of the particles ended in clumps of up to 48 times it (the strict solve as the
/// default), and a sub-step cost 2.5 to 4 times a calm one; with the weight the block spreads
/// to within 0.3% of the rest density.
#[inline]
fn wall_weight(density: f32) -> f32 {
    1.0 + (density - MIRRORED_FROM).max(0.0)
}

/// The relative density beyond which walls mirror a particle's density ([`wall_weight`]): the
/// crushing the grid start calls crushed too (`grid_start::MAX_START_DENSITY`), above any that
/// a flow reaches (a dam break's surge stays within 2%), so that flows keep their walls bit for
/// bit. Measured: mirrored from the rest density, the 2 m resting layer at 2 cm (100 particles
/// deep) no longer rested under the default's fixed budget (slope 0.66, fastest 1 m/s); from
/// 1.1, a crate dropped from half a metre into the harbour still rocked at 0.094 m/s after five
/// seconds (from 1.25: 0.129 m/s; from 1.5: 0.054, afloat at 0.487 of its height for a relative
/// density of 0.5).
const MIRRORED_FROM: f32 = 1.5;

/// Per-particle values of the current sub-step, by sorted slot.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct SlotState {
    /// Cached fluid neighbours.
    count: u32,
    /// `ρ/ρ₀` by summation over fluid and wall particles, `ρ₀` its own liquid's: `V Σ W`, the
    /// number density of Solenthaler & Pajarola (2008), which holds at one across the surface
    /// between two liquids.
    density: f32,
    /// One over the particle's rest density ratio (`Particles::rest_ratio`): the pressure
    /// moves a particle of a lighter liquid the more.
    inverse_mass: f32,
    /// The DFSPH factor `1/(|Σⱼ gᵢⱼ + 2 g_wall|² + Σⱼ |gᵢⱼ|²)`, m² (zero without neighbours or
    /// when pinned, [`PINNED_DIAGONAL`]): the inverse of the diagonal of the pressure equations,
    /// per `dt²`.
    factor: f32,
    /// Whether the neighbourhood is deficient (see [`DEFICIENT_NEIGHBORHOOD`]).
    deficient: bool,
    /// `w Σ_b s V ∇W_ib` over wall particles, 1/m, with the walls' weight `w`
    /// ([`wall_weight`]).
    wall_gradient: Vec2,
    /// `Σ_b V (r·∇W)/(r² + η²)` over wall particles (dimensionless, negative), for wall friction.
    wall_viscosity: f32,
    /// `Σ_b V (r·∇W)/(r² + η²) v_b` over wall particles, m/s: the friction of moving solids.
    wall_drag: Vec2,
    /// `w Σ_b s V ∇W_ib · v_b` over wall particles, 1/s: what moving solids add to the density
    /// change rate (mirrored, twice it).
    wall_flux: f32,
    /// `−Σ_b (g·(x_b − xᵢ)) s V ∇W_ib`, m/s²: the hydrostatic head of the walls' mirrored
    /// pressure (Adami et al. 2012), which a pressed particle feels on top of its own.
    wall_head: Vec2,
}

/// Scratch of the solves, by sorted slot.
#[derive(Debug, Clone, Default)]
struct Scratch {
    /// The solve's search direction (and the smoothed warm start), by slot.
    delta: Vec<f32>,
    /// The pressure push of the search direction, by slot.
    push: Vec<Vec2>,
    /// What the solve keeps of each particle.
    unknowns: Vec<solve::Unknown>,
}

/// What the last sub-step's solves did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DfsphReport {
    /// Iterations of the density solve.
    pub density_iterations: u32,
    /// Iterations of the divergence solve.
    pub divergence_iterations: u32,
    /// Mean predicted density error left after the density solve, fraction.
    pub density_error: f32,
    /// Mean density change per step left after the divergence solve, fraction.
    pub divergence_error: f32,
    /// Conjugate-gradient iterations of the grid pressure that started the density solve
    /// (zero without [`grid_start`](super::config::DfsphSettings::grid_start)).
    pub grid_iterations: u32,
}

/// The divergence-free solver's state for one sub-step, by sorted slot (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Dfsph {
    /// Each particle's cached fluid neighbours with their volume-weighted kernel gradients.
    rows: Rows,
    state: Vec<SlotState>,
    velocity: Vec<Vec2>,
    kappa: Vec<f32>,
    kappa_divergence: Vec<f32>,
    /// The step the last divergence solve pushed with, s (zero if it did not run).
    divergence_dt: f32,
    scratch: Scratch,
    /// The length `1/λ_max` of the solve's projected gradient steps (see
    /// [`lattice_spectral_radius`]).
    expansion_step: f32,
    /// The kernel and support ratio `expansion_step` was computed for.
    expansion_key: Option<(super::kernels::KernelKind, u32)>,
    /// The density solve's start on a coarse grid, when the settings ask for it.
    grid_start: grid_start::GridStart,
    /// The largest acceleration of the last prediction, m/s² (what
    /// [`predict`](Self::predict) returned, for the density solve's accuracy bound).
    predicted_acceleration: f32,
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

    /// Step 1: caches neighbours and gradients, sums densities, computes the DFSPH factors, and
    /// takes the velocities from the snapshot. `warm_start(slot)` gives each particle's
    /// stiffness `[κ, κᵛ]` from the last sub-step (m²/s²).
    ///
    /// The density solve's warm start is the SPH average of `κ` over each particle's
    /// neighbourhood (Shepard: `Σⱼ Vⱼ Wᵢⱼ κⱼ / Σⱼ Vⱼ Wᵢⱼ`, the particle included), summed in the
    /// same pass. The pressure equations do not see a stiffness that alternates from one
    /// particle to the next (on the lattice its push is zero), so nothing in the solve removes
    /// it; carried from sub-step to sub-step by the warm start it grew (measured: ±300 Pa in a
    /// resting 0.2 m layer whose floor pressure is 1,960 Pa). The average halves it every
    /// sub-step and keeps a linear field.
    pub fn prepare(
        &mut self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &Walls,
        warm_start: impl Fn(usize) -> Vec2 + Sync,
        parallel: &impl Parallel,
    ) {
        let n = fluid.len();
        // The neighbour pass writes every slot's state, velocity and stiffness.
        self.state.resize(n, SlotState::default());
        self.velocity.resize(n, Vec2::ZERO);
        self.kappa.resize(n, 0.0);
        self.kappa_divergence.resize(n, 0.0);
        self.scratch.delta.resize(n, 0.0);
        let warm = c.dfsph.warm_start;
        let start = |slot: usize| {
            let [_, _, vx, vy] = fluid.kinematics[slot];
            let k = if warm { warm_start(slot) } else { Vec2::ZERO };
            (Vec2::new(vx, vy), k.max(Vec2::ZERO))
        };
        // Rows a little longer than a rest neighbourhood: the iterations stream them, so they are
        // kept short. A compressed particle with more neighbours makes them long enough for the
        // most seen, and the pass runs again.
        let lattice = lattice_neighbors(c) as usize;
        let mut stride = (lattice + lattice / 2)
            .next_multiple_of(BLOCK)
            .max(self.rows.stride());
        loop {
            // Rows are written before they are read (up to each particle's count).
            self.rows.resize(n, stride);
            let most = with_kernels!(c.kernel, c.support, |w, g| {
                // The density solve's warm start, smoothed (see above) with the particle's own
                // weight.
                let smooth = warm.then(|| c.volume * w.value_sq_x4(Vec4::ZERO).x);
                self.gather_neighbors(
                    &w,
                    &g,
                    c,
                    (fluid, walls),
                    (&start, smooth),
                    stride,
                    parallel,
                )
            });
            if most <= stride {
                break;
            }
            stride = (most + 4).next_multiple_of(BLOCK);
        }
        self.report = DfsphReport::default();
        let key = Some((c.kernel, (c.support / c.spacing).to_bits()));
        if self.expansion_key != key {
            let radius = with_kernels!(c.kernel, c.support, |_w, g| lattice_spectral_radius(&g, c));
            self.expansion_step = 1.0 / radius.max(1.0);
            self.expansion_key = key;
        }
    }

    /// Step 2: makes the velocity field divergence-free for a step of `dt` seconds (the last
    /// sub-step's length). Returns the iterations taken.
    pub fn solve_divergence(&mut self, c: &SphConstants, dt: f32, parallel: &impl Parallel) -> u32 {
        let settings = c.dfsph;
        self.divergence_dt = 0.0;
        if self.is_empty() || dt <= 0.0 || settings.max_divergence_iterations == 0 {
            return 0;
        }
        self.divergence_dt = dt;
        let (iterations, error) =
            self.solve(dt, Target::Divergence, f32::INFINITY, &settings, parallel);
        self.report.divergence_iterations = iterations;
        self.report.divergence_error = error;
        iterations
    }

    /// Step 4, first: predicts velocities with each particle's acceleration `acceleration(slot)`
    /// (m/s², by sorted slot: gravity, viscosity and external forces) over a step of `dt`
    /// seconds. Returns the largest acceleration, m/s².
    pub fn predict(&mut self, dt: f32, acceleration: impl Fn(usize) -> Vec2) -> f32 {
        let mut most = 0.0f32;
        for (slot, v) in self.velocity.iter_mut().enumerate() {
            let a = acceleration(slot);
            most = most.max(a.length_squared());
            *v += dt * a;
        }
        most.sqrt()
    }

    /// Step 4, then: solves for the pressure that keeps the density of the predicted velocities
    /// at rest after a step of `dt` seconds, under accelerations of at most `max_acceleration`
    /// (m/s², what [`predict`](Self::predict) returned). Returns the iterations.
    pub fn solve_density(
        &mut self,
        c: &SphConstants,
        dt: f32,
        max_acceleration: f32,
        parallel: &impl Parallel,
    ) -> u32 {
        if self.is_empty() || dt <= 0.0 {
            return 0;
        }
        let settings = c.dfsph;
        // A pressure error that pushes a whole column by `δa` shows as a density error of only
        // `δa dt²/Δx` at its floor: the largest error allowed keeps it under a fraction of the
        // accelerations the pressure balances, at any depth.
        let largest = PRESSURE_ACCURACY * max_acceleration * dt * dt / c.spacing;
        let (iterations, error) = self.solve(dt, Target::Density, largest, &settings, parallel);
        self.report.density_iterations = iterations;
        self.report.density_error = error;
        iterations
    }

    /// Gravity plus laminar (Lo & Shao 2002) and artificial (Monaghan) viscosity at sorted
    /// `slot`, m/s², from the cached neighbours and the divergence-free velocities. Walls add
    /// laminar friction, as in [`wcsph`](super::wcsph), and the hydrostatic head of their
    /// mirrored pressure.
    pub fn non_pressure_acceleration(
        &self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        slot: usize,
    ) -> Vec2 {
        let s = self.state[slot];
        let (xi, vi) = (fluid.points.get(slot), self.velocity[slot]);
        let ratios = &fluid.rest_ratio;
        let rho_i = s.density * c.rest_density * ratios[slot];
        let h = c.smoothing_length;
        let eta_sq = Vec4::splat(0.01 * h * h);
        // m ∇W = ρ₀ g / s.
        let to_mass_gradient = c.rest_density / c.gradient_scale;
        let laminar = Laminar::at(fluid, c.kinematic_viscosity, slot);
        let artificial = 2.0 * c.artificial_viscosity * c.speed_of_sound * h;
        let (rest, rho_i4) = (Vec4::splat(c.rest_density), Vec4::splat(rho_i));
        // Four neighbours a block, on lanes (the padding, the particle itself at zero
        // gradient, adds exactly nothing).
        let (mut ax, mut ay) = (Vec4::ZERO, Vec4::ZERO);
        for (slots, gradients) in self.rows.row(slot, s.count).blocks() {
            let rx = Vec4::splat(xi.x) - lanes(slots, |j| fluid.points.x[j]);
            let ry = Vec4::splat(xi.y) - lanes(slots, |j| fluid.points.y[j]);
            let vx = Vec4::splat(vi.x) - lanes(slots, |j| self.velocity[j].x);
            let vy = Vec4::splat(vi.y) - lanes(slots, |j| self.velocity[j].y);
            // mⱼ = rⱼ ρ₀ V: the pair's terms are symmetric in mᵢ mⱼ, so momentum is kept.
            let mass_j = lanes(slots, |j| ratios[j]);
            let gx = to_mass_gradient
                * mass_j
                * Vec4::new(
                    gradients[0].x,
                    gradients[1].x,
                    gradients[2].x,
                    gradients[3].x,
                );
            let gy = to_mass_gradient
                * mass_j
                * Vec4::new(
                    gradients[0].y,
                    gradients[1].y,
                    gradients[2].y,
                    gradients[3].y,
                );
            let r2 = rx * rx + ry * ry;
            let rho_j = lanes(slots, |j| self.state[j].density) * rest * mass_j;
            let inv = Vec4::ONE / ((r2 + eta_sq) * (rho_i4 + rho_j));
            let approach = (vx * rx + vy * ry).min(Vec4::ZERO);
            let laminar = laminar.lanes(|nu| lanes(slots, |j| nu[j]));
            let viscous = laminar * inv * (rx * gx + ry * gy);
            let shock = artificial * approach * inv;
            ax += viscous * vx + shock * gx;
            ay += viscous * vy + shock * gy;
        }
        let sum = |v: Vec4| (v.x + v.z) + (v.y + v.w);
        let a = Vec2::new(sum(ax), sum(ay));
        let wall = laminar.own() * c.rest_density / (rho_i + c.rest_density);
        let wall = wall * (s.wall_viscosity * vi - s.wall_drag);
        // The walls mirror a particle's pressure with the hydrostatic head (Adami et al. 2012):
        // the solves push with the particle's own stiffness (`2κᵢ g_wall`), the head follows
        // here for particles within the fluid (a full neighbourhood), not for spray. (Switched
        // by the last sub-step's pressure instead, it flickered on and off along the floor and
        // set the bottom row bouncing.)
        let head = if s.deficient { Vec2::ZERO } else { s.wall_head };
        a + wall + head + c.gravity
    }

    /// The largest stable step (s) for the fastest particle after the divergence solve and the
    /// largest acceleration `max_acceleration` (m/s²): the flow's CFL limit `C Δx / v_max`, the
    /// force limit `¼√(h/a)`, the viscous limit `⅛h²/ν` for the laminar viscosity plus the
    /// artificial one (`ν ≈ α c₀ h / 8` in 2D), and the settings' longest step.
    pub fn stable_time_step(&self, c: &SphConstants, max_acceleration: f32) -> f32 {
        let largest_stiffness = (self.kappa.iter().zip(&self.state))
            .fold(0.0f32, |a, (&k, s)| a.max(k * s.inverse_mass));
        let speed = max_length(&self.velocity).max(pressure_speed(largest_stiffness));
        stable_time_step(c, speed, max_acceleration)
    }

    /// Velocity at sorted `slot`, m/s: divergence-free after step 2, solved after step 4.
    #[inline]
    pub fn velocity(&self, slot: usize) -> Vec2 {
        self.velocity[slot]
    }

    /// Summed density at sorted `slot`, kg/m³.
    #[inline]
    pub fn density(&self, c: &SphConstants, slot: usize) -> f32 {
        let s = &self.state[slot];
        s.density * c.rest_density / s.inverse_mass
    }

    /// Stiffness `[κ, κᵛ]` at sorted `slot` (m²/s²), to warm-start the next sub-step.
    #[inline]
    pub fn stiffness(&self, slot: usize) -> Vec2 {
        Vec2::new(self.kappa[slot], self.kappa_divergence[slot])
    }

    /// Pressure at sorted `slot`, Pa: `ρ₀ κ`, the density solve's pressure, which holds the
    /// fluid at rest density (the divergence solve's `κᵛ` is a velocity correction of its own
    /// and is not counted).
    #[inline]
    pub fn pressure(&self, c: &SphConstants, slot: usize) -> f32 {
        c.rest_density * self.kappa[slot]
    }
}

/// The speed (m/s) a particle reaches from rest when a stiffness `κ = p/ρ₀` (m²/s²) is released
/// (Bernoulli: `√(2p/ρ₀)`). The flow's CFL limit takes it as a speed the fluid can have: the
/// pressure force on a particle depends on where its neighbours are, with a stiffness that grows
/// with the pressure, and the explicit move of the positions is stable only while a step is short
/// against `Δx/√(2κ)` (measured: a layer 25 particles deep at 4 mm spacing boiled at 4 ms steps,
/// with its fastest particle at 44% of `√(gD)`, and settled at this limit's 2 ms).
pub(crate) fn pressure_speed(stiffness: f32) -> f32 {
    (2.0 * stiffness.max(0.0)).sqrt()
}

/// The step the divergence solve makes the velocities divergence-free for: the last sub-step's
/// length, or on the first sub-step the flow's limit at the current speed (both drivers use it).
pub(crate) fn divergence_step(clock: &SubstepClock, c: &SphConstants, max_speed: f32) -> f32 {
    if clock.dt > 0.0 {
        clock.dt
    } else {
        stable_time_step(c, max_speed, 0.0)
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

/// Neighbours (the particle itself not counted) of an interior particle of the rest lattice.
fn lattice_neighbors(c: &SphConstants) -> u32 {
    let reach = (c.support / c.spacing).ceil() as i32;
    let mut count = 0;
    for j in -reach..=reach {
        for i in -reach..=reach {
            let r2 = ((i * i + j * j) as f32) * c.spacing * c.spacing;
            if r2 > 0.0 && r2 < c.support_sq {
                count += 1;
            }
        }
    }
    count
}

/// The largest eigenvalue `λ_max` of the DFSPH pressure operator scaled by its diagonal on the
/// interior of the rest lattice: with a stiffness wave `κ = e^{ik·x}`, the operator is
/// `|S(k)|²` with `S(k) = Σⱼ gⱼ sin(k·dⱼ)` over the neighbour offsets `dⱼ`, the diagonal `Σⱼ |gⱼ|²`.
/// It is above 2 in 2D (about 2.5 for the Wendland kernel at 2.5 spacings, 3.3 at 3), so the
/// plain Jacobi update of Bender & Koschier diverges here (measured); the solve's projected
/// gradient steps take `1/λ_max`.
fn lattice_spectral_radius<G: RadialKernel>(g: &G, c: &SphConstants) -> f32 {
    let reach = (c.support / c.spacing).ceil() as i32;
    let mut offsets = Vec::new();
    for j in -reach..=reach {
        for i in -reach..=reach {
            let d = Vec2::new(i as f32, j as f32) * c.spacing;
            let r2 = d.length_squared();
            if r2 > 0.0 && r2 < c.support_sq {
                offsets.push((d, g.derivative_over_r(r2.sqrt()) * d));
            }
        }
    }
    let diagonal: f32 = offsets.iter().map(|(_, g)| g.length_squared()).sum();
    if diagonal <= 0.0 {
        return 1.0;
    }
    const SAMPLES: usize = 48;
    let mut largest = 0.0f32;
    for a in 0..=SAMPLES {
        for b in 0..=SAMPLES {
            let k = Vec2::new(a as f32, b as f32)
                * (core::f32::consts::PI / (SAMPLES as f32 * c.spacing));
            let s: Vec2 = offsets.iter().map(|&(d, g)| k.dot(d).sin() * g).sum();
            largest = largest.max(s.length_squared() / diagonal);
        }
    }
    largest
}

/// `Σⱼ |gⱼ|²` of an interior particle of the rest lattice, 1/m²: the diagonal of its pressure
/// equation (per `dt²`, the inverse of its DFSPH factor), with the lattice-corrected,
/// volume-weighted gradients (2.2·10⁴ /m² at 5 mm spacing). The scale of
/// [`PINNED_DIAGONAL`].
fn lattice_diagonal<G: RadialKernel>(g: &G, c: &SphConstants) -> f32 {
    let reach = (c.support / c.spacing).ceil() as i32;
    let mut sum = 0.0;
    for j in -reach..=reach {
        for i in -reach..=reach {
            let d = Vec2::new(i as f32, j as f32) * c.spacing;
            let r2 = d.length_squared();
            if r2 > 0.0 && r2 < c.support_sq {
                let gradient = c.gradient_scale * c.volume * g.derivative_over_r(r2.sqrt()) * d;
                sum += gradient.length_squared();
            }
        }
    }
    sum
}

// A block is one lane vector.
const _: () = assert!(BLOCK == 4);

/// `value(j)` of a block's [`BLOCK`] neighbour slots, as lanes.
#[inline(always)]
fn lanes(slots: &[u32], value: impl Fn(usize) -> f32) -> Vec4 {
    Vec4::new(
        value(slots[0] as usize),
        value(slots[1] as usize),
        value(slots[2] as usize),
        value(slots[3] as usize),
    )
}

/// `(Σⱼ (xᵢ + xⱼ) gᵢⱼ + 2 xᵢ g_wall,ᵢ) / rᵢ`: the pressure acceleration of stiffness `x` on
/// particle `slot`, per unit stiffness (walls mirror the particle's own stiffness,
/// [`WALL_MIRROR`]; `rᵢ` its rest density ratio: the force is the pressure's, the particle's
/// mass its liquid's).
#[inline(always)]
fn pressure_push(rows: &Rows, simd: Simd, s: &SlotState, slot: usize, x: &[f32]) -> Vec2 {
    let own = x[slot];
    s.inverse_mass
        * (WALL_MIRROR * own * s.wall_gradient + rows.row(slot, s.count).push(simd, x, own))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::{PressureSolver, SphParams};
    use crate::sim::config::DfsphSettings;
    use crate::sim::parallel::Sequential;

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
        fluid.rebuild(
            &c,
            (&points, &vec![Vec2::ZERO; points.len()], &[], &[]),
            &Sequential,
        );
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

    /// A block of `nx × ny` particles at rest on the floor of a tank `tank` wide (0.3 m
    /// tall), with `settings` applied, after one density solve of 4 ms from zero pressure:
    /// the constants, the snapshot, the solver and its iterations.
    fn solve_resting_block(
        (nx, ny): (usize, usize),
        tank: f32,
        settings: impl FnOnce(&mut DfsphSettings),
    ) -> (SphConstants, FluidSnapshot, Dfsph, u32) {
        use crate::sim::boundary::Tank;
        let mut p = params();
        p.tank = Some(Tank::new(tank, 0.3));
        settings(&mut p.dfsph);
        let c = p.constants().unwrap();
        let dx = p.particle_spacing;
        let points: Vec<Vec2> = (0..nx * ny)
            .map(|k| Vec2::new((k % nx) as f32 + 0.5, (k / nx) as f32 + 0.5) * dx)
            .collect();
        let mut fluid = FluidSnapshot::default();
        fluid.rebuild(
            &c,
            (&points, &vec![Vec2::ZERO; points.len()], &[], &[]),
            &Sequential,
        );
        let mut walls = Walls::default();
        walls.rebuild(&c);
        let mut dfsph = Dfsph::default();
        dfsph.prepare(&c, &fluid, &walls, |_| Vec2::ZERO, &Sequential);
        let accelerations: Vec<Vec2> = (0..fluid.len())
            .map(|slot| dfsph.non_pressure_acceleration(&c, &fluid, slot))
            .collect();
        let most = dfsph.predict(0.004, |slot| accelerations[slot]);
        let iterations = dfsph.solve_density(&c, 0.004, most, &Sequential);
        (c, fluid, dfsph, iterations)
    }

    /// The density solve's iterations on a resting 10 × 10 block from zero pressure.
    fn resting_layer_iterations(tolerance: f32, most: u32, fixed_budget: bool) -> u32 {
        let (.., iterations) = solve_resting_block((10, 10), 0.1, |d| {
            d.density_tolerance = tolerance;
            d.max_density_iterations = most;
            d.fixed_budget = fixed_budget;
        });
        iterations
    }

    #[test]
    fn a_fixed_budget_runs_every_iteration_and_a_tolerance_stops_early() {
        // A loose tolerance is met within a few iterations; with a fixed budget the same solve
        // runs all of them.
        let stopped = resting_layer_iterations(0.05, 40, false);
        assert!(
            stopped < 40,
            "the tolerance stop took {stopped} of 40 iterations"
        );
        assert_eq!(resting_layer_iterations(0.05, 40, true), 40);
        assert_eq!(resting_layer_iterations(0.05, 3, true), 3);
    }

    #[test]
    fn one_solve_from_rest_gives_hydrostatic_pressure() {
        let (w, d) = (0.2f32, 0.2f32);
        let dx = params().particle_spacing;
        let (nx, ny) = ((w / dx) as usize, (d / dx) as usize);
        let (c, fluid, dfsph, iterations) = solve_resting_block((nx, ny), w, |d| {
            d.density_tolerance = 1e-6;
            d.max_density_iterations = 2000;
        });
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
            ..SphParams::reference()
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
        let delta = dfsph.kappa.clone();
        let mut kappa = vec![0.0; delta.len()];
        dfsph.push(1.0, &delta, &mut kappa);
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
