//! The one order of a fluid sub-step. Both drivers call it: the plain-vector world
//! ([`world`](super::world)) runs [`FluidStep::substep`], and the ECS driver runs the same
//! [`Stage`]s one by one (with the game's force hooks between [`Stage::Forces`] and
//! [`Stage::Integrate`]), so the two cannot drift.
//!
//! A sub-step works on the fluid's [`Particles`] (by the driver's index) and on the
//! [`FluidStep`] (the cell-sorted snapshot, the walls, the clock and the pressure solver's own
//! state, by sorted slot). Each pressure solver fills in its part of the stages through
//! [`PressureStages`]; the solvers are listed once, in [`SolverState`], whose exhaustive
//! `match` is the one place a new solver is added.

use super::clock::SubstepClock;
use super::config::{PressureSolver, SphConstants};
use super::density::{max_length, mean_neighbors, with_kernels};
use super::dfsph::Dfsph;
use super::integrate::advance_particle;
use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, Walls};
use super::parallel::{CHUNK, Parallel, run_jobs};
use super::profile::{StageProfile, SubstepPart};
use super::solid::{MovingSolid, SolidMotion, SolidResponse};
use super::tension::{SurfaceTension, capillary_time_step};
use super::wcsph::Wcsph;
use bevy::math::Vec2;

/// A solid's outline point is under water where the fluid particles' `Σ V W` there reaches this
/// (measured: a point of the outer ring, half a spacing inside a wetted side, reads 0.13; a
/// side's corner point about 0.25): the waterline is found to within about a spacing.
pub const WET_WEIGHT: f32 = 0.1;

/// The fluid's particles as a structure of arrays, by the driver's index (the world's vector
/// order, the ECS query's order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// Positions, m.
    pub position: Vec<Vec2>,
    /// Velocities, m/s.
    pub velocity: Vec<Vec2>,
    /// Accelerations of the last sub-step, m/s² (DFSPH: without pressure).
    pub acceleration: Vec<Vec2>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// Pressures, Pa.
    pub pressure: Vec<f32>,
    /// DFSPH stiffness `[κ, κᵛ]`, m²/s², carried to the next sub-step.
    pub stiffness: Vec<Vec2>,
    /// Each particle's rest density over [`SphConstants::rest_density`] (its liquid's, 1 for
    /// the base liquid); empty when every particle is the base liquid. When not empty it is as
    /// long as the other arrays.
    pub rest_ratio: Vec<f32>,
    /// Each particle's kinematic viscosity (its liquid's), m²/s; empty when every particle has
    /// [`SphConstants::kinematic_viscosity`]. When not empty it is as long as the other arrays.
    pub viscosity: Vec<f32>,
}

impl Particles {
    /// Particles at rest at `positions`, at `rest_density`.
    pub fn at_rest(positions: Vec<Vec2>, rest_density: f32) -> Self {
        let n = positions.len();
        Self {
            position: positions,
            velocity: vec![Vec2::ZERO; n],
            acceleration: vec![Vec2::ZERO; n],
            density: vec![rest_density; n],
            pressure: vec![0.0; n],
            stiffness: vec![Vec2::ZERO; n],
            rest_ratio: Vec::new(),
            viscosity: Vec::new(),
        }
    }

