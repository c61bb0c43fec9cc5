//! Gameplay on top of the fluid: emitters and drains ([`FluidEmitter`], [`FluidDrain`]),
//! sensors with messages and the fluid as a system reads it ([`FluidSensor`], [`FluidQuery`]), spawners
//! ([`FluidBlock`]), scenarios ([`SphScenario`]) and save and restore ([`save_fluid`],
//! [`SnapshotSlot`]). [`FluidGameplayPlugin`] runs them; the fluid's
//! [`SphPlugin`](crate::fluid::SphPlugin) adds it.

mod save;
mod scenario;
mod sensors;
mod sources;
mod spawn;

pub use crate::sim::region::FluidRegion;
pub use save::{
    FileStorage, LoadSlot, SaveSlot, SnapshotError, SnapshotSlot, SnapshotStorage, load_fluid,
    load_fluid_from, save_fluid, save_fluid_to,
};
pub use scenario::{SCENARIO_TANK, ScenarioKind, SphScenario};
pub use sensors::{FluidEntered, FluidLeft, FluidQuery, FluidSample, FluidSensor, SensorReading};
pub use sources::{EmitterRate, FluidDrain, FluidEmitter};
pub use spawn::FluidBlock;

use crate::control::simulation_running;
use crate::fluid::{SphParams, SphSystems, update_stats};
use crate::params::apply_params;
use crate::schedule::ParticleSchedule;
use bevy::prelude::*;

/// Runs the gameplay components in the fluid's schedule: on
/// [`ResetSimulation`](crate::control::ResetSimulation) the [`SphScenario`] respawns (in
/// [`SphSystems::Prepare`], before the parameters are checked); after the sub-steps, in
/// [`SphSystems::Finish`] and before the statistics, while the simulation runs (not paused),
/// [`FluidEmitter`]s pour, [`FluidDrain`]s remove and [`FluidSensor`]s measure (sending [`FluidEntered`] and [`FluidLeft`]).
/// [`SphPlugin`](crate::fluid::SphPlugin) adds it.
#[derive(Debug, Clone, Copy, Default)]
pub struct FluidGameplayPlugin;

impl Plugin for FluidGameplayPlugin {
    fn build(&self, app: &mut App) {
        let schedule = ParticleSchedule::of(app);
        app.register_type::<SphScenario>()
            .register_type::<FluidEmitter>()
            .register_type::<FluidDrain>()
            .register_type::<FluidSensor>()
            .add_message::<FluidEntered>()
            .add_message::<FluidLeft>()
            .init_resource::<SnapshotSlot>()
            .add_systems(
                schedule,
                (
                    scenario::reset_scenario
                        .in_set(SphSystems::Prepare)
                        .before(apply_params::<SphParams>),
                    (
                        sources::run_emitters,
                        sources::run_drains,
                        sensors::run_sensors,
                    )
                        .chain()
                        .run_if(simulation_running)
                        .in_set(SphSystems::Finish)
                        .before(update_stats),
                ),
            );
    }
}
