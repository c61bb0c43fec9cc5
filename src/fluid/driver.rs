//! [`SphSystems::Simulate`](super::SphSystems::Simulate): the ECS driver of the core's one
//! sub-step order ([`sim::step`](crate::sim::step)).
//!
//! Each tick [`run_substeps`] splits the tick into stable sub-steps. Where no game system runs
//! inside [`SphSubstep`] (only the fluid's own stage systems are there), it copies the
//! components into the solver's [`Particles`] once, runs every sub-step on them, and copies
//! the results back once. Where a game's systems hook in between the stages (gravity on fluid
//! particles, the mouse tools, a game's own forces), it runs the [`SphSubstep`] schedule once per
//! sub-step: its stage systems call the same stages one by one, copying in what the stages read
//! (positions, velocities, stiffnesses; the accelerations after the hooks) and out what they
//! write, so the hooks read and write current values. Particles learn their index only when the
//! gathering changes (a particle spawned, despawned or moved since the last one).

use super::components::{
    Acceleration, Density, FluidIndex, FluidParticle, Position, Pressure, Stiffness, Velocity,
};
use super::liquids::{FluidMaterial, LiquidConstants};
use super::resources::{SphSolver, SphStats};
use crate::schedule::{SphSubstep, SphSubstepSystems};
use crate::sim::parallel::{PARALLEL_SLOTS, Parallel, Rayon, Sequential};
use crate::sim::step::{Particles, Stage, StepLength};
use bevy::ecs::query::QueryData;
use bevy::platform::time::Instant;
use bevy::prelude::*;

/// What the driver copies between a particle's components and the solver's [`Particles`].
#[derive(QueryData)]
#[query_data(mutable)]
pub(crate) struct FluidData {
    position: &'static mut Position,
    velocity: &'static mut Velocity,
    acceleration: &'static mut Acceleration,
    density: &'static mut Density,
    pressure: &'static mut Pressure,
    stiffness: &'static mut Stiffness,
    /// Which liquid (read only: the solver takes its rest density ratio).
    material: Option<&'static FluidMaterial>,
}