    /// The rest density ratio of particle `i` (see [`rest_ratio`](Self::rest_ratio)).
    #[inline]
    pub fn ratio(&self, i: usize) -> f32 {
        self.rest_ratio.get(i).copied().unwrap_or(1.0)
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Empties every array, keeping their memory.
    pub fn clear(&mut self) {
        self.position.clear();
        self.velocity.clear();
        self.acceleration.clear();
        self.density.clear();
        self.pressure.clear();
        self.stiffness.clear();
        self.rest_ratio.clear();
        self.viscosity.clear();
    }

    /// Sets the number of particles to `n`, keeping the first ones; new ones at rest at the
    /// origin (and, where the lists are not empty, of rest density ratio one and no viscosity),
    /// for a driver to overwrite.
    pub fn resize(&mut self, n: usize) {
        self.position.resize(n, Vec2::ZERO);
        self.velocity.resize(n, Vec2::ZERO);
        self.acceleration.resize(n, Vec2::ZERO);
        self.density.resize(n, 0.0);
        self.pressure.resize(n, 0.0);
        self.stiffness.resize(n, Vec2::ZERO);
        if !self.rest_ratio.is_empty() {
            self.rest_ratio.resize(n, 1.0);
        }
        if !self.viscosity.is_empty() {
            self.viscosity.resize(n, 0.0);
        }
    }
}

/// The stages of one sub-step, in order ([`Stage::ALL`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// The cell grid and the sorted snapshot from the particles' positions and velocities.
    Neighbors,
    /// WCSPH: density, pressure, wall pressure. DFSPH: cached neighbours, densities and
    /// factors, then the divergence-free solve.
    Density,
    /// Accelerations into [`Particles::acceleration`] (WCSPH: pressure, viscosity, gravity;
    /// DFSPH: viscosity and gravity), with the densities and (WCSPH) the pressures or (DFSPH)
    /// the divergence-free velocities ([`FluidStep::forces_write`]). A driver adds its external
    /// forces after it.
    Forces,
    /// The step length, then (DFSPH) the density solve under every acceleration, and the move.
    Integrate,
}

impl Stage {
    /// Every stage, in the order of a sub-step.
    pub const ALL: [Stage; 4] = [
        Self::Neighbors,
        Self::Density,
        Self::Forces,
        Self::Integrate,
    ];
}

/// How a sub-step's length is taken from the stability limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepLength {
    /// Within the current tick of the clock ([`SubstepClock::take_substep`]).
    InTick,
    /// The longest stable step, outside any tick ([`SubstepClock::take_free_substep`]).
    Free,
}

/// Iterations of the pressure solves, counted over ticks.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverIterations {
    /// Density-solve iterations in the current (or last) tick.
    pub density: u32,
    /// Divergence-solve iterations in the current (or last) tick.
    pub divergence: u32,
    /// Iterations of both solves since start-up.
    pub total: u64,
    /// Of those, the density solve's.
    pub total_density: u64,
}

/// What every pressure solver's stages share: the constants, the sorted snapshot, the walls,
/// the accelerations by sorted slot and the clock.
#[derive(Debug, Clone)]
pub struct Shared {
    /// The constants the sub-steps run on.
    pub constants: SphConstants,
    /// The cell-sorted snapshot of the current sub-step.
    pub snapshot: FluidSnapshot,
    /// The tank's and the solids' boundary particles.
    pub walls: Walls,
    /// Accelerations by sorted slot from the force stage.
    pub accelerations: Vec<Vec2>,
    /// The sub-step clock.
    pub clock: SubstepClock,
    /// Solver iterations.
    pub iterations: SolverIterations,
    /// Particle updates held back because they would not have been finite.
    pub non_finite: u64,
    /// The largest acceleration (m/s²) of particles a driver moves outside the snapshot this
    /// sub-step (spawned between its stages): the step length counts it too.
    pub outsider_acceleration: f32,
    /// Where the sub-steps' time goes, while a driver has switched it on.
    pub profile: Option<StageProfile>,
}

/// A pressure solver's part of the stages of [`Stage`] (the shared parts, the snapshot and the
/// step length, are [`FluidStep`]'s).
pub trait PressureStages {
    /// [`Stage::Density`], up to what a state read without advancing needs: densities,
    /// pressures, neighbour caches ([`FluidStep::refresh`] stops here).
    fn density(&mut self, s: &mut Shared, particles: &Particles, parallel: &impl Parallel);

    /// The rest of [`Stage::Density`]: a correction of the velocities before the forces (the
    /// divergence-free solve); none by default.
    fn correct_velocities(&mut self, _s: &mut Shared, _parallel: &impl Parallel) {}

    /// What [`Stage::Forces`] writes besides accelerations and densities.
    const FORCES_WRITE: ForcesWrite;

    /// [`Stage::Forces`]: fills `s.accelerations` by slot, and writes each particle's
    /// acceleration and density, and what [`FORCES_WRITE`](Self::FORCES_WRITE) says.
    fn forces(&mut self, s: &mut Shared, particles: &mut Particles, parallel: &impl Parallel);

