//! The pressure solves of [`Dfsph`]: a bound-constrained, Jacobi-preconditioned conjugate
//! gradient (Dostál's MPRGP: "modified proportioning with reduced gradient projections", Dostál
//! & Schöberl 2005) on the symmetric DFSPH pressure equations. Pure, no ECS.
//!
//! Both solves look for the stiffness `κ ≥ 0` (pressure pushes, never pulls) that minimises
//! `½ dt² κᵀAκ − κᵀe₀`, where `A = DDᵀ`, `D` is the density rate of the velocities and its
//! transpose `Dᵀ` the pressure push (see [`pressure_push`](super::pressure_push)), and `e₀` the
//! error each particle would have without pressure ([`Target::error`]). The gradient of that
//! function is minus the error `e` left with the current stiffness, so at the minimum every
//! particle is either at rest density (`e = 0`, `κ > 0`) or not compressed at zero pressure
//! (`e ≤ 0`, `κ = 0`): a linear complementarity problem. The iteration count of a conjugate
//! gradient grows with the square root of the condition number, so with the depth in particles,
//! where projected Jacobi grows with its square; warm-started, a resting layer 100 particles
//! deep takes a few tens of iterations per sub-step.
//!
//! The iterations work in the variables `y = κ/√αᵢ` scaled by the DFSPH factor (the Jacobi
//! preconditioner: the scaled operator has a unit diagonal), in which the bound `κ ≥ 0` is
//! unchanged. Each one is one pressure push and one density-rate pass, like a Jacobi iteration:
//! - a conjugate-gradient step on the particles with pressure (the free set) while it stays
//!   feasible;
//! - an expansion step where it would take a stiffness below zero: as far as feasible, then a
//!   projected gradient step of fixed length (`1/λ_max`), which can release many particles at
//!   once;
//! - a proportioning step, which lets compressed particles at zero pressure take pressure, when
//!   their error outweighs what the free set can still gain.
//!
//! It stops once the mean error is under the tolerance and the largest under
//! [`LARGEST_ERROR_RATIO`] times it, so that no deep particle hides its error in the mean.
//!
//! Under a fixed budget ([`DfsphSettings::fixed_budget`]) the density solve's iterations are
//! projected gradient steps alone ([`REACH`]), one push and one density-rate pass each. Measured
//! on the demo's dam break under the default budget, 94% of MPRGP's iterations were expansions
//! (a free surface always has a particle that a conjugate-gradient step would take below zero),
//! whose feasible part moved a median 3% of the step (none at all in the first iteration) at
//! the cost of a second push and rate pass.

use super::rows::Rows;
use super::{Dfsph, SlotState, WALL_MIRROR, pressure_push};
use crate::sim::config::DfsphSettings;
use crate::sim::parallel::{Parallel, fold_slots, fold_slots2};
use crate::sim::simd::{Simd, simd};
use bevy::math::Vec2;

/// The largest error a solve may leave at any particle, as a multiple of its tolerance on the
/// mean.
pub const LARGEST_ERROR_RATIO: f32 = 10.0;

/// The fastest a compressed particle's density excess is relieved, 1/s (a fraction of the
/// excess per second). Flows keep their density within a fraction of a percent, which one step
/// relieves whole; a block spawned too densely (four times the rest density, say) asked to expand
/// in one step would fly apart at `3Δx/dt`: it expands at this rate instead, at about a metre per
/// second over a tank's width.
pub const MAX_RELIEF_RATE: f32 = 10.0;

/// The length of a fixed budget's projected gradient steps, as a multiple of `ᾱ = 1/λ_max`,
/// each cut short to where it lowers the energy most. `ᾱ` alone is the step that can never
/// overshoot on the lattice, and a short one for the smooth errors that a body's weight
/// leaves: boxes of relative density 0.5 floated 6.1% deep with it (on the free set alone),
/// 0.4-3.3% with twice it.
const REACH: f32 = 2.0;

