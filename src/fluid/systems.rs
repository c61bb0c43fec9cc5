//! The fluid's ECS systems: thin glue that gathers particles into the solver's cell-sorted
//! snapshot, runs the solvers' passes over it by sorted slot in parallel regions
//! ([`compute::region`](crate::compute::region)), and copies the results into the components.
//! See [`SphPlugin`](crate::fluid::SphPlugin) for the schedule they run in.

use super::SphSubstep;
use super::boundary::Obstacle;
use super::clock::SubstepClock;
use super::components::{
    Acceleration, Density, FluidParticle, NeighborSlot, Position, Pressure, Stiffness, Velocity,
};
use super::dfsph::Dfsph;
use super::dfsph::divergence_step;
use super::layout::{FluidSnapshot, NeighborList, Walls};
use super::parallel::{PARALLEL_SLOTS, Parallel, Rayon, Sequential, for_each_slot};
use super::params::{PressureSolver, SphParams, SphParamsError};
use super::solver::{
    SphConstants, advance_particle, density_and_neighbors_at, move_particle, with_kernels,
};
use super::wcsph::{acceleration_at, pressure_from_density, stable_time_step, wall_state_at};
use bevy::ecs::batching::BatchingStrategy;
use bevy::ecs::query::QueryItem;
use bevy::platform::time::Instant;
use bevy::prelude::*;
use core::sync::atomic::{AtomicU32, Ordering};

/// Smallest amount of per-particle work worth a task of its own: below it, waking a thread
/// costs more than it saves.
const MIN_PARALLEL_CHUNK: usize = 1024;

/// One batch per thread: each task Bevy's pool starts costs more than the unevenness it would
/// even out (measured with the `bench` example, WCSPH, 2 threads: at 2,520 particles a
/// sub-step took 0.52 ms with eight batches per thread and 0.47 ms with one; at 100,000 the
/// same).
const BATCHING: BatchingStrategy = BatchingStrategy {
    batch_size_limits: MIN_PARALLEL_CHUNK..usize::MAX,
    batches_per_thread: 1,
};

/// Fewest particles whose passes over components (copying solver results into them,
/// integration) run in parallel on Bevy's pool: these passes are light, and at the demo's 2,500
/// particles running them in parallel made the DFSPH dam break 8% slower.
pub const MIN_PARALLEL_LIGHT_PARTICLES: usize = 8192;

/// Runs `$work` over `$query`'s items, in parallel batches from
/// [`MIN_PARALLEL_LIGHT_PARTICLES`] particles (`$n`) on, on the calling thread below.
macro_rules! for_each_particle {
    ($query:expr, $n:expr, $data:ty, $work:expr) => {{
        let work = |item: QueryItem<'_, '_, $data>| ($work)(item);
        if $n < MIN_PARALLEL_LIGHT_PARTICLES {
            $query.iter_mut().for_each(work);
        } else {
            $query
                .par_iter_mut()
                .batching_strategy(BATCHING)
                .for_each(work);
        }
    }};
}

/// The solver's working state: derived constants, the neighbour snapshot, the wall particles
/// and the sub-step clock. Read it for diagnostics; the systems own it.
#[derive(Resource, Debug, Clone)]
pub struct SphSolver {
    constants: SphConstants,
    snapshot: FluidSnapshot,
    walls: Walls,
    walls_dirty: bool,
    dfsph: Dfsph,
    gathered_position: Vec<Vec2>,
    gathered_velocity: Vec<Vec2>,
    gathered_stiffness: Vec<Vec2>,
    /// WCSPH: each particle's fluid neighbours by sorted slot, from the density pass.
    neighbor_lists: Vec<NeighborList>,
    /// Accelerations by sorted slot from the force pass (DFSPH: without pressure).
    accelerations: Vec<Vec2>,
    clock: SubstepClock,
    iterations: SolverIterations,
    /// Counts snapshot rebuilds; [`NeighborSlot`]s carry the one they were assigned in.
    generation: u32,
    non_finite: u64,
    /// Particles the guard removed for a non-finite state, and for leaving the tank.
    removed_non_finite: u64,
    removed_escaped: u64,
}