/// The fluid's state components, with the particle's gathered index.
type IndexedData = (&'static mut FluidIndex, FluidData);

/// The fluid's state components, with the particle's gathered index to read.
type WriteData = (&'static FluidIndex, FluidData);

impl FluidDataItem<'_, '_> {
    /// Takes particle `i`'s values from `particles`.
    fn set(&mut self, particles: &Particles, i: usize) {
        self.position.0 = particles.position[i];
        self.velocity.0 = particles.velocity[i];
        self.acceleration.0 = particles.acceleration[i];
        self.density.0 = particles.density[i];
        self.pressure.0 = particles.pressure[i];
        self.stiffness.0 = particles.stiffness[i];
    }
}

impl FluidDataReadOnlyItem<'_, '_> {
    /// Writes its values into `particles` at `i`.
    fn put(&self, particles: &mut Particles, i: usize) {
        particles.position[i] = self.position.0;
        particles.velocity[i] = self.velocity.0;
        particles.acceleration[i] = self.acceleration.0;
        particles.density[i] = self.density.0;
        particles.pressure[i] = self.pressure.0;
        particles.stiffness[i] = self.stiffness.0;
    }
}

impl SphSolver {
    /// Copies every particle's components into the solver's particles, in query order, as a
    /// new gathering (a [`FluidIndex`] given before it is stale).
    fn gather<'w, 's>(
        &mut self,
        items: impl ExactSizeIterator<Item = FluidDataReadOnlyItem<'w, 's>>,
    ) {
        self.generation = self.generation.wrapping_add(1).max(1);
        self.particles.resize(items.len());
        self.particles.rest_ratio.clear();
        self.particles.viscosity.clear();
        for (i, item) in items.enumerate() {
            item.put(&mut self.particles, i);
            note_liquid(&mut self.particles, &self.liquids, i, item.material);
        }
    }
}

/// Where a stage's slot passes run (a [`Parallel`]): in a
/// [`compute::region`](crate::compute::region), or on the calling thread.
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

    fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA + Send,
        B: FnOnce() -> RB + Send,
        RA: Send,
        RB: Send,
    {
        match self {
            Self::Region => Rayon.join(a, b),
            Self::Here => Sequential.join(a, b),
        }
    }
}

/// Runs `work` over `n` particles in a [`compute::region`](crate::compute::region) from
/// [`PARALLEL_SLOTS`] particles on with more than one compute thread, on the calling thread
/// otherwise (where handing the work to another thread costs and gains nothing).
fn slot_region<R: Send>(n: usize, work: impl FnOnce(Passes) -> R + Send) -> R {
    if n < PARALLEL_SLOTS || crate::compute::threads() <= 1 {
        work(Passes::Here)
    } else {
        crate::compute::region(|| work(Passes::Region))
    }
}

impl SphSolver {
    /// Runs one stage on the gathered particles.
    fn run_stage(&mut self, stage: Stage) {
        let (step, particles) = (&mut self.step, &mut self.particles);
        slot_region(particles.len(), |passes| {
            step.stage(stage, particles, StepLength::InTick, &passes);
        });
    }

    /// Runs one whole sub-step, every stage, on the gathered particles.
    fn run_substep(&mut self) {
        let (step, particles) = (&mut self.step, &mut self.particles);
        slot_region(particles.len(), |passes| {
            step.substep(particles, StepLength::InTick, &passes);
        });
    }
}

/// The fluid's own systems in [`SphSubstep`]: one per [`Stage`].
const STAGE_SYSTEMS: usize = Stage::ALL.len();

/// The crate's other systems in [`SphSubstep`] (gravity on fluid particles, the mouse tools),
/// each with a test of whether it has work this tick: while none has, the fluid still runs
/// the tick on one copy of the components.
#[derive(Resource, Clone, Default)]
pub(crate) struct SubstepHooks(Vec<(usize, HookActive)>);

/// Whether a hook in [`SphSubstep`] has work this tick.
type HookActive = fn(&mut World) -> bool;

impl SubstepHooks {
    /// Declares `systems` systems a plugin added to [`SphSubstep`], with work while `active`.
    pub(crate) fn register(app: &mut App, systems: usize, active: HookActive) {
        let world = app.world_mut();
        world
            .get_resource_or_init::<Self>()
            .0
            .push((systems, active));
    }
}

/// Whether systems in [`SphSubstep`] besides the fluid's stages have work this tick: a game's
/// own (any system the crate did not declare), or one of the crate's that is active.
fn hooks_present(world: &mut World) -> bool {
    let hooks = world
        .get_resource::<SubstepHooks>()
        .cloned()
        .unwrap_or_default();
    let known: usize = hooks.0.iter().map(|(systems, _)| systems).sum();
    let systems = world
        .resource::<Schedules>()
        .get(SphSubstep)
        .map_or(0, |schedule| schedule.systems_len());
    systems > STAGE_SYSTEMS + known || hooks.0.iter().any(|(_, active)| active(world))
}

/// Splits the tick into stable sub-steps and runs them (see the module docs).
pub(crate) fn run_substeps(
    world: &mut World,
    fluid: &mut QueryState<FluidData, With<FluidParticle>>,
) {
    let tick = world.resource::<Time>().delta_secs_f64();
    if tick <= 0.0 {
        return;
    }
    let started = Instant::now();
    world.resource_mut::<SphSolver>().step.begin_tick(tick);
    if hooks_present(world) {
        while world.resource::<SphSolver>().step.wants_substep() {
            world.run_schedule(SphSubstep);
        }
    } else {
        world.resource_scope(|world, mut solver: Mut<SphSolver>| {
            solver.gather(fluid.iter(world));
            while solver.step.wants_substep() {
                solver.run_substep();
            }
            for (i, mut item) in fluid.iter_mut(world).enumerate() {
                item.set(&solver.particles, i);
            }
        });
    }
    let mut solver = world.resource_mut::<SphSolver>();
    solver.step.end_tick();
    world.resource_mut::<SphStats>().tick_ms = started.elapsed().as_secs_f32() * 1000.0;
}

/// Adds the stage systems to [`SphSubstep`], each in its [`SphSubstepSystems`] set.
pub(crate) fn add_stage_systems(substep: &mut Schedule) {
    for stage in Stage::ALL {
        match stage {
            Stage::Neighbors => {
                substep.add_systems(neighbors_stage.in_set(SphSubstepSystems::Neighbors))
            }
            Stage::Density => substep.add_systems(density_stage.in_set(SphSubstepSystems::Density)),
            Stage::Forces => substep.add_systems(forces_stage.in_set(SphSubstepSystems::Forces)),
            Stage::Integrate => {
                substep.add_systems(integrate_stage.in_set(SphSubstepSystems::Integrate))
            }
        };
    }
}

/// [`SphSubstepSystems::Neighbors`]: gathers the components and rebuilds the sorted snapshot.
/// Where a particle is no longer at its index (spawned, despawned or moved since the last
/// gathering), the gathering is new and every particle learns its index.
fn neighbors_stage(
    mut solver: ResMut<SphSolver>,
    mut fluid: Query<IndexedData, With<FluidParticle>>,
) {
    let solver = &mut *solver;
    let n = fluid.iter().len();
    let generation = solver.generation;
    let mut same = n == solver.particles.len();
    solver.particles.resize(n);
    // What the stages read before they write it: the accelerations, densities and pressures
    // are theirs, and the stages below write every one of them back.
    let p = &mut solver.particles;
    p.rest_ratio.clear();
    p.viscosity.clear();
    for (i, (slot, data)) in fluid.iter().enumerate() {
        p.position[i] = data.position.0;
        p.velocity[i] = data.velocity.0;
        p.stiffness[i] = data.stiffness.0;
        note_liquid(p, &solver.liquids, i, data.material);
        same &= slot.index as usize == i && slot.generation == generation;
    }
    if !same {
        solver.generation = generation.wrapping_add(1).max(1);
        let generation = solver.generation;
        for (index, mut slot) in fluid.iter_mut().map(|(slot, _)| slot).enumerate() {
            *slot = FluidIndex {
                index: index as u32,
                generation,
            };
        }
    }
    solver.run_stage(Stage::Neighbors);
}

/// What the solver needs of `material`'s liquid (the base liquid's without one), from
/// `liquids`, by material.
pub(super) fn liquid_of(
    liquids: &[LiquidConstants],
    material: Option<&FluidMaterial>,
) -> LiquidConstants {
    let base = liquids[0];
    material
        .and_then(|m| liquids.get(m.0 as usize))
        .copied()
        .unwrap_or(base)
}

/// Notes particle `i`'s liquid (of `material`) in `particles`' rest density ratios and
/// viscosities, each of which stays empty while every particle so far has the base liquid's
/// (see [`Particles::rest_ratio`]).
fn note_liquid(
    particles: &mut Particles,
    liquids: &[LiquidConstants],
    i: usize,
    material: Option<&FluidMaterial>,
) {
    let (base, liquid) = (liquids[0], liquid_of(liquids, material));
    note(&mut particles.rest_ratio, i, liquid.ratio, base.ratio);
    note(
        &mut particles.viscosity,
        i,
        liquid.viscosity,
        base.viscosity,
    );
}

/// Pushes particle `i`'s `value` onto `values`, which stays empty while every value so far is
/// `base`.
fn note(values: &mut Vec<f32>, i: usize, value: f32, base: f32) {
    if values.is_empty() && value != base {
        values.resize(i, base);
    }
    if !values.is_empty() {
        values.push(value);
    }
}

/// [`SphSubstepSystems::Density`].
fn density_stage(mut solver: ResMut<SphSolver>) {
    solver.run_stage(Stage::Density);
}

/// [`SphSubstepSystems::Forces`]: the accelerations and densities into the components (the
/// acceleration overwritten: the hooks after it add to it), with the pressures (WCSPH) or the
/// divergence-free velocities (DFSPH).
fn forces_stage(mut solver: ResMut<SphSolver>, mut fluid: Query<WriteData, With<FluidParticle>>) {
    solver.run_stage(Stage::Forces);
    let (gravity, write) = (solver.constants().gravity, solver.step.forces_write());
    let solver = &*solver;
    let p = &solver.particles;
    for (slot, mut data) in &mut fluid {
        let Some(i) = solver.index_of(slot) else {
            data.acceleration.0 = gravity;
            continue;
        };
        data.acceleration.0 = p.acceleration[i];
        data.density.0 = p.density[i];
        if write.pressure {
            data.pressure.0 = p.pressure[i];
        }
        if write.velocity {
            data.velocity.0 = p.velocity[i];
        }
    }
}

/// [`SphSubstepSystems::Integrate`]: takes the positions, velocities and accelerations as the
/// hooks left them (the densities, pressures and stiffnesses are the solver's own, written by
/// the stages), steps, and writes the results back. A particle spawned since the neighbours
/// stage advances with its own acceleration.
fn integrate_stage(
    mut solver: ResMut<SphSolver>,
    mut fluid: Query<WriteData, With<FluidParticle>>,
) {
    let solver = &mut *solver;
    // A particle despawned since the neighbours stage pushes nothing; one spawned since counts
    // in the step length.
    let mut seen = vec![false; solver.particles.len()];
    let mut outsider = 0.0f32;
    for (slot, data) in &fluid {
        match solver.index_of(slot) {
            Some(i) => {
                let p = &mut solver.particles;
                p.position[i] = data.position.0;
                p.velocity[i] = data.velocity.0;
                p.acceleration[i] = data.acceleration.0;
                seen[i] = true;
            }
            None => outsider = outsider.max(data.acceleration.length()),
        }
    }
    for (a, _) in solver
        .particles
        .acceleration
        .iter_mut()
        .zip(&seen)
        .filter(|(_, s)| !**s)
    {
        *a = Vec2::ZERO;
    }
    solver.step.shared.outsider_acceleration = outsider;
    solver.run_stage(Stage::Integrate);
    let mut held_back = 0;
    for (slot, mut data) in &mut fluid {
        let p = &solver.particles;
        if let Some(i) = solver.index_of(slot) {
            data.position.0 = p.position[i];
            data.velocity.0 = p.velocity[i];
            data.pressure.0 = p.pressure[i];
            data.stiffness.0 = p.stiffness[i];
        } else {
            let a = data.acceleration.0;
            let (x, v) = (&mut data.position.0, &mut data.velocity.0);
            held_back += u64::from(!solver.step.advance_outsider(x, v, a));
        }
    }
    solver.step.shared.non_finite += held_back;
}

impl SphSolver {
    /// The particle's index in this sub-step's gathered particles, if it was gathered.
    fn index_of(&self, slot: &FluidIndex) -> Option<usize> {
        let index = slot.index as usize;
        (slot.generation == self.generation && index < self.particles.len()).then_some(index)
    }
}

/// Recomputes density, pressure, wall pressure and acceleration of every particle from the
/// current positions and velocities, without advancing time: for reading a consistent state
/// right after spawning (the solver otherwise computes them during the next sub-step).
pub fn refresh_fluid_state(world: &mut World) {
    let results = [
        world.run_system_cached(crate::params::apply_params::<super::SphParams>),
        world.run_system_cached(super::prepare::guard_particles),
        world.run_system_cached(super::prepare::rebuild_walls),
        world.run_system_cached(super::solids::sync_solids),
        world.run_system_cached(refresh_stages),
    ];
    for error in results.into_iter().filter_map(Result::err) {
        error!("refresh_fluid_state: {error}");
    }
}

/// The stages of a sub-step before the step is taken, on every particle.
fn refresh_stages(mut solver: ResMut<SphSolver>, mut fluid: Query<FluidData, With<FluidParticle>>) {
    solver.gather(fluid.iter());
    let solver = &mut *solver;
    let (step, particles) = (&mut solver.step, &mut solver.particles);
    slot_region(particles.len(), |passes| step.refresh(particles, &passes));
    for (i, mut item) in fluid.iter_mut().enumerate() {
        item.set(&solver.particles, i);
    }
}