/// Dostál's proportioning constant `Γ`: a proportioning step is taken when the chopped gradient
/// (compressed particles at zero pressure) exceeds `Γ` times the reduced free gradient.
const PROPORTIONING: f64 = 1.0;

/// Which of the two pressure equations a solve works on.
#[derive(Clone, Copy)]
pub(super) enum Target {
    /// The constant-density solve: stiffness `κ`.
    Density,
    /// The divergence-free solve: stiffness `κᵛ`.
    Divergence,
}

impl Target {
    /// Whether the solve gives the particle a stiffness: not without neighbours or when pinned
    /// (a zero factor, [`PINNED_DIAGONAL`](super::PINNED_DIAGONAL)), and not in the divergence solve for a deficient neighbourhood, which keeps splashes and the
    /// free surface from being pinned.
    #[inline]
    fn solves(self, s: &SlotState) -> bool {
        s.factor > 0.0 && !(matches!(self, Self::Divergence) && s.deficient)
    }

    /// The error `eᵢ` a particle's stiffness should cancel, from its density change rate `rate`
    /// (1/s) over a step of `dt`: the predicted density excess `ρ̂ᵢ + dt Dρ̂ᵢ/Dt − 1`, of which
    /// one step relieves at most `dt` times [`MAX_RELIEF_RATE`], or the density change of one
    /// step `dt Dρ̂ᵢ/Dt`.
    #[inline]
    fn error(self, dt: f32, rate: f32, s: &SlotState) -> f32 {
        match self {
            Self::Density => (s.density - 1.0).min(dt * MAX_RELIEF_RATE) + dt * rate,
            Self::Divergence => dt * rate,
        }
    }

    /// The tolerance on the mean error, and the fewest and most iterations.
    fn limits(self, settings: &DfsphSettings) -> (f32, u32, u32) {
        match self {
            Self::Density => (
                settings.density_tolerance,
                1,
                settings.max_density_iterations,
            ),
            Self::Divergence => (
                settings.divergence_tolerance,
                0,
                settings.max_divergence_iterations,
            ),
        }
    }

    /// The largest error a solve may leave: the caller's bound `largest` (if positive), within
    /// [`LARGEST_ERROR_RATIO`] times the tolerance on the mean.
    pub(super) fn largest(self, largest: f32, tolerance: f32) -> f32 {
        if largest > 0.0 {
            largest.min(LARGEST_ERROR_RATIO * tolerance)
        } else {
            LARGEST_ERROR_RATIO * tolerance
        }
    }

    /// The fraction of the last sub-step's stiffness a solve starts from: all of it for the
    /// density, half for the divergence, as Bender & Koschier do.
    fn warm_start(self) -> f32 {
        match self {
            Self::Density => 1.0,
            Self::Divergence => 0.5,
        }
    }
}

/// What one solve keeps for each particle of its own (read by no neighbour).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Unknown {
    /// Stiffness, m²/s².
    kappa: f32,
    /// The error left with it ([`Target::error`]), fraction.
    error: f32,
    /// The velocity with its pressure, m/s.
    velocity: Vec2,
    /// The inverse diagonal of the pressure equations, `αᵢ/dt²` (m²/s²), zero
    /// for a particle the solve leaves alone.
    inverse_diagonal: f32,
}

impl Unknown {
    /// Whether the particle is in the free set (has pressure).
    #[inline]
    fn free(&self) -> bool {
        self.kappa > 0.0
    }
}

/// The sums one pass over the particles gathers (see [`fold_slots`]).
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    /// The sum of each particle's error as the solve counts it: `|e|` with pressure, the
    /// compression `max(e, 0)` without.
    error_sum: f64,
    /// The largest such error.
    error_max: f32,
    /// `Σ_free (M⁻¹g)ᵢ qᵢ`, where `q = dt²Ap` of the last direction: Gram-Schmidt against it.
    conjugate: f64,
    /// `‖β‖²`, the chopped gradient (compressed particles at zero pressure), preconditioned.
    chopped: f64,
    /// `φ̃ᵀφ`, the reduced free gradient against the free gradient, preconditioned.
    reduced_free: f64,
    /// `gᵀp` of the next projected gradient step, where the pass set one
    /// ([`Solve::projected_steps`]).
    slope: f64,
}