    /// The longest stable step (s) under the largest acceleration, m/s².
    fn step_limit(&self, s: &Shared, max_acceleration: f32) -> f32;

    /// [`Stage::Integrate`] after the step `dt` is chosen, before
    /// [`grid_pressure`](Self::grid_pressure): what the solve starts from (DFSPH's predicted
    /// velocities); nothing by default.
    fn start_pressure(
        &mut self,
        _s: &mut Shared,
        _particles: &Particles,
        _dt: f32,
        _parallel: &impl Parallel,
    ) {
    }

    /// [`Stage::Integrate`] after [`start_pressure`](Self::start_pressure): the pressure the
    /// solve starts from where the settings ask for one (DFSPH's coarse grid); none by default.
    fn grid_pressure(&mut self, _s: &mut Shared, _dt: f32, _parallel: &impl Parallel) {}

    /// [`Stage::Integrate`] after [`grid_pressure`](Self::grid_pressure), before the move: a
    /// pressure solve under every particle's acceleration (DFSPH's density solve); none by
    /// default.
    fn solve_pressure(
        &mut self,
        _s: &mut Shared,
        _particles: &Particles,
        _dt: f32,
        _parallel: &impl Parallel,
    ) {
    }

    /// [`Stage::Integrate`] after [`solve_pressure`](Self::solve_pressure): moves every
    /// particle (and stores its pressure and stiffness); returns how many updates were held
    /// back as not finite.
    fn integrate(
        &mut self,
        s: &mut Shared,
        particles: &mut Particles,
        dt: f32,
        parallel: &impl Parallel,
    ) -> u64;

    /// The end of [`Stage::Integrate`]: gives each solid the impulse of the sub-step of `dt`
    /// seconds, minus what its boundary particles gave the fluid, pair by pair
    /// ([`MovingSolid::end_substep`](super::solid::MovingSolid)).
    fn solid_impulses(&mut self, s: &mut Shared, dt: f32);
}

/// What a solver's [`Stage::Forces`] writes into the [`Particles`] besides accelerations and
/// densities (a driver copies just these into its own storage before its force hooks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ForcesWrite {
    /// Pressures (WCSPH: from the equation of state).
    pub pressure: bool,
    /// Velocities (DFSPH: made divergence-free).
    pub velocity: bool,
}

/// Each pressure solver's own state; the one list of solvers.
#[derive(Debug, Clone)]
pub enum SolverState {
    /// [`PressureSolver::Wcsph`].
    Wcsph(Wcsph),
    /// [`PressureSolver::Dfsph`].
    Dfsph(Box<Dfsph>),
}

impl SolverState {
    /// Fresh state for `solver`.
    pub fn new(solver: PressureSolver) -> Self {
        match solver {
            PressureSolver::Wcsph => Self::Wcsph(Wcsph::default()),
            PressureSolver::Dfsph => Self::Dfsph(Box::default()),
        }
    }

    /// The solver this is the state of.
    pub fn kind(&self) -> PressureSolver {
        match self {
            Self::Wcsph(_) => PressureSolver::Wcsph,
            Self::Dfsph(_) => PressureSolver::Dfsph,
        }
    }
}

/// Runs `$body` with `$solver` bound to the state of the solver in use, as a
/// [`PressureStages`].
macro_rules! with_solver {
    ($state:expr, |$solver:ident| $body:expr) => {
        match $state {
            SolverState::Wcsph($solver) => $body,
            SolverState::Dfsph($solver) => {
                let $solver = &mut **$solver;
                $body
            }
        }
    };
}

/// Runs `$body` with `$solver` bound to the type of the solver in use.
macro_rules! with_solver_type {
    ($state:expr, |$solver:ident| $body:expr) => {
        match $state {
            SolverState::Wcsph(_) => {
                type $solver = Wcsph;
                $body
            }
            SolverState::Dfsph(_) => {
                type $solver = Dfsph;
                $body
            }
        }
    };
}

/// The state of the sub-steps that both drivers share (see the module docs).
#[derive(Debug, Clone)]
pub struct FluidStep {
    /// What every solver's stages share.
    pub shared: Shared,
    /// The pressure solver's own state.
    pub solver: SolverState,
    /// The surface tension pass's scratch.
    tension: SurfaceTension,
}