impl Default for SphSolver {
    fn default() -> Self {
        Self::new(
            SphParams::default()
                .constants()
                .expect("the default parameters are valid"),
        )
    }
}

impl SphSolver {
    fn new(constants: SphConstants) -> Self {
        Self {
            constants,
            snapshot: FluidSnapshot::default(),
            walls: Walls::default(),
            walls_dirty: true,
            dfsph: Dfsph::default(),
            gathered_position: Vec::new(),
            gathered_velocity: Vec::new(),
            gathered_stiffness: Vec::new(),
            neighbor_lists: Vec::new(),
            accelerations: Vec::new(),
            clock: SubstepClock::default(),
            iterations: SolverIterations::default(),
            generation: 0,
            non_finite: 0,
            removed_non_finite: 0,
            removed_escaped: 0,
        }
    }

    /// The constants in use: those of the last valid [`SphParams`].
    pub fn constants(&self) -> &SphConstants {
        &self.constants
    }

    /// The cell-sorted snapshot of the last sub-step.
    pub(crate) fn snapshot(&self) -> &FluidSnapshot {
        &self.snapshot
    }

    /// The sub-step clock.
    pub fn clock(&self) -> &SubstepClock {
        &self.clock
    }

    /// DFSPH iteration counts.
    pub fn iterations(&self) -> &SolverIterations {
        &self.iterations
    }

    /// The divergence-free solver's state of the last sub-step.
    pub(crate) fn dfsph(&self) -> &Dfsph {
        &self.dfsph
    }

    /// What the last DFSPH sub-step's solves did.
    pub fn dfsph_report(&self) -> &super::dfsph::DfsphReport {
        &self.dfsph.report
    }

    /// The particle's slot in this sub-step's DFSPH state, if it was in the snapshot (a particle
    /// spawned since has none).
    fn dfsph_slot(&self, slot: &NeighborSlot) -> Option<usize> {
        let index = slot.slot as usize;
        (slot.generation == self.generation && index < self.dfsph.len()).then_some(index)
    }

    /// The particle's slot in this sub-step's snapshot, if it was in it.
    fn snapshot_slot(&self, slot: &NeighborSlot) -> Option<usize> {
        let index = slot.slot as usize;
        (slot.generation == self.generation && index < self.snapshot.len()).then_some(index)
    }

    /// Puts the clock where a saved run left it (see [`load_fluid`](super::load_fluid)).
    pub(crate) fn restore_clock(&mut self, clock: SubstepClock) {
        self.clock = clock;
    }

    /// Starts simulated time again from zero (after a reset).
    pub fn restart_clock(&mut self) {
        self.clock = SubstepClock::default();
        self.iterations = SolverIterations::default();
    }
}

/// DFSPH iterations counted over ticks.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverIterations {
    /// Density-solve iterations in the current (or last) tick.
    pub density: u32,
    /// Divergence-solve iterations in the current (or last) tick.
    pub divergence: u32,
    /// Iterations of both solves since start-up.
    pub total: u64,
}

/// Whether the last change to [`SphParams`] was accepted (`error`: why not).
pub type SphParamsStatus = crate::params::ParamsStatus<SphParams>;