impl Tally {
    fn add(self, other: Self) -> Self {
        Self {
            error_sum: self.error_sum + other.error_sum,
            error_max: self.error_max.max(other.error_max),
            conjugate: self.conjugate + other.conjugate,
            chopped: self.chopped + other.chopped,
            reduced_free: self.reduced_free + other.reduced_free,
            slope: self.slope + other.slope,
        }
    }
}

/// The sums of a new search direction `p`: `gᵀp`, and the longest step `x − αp` that keeps
/// every stiffness non-negative.
#[derive(Debug, Clone, Copy)]
struct Direction {
    slope: f64,
    feasible_step: f32,
}

impl Default for Direction {
    fn default() -> Self {
        Self {
            slope: 0.0,
            feasible_step: f32::INFINITY,
        }
    }
}

impl Direction {
    fn add(self, other: Self) -> Self {
        Self {
            slope: self.slope + other.slope,
            feasible_step: self.feasible_step.min(other.feasible_step),
        }
    }
}

/// The next search direction after a step.
#[derive(Clone, Copy)]
enum Next {
    /// The preconditioned free gradient, conjugated against the last direction by `γ`.
    Conjugate(f32),
    /// The preconditioned free gradient alone (a restart).
    Free,
    /// The preconditioned chopped gradient: compressed particles at zero pressure.
    Chopped,
}

/// When MPRGP stops: the mean error under `tolerance` and the largest under `largest`, within
/// `iterations`; under a fixed `budget`, at the most iterations only.
struct Stop {
    tolerance: f32,
    largest: f32,
    iterations: core::ops::RangeInclusive<u32>,
    budget: bool,
}

/// The state of one solve, borrowed from [`Dfsph`] and its scratch.
struct Solve<'a, P: Parallel> {
    rows: &'a Rows,
    state: &'a [SlotState],
    /// The SIMD path of the row sums.
    simd: Simd,
    unknowns: &'a mut [Unknown],
    /// The search direction `p`, by slot (read by neighbours in the push).
    direction: &'a mut [f32],
    /// The pressure push `Dᵀp` of the direction, by slot (read by neighbours in the rate).
    push: &'a mut [Vec2],
    target: Target,
    dt: f32,
    /// The length `ᾱ` of the projected gradient steps in the scaled variables, `1/λ_max`.
    expansion: f32,
    parallel: &'a P,
}