impl FluidStep {
    /// A step with `constants` and no walls yet ([`FluidStep::rebuild_walls`]).
    pub fn new(constants: SphConstants) -> Self {
        Self {
            shared: Shared {
                constants,
                snapshot: FluidSnapshot::default(),
                walls: Walls::default(),
                accelerations: Vec::new(),
                clock: SubstepClock::default(),
                iterations: SolverIterations::default(),
                non_finite: 0,
                outsider_acceleration: 0.0,
                profile: None,
            },
            solver: SolverState::new(constants.solver),
            tension: SurfaceTension::default(),
        }
    }

    /// The constants in use.
    pub fn constants(&self) -> &SphConstants {
        &self.shared.constants
    }

    /// Takes new constants; a change of solver starts that solver's state afresh.
    pub fn set_constants(&mut self, constants: SphConstants) {
        self.shared.constants = constants;
        if self.solver.kind() != constants.solver {
            self.solver = SolverState::new(constants.solver);
        }
    }

    /// Re-samples the wall particles of the tank.
    pub fn rebuild_walls(&mut self) {
        let s = &mut self.shared;
        s.walls.rebuild(&s.constants);
    }

    /// Starts a tick of `tick` seconds: the clock's, the per-tick iteration counts and the
    /// solids' impulses.
    pub fn begin_tick(&mut self, tick: f64) {
        let s = &mut self.shared;
        s.clock.begin_tick(tick);
        s.iterations.density = 0;
        s.iterations.divergence = 0;
        for solid in &mut s.walls.solids {
            solid.begin_tick();
        }
    }

    /// Ends a tick: the clock's, and each solid's load (force and torque averaged over the
    /// tick, and the submerged area: an outline point is wet where the fluid's
    /// [`sample`](Self::sample) weight `Σ V W` reaches [`WET_WEIGHT`]).
    pub fn end_tick(&mut self) {
        self.shared.clock.end_tick();
        let mut solids = core::mem::take(&mut self.shared.walls.solids);
        let c = &self.shared.constants;
        let (volume, spacing) = (c.volume, c.spacing);
        let head = c.rest_density * c.gravity.length();
        for solid in &mut solids {
            solid.end_tick(|x| self.weight(x) * volume, WET_WEIGHT);
            let touches = |x, n| self.shared.walls.touches(x, n, spacing);
            let pressure = |x| self.sample(x, true).map(|sample| sample.2);
            solid.seep(
                |x| self.weight(x) * volume,
                WET_WEIGHT,
                pressure,
                touches,
                head,
            );
        }
        self.shared.walls.solids = solids;
    }

    /// The solids in the fluid.
    pub fn solids(&self) -> &[MovingSolid] {
        &self.shared.walls.solids
    }

    /// The solids, to add, remove, re-sample or move: set a solid's pose and velocities with
    /// [`MovingSolid::set_motion`] before a tick; its boundary particles follow through the sub-steps.
    pub fn solids_mut(&mut self) -> &mut Vec<MovingSolid> {
        self.shared.walls.solids_changed();
        &mut self.shared.walls.solids
    }

    /// Sets solid `k`'s pose and velocities ([`MovingSolid::set_motion`]); `false` if they are
    /// not finite or there is no such solid.
    pub fn set_solid_motion(&mut self, k: usize, motion: SolidMotion) -> bool {
        let solids = &mut self.shared.walls.solids;
        solids
            .get_mut(k)
            .is_some_and(|solid| solid.set_motion(motion))
    }

    /// Sets the liquid's contact angle on solid `k`, degrees (`None`: the tank's;
    /// [`MovingSolid::set_contact_angle`]), unless it has it already; `false` if it is out of
    /// range or there is no such solid.
    pub fn set_solid_contact_angle(&mut self, k: usize, degrees: Option<f32>) -> bool {
        let walls = &mut self.shared.walls;
        let Some(solid) = walls.solids.get_mut(k) else {
            return false;
        };
        if solid.contact_angle() == degrees {
            return true;
        }
        let set = solid.set_contact_angle(degrees);
        walls.solids_changed();
        set
    }