/// Statistics of the last fixed tick, for panels and logs.
#[derive(Resource, Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct SphStats {
    /// Fluid particles.
    pub particles: usize,
    /// Wall particles of the tank and obstacles.
    pub wall_particles: usize,
    /// Sub-steps in the last tick.
    pub substeps: u32,
    /// Sub-steps since start-up (or the last reset).
    pub total_substeps: u64,
    /// Length of the last sub-step, s.
    pub dt: f32,
    /// Simulated time, s.
    pub time: f64,
    /// Simulated time dropped because a tick needed more than `max_substeps`, s.
    pub dropped_time: f64,
    /// Wall-clock time the last tick's sub-steps took, ms.
    pub tick_ms: f32,
    /// Fastest particle, m/s.
    pub max_speed: f32,
    /// Largest compression `(ρ − ρ₀)/ρ₀`, % (free-surface particles read below `ρ₀` by design of
    /// summation density, so only compression counts as error).
    pub max_density_error: f32,
    /// Mean compression over all particles, %.
    pub mean_density_error: f32,
    /// Particle updates that would have produced a non-finite value and were held back (should
    /// stay zero).
    pub non_finite_resets: u64,
    /// Particles the stability guard removed because their state was not finite (since
    /// start-up; should stay zero).
    pub removed_non_finite: u64,
    /// Particles the guard removed because they were outside the tank (since start-up).
    pub removed_escaped: u64,
    /// Whether the last tick needed more sub-steps than `max_substeps` allows, so the fluid ran
    /// in slow motion (see `dropped_time`).
    pub slow_motion: bool,
    /// The pressure solver in use.
    pub solver: PressureSolver,
    /// DFSPH density-solve iterations in the last tick (all its sub-steps).
    pub density_iterations: u32,
    /// DFSPH divergence-solve iterations in the last tick.
    pub divergence_iterations: u32,
    /// DFSPH iterations of both solves since start-up (or the last reset).
    pub total_iterations: u64,
    /// Mean predicted compression left by the last density solve, %.
    pub solver_density_error: f32,
}

impl crate::params::Params for SphParams {
    type Solver = SphSolver;
    const WHAT: &'static str = "the fluid";

    /// Derives the constants and re-samples the walls if the geometry changed.
    fn adopt(&self, solver: &mut SphSolver) -> Result<(), SphParamsError> {
        let constants = self.constants()?;
        let old = solver.constants;
        let geometry_changed = old.tank != constants.tank
            || old.spacing != constants.spacing
            || old.support != constants.support
            || old.wall_layers != constants.wall_layers;
        solver.constants = constants;
        if geometry_changed {
            solver.walls_dirty = true;
        }
        Ok(())
    }
}

/// The stability guard, before each tick's sub-steps: despawns every particle whose position or
/// velocity is not finite, or that lies outside the tank by more than a spacing (a game's own
/// system put it there), with a warning naming the cause, and counts them in [`SphStats`], so
/// one bad particle never reaches its neighbours' sums. The solver itself never produces such a
/// particle (it holds back an update that would), so this changes nothing in a stable run.
pub(crate) fn guard_particles(
    mut commands: Commands,
    mut solver: ResMut<SphSolver>,
    particles: Query<(Entity, &Position, &Velocity), With<FluidParticle>>,
) {
    let c = solver.constants;
    let margin = c.spacing;
    let (mut non_finite, mut escaped) = (0u64, 0u64);
    for (entity, position, velocity) in &particles {
        let cause = if !position.is_finite() || !velocity.is_finite() {
            non_finite += 1;
            "not finite"
        } else if c.tank.is_some_and(|tank| {
            let p = position.0;
            p.x < -margin
                || p.y < -margin
                || p.x > tank.width + margin
                || p.y > tank.height + margin
        }) {
            escaped += 1;
            "outside the tank"
        } else {
            continue;
        };
        if non_finite + escaped <= 3 {
            warn!(
                "fluid particle {entity} at position {} with velocity {}: {cause}, removed",
                position.0, velocity.0
            );
        }
        commands.entity(entity).despawn();
    }
    if non_finite + escaped > 3 {
        warn!(
            "{} more fluid particles removed this tick",
            non_finite + escaped - 3
        );
    }
    if non_finite + escaped > 0 {
        solver.removed_non_finite += non_finite;
        solver.removed_escaped += escaped;
    }
}

