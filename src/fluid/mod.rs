//! The SPH fluid plugin. See [`SphPlugin`].

mod boundary;
mod clock;
mod components;
mod dfsph;
mod grid;
pub mod kernels;
mod layout;
#[doc(hidden)]
pub mod parallel;
mod params;
mod region;
mod save;
mod scenario;
mod sensors;
mod slices;
mod solver;
mod sources;
mod spawn;
mod systems;
pub mod validation;
mod wcsph;

use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
use bevy::prelude::*;

use crate::control::simulation_running;
use crate::schedule::{ParticleSchedulePlugin, ParticleSystems};

pub use crate::schedule::{SphSubstep, SphSubstepSystems};
pub use boundary::{Obstacle, Tank};
pub use clock::SubstepClock;
pub use components::{Acceleration, Density, FluidParticle, Position, Pressure, Velocity};
pub(crate) use components::{NeighborSlot, Stiffness};
pub use dfsph::{DfsphReport, LARGEST_ERROR_RATIO, MAX_RELIEF_RATE, PRESSURE_ACCURACY};
pub use grid::NeighborGrid;
pub use kernels::KernelKind;
pub use params::{DfsphSettings, PressureSolver, SphParams, SphParamsError};
pub use region::FluidRegion;
pub use save::{
    FileStorage, LoadSlot, SaveSlot, SnapshotError, SnapshotSlot, SnapshotStorage, load_fluid,
    load_fluid_from, save_fluid, save_fluid_to,
};
pub use scenario::{SCENARIO_TANK, ScenarioKind, SphScenario};
pub use sensors::{
    FluidEntered, FluidLeft, FluidSample, FluidSensor, SensorReading, probe, wall_pressure,
};
pub use slices::SliceFluid;
pub use solver::SphConstants;
pub use sources::{EmitterRate, FluidDrain, FluidEmitter};
pub use spawn::FluidBlock;
pub use systems::{SolverIterations, SphParamsStatus, SphSolver, SphStats, refresh_fluid_state};

/// SPH fluid, simulated in a fixed-step schedule ([`FixedUpdate`] by default) with a stable
/// number of sub-steps per tick, incompressible through the divergence-free solver (DFSPH, the
/// default) or weakly compressible (WCSPH); see [`PressureSolver`].
///
/// Spawn [`FluidParticle`]s (or queue a [`FluidBlock`]) and tune [`SphParams`]; read
/// [`SphStats`]. Add [`Obstacle`] components for solids inside the tank.
///
/// # Schedule
/// In the plugin's schedule, in order ([`SphSystems`]):
/// 1. [`SphSystems::Prepare`]: respawn the [`SphScenario`] on
///    [`ResetSimulation`](crate::control::ResetSimulation), validate changed [`SphParams`],
///    remove particles whose state is not finite or that a game put outside the tank (the
///    stability guard, counted in [`SphStats`]), re-sample walls and obstacles.
/// 2. [`SphSystems::Simulate`] (skipped while
///    [`SimulationControl`](crate::control::SimulationControl) pauses): split the tick into stable sub-steps and run the [`SphSubstep`]
///    schedule once per sub-step. In it, in order ([`SphSubstepSystems`]):
///    1. [`SphSubstepSystems::Neighbors`]: rebuild the cell grid and the sorted snapshot.
///    2. [`SphSubstepSystems::Density`]: WCSPH: density and pressure with each particle's
///       neighbour list, wall pressure. DFSPH: neighbour lists with cached kernel gradients,
///       densities and factors, then the divergence-free solve.
///    3. [`SphSubstepSystems::Forces`]: into [`Acceleration`] (this overwrites the previous
///       sub-step's value), with [`Density`] and [`Pressure`]: WCSPH: pressure, viscosity and
///       gravity. DFSPH: viscosity and gravity, the pressure following in `Integrate`.
///    4. [`SphSubstepSystems::FieldForces`] and [`SphSubstepSystems::PointerForces`]: gravity
///       on fluid particles with a mass, and the mouse tools (when those plugins run).
///    5. [`SphSubstepSystems::ExternalForces`]: empty, for your own forces: add to
///       [`Acceleration`] with `+=`, e.g.
///       `app.add_systems(SphSubstep, wind.in_set(SphSubstepSystems::ExternalForces))`.
///    6. [`SphSubstepSystems::Integrate`]: choose the step; DFSPH solves for the pressure that
///       keeps the density at rest under all the accelerations above; advance, keep particles
///       in the tank and out of obstacles.
/// 3. [`SphSystems::Finish`]: [`FluidEmitter`]s pour, [`FluidDrain`]s remove, [`FluidSensor`]s
///    measure (and send [`FluidEntered`] and [`FluidLeft`]), then fill [`SphStats`].
///
/// The grid rebuild and the passes over neighbours run by sorted slot in parallel regions on the
/// crate's pool (as many threads as Bevy's
/// `ComputeTaskPool`, whose own threads would sleep between passes); the light passes over
/// components (`par_iter_mut` from 8,192 particles) use the `ComputeTaskPool`. On machines with
/// few cores
/// Bevy's default pool sizes leave one compute thread; set `TaskPoolPlugin`'s options to use
/// them all.
pub struct SphPlugin {
    /// The schedule the fluid steps in when it is the first of the crate's plugins added (it
    /// then adds [`ParticleSchedulePlugin`] with it); otherwise the schedule already owned.
    pub schedule: Interned<dyn ScheduleLabel>,
    /// Parameters inserted at start-up.
    pub params: SphParams,
    /// Fixed-step rate to set, Hz (`None` keeps the app's `Time<Fixed>`).
    pub fixed_hz: Option<f64>,
}