impl<P: Parallel> Solve<'_, P> {
    /// The push `u = R⁻¹Dᵀp` of the current direction into [`Self::push`] (`R` the particles'
    /// rest density ratios); returns `pᵀ(dt²A)p = dt² Σ rᵢ|uᵢ|²`.
    fn push_direction(&mut self) -> f64 {
        let (rows, state, simd, direction) = (self.rows, self.state, self.simd, &*self.direction);
        let sum = fold_slots(
            self.push,
            self.parallel,
            |slot, u| {
                *u = pressure_push(rows, simd, &state[slot], slot, direction);
                u.length_squared() as f64 / state[slot].inverse_mass as f64
            },
            |a, b| a + b,
        );
        sum * (self.dt * self.dt) as f64
    }

    /// Moves along the direction by `step` (`κ ← max(κ − step p, 0)`, the velocities with the
    /// pushes of it, the errors by `step q` with `q = dt² D u`) and tallies the new state; the
    /// conjugation sum is against `q`. With `next`, sets the direction to the projected
    /// gradient step of that length from the new state ([`projected`]) and tallies its slope.
    fn advance(&mut self, step: f32, next: Option<f32>) -> Tally {
        let (rows, state, simd) = (self.rows, self.state, self.simd);
        let push = &*self.push;
        let (dt, expansion) = (self.dt, self.expansion);
        fold_slots2(
            self.unknowns,
            self.direction,
            self.parallel,
            |slot, x, p| {
                let mut sums = if step != 0.0 {
                    let q = dt * dt * push_rate(rows, simd, &state[slot], slot, push);
                    if *p != 0.0 {
                        let kappa = x.kappa - step * *p;
                        // The particle that limits a feasible step lands on the bound exactly.
                        x.kappa = if kappa <= 1e-6 * x.kappa { 0.0 } else { kappa };
                    }
                    x.velocity += step * dt * push[slot];
                    x.error += step * q;
                    tally(x, q, expansion)
                } else {
                    tally(x, 0.0, expansion)
                };
                if let Some(length) = next {
                    (*p, sums.slope) = next_step(x, length);
                }
                sums
            },
            Tally::add,
        )
    }

    /// The warm start: the direction `p = −warm κ` (on the particles the solve works on), its
    /// push `Dᵀp`, and every unknown from the velocity under that push, `velocity + dt Dᵀp`, with
    /// the stiffness `warm κ`, its errors from that velocity and its inverse diagonal `αᵢ/dt²`
    /// from `inv_dt_sq` (zero where the solve leaves the particle alone). Tallies them. The same
    /// state as a step of one along `p` from zero stiffness, in two passes over the neighbours
    /// instead of three (the errors from the pushed velocities, not added to them). With
    /// `next`, sets the direction to the first projected gradient step, as
    /// [`advance`](Self::advance) does.
    fn start(
        &mut self,
        velocity: &[Vec2],
        (kappa, warm, inv_dt_sq): (&[f32], f32, f32),
        next: Option<f32>,
    ) -> Tally {
        self.set_warm_direction(kappa, warm);
        self.push_warm(velocity);
        self.set_unknowns(inv_dt_sq, next)
    }

    /// The warm start's direction `p = −warm κ` on the particles the solve works on.
    fn set_warm_direction(&mut self, kappa: &[f32], warm: f32) {
        let (state, target) = (self.state, self.target);
        fold_slots(
            self.direction,
            self.parallel,
            |slot, p| {
                *p = if target.solves(&state[slot]) {
                    -warm * kappa[slot].max(0.0)
                } else {
                    0.0
                };
            },
            |(), ()| (),
        );
    }

    /// The velocities under the warm start's push, `velocity + dt Dᵀp`, into the push scratch
    /// (which holds them until the next push).
    fn push_warm(&mut self, velocity: &[Vec2]) {
        let (rows, state, simd, dt) = (self.rows, self.state, self.simd, self.dt);
        let direction = &*self.direction;
        fold_slots(
            self.push,
            self.parallel,
            |slot, u| {
                let push = pressure_push(rows, simd, &state[slot], slot, direction);
                *u = velocity[slot] + dt * push;
            },
            |(), ()| (),
        );
    }

    /// Every unknown from the warm start's direction and pushed velocities (see
    /// [`start`](Self::start)), tallied; with `next`, the first projected step's direction.
    fn set_unknowns(&mut self, inv_dt_sq: f32, next: Option<f32>) -> Tally {
        let (rows, state, simd, dt) = (self.rows, self.state, self.simd, self.dt);
        let (target, expansion, pushed) = (self.target, self.expansion, &*self.push);
        fold_slots2(
            self.unknowns,
            self.direction,
            self.parallel,
            |slot, x, p| {
                let s = &state[slot];
                let inverse_diagonal = if target.solves(s) {
                    s.factor * inv_dt_sq
                } else {
                    0.0
                };
                let kappa = -*p;
                *x = Unknown {
                    kappa: if kappa > 0.0 { kappa } else { 0.0 },
                    error: 0.0,
                    velocity: pushed[slot],
                    inverse_diagonal,
                };
                if inverse_diagonal > 0.0 {
                    let rate = density_rate(rows, simd, s, slot, pushed);
                    x.error = target.error(dt, rate, s);
                }
                let mut sums = tally(x, 0.0, expansion);
                if let Some(length) = next {
                    (*p, sums.slope) = next_step(x, length);
                }
                sums
            },
            Tally::add,
        )
    }

    /// Writes the next search direction and returns its sums.
    fn set_direction(&mut self, next: Next) -> Direction {
        let unknowns = &*self.unknowns;
        fold_slots(
            self.direction,
            self.parallel,
            |slot, p| {
                let x = unknowns[slot];
                // The preconditioned gradient `M⁻¹g` with `g = −e`.
                let gradient = -x.error;
                let scaled = x.inverse_diagonal * gradient;
                *p = match next {
                    Next::Conjugate(gamma) if x.free() => scaled - gamma * *p,
                    Next::Free if x.free() => scaled,
                    Next::Chopped if !x.free() && gradient < 0.0 => scaled,
                    _ => 0.0,
                };
                Direction {
                    slope: (gradient * *p) as f64,
                    feasible_step: if *p > 0.0 {
                        x.kappa / *p
                    } else {
                        f32::INFINITY
                    },
                }
            },
            Direction::add,
        )
    }

    /// A proportioning step along the chopped gradient, with its exact length; `None` when the
    /// tally has no compressed particle at zero pressure (or the step is degenerate).
    fn proportion(&mut self, tally: Tally) -> Option<Tally> {
        if tally.chopped <= 0.0 {
            return None;
        }
        let d = self.set_direction(Next::Chopped);
        let curvature = self.push_direction();
        (d.slope > 0.0 && curvature > 0.0).then(|| self.advance((d.slope / curvature) as f32, None))
    }

    /// The projected gradient step of an expansion: sets the direction to `κ − max(κ − ᾱ M⁻¹g,
    /// 0)` on the free set, the change that [`advance`](Self::advance) by one makes.
    fn set_projection(&mut self, length: f32) {
        let unknowns = &*self.unknowns;
        fold_slots(
            self.direction,
            self.parallel,
            |slot, p| {
                let x = unknowns[slot];
                *p = if x.free() { projected(&x, length) } else { 0.0 };
            },
            |(), ()| (),
        )
    }

    /// MPRGP's iterations from the tally of the start, until `stop`; returns the iterations
    /// and the last tally.
    fn mprgp(&mut self, mut tally: Tally, stop: Stop) -> (u32, Tally) {
        let n = self.unknowns.len();
        let mut iterations = 0u32;
        let mut next = Next::Free;
        loop {
            let mean = (tally.error_sum / n as f64) as f32;
            let converged = mean <= stop.tolerance && tally.error_max <= stop.largest;
            if (iterations >= *stop.iterations.start() && converged && !stop.budget)
                || iterations >= *stop.iterations.end()
                || !mean.is_finite()
            {
                return (iterations, tally);
            }
            iterations += 1;
            // Proportional: the free set can still gain more than the chopped gradient offers.
            let proportional = tally.chopped <= PROPORTIONING * PROPORTIONING * tally.reduced_free;
            let (d, curvature) = if proportional {
                let d = self.set_direction(next);
                (d, self.push_direction())
            } else {
                (Direction::default(), 0.0)
            };
            if d.slope <= 0.0 || curvature <= 0.0 {
                // Not proportional, or nothing left to gain on the free set: compressed
                // particles at zero pressure take pressure (a proportioning step).
                match self.proportion(tally) {
                    Some(after) => (tally, next) = (after, Next::Free),
                    None => return (iterations, tally),
                }
                continue;
            }
            let step = (d.slope / curvature) as f32;
            if step <= d.feasible_step {
                tally = self.advance(step, None);
                next = Next::Conjugate((tally.conjugate / curvature) as f32);
            } else {
                // Expansion: as far as feasible, then a projected gradient step.
                self.advance(d.feasible_step, None);
                self.set_projection(self.expansion);
                self.push_direction();
                tally = self.advance(1.0, None);
                next = Next::Free;
            }
        }
    }

    /// The length of a fixed budget's projected gradient steps, [`REACH`] times `ᾱ`.
    fn reach(&self) -> f32 {
        REACH * self.expansion
    }

    /// `most` projected gradient steps from the tally of the start (which set the first
    /// direction), each one push and one density-rate pass: [`REACH`] times `ᾱ` along the
    /// preconditioned gradient over every particle the solve works on (compressed ones at zero
    /// pressure included), projected onto `κ ≥ 0` ([`projected`]) and cut short where the
    /// energy is lowest. Returns the iterations and the last tally; stops early when a step has
    /// nothing to gain.
    fn projected_steps(&mut self, mut tally: Tally, most: u32) -> (u32, Tally) {
        let mut iterations = 0u32;
        while iterations < most && tally.error_sum.is_finite() && tally.slope > 0.0 {
            let curvature = self.push_direction();
            if curvature.is_nan() || curvature <= 0.0 {
                break;
            }
            iterations += 1;
            // As far along the step as it lowers the energy (never past its end, where the
            // projection keeps every stiffness at or above zero): a clump of particles closer
            // than the lattice is stiffer than `1/ᾱ`.
            let step = (tally.slope / curvature).min(1.0) as f32;
            let next = (iterations < most).then_some(self.reach());
            tally = self.advance(step, next);
        }
        (iterations, tally)
    }
}