    /// Sets how solid `k` answers the fluid within a tick ([`MovingSolid::set_response`]);
    /// `false` if a value is not finite or there is no such solid.
    pub fn set_solid_response(&mut self, k: usize, response: Option<SolidResponse>) -> bool {
        let solids = &mut self.shared.walls.solids;
        solids
            .get_mut(k)
            .is_some_and(|solid| solid.set_response(response))
    }

    /// `Σ W` of the fluid particles of the last sub-step at `x`, 1/m².
    fn weight(&self, x: Vec2) -> f32 {
        let s = &self.shared;
        let mut weight = 0.0f32;
        with_kernels!(s.constants.kernel, s.constants.support, |w, _g| {
            s.snapshot.points.for_each_batch(x, |_, _, _, r2| {
                weight += w.value_sq_x4(r2).element_sum();
            });
        });
        weight
    }

    /// Whether the tick wants another sub-step.
    pub fn wants_substep(&self) -> bool {
        let s = &self.shared;
        s.clock.wants_substep(s.constants.max_substeps)
    }

    /// What [`Stage::Forces`] writes besides accelerations and densities.
    pub fn forces_write(&self) -> ForcesWrite {
        with_solver_type!(&self.solver, |S| S::FORCES_WRITE)
    }

    /// The stages before the step is taken, without the velocity correction and without
    /// advancing time: densities, pressures and accelerations for the current positions and
    /// velocities (for reading a consistent state right after spawning).
    pub fn refresh(&mut self, particles: &mut Particles, parallel: &impl Parallel) {
        let length = StepLength::Free;
        self.stage(Stage::Neighbors, particles, length, parallel);
        let s = &mut self.shared;
        with_solver!(&mut self.solver, |solver| solver
            .density(s, particles, parallel));
        self.stage(Stage::Forces, particles, length, parallel);
    }

    /// The divergence-free solver's state, when it is the solver in use.
    pub fn dfsph(&self) -> Option<&Dfsph> {
        match &self.solver {
            SolverState::Dfsph(dfsph) => Some(dfsph),
            SolverState::Wcsph(_) => None,
        }
    }

    /// Mean number of particles (fluid and wall, the particle itself included) within the
    /// kernel support of each fluid particle, as of the last sub-step.
    pub fn mean_neighbors(&self) -> f64 {
        let s = &self.shared;
        mean_neighbors(&s.constants, &s.snapshot, &s.walls)
    }

    /// One whole sub-step: every [`Stage`] in order. Returns its length, s.
    pub fn substep(
        &mut self,
        particles: &mut Particles,
        length: StepLength,
        parallel: &impl Parallel,
    ) -> f32 {
        for stage in Stage::ALL {
            self.stage(stage, particles, length, parallel);
        }
        self.shared.clock.dt
    }

    /// One stage of a sub-step.
    pub fn stage(
        &mut self,
        stage: Stage,
        particles: &mut Particles,
        length: StepLength,
        parallel: &impl Parallel,
    ) {
        match stage {
            Stage::Neighbors => self.timed(SubstepPart::Neighbors, |step| {
                let s = &mut step.shared;
                let c = s.constants;
                s.walls.place(&c);
                s.snapshot.rebuild(
                    &c,
                    (
                        &particles.position,
                        &particles.velocity,
                        &particles.rest_ratio,
                        &particles.viscosity,
                    ),
                    parallel,
                );
            }),
            Stage::Density => {
                self.timed(SubstepPart::Density, |step| {
                    let s = &mut step.shared;
                    with_solver!(&mut step.solver, |solver| solver
                        .density(s, particles, parallel))
                });
                self.timed(SubstepPart::DivergenceSolve, |step| {
                    let s = &mut step.shared;
                    with_solver!(&mut step.solver, |solver| solver
                        .correct_velocities(s, parallel))
                });
            }
            Stage::Forces => self.timed(SubstepPart::Forces, |step| {
                let s = &mut step.shared;
                with_solver!(&mut step.solver, |solver| solver
                    .forces(s, particles, parallel));
                step.non_pressure_forces(particles, parallel);
            }),
            Stage::Integrate => {
                let dt = self.timed(SubstepPart::Integrate, |step| {
                    step.take_step(particles, length)
                });
                self.timed(SubstepPart::PressureStart, |step| {
                    let s = &mut step.shared;
                    with_solver!(&mut step.solver, |solver| solver
                        .start_pressure(s, particles, dt, parallel))
                });
                self.timed(SubstepPart::GridPressure, |step| {
                    let s = &mut step.shared;
                    with_solver!(&mut step.solver, |solver| solver
                        .grid_pressure(s, dt, parallel))
                });
                self.timed(SubstepPart::DensitySolve, |step| {
                    let s = &mut step.shared;
                    with_solver!(&mut step.solver, |solver| solver
                        .solve_pressure(s, particles, dt, parallel))
                });
                self.timed(SubstepPart::Integrate, |step| {
                    step.integrate(particles, dt, parallel);
                });
                if let Some(profile) = &mut self.shared.profile {
                    profile.count_substep();
                }
            }
        }
    }