impl Default for SphPlugin {
    fn default() -> Self {
        Self {
            schedule: FixedUpdate.intern(),
            params: SphParams::default(),
            fixed_hz: None,
        }
    }
}

impl SphPlugin {
    /// Steps the fluid in `schedule` instead of [`FixedUpdate`] (when added on its own; see
    /// [`schedule`](Self::schedule)).
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: schedule.intern(),
            ..default()
        }
    }

    /// Starts with these parameters.
    pub fn with_params(mut self, params: SphParams) -> Self {
        self.params = params;
        self
    }

    /// Sets the app's fixed-step rate, Hz.
    pub fn with_fixed_hz(mut self, hz: f64) -> Self {
        self.fixed_hz = Some(hz);
        self
    }
}

/// The fluid's stages in the plugin's schedule, chained in this order.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SphSystems {
    /// Parameter validation and wall sampling.
    Prepare,
    /// All sub-steps of this tick (runs [`SphSubstep`]).
    Simulate,
    /// Emitters, drains and sensors, then statistics.
    Finish,
}

impl Plugin for SphPlugin {
    fn build(&self, app: &mut App) {
        if let Err(error) = self.params.validate() {
            error!("SphPlugin: {error}; starting with SphParams::default() until it is fixed");
        }
        if let Some(hz) = self.fixed_hz {
            app.insert_resource(Time::<Fixed>::from_hz(hz));
        }
        let schedule = ParticleSchedulePlugin::ensure(app, self.schedule);
        app.register_type::<SphParams>()
            .register_type::<SphScenario>()
            .register_type::<SphStats>()
            .register_type::<FluidParticle>()
            .register_type::<Position>()
            .register_type::<Velocity>()
            .register_type::<Acceleration>()
            .register_type::<Density>()
            .register_type::<Pressure>()
            .register_type::<Stiffness>()
            .register_type::<NeighborSlot>()
            .register_type::<Obstacle>()
            .register_type::<FluidEmitter>()
            .register_type::<FluidDrain>()
            .register_type::<FluidSensor>()
            .add_message::<FluidEntered>()
            .add_message::<FluidLeft>()
            .insert_resource(self.params.clone())
            .init_resource::<SphSolver>()
            .init_resource::<SphStats>()
            .init_resource::<SphParamsStatus>()
            .init_resource::<SnapshotSlot>();

        // Edited rather than replaced: other plugins (gravity) may have added systems to it.
        app.init_schedule(SphSubstep);
        app.edit_schedule(SphSubstep, |substep| {
            substep.set_executor(SingleThreadedExecutor::new());
            substep.configure_sets(
                (
                    SphSubstepSystems::Neighbors,
                    SphSubstepSystems::Density,
                    SphSubstepSystems::Forces,
                    SphSubstepSystems::FieldForces,
                    SphSubstepSystems::PointerForces,
                    SphSubstepSystems::ExternalForces,
                    SphSubstepSystems::Integrate,
                )
                    .chain(),
            );
            let wcsph = systems::uses_solver(PressureSolver::Wcsph);
            let dfsph = systems::uses_solver(PressureSolver::Dfsph);
            // The solvers' systems exclude each other by run condition; chaining them makes
            // that order explicit to the scheduler (WCSPH's, then DFSPH's, in each stage).
            substep.add_systems((
                systems::build_neighbor_grid.in_set(SphSubstepSystems::Neighbors),
                (
                    systems::compute_density.run_if(wcsph.clone()),
                    (systems::prepare_dfsph, systems::solve_divergence)
                        .chain()
                        .run_if(dfsph.clone()),
                )
                    .chain()
                    .in_set(SphSubstepSystems::Density),
                (
                    systems::compute_forces.run_if(wcsph.clone()),
                    systems::compute_dfsph_forces.run_if(dfsph.clone()),
                )
                    .chain()
                    .in_set(SphSubstepSystems::Forces),
                (
                    (systems::choose_time_step, systems::integrate_particles)
                        .chain()
                        .run_if(wcsph),
                    (systems::solve_density, systems::integrate_dfsph)
                        .chain()
                        .run_if(dfsph),
                )
                    .chain()
                    .in_set(SphSubstepSystems::Integrate),
            ));
        });

        app.configure_sets(
            schedule,
            (
                SphSystems::Prepare.in_set(ParticleSystems::Prepare),
                SphSystems::Simulate.in_set(ParticleSystems::Fluid),
                SphSystems::Finish.in_set(ParticleSystems::Finish),
            ),
        )
        .add_systems(
            schedule,
            (
                (
                    scenario::reset_scenario,
                    crate::params::apply_params::<SphParams>,
                    systems::guard_particles,
                    systems::rebuild_walls,
                )
                    .chain()
                    .in_set(SphSystems::Prepare),
                systems::run_substeps
                    .run_if(simulation_running)
                    .in_set(SphSystems::Simulate),
                (
                    sources::run_emitters,
                    sources::run_drains,
                    sensors::run_sensors,
                    systems::update_stats,
                )
                    .chain()
                    .in_set(SphSystems::Finish),
            ),
        );
    }
}