/// Re-samples the wall particles when the tank, spacing or obstacles change.
pub(crate) fn rebuild_walls(
    mut solver: ResMut<SphSolver>,
    obstacles: Query<&Obstacle>,
    changed: Query<(), Changed<Obstacle>>,
    mut removed: RemovedComponents<Obstacle>,
) {
    let removed_any = removed.read().count() > 0;
    if !(solver.walls_dirty || removed_any || !changed.is_empty()) {
        return;
    }
    let list: Vec<Obstacle> = obstacles.iter().copied().collect();
    for obstacle in list.iter().filter(|o| !o.is_valid()) {
        warn!("ignoring obstacle {obstacle:?}: coordinates must be finite and radii positive");
    }
    let solver = &mut *solver;
    solver.walls.rebuild(&solver.constants, &list);
    solver.walls_dirty = false;
}

/// Recomputes density, pressure, wall pressure and acceleration of every particle from the
/// current positions and velocities, without advancing time: for reading a consistent state
/// right after spawning (the solver otherwise computes them during the next sub-step).
pub fn refresh_fluid_state(world: &mut World) {
    let mut results = vec![
        world.run_system_cached(crate::params::apply_params::<SphParams>),
        world.run_system_cached(guard_particles),
        world.run_system_cached(rebuild_walls),
        world.run_system_cached(build_neighbor_grid),
    ];
    match world.resource::<SphSolver>().constants.solver {
        PressureSolver::Wcsph => results.extend([
            world.run_system_cached(compute_density),
            world.run_system_cached(compute_forces),
        ]),
        PressureSolver::Dfsph => results.extend([
            world.run_system_cached(prepare_dfsph),
            world.run_system_cached(compute_dfsph_forces),
        ]),
    }
    for error in results.into_iter().filter_map(Result::err) {
        error!("refresh_fluid_state: {error}");
    }
}

/// Splits the tick into stable sub-steps and runs [`SphSubstep`] once for each.
pub(crate) fn run_substeps(world: &mut World) {
    let tick = world.resource::<Time>().delta_secs_f64();
    if tick <= 0.0 {
        return;
    }
    let started = Instant::now();
    {
        let mut solver = world.resource_mut::<SphSolver>();
        solver.clock.begin_tick(tick);
        solver.iterations.density = 0;
        solver.iterations.divergence = 0;
    }
    loop {
        let solver = world.resource::<SphSolver>();
        if !solver.clock.wants_substep(solver.constants.max_substeps) {
            break;
        }
        world.run_schedule(SphSubstep);
    }
    world.resource_mut::<SphSolver>().clock.end_tick();
    world.resource_mut::<SphStats>().tick_ms = started.elapsed().as_secs_f32() * 1000.0;
}

/// [`SphSubstepSystems::Neighbors`](super::SphSubstepSystems::Neighbors): copies positions and
/// velocities into the cell-sorted snapshot and tells each particle its slot.
pub(crate) fn build_neighbor_grid(
    mut solver: ResMut<SphSolver>,
    mut particles: Query<
        (&Position, &Velocity, &Stiffness, &mut NeighborSlot),
        With<FluidParticle>,
    >,
) {
    let solver = &mut *solver;
    let (positions, velocities) = (&mut solver.gathered_position, &mut solver.gathered_velocity);
    let stiffnesses = &mut solver.gathered_stiffness;
    positions.clear();
    velocities.clear();
    stiffnesses.clear();
    let dfsph = solver.constants.solver == PressureSolver::Dfsph;
    // Whole table columns at a time where the storage allows (it always does for the
    // required components); item by item otherwise. Both visit entities in the same order.
    match particles.contiguous_iter() {
        Ok(tables) => {
            for (p, v, k, _) in tables {
                positions.extend(p.iter().map(|p| p.0));
                velocities.extend(v.iter().map(|v| v.0));
                if dfsph {
                    stiffnesses.extend(k.iter().map(|k| k.0));
                }
            }
        }
        Err(_) => {
            for (p, v, k, _) in &particles {
                positions.push(p.0);
                velocities.push(v.0);
                if dfsph {
                    stiffnesses.push(k.0);
                }
            }
        }
    }
    let (snapshot, c) = (&mut solver.snapshot, &solver.constants);
    let (positions, velocities) = (&solver.gathered_position, &solver.gathered_velocity);
    slot_region(positions.len(), |passes| {
        snapshot.rebuild(c, positions, velocities, &passes);
    });
    // Same query, same system, no structural change in between: the same order as above.
    // Generation 0 marks particles that never had a slot.
    solver.generation = solver.generation.wrapping_add(1).max(1);
    let generation = solver.generation;
    let mut slots = solver.snapshot.grid().slot_of();
    match particles.contiguous_iter_mut() {
        Ok(tables) => {
            for (_, _, _, mut table) in tables {
                let (here, rest) = slots.split_at(table.len());
                for (slot, &s) in table.iter_mut().zip(here) {
                    *slot = NeighborSlot {
                        slot: s,
                        generation,
                    };
                }
                slots = rest;
            }
        }
        Err(_) => {
            for ((_, _, _, mut slot), &s) in particles.iter_mut().zip(slots) {
                *slot = NeighborSlot {
                    slot: s,
                    generation,
                };
            }
        }
    }
}