    /// The shared non-pressure passes of [`Stage::Forces`] after the solver's: surface tension,
    /// added by sorted slot and to each particle's acceleration.
    fn non_pressure_forces(&mut self, particles: &mut Particles, parallel: &impl Parallel) {
        let s = &mut self.shared;
        let (c, snapshot, walls) = (&s.constants, &s.snapshot, &s.walls);
        let Some(tension) = self.tension.accelerations(c, snapshot, walls, parallel) else {
            return;
        };
        for (a, pull) in s.accelerations.iter_mut().zip(tension) {
            *a += *pull;
        }
        let slot_of = snapshot.grid().slot_of();
        for_each_particle(particles, parallel, |i, p| {
            *p.acceleration += tension[slot_of[i] as usize];
            0
        });
    }

    /// Runs `work`, adding its wall time to `part` of the profile when one is on.
    #[inline]
    fn timed<R>(&mut self, part: SubstepPart, work: impl FnOnce(&mut Self) -> R) -> R {
        let started = self.shared.profile.as_ref().map(StageProfile::now);
        let result = work(self);
        if let (Some(profile), Some(started)) = (&mut self.shared.profile, started) {
            profile.add(part, started);
        }
        result
    }

    /// The step length of [`Stage::Integrate`] from the stability limit (the clock takes it).
    fn take_step(&mut self, particles: &Particles, length: StepLength) -> f32 {
        let s = &mut self.shared;
        let max_acceleration =
            max_length(&particles.acceleration).max(core::mem::take(&mut s.outsider_acceleration));
        let stable = with_solver!(&mut self.solver, |solver| solver
            .step_limit(s, max_acceleration))
        .min(capillary_time_step(&s.constants));
        s.clock.max_acceleration = max_acceleration;
        let empty = particles.is_empty();
        let max_substeps = s.constants.max_substeps;
        match length {
            StepLength::InTick => s.clock.take_substep(stable, max_substeps, empty),
            StepLength::Free => s.clock.take_free_substep(stable),
        }
    }

    /// The move of [`Stage::Integrate`] over `dt`: every particle, the solids' impulses and
    /// their boundary particles.
    fn integrate(&mut self, particles: &mut Particles, dt: f32, parallel: &impl Parallel) {
        let s = &mut self.shared;
        let held_back = with_solver!(&mut self.solver, |solver| {
            let held_back = solver.integrate(s, particles, dt, parallel);
            solver.solid_impulses(s, dt);
            held_back
        });
        s.non_finite += held_back;
        for solid in &mut s.walls.solids {
            solid.advance(dt);
        }
    }

    /// Advances one particle that was not in this sub-step's snapshot (a driver's particle
    /// spawned between stages) by the sub-step's `dt` with its own acceleration. Returns
    /// `false` if the update was held back as not finite.
    pub fn advance_outsider(&self, position: &mut Vec2, velocity: &mut Vec2, a: Vec2) -> bool {
        let s = &self.shared;
        advance_particle(&s.constants, &s.walls, position, velocity, a, s.clock.dt)
    }