/// The change `κ − max(κ − length M⁻¹g, 0)` of a projected gradient step of `length` at a
/// particle (zero for one the solve leaves alone, whose inverse diagonal is zero).
#[inline]
fn projected(x: &Unknown, length: f32) -> f32 {
    x.kappa - (x.kappa + length * x.inverse_diagonal * x.error).max(0.0)
}

/// A particle's direction of the next projected gradient step of `length` and its share of the
/// slope `gᵀp`: none for a particle the solve leaves alone (whatever error it carries).
#[inline]
fn next_step(x: &Unknown, length: f32) -> (f32, f64) {
    if x.inverse_diagonal > 0.0 {
        let p = projected(x, length);
        (p, (-x.error * p) as f64)
    } else {
        (0.0, 0.0)
    }
}

/// A particle's share of a [`Tally`]; `q` is `dt²Ap` of the direction just taken (zero when
/// none was), `expansion` the projected step `ᾱ`.
#[inline]
fn tally(x: &Unknown, q: f32, expansion: f32) -> Tally {
    if x.inverse_diagonal == 0.0 {
        return Tally::default();
    }
    let (g, m) = (-x.error, x.inverse_diagonal);
    if x.free() {
        // In the scaled variables `y = κ/√M⁻¹`: `φ̃ᵢφᵢ = min(yᵢ/ᾱ, φᵢ) φᵢ = gᵢ min(κᵢ/ᾱ, M⁻¹gᵢ)`.
        let reduced = if g < 0.0 {
            m * g * g
        } else {
            g * (x.kappa / expansion).min(m * g)
        };
        Tally {
            error_sum: g.abs() as f64,
            error_max: g.abs(),
            conjugate: (m * g * q) as f64,
            chopped: 0.0,
            reduced_free: reduced as f64,
            slope: 0.0,
        }
    } else {
        let compression = (-g).max(0.0);
        Tally {
            error_sum: compression as f64,
            error_max: compression,
            conjugate: 0.0,
            chopped: (m * compression * compression) as f64,
            reduced_free: 0.0,
            slope: 0.0,
        }
    }
}