/// [`SphSubstepSystems::Density`](super::SphSubstepSystems::Density) for WCSPH: summed density
/// and the equation of state by sorted slot, stored in the snapshot for the force pass (with
/// each particle's fluid neighbours, which the force pass reuses), then the wall particles'
/// pressure extrapolated from the fluid; one parallel region (see [`slot_region`]).
pub(crate) fn compute_density(mut solver: ResMut<SphSolver>) {
    let solver = &mut *solver;
    let c = solver.constants;
    let n = solver.snapshot.len();
    solver.neighbor_lists.resize(n, NeighborList::default());
    let (snapshot, walls, lists) = (
        &solver.snapshot,
        &mut solver.walls,
        &mut solver.neighbor_lists,
    );
    with_kernels!(c.kernel, c.support, |w, _g| {
        slot_region(n, |passes| {
            let walls_ref = &*walls;
            for_each_slot(lists, &passes, |slot, list| {
                let x = snapshot.points.get(slot);
                let rho = density_and_neighbors_at(&w, &c, x, snapshot, walls_ref, list);
                snapshot.set_pressure(slot, rho, pressure_from_density(&c, rho));
                0.0
            });
            walls.update_pressure(|states, points| {
                for_each_slot(states, &passes, |slot, state| {
                    *state = wall_state_at(&w, &c, points.get(slot), snapshot);
                    0.0
                });
            });
        });
    });
}

/// What the WCSPH force pass writes per particle.
type ForceData = (
    &'static NeighborSlot,
    &'static mut Density,
    &'static mut Pressure,
    &'static mut Acceleration,
);

/// [`SphSubstepSystems::Forces`](super::SphSubstepSystems::Forces) for WCSPH: pressure,
/// viscosity and gravity by sorted slot in one parallel region, then each particle's
/// [`Density`], [`Pressure`] and [`Acceleration`] (overwritten; add your own forces after it).
pub(crate) fn compute_forces(
    mut solver: ResMut<SphSolver>,
    mut particles: Query<ForceData, With<FluidParticle>>,
) {
    let solver = &mut *solver;
    let c = solver.constants;
    let n = solver.snapshot.len();
    solver.accelerations.resize(n, Vec2::ZERO);
    let (snapshot, walls, lists) = (&solver.snapshot, &solver.walls, &solver.neighbor_lists);
    let accelerations = &mut solver.accelerations;
    with_kernels!(c.kernel, c.support, |_w, g| {
        slot_region(n, |passes| {
            for_each_slot(accelerations, &passes, |slot, a| {
                let [x, y, vx, vy] = snapshot.kinematics[slot];
                let rho = snapshot.pressure.get(slot).0;
                let p = pressure_from_density(&c, rho);
                *a = acceleration_at(
                    &g,
                    &c,
                    Vec2::new(x, y),
                    Vec2::new(vx, vy),
                    rho,
                    p,
                    &lists[slot],
                    snapshot,
                    walls,
                );
                0.0
            });
        });
    });
    let solver = &*solver;
    for_each_particle!(particles, n, ForceData, |(
        slot,
        mut density,
        mut pressure,
        mut acceleration,
    ): QueryItem<
        '_,
        '_,
        ForceData,
    >| {
        if let Some(slot) = solver.snapshot_slot(slot) {
            let rho = solver.snapshot.pressure.get(slot).0;
            density.0 = rho;
            pressure.0 = pressure_from_density(&c, rho);
            acceleration.0 = solver.accelerations[slot];
        } else {
            acceleration.0 = c.gravity;
        }
    });
}