    /// The fluid's density, velocity and pressure at `x` (m), interpolated from the particles of
    /// the last sub-step within one kernel support by Shepard's normalised sum; with `head`,
    /// each particle's pressure carried to `x` hydrostatically (as a wall takes it). `None`
    /// where no particle is that close. Returns `(density, velocity, pressure, weight)`, the
    /// weight being `Σ W`.
    pub fn sample(&self, x: Vec2, head: bool) -> Option<(f32, Vec2, f32, f32)> {
        let s = &self.shared;
        let (c, snapshot) = (&s.constants, &s.snapshot);
        if snapshot.is_empty() || !x.is_finite() {
            return None;
        }
        let n = snapshot.len();
        let dfsph = self.dfsph().filter(|dfsph| dfsph.len() == n);
        let at = |slot: usize| -> (f32, f32, Vec2) {
            let [px, py, vx, vy] = snapshot.kinematics[slot];
            let (density, pressure, velocity) = match dfsph {
                Some(dfsph) => (
                    dfsph.density(c, slot),
                    dfsph.pressure(c, slot),
                    dfsph.velocity(slot),
                ),
                None => {
                    let (density, term) = snapshot.pressure.get(slot);
                    (density, term * density * density, Vec2::new(vx, vy))
                }
            };
            let carried = if head {
                density * c.gravity.dot(x - Vec2::new(px, py))
            } else {
                0.0
            };
            (density, pressure + carried, velocity)
        };
        let (mut weight, mut density, mut pressure, mut velocity) =
            (0.0f32, 0.0f32, 0.0f32, Vec2::ZERO);
        with_kernels!(c.kernel, c.support, |w, _g| {
            snapshot.points.for_each_batch(x, |first, _dx, _dy, r2| {
                let values = w.value_sq_x4(r2).to_array();
                for (lane, &value) in values.iter().enumerate() {
                    let slot = first + lane;
                    if value > 0.0 && slot < n {
                        let (rho, p, v) = at(slot);
                        weight += value;
                        density += value * rho;
                        pressure += value * p;
                        velocity += value * v;
                    }
                }
            });
        });
        (weight > 0.0).then(|| {
            (
                density / weight,
                velocity / weight,
                pressure / weight,
                weight,
            )
        })
    }
}

/// One particle's values in [`Particles`], for a pass that writes several of them.
pub(crate) struct ParticleMut<'a> {
    pub position: &'a mut Vec2,
    pub velocity: &'a mut Vec2,
    pub acceleration: &'a mut Vec2,
    pub density: &'a mut f32,
    pub pressure: &'a mut f32,
    pub stiffness: &'a mut Vec2,
}

/// Runs `work(index, particle)` for every particle, in parallel chunks of [`CHUNK`], and returns
/// the sum of what it returns (a count), the same on any number of threads: one pass however
/// many of a particle's values it writes.
pub(crate) fn for_each_particle(
    particles: &mut Particles,
    parallel: &impl Parallel,
    work: impl Fn(usize, ParticleMut<'_>) -> u64 + Sync,
) -> u64 {
    let n = particles.len();
    let p = particles;
    let mut jobs: Vec<_> = p
        .position
        .chunks_mut(CHUNK)
        .zip(p.velocity.chunks_mut(CHUNK))
        .zip(p.acceleration.chunks_mut(CHUNK))
        .zip(p.density.chunks_mut(CHUNK))
        .zip(p.pressure.chunks_mut(CHUNK))
        .zip(p.stiffness.chunks_mut(CHUNK))
        .enumerate()
        .map(|(k, (((((x, v), a), rho), pressure), stiffness))| {
            (k * CHUNK, (x, v, a, rho, pressure, stiffness), 0u64)
        })
        .collect();
    run_jobs(
        parallel,
        n,
        &mut jobs,
        |(start, (x, v, a, rho, p, k), count)| {
            let rows = x.iter_mut().zip(v.iter_mut()).zip(a.iter_mut());
            let rows = rows.zip(rho.iter_mut()).zip(p.iter_mut()).zip(k.iter_mut());
            for (j, (((((x, v), a), rho), p), k)) in rows.enumerate() {
                let particle = ParticleMut {
                    position: x,
                    velocity: v,
                    acceleration: a,
                    density: rho,
                    pressure: p,
                    stiffness: k,
                };
                *count += work(*start + j, particle);
            }
        },
    );
    jobs.iter().map(|job| job.2).sum()
}
