//! The SPH fluid plugin. See [`SphPlugin`].

mod components;
mod driver;
mod liquids;
mod params;
mod prepare;
mod resources;
mod solids;
mod stats;

use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
use bevy::prelude::*;

use crate::control::simulation_running;
use crate::gameplay::FluidGameplayPlugin;
use crate::schedule::{ParticleSchedulePlugin, ParticleSystems};

pub use crate::schedule::{SphSubstep, SphSubstepSystems};
pub use crate::sim::boundary::Tank;
pub use crate::sim::config::{DfsphSettings, PressureSolver};
pub use crate::sim::kernels::{self, KernelKind};
pub use crate::sim::parallel::PARALLEL_SLOTS;
pub use crate::sim::solid::{Part, Pose, SolidResponse, SolidShape, coupled_acceleration};
pub use components::{Acceleration, Density, FluidParticle, Position, Pressure, Velocity};
pub(crate) use components::{FluidIndex, Stiffness};
pub(crate) use driver::SubstepHooks;
pub use driver::refresh_fluid_state;
pub use liquids::{FluidMaterial, Liquid, MAX_DENSITY_RATIO};
pub use params::STANDARD_GRAVITY;
pub use params::{SphParams, SphParamsError};
pub use resources::{SphParamsStatus, SphSolver, SphStats};
pub(crate) use solids::pose_of;
pub use solids::{
    ContactAngle, FluidForce, SOLID_ENTER_FRACTION, SOLID_LEAVE_FRACTION, Solid, SolidDynamics,
    SolidEntered, SolidLeft, SolidVelocity, Submerged,
};
pub(crate) use stats::update_stats;

/// SPH fluid, simulated in a fixed-step schedule ([`FixedUpdate`] by default) with a stable
/// number of sub-steps per tick, incompressible through the divergence-free solver (DFSPH, the
/// default) or weakly compressible (WCSPH); see [`PressureSolver`]. It drives the crate's pure
/// simulation core, whose one sub-step order the plain-vector [`SliceFluid`](crate::slices::SliceFluid) drives too.
///
/// Spawn [`FluidParticle`]s (or queue a [`FluidBlock`](crate::gameplay::FluidBlock)) and tune
/// [`SphParams`]; read [`SphStats`]. Add [`Solid`]s (still or moving) inside the tank.
/// It adds the [`FluidGameplayPlugin`] (emitters, drains, sensors, scenarios, save and restore).
///
/// # Schedule
/// In the plugin's schedule, in order ([`SphSystems`]):
/// 1. [`SphSystems::Prepare`]: respawn the [`SphScenario`](crate::gameplay::SphScenario) on
///    [`ResetSimulation`](crate::control::ResetSimulation), validate changed [`SphParams`],
///    remove particles whose state is not finite or that a game put outside the tank (the
///    stability guard, counted in [`SphStats`]), re-sample walls and obstacles.
/// 2. [`SphSystems::Simulate`] (skipped while
///    [`SimulationControl`](crate::control::SimulationControl) pauses): split the tick into
///    stable sub-steps, each with the stages below ([`SphSubstepSystems`], in the
///    [`SphSubstep`] schedule):
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
///
///    While no system besides the fluid's own stages has work in [`SphSubstep`], the tick runs
///    without it: the components are copied into the solver once, every sub-step runs on the
///    copy, and the results are copied back once. A system of yours in [`SphSubstep`] (or the
///    gravity plugin's while fluid particles have a mass, or the mouse tools' while one
///    pushes or pulls) makes every sub-step run the schedule, with the components current
///    between the stages.
/// 3. [`SphSystems::Finish`]: the gameplay components act ([`FluidGameplayPlugin`]), then
///    [`SphStats`] is filled.
///
/// The grid rebuild and the passes over particles run by sorted slot in parallel regions on the
/// crate's rayon pool (as many threads as Bevy's `ComputeTaskPool`, whose own threads would
/// sleep between passes), from 1,024 particles on. On machines with few
/// cores Bevy's default pool sizes leave one compute thread; set `TaskPoolPlugin`'s options (or
/// use [`task_pool_plugin`](crate::task_pool_plugin)) to use them all.
pub struct SphPlugin {
    /// The schedule the fluid steps in when it is the first of the crate's plugins added (it
    /// then adds [`ParticleSchedulePlugin`] with it); otherwise the schedule already owned.
    pub schedule: Interned<dyn ScheduleLabel>,
    /// Parameters inserted at start-up.
    pub params: SphParams,
}

impl Default for SphPlugin {
    fn default() -> Self {
        Self {
            schedule: FixedUpdate.intern(),
            params: SphParams::default(),
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
        let schedule = ParticleSchedulePlugin::ensure(app, self.schedule);
        app.register_type::<SphParams>()
            .register_type::<SphStats>()
            .register_type::<FluidParticle>()
            .register_type::<FluidMaterial>()
            .register_type::<Liquid>()
            .register_type::<Position>()
            .register_type::<Velocity>()
            .register_type::<Acceleration>()
            .register_type::<Density>()
            .register_type::<Pressure>()
            .register_type::<Stiffness>()
            .register_type::<FluidIndex>()
            .register_type::<Solid>()
            .register_type::<SolidVelocity>()
            .register_type::<SolidDynamics>()
            .register_type::<ContactAngle>()
            .register_type::<FluidForce>()
            .register_type::<Submerged>()
            .add_message::<SolidEntered>()
            .add_message::<SolidLeft>()
            .insert_resource(self.params.clone())
            .init_resource::<SphSolver>()
            .init_resource::<SphStats>()
            .init_resource::<SphParamsStatus>();
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
            driver::add_stage_systems(substep);
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
                    crate::params::apply_params::<SphParams>,
                    prepare::guard_particles,
                    prepare::rebuild_walls,
                    solids::sync_solids,
                )
                    .chain()
                    .in_set(SphSystems::Prepare),
                driver::run_substeps
                    .run_if(simulation_running)
                    .in_set(SphSystems::Simulate),
                (stats::update_stats, solids::write_solid_loads).in_set(SphSystems::Finish),
            ),
        );
        if !app.is_plugin_added::<FluidGameplayPlugin>() {
            app.add_plugins(FluidGameplayPlugin);
        }
    }
}