/// Picks the WCSPH sub-step length from the stability limits and what is left of the tick.
pub(crate) fn choose_time_step(
    mut solver: ResMut<SphSolver>,
    particles: Query<&Acceleration, With<FluidParticle>>,
) {
    let max_acceleration = max_acceleration(&particles);
    let solver = &mut *solver;
    let c = solver.constants;
    let stable = stable_time_step(&c, solver.snapshot.max_speed, max_acceleration);
    solver.clock.max_acceleration = max_acceleration;
    solver
        .clock
        .take_substep(stable, c.max_substeps, solver.snapshot.is_empty());
}

fn max_acceleration(particles: &Query<&Acceleration, With<FluidParticle>>) -> f32 {
    particles
        .iter()
        .fold(0.0f32, |m, a| m.max(a.length_squared()))
        .sqrt()
}

/// What the WCSPH integration reads and writes per particle.
type MoveData = (
    &'static mut Position,
    &'static mut Velocity,
    &'static Acceleration,
);

/// [`SphSubstepSystems::Integrate`](super::SphSubstepSystems::Integrate) for WCSPH: symplectic
/// Euler, walls and obstacles, per particle.
pub(crate) fn integrate_particles(
    mut solver: ResMut<SphSolver>,
    mut particles: Query<MoveData, With<FluidParticle>>,
) {
    let non_finite = AtomicU32::new(0);
    {
        let solver = &*solver;
        let c = solver.constants;
        let dt = solver.clock.dt;
        let obstacles = &solver.walls.obstacles;
        for_each_particle!(
            particles,
            solver.snapshot.len(),
            MoveData,
            |(mut position, mut velocity, acceleration): QueryItem<'_, '_, MoveData>| {
                if !advance_particle(
                    &c,
                    obstacles,
                    &mut position.0,
                    &mut velocity.0,
                    acceleration.0,
                    dt,
                ) {
                    non_finite.fetch_add(1, Ordering::Relaxed);
                }
            }
        );
    }
    solver.non_finite += non_finite.into_inner() as u64;
}

/// [`SphSubstepSystems::Density`](super::SphSubstepSystems::Density) for DFSPH: caches
/// neighbours and gradients, sums densities.
pub(crate) fn prepare_dfsph(mut solver: ResMut<SphSolver>) {
    let solver = &mut *solver;
    let c = solver.constants;
    let (order, stiffness) = (solver.snapshot.grid().order(), &solver.gathered_stiffness);
    let (dfsph, snapshot, walls) = (&mut solver.dfsph, &solver.snapshot, &solver.walls);
    slot_region(snapshot.len(), |passes| {
        dfsph.prepare(
            &c,
            snapshot,
            walls,
            |slot| stiffness[order[slot] as usize],
            &passes,
        )
    });
}

/// Where a step's slot passes run (a [`Parallel`]): in a [`compute::region`](crate::compute::region), or on the calling
/// thread.
#[derive(Debug, Clone, Copy)]
enum Passes {
    Region,
    Here,
}

impl Parallel for Passes {
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F) {
        match self {
            Self::Region => Rayon.for_each(items, work),
            Self::Here => Sequential.for_each(items, work),
        }
    }
}

/// Runs `work`, a step of slot passes over `n` particles, in a
/// [`compute::region`](crate::compute::region) from
/// [`PARALLEL_SLOTS`] particles on with more than one compute thread, on the calling thread
/// otherwise (where handing the step to another thread costs and gains nothing).
fn slot_region<R: Send>(n: usize, work: impl FnOnce(Passes) -> R + Send) -> R {
    if n < PARALLEL_SLOTS || crate::compute::threads() <= 1 {
        work(Passes::Here)
    } else {
        crate::compute::region(|| work(Passes::Region))
    }
}