/// `Σⱼ gᵢⱼ·(uᵢ − uⱼ) + 2 Σ_b g_ib·uᵢ`: the density change rate (1/s² for a push in m/s²) that
/// a pressure push `u` adds to particle `slot`; [`density_rate`] without the walls' own motion,
/// which no pressure changes.
#[inline(always)]
fn push_rate(rows: &Rows, simd: Simd, s: &SlotState, slot: usize, u: &[Vec2]) -> f32 {
    let ui = u[slot];
    WALL_MIRROR * s.wall_gradient.dot(ui) + rows.row(slot, s.count).rate(simd, u, ui)
}

/// `Σⱼ gᵢⱼ·(uᵢ − uⱼ) + 2 Σ_b g_ib·(uᵢ − v_b)`: the density change rate (1/s) of particle `slot`
/// under the velocity field `u` (walls mirror the particle's velocity about their own,
/// [`WALL_MIRROR`]).
#[inline(always)]
fn density_rate(rows: &Rows, simd: Simd, s: &SlotState, slot: usize, u: &[Vec2]) -> f32 {
    let ui = u[slot];
    WALL_MIRROR * (s.wall_gradient.dot(ui) - s.wall_flux)
        + rows.row(slot, s.count).rate(simd, u, ui)
}

impl Dfsph {
    /// MPRGP on the DFSPH pressure equations of `target` (see the module docs), or under a
    /// fixed budget for the density, projected gradient steps ([`Solve::projected_steps`]),
    /// from the target's stiffness of the last sub-step (warm start) or zero. Returns the
    /// iterations and the mean error left.
    pub(super) fn solve(
        &mut self,
        dt: f32,
        target: Target,
        largest: f32,
        settings: &DfsphSettings,
        parallel: &impl Parallel,
    ) -> (u32, f32) {
        let n = self.state.len();
        let (tolerance, min_iterations, max_iterations) = target.limits(settings);
        let largest = target.largest(largest, tolerance);
        let inv_dt_sq = 1.0 / (dt * dt);
        let expansion = self.expansion_step;
        let kappa = match target {
            Target::Density => &mut self.kappa,
            Target::Divergence => &mut self.kappa_divergence,
        };
        let warm = target.warm_start();
        let mut unknowns = core::mem::take(&mut self.scratch.unknowns);
        unknowns.resize(n, Unknown::default());
        let mut direction = core::mem::take(&mut self.scratch.delta);
        direction.resize(n, 0.0);
        let mut push = core::mem::take(&mut self.scratch.push);
        push.resize(n, Vec2::ZERO);
        let mut solve = Solve {
            rows: &self.rows,
            state: &self.state,
            simd: simd(),
            unknowns: &mut unknowns,
            direction: &mut direction,
            push: &mut push,
            target,
            dt,
            expansion,
            parallel,
        };
        let projected = settings.fixed_budget && matches!(target, Target::Density);
        let first = (projected && max_iterations > 0).then(|| solve.reach());
        let tally = solve.start(&self.velocity, (&kappa[..], warm, inv_dt_sq), first);
        // The divergence solve keeps MPRGP under a budget too: with projected gradient steps
        // alone (one or two), a resting layer 25 deep at 1 cm still moved at 1-2% of `√(gD)`
        // from 1.25 to 2 s, with MPRGP's one iteration at 0.3-1%.
        let (iterations, tally) = if projected {
            solve.projected_steps(tally, max_iterations)
        } else {
            let stop = Stop {
                tolerance,
                largest,
                iterations: min_iterations..=max_iterations,
                budget: settings.fixed_budget,
            };
            solve.mprgp(tally, stop)
        };
        for (v, x) in self.velocity.iter_mut().zip(unknowns.iter()) {
            *v = x.velocity;
        }
        kappa.clear();
        kappa.extend(unknowns.iter().map(|x| x.kappa));
        self.scratch.unknowns = unknowns;
        self.scratch.delta = direction;
        self.scratch.push = push;
        (iterations, (tally.error_sum / n.max(1) as f64) as f32)
    }

    /// Adds the stiffness changes `delta` to `kappa` and their pressure accelerations over `dt`
    /// to the velocities (no bound: the tests' way to apply a stiffness field).
    #[cfg(test)]
    pub(super) fn push(&mut self, dt: f32, delta: &[f32], kappa: &mut [f32]) {
        let (rows, state, simd) = (&self.rows, &self.state, simd());
        for (slot, v) in self.velocity.iter_mut().enumerate() {
            *v -= dt * pressure_push(rows, simd, &state[slot], slot, delta);
        }
        for (k, d) in kappa.iter_mut().zip(delta) {
            *k += d;
        }
    }
}
