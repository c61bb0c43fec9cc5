//! The Barnes-Hut gravity plugin. See [`GravityPlugin`].

mod params;
mod scenario;
mod systems;

use crate::control::simulation_running;
use crate::fluid::SubstepHooks;
use crate::particle::{Position, Velocity};
use crate::schedule::{
    BodyForceSystems, ParticleSchedulePlugin, ParticleSystems, SphSubstep, SphSubstepSystems,
};
use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::ScheduleLabel;
use bevy::prelude::*;

pub use crate::sim::gravity::quadtree::{
    Field, FieldQuery, Multipole, Node, QuadTree, direct_field_at,
};
pub use params::{GravityParams, GravityParamsError, GravityParamsStatus};
pub use scenario::{FluidPlanets, GalaxyDisc, GravityScenario};
pub use systems::{GravitySolver, GravityStats};

/// Builds the tree and evaluates every body's field now, without moving anything (for reading
/// a consistent state right after spawning, as the fluid's
/// [`refresh_fluid_state`](crate::fluid::refresh_fluid_state) does). Run it with
/// `world.run_system_cached(refresh_gravity_field)`.
pub fn refresh_gravity_field(world: &mut World) {
    let results = [
        world.run_system_cached(crate::params::apply_params::<GravityParams>),
        world.run_system_cached(systems::compute_gravity_field),
        world.run_system_cached(systems::update_gravity_stats),
    ];
    for error in results.into_iter().filter_map(Result::err) {
        error!("refresh_gravity_field: {error}");
    }
}

/// Mass of a body, kg. Any entity with a [`Position`], [`Velocity`] and `Mass` attracts every
/// other one (the marker requires the rest). Fluid particles with a `Mass` take part too.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
#[require(Position, Velocity, GravityAcceleration, GravityPotential, GravitySlot)]
pub struct Mass(pub f32);

/// Where the body was gathered in the last field evaluation (the solver's bookkeeping).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub(crate) struct GravitySlot(pub u32);

/// Gravitational acceleration of the body at the last tree evaluation, m/s².
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct GravityAcceleration(pub Vec2);

/// Gravitational potential at the body (other bodies only), J/kg.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct GravityPotential(pub f32);

/// Barnes-Hut gravity between every entity with a [`Mass`], in a fixed-step schedule
/// ([`FixedUpdate`] by default).
///
/// # Schedule
/// In order ([`GravitySystems`]; `Prepare` in [`ParticleSystems::Prepare`], the rest in
/// [`ParticleSystems::Bodies`], before the fluid's sub-steps):
/// 1. [`GravitySystems::Prepare`]: respawn the [`GravityScenario`] on
///    [`ResetSimulation`](crate::control::ResetSimulation); validate changed [`GravityParams`];
///    if bodies appeared,
///    evaluate the field once so their first kick has an acceleration.
/// 2. [`GravitySystems::Drift`]: leapfrog half kick and drift of bodies that are not fluid
///    particles (`par_iter_mut`).
/// 3. [`GravitySystems::Field`]: build the quadtree (parallel sort and top levels on the crate's
///    compute pool),
///    evaluate the field at every body with a group walk ([`QuadTree::fields`], in parallel on
///    rayon, in the tree's cache-friendly order) and store each body's acceleration and
///    potential (`par_iter_mut`).
/// 4. [`BodyForceSystems`]: other forces on bodies this tick (the mouse tools' push), added to
///    [`GravityAcceleration`].
/// 5. [`GravitySystems::Kick`]: the second half kick; energy and momentum into
///    [`GravityStats`].
///
/// Fluid particles with a `Mass` keep the fluid's own stepping: their gravitational
/// acceleration of the tick is added to the SPH forces in every sub-step
/// ([`SphSubstepSystems::FieldForces`]).
pub struct GravityPlugin {
    /// The schedule gravity steps in when it is the first of the crate's plugins added (it then
    /// adds [`ParticleSchedulePlugin`] with it); otherwise the schedule already owned.
    pub schedule: Interned<dyn ScheduleLabel>,
    /// Parameters inserted at start-up.
    pub params: GravityParams,
}

impl Default for GravityPlugin {
    fn default() -> Self {
        Self {
            schedule: FixedUpdate.intern(),
            params: GravityParams::default(),
        }
    }
}

impl GravityPlugin {
    /// Steps gravity in `schedule` instead of [`FixedUpdate`] (when added on its own; see
    /// [`schedule`](Self::schedule)).
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: schedule.intern(),
            ..default()
        }
    }

    /// Starts with these parameters.
    pub fn with_params(mut self, params: GravityParams) -> Self {
        self.params = params;
        self
    }
}

/// The gravity stages, chained in this order.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GravitySystems {
    /// Resets and parameter validation.
    Prepare,
    /// The field of bodies new this tick, then half kick and drift.
    Drift,
    /// Tree build and field evaluation.
    Field,
    /// Half kick and statistics.
    Kick,
}

impl Plugin for GravityPlugin {
    fn build(&self, app: &mut App) {
        if let Err(error) = self.params.validate() {
            error!("GravityPlugin: {error}; starting with GravityParams::default()");
        }
        let schedule = ParticleSchedulePlugin::ensure(app, self.schedule);
        app.register_type::<GravityParams>()
            .register_type::<GravityStats>()
            .register_type::<Mass>()
            .register_type::<GravityAcceleration>()
            .register_type::<GravityPotential>()
            .register_type::<GravitySlot>()
            .register_type::<GravityScenario>()
            .register_type::<Multipole>()
            .insert_resource(self.params.clone())
            .init_resource::<systems::GravitySolver>()
            .init_resource::<GravityStats>()
            .init_resource::<crate::params::ParamsStatus<GravityParams>>()
            .configure_sets(
                schedule,
                (
                    GravitySystems::Prepare.in_set(ParticleSystems::Prepare),
                    (
                        GravitySystems::Drift,
                        GravitySystems::Field,
                        BodyForceSystems::Pointer,
                        BodyForceSystems::External,
                        GravitySystems::Kick,
                    )
                        .chain()
                        .in_set(ParticleSystems::Bodies),
                ),
            )
            .add_systems(
                schedule,
                (
                    (
                        scenario::reset_bodies,
                        crate::params::apply_params::<GravityParams>,
                    )
                        .chain()
                        .in_set(GravitySystems::Prepare),
                    // Bodies spawned this tick, by a reset or in `ParticleSystems::Input`, get
                    // their field before the first half kick.
                    (
                        systems::compute_gravity_field.run_if(systems::bodies_added),
                        systems::kick_and_drift.run_if(simulation_running),
                    )
                        .chain()
                        .in_set(GravitySystems::Drift),
                    systems::compute_gravity_field
                        .run_if(simulation_running)
                        .in_set(GravitySystems::Field),
                    (systems::kick, systems::update_gravity_stats)
                        .chain()
                        .run_if(simulation_running)
                        .in_set(GravitySystems::Kick),
                ),
            );
        // Runs only if the fluid plugin runs its sub-steps: the field at the sub-step's
        // positions, then its pull on the fluid particles that have a mass.
        app.add_systems(
            SphSubstep,
            (
                systems::compute_gravity_field,
                systems::apply_gravity_to_fluid,
            )
                .chain()
                .run_if(systems::fluid_has_mass)
                .in_set(SphSubstepSystems::FieldForces),
        );
        SubstepHooks::register(app, 2, |world| {
            world
                .run_system_cached(systems::fluid_has_mass)
                .unwrap_or(true)
        });
    }
}