/// [`SphSubstepSystems::Density`](super::SphSubstepSystems::Density) for DFSPH, after
/// [`prepare_dfsph`]: makes the velocity field divergence-free.
pub(crate) fn solve_divergence(mut solver: ResMut<SphSolver>) {
    let solver = &mut *solver;
    let c = solver.constants;
    let dt = divergence_step(&solver.clock, &c, solver.snapshot.max_speed);
    let dfsph = &mut solver.dfsph;
    let iterations = slot_region(dfsph.len(), |passes| {
        dfsph.solve_divergence(&c, dt, &passes)
    });
    solver.iterations.divergence += iterations;
    solver.iterations.total += iterations as u64;
}

/// What the DFSPH force pass reads and writes per particle.
type DfsphForceData = (
    &'static NeighborSlot,
    &'static mut Velocity,
    &'static mut Density,
    &'static mut Acceleration,
);

/// [`SphSubstepSystems::Forces`](super::SphSubstepSystems::Forces) for DFSPH: takes the
/// divergence-free velocity and the density, and sets [`Acceleration`] to gravity and viscosity
/// (pressure comes from the density solve in `Integrate`, after your external forces).
pub(crate) fn compute_dfsph_forces(
    mut solver: ResMut<SphSolver>,
    mut particles: Query<DfsphForceData, With<FluidParticle>>,
) {
    let solver = &mut *solver;
    let c = solver.constants;
    let n = solver.dfsph.len();
    solver.accelerations.resize(n, Vec2::ZERO);
    let (dfsph, snapshot) = (&solver.dfsph, &solver.snapshot);
    let accelerations = &mut solver.accelerations;
    slot_region(n, |passes| {
        for_each_slot(accelerations, &passes, |slot, a| {
            *a = dfsph.non_pressure_acceleration(&c, snapshot, slot);
            0.0
        });
    });
    let solver = &*solver;
    let dfsph = &solver.dfsph;
    for_each_particle!(particles, n, DfsphForceData, |(
        slot,
        mut velocity,
        mut density,
        mut acceleration,
    ): QueryItem<
        '_,
        '_,
        DfsphForceData,
    >| {
        if let Some(slot) = solver.dfsph_slot(slot) {
            velocity.0 = dfsph.velocity(slot);
            density.0 = dfsph.density(&c, slot);
            acceleration.0 = solver.accelerations[slot];
        } else {
            acceleration.0 = c.gravity;
        }
    });
}

/// [`SphSubstepSystems::Integrate`](super::SphSubstepSystems::Integrate) for DFSPH: takes every
/// particle's acceleration (external forces included), picks the step from the flow's CFL and
/// the force limits, and solves for the pressure that keeps the density at rest.
pub(crate) fn solve_density(
    mut solver: ResMut<SphSolver>,
    particles: Query<(&NeighborSlot, &Acceleration), With<FluidParticle>>,
) {
    let solver = &mut *solver;
    let c = solver.constants;
    let mut max_sq = 0.0f32;
    for (slot, acceleration) in &particles {
        if let Some(slot) = solver.dfsph_slot(slot) {
            solver.dfsph.set_acceleration(slot, acceleration.0);
        }
        max_sq = max_sq.max(acceleration.length_squared());
    }
    let max_acceleration = max_sq.sqrt();
    let stable = solver.dfsph.stable_time_step(&c, max_acceleration);
    solver.clock.max_acceleration = max_acceleration;
    let dt = solver
        .clock
        .take_substep(stable, c.max_substeps, solver.snapshot.is_empty());
    let dfsph = &mut solver.dfsph;
    let iterations = slot_region(dfsph.len(), |passes| dfsph.solve_density(&c, dt, &passes));
    solver.iterations.density += iterations;
    solver.iterations.total += iterations as u64;
}

/// What the DFSPH integration reads and writes per particle.
type DfsphMoveData = (
    &'static NeighborSlot,
    &'static mut Position,
    &'static mut Velocity,
    &'static mut Pressure,
    &'static mut Stiffness,
    &'static Acceleration,
);

/// [`SphSubstepSystems::Integrate`](super::SphSubstepSystems::Integrate) for DFSPH, after
/// [`solve_density`]: moves each particle with its solved velocity, keeps it in the tank and out
/// of obstacles, and stores its pressure and stiffness.
pub(crate) fn integrate_dfsph(
    mut solver: ResMut<SphSolver>,
    mut particles: Query<DfsphMoveData, With<FluidParticle>>,
) {
    let non_finite = AtomicU32::new(0);
    {
        let solver = &*solver;
        let c = solver.constants;
        let dt = solver.clock.dt;
        let (dfsph, obstacles) = (&solver.dfsph, &solver.walls.obstacles);
        for_each_particle!(
            particles,
            solver.snapshot.len(),
            DfsphMoveData,
            |(slot, mut position, mut velocity, mut pressure, mut stiffness, acceleration): QueryItem<
                '_,
                '_,
                DfsphMoveData,
            >| {
                let moved = if let Some(slot) = solver.dfsph_slot(slot) {
                    pressure.0 = dfsph.pressure(&c, slot);
                    stiffness.0 = dfsph.stiffness(slot);
                    let v = dfsph.velocity(slot);
                    move_particle(&c, obstacles, &mut position.0, &mut velocity.0, v, dt)
                } else {
                    advance_particle(
                        &c,
                        obstacles,
                        &mut position.0,
                        &mut velocity.0,
                        acceleration.0,
                        dt,
                    )
                };
                if !moved {
                    non_finite.fetch_add(1, Ordering::Relaxed);
                }
            }
        );
    }
    solver.non_finite += non_finite.into_inner() as u64;
}

/// Whether the fluid runs on `solver` (a run condition for the solver-specific systems).
pub(crate) fn uses_solver(solver: PressureSolver) -> impl Fn(Res<SphSolver>) -> bool + Clone {
    move |state: Res<SphSolver>| state.constants.solver == solver
}

/// Fills [`SphStats`] after the tick.
pub(crate) fn update_stats(
    solver: Res<SphSolver>,
    particles: Query<(&Velocity, &Density), With<FluidParticle>>,
    mut stats: ResMut<SphStats>,
) {
    let rest = solver.constants.rest_density;
    let mut count = 0usize;
    let mut max_speed_sq = 0.0f32;
    let mut max_error = 0.0f32;
    let mut sum_error = 0.0f64;
    for (velocity, density) in &particles {
        count += 1;
        max_speed_sq = max_speed_sq.max(velocity.length_squared());
        let error = (density.0 / rest - 1.0).max(0.0);
        max_error = max_error.max(error);
        sum_error += error as f64;
    }
    let clock = solver.clock;
    *stats = SphStats {
        particles: count,
        wall_particles: solver.walls.len(),
        substeps: clock.substeps,
        total_substeps: clock.total_substeps,
        dt: clock.dt,
        time: clock.time,
        dropped_time: clock.dropped,
        tick_ms: stats.tick_ms,
        max_speed: max_speed_sq.sqrt(),
        max_density_error: 100.0 * max_error,
        mean_density_error: if count > 0 {
            (100.0 * sum_error / count as f64) as f32
        } else {
            0.0
        },
        non_finite_resets: solver.non_finite,
        removed_non_finite: solver.removed_non_finite,
        removed_escaped: solver.removed_escaped,
        slow_motion: clock.dropped > stats.dropped_time,
        solver: solver.constants.solver,
        density_iterations: solver.iterations.density,
        divergence_iterations: solver.iterations.divergence,
        total_iterations: solver.iterations.total,
        solver_density_error: 100.0 * solver.dfsph.report.density_error,
    };
}
