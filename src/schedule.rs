//! The one schedule every plugin of the crate steps in, and the crate-wide sets they nest
//! under. See [`ParticleSchedulePlugin`].
//!
//! A plugin orders its own sets against these, never against another plugin's: the fluid nests
//! under [`ParticleSystems::Fluid`], gravity under [`ParticleSystems::Bodies`], the mouse tools
//! under [`ParticleSystems::Input`] and [`BodyForceSystems::Pointer`], and so on. The fluid's sub-steps
//! run in their own schedule, [`SphSubstep`], whose stages ([`SphSubstepSystems`]) are
//! crate-wide in the same way.

use crate::control::{SimulationControlPlugin, SimulationControlSystems};
use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::{LogLevel, ScheduleLabel};
use bevy::prelude::*;

/// The crate's stages in the particle schedule ([`FixedUpdate`] unless
/// [`ParticlePlugins::new`](crate::ParticlePlugins::new) says otherwise), chained in this
/// order after [`SimulationControlSystems`].
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParticleSystems {
    /// Resets, parameter validation, the fluid's stability guard and walls, the field of new
    /// bodies, and what the renderer keeps of the last tick.
    Prepare,
    /// What the player does before anything moves: the mouse tools pour, erase and spawn.
    Input,
    /// Gravity bodies: drift, field, [`BodyForceSystems`], kick.
    Bodies,
    /// The fluid's sub-steps ([`SphSubstep`]).
    Fluid,
    /// Emitters, drains, sensors, statistics.
    Finish,
}

/// Forces on gravity bodies this tick, inside [`ParticleSystems::Bodies`], chained in this
/// order after the tree's field is stored and before the closing half kick: add to
/// [`GravityAcceleration`](crate::gravity::GravityAcceleration) with `+=`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BodyForceSystems {
    /// The mouse tools' push and pull.
    Pointer,
    /// A game's own forces on bodies.
    External,
}

/// The schedule of one fluid sub-step, run as many times per tick as stability needs (inside
/// [`ParticleSystems::Fluid`]).
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SphSubstep;

/// The stages of one sub-step in [`SphSubstep`], chained in this order.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SphSubstepSystems {
    /// Cell grid and sorted snapshot.
    Neighbors,
    /// Density, pressure, wall pressure.
    Density,
    /// Accelerations from pressure, viscosity and gravity.
    Forces,
    /// Accelerations from fields that other plugins compute once a tick (Barnes-Hut gravity on
    /// fluid particles with a [`Mass`](crate::gravity::Mass)), added with `+=`.
    FieldForces,
    /// The mouse tools' push, pull and drag.
    PointerForces,
    /// Empty, for a game's own forces: add to [`Acceleration`](crate::fluid::Acceleration)
    /// with `+=` before integration.
    ExternalForces,
    /// Time step, integration, collisions.
    Integrate,
}

/// The schedule the crate's plugins step in, as inserted by [`ParticleSchedulePlugin`]: the
/// render and interaction plugins read it in `Plugin::finish`, once every plugin is built.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParticleSchedule(pub Interned<dyn ScheduleLabel>);

impl ParticleSchedule {
    /// The schedule in `app` (the fixed step if no simulation plugin was added yet).
    pub fn of(app: &App) -> Interned<dyn ScheduleLabel> {
        app.world()
            .get_resource::<ParticleSchedule>()
            .map_or(FixedUpdate.intern(), |schedule| schedule.0)
    }
}

/// Owns the particle schedule: inserts [`ParticleSchedule`], adds pause, step and reset
/// ([`SimulationControlPlugin`]) in it, chains the [`ParticleSystems`], and turns the
/// scheduler's ambiguity detection on in it and in [`SphSubstep`] (two systems that touch the
/// same data with no order between them are reported; a level a game set first is kept if it is
/// stricter).
///
/// [`ParticlePlugins`](crate::ParticlePlugins) adds it first; a simulation plugin added on its
/// own adds it with its own schedule.
#[derive(Debug, Clone)]
pub struct ParticleSchedulePlugin {
    /// The schedule every plugin of the crate steps in.
    pub schedule: Interned<dyn ScheduleLabel>,
    /// How ambiguous system orders are reported: `Warn` by default, since a game's own
    /// unordered systems in the same schedule are reported too; tests use `Error`. It only
    /// raises the schedule's level: a stricter one set first is kept, and `Ignore` changes
    /// nothing.
    pub ambiguity_detection: LogLevel,
}

impl Default for ParticleSchedulePlugin {
    fn default() -> Self {
        Self::new(FixedUpdate)
    }
}

impl ParticleSchedulePlugin {
    /// The crate's plugins step in `schedule`.
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: schedule.intern(),
            ambiguity_detection: LogLevel::Warn,
        }
    }

    /// Adds the plugin to `app` with `schedule` unless one was added already; returns the
    /// schedule in use (the first one added wins).
    pub(crate) fn ensure(
        app: &mut App,
        schedule: Interned<dyn ScheduleLabel>,
    ) -> Interned<dyn ScheduleLabel> {
        if !app.is_plugin_added::<Self>() {
            app.add_plugins(Self {
                schedule,
                ..Self::default()
            });
        }
        ParticleSchedule::of(app)
    }
}

impl Plugin for ParticleSchedulePlugin {
    fn build(&self, app: &mut App) {
        let control: Vec<_> = app
            .get_added_plugins::<SimulationControlPlugin>()
            .iter()
            .map(|control| control.schedule)
            .collect();
        match control.first() {
            None => {
                app.add_plugins(SimulationControlPlugin {
                    schedule: self.schedule,
                });
            }
            Some(&other) if other != self.schedule => warn!(
                "SimulationControlPlugin decides each tick in {other:?}, but the particle \
                 schedule is {:?}: the simulations will not step; add it with the same schedule \
                 or leave it to ParticleSchedulePlugin",
                self.schedule
            ),
            Some(_) => {}
        }
        app.insert_resource(ParticleSchedule(self.schedule))
            .configure_sets(
                self.schedule,
                (
                    ParticleSystems::Prepare,
                    ParticleSystems::Input,
                    ParticleSystems::Bodies,
                    ParticleSystems::Fluid,
                    ParticleSystems::Finish,
                )
                    .chain()
                    .after(SimulationControlSystems),
            )
            .configure_sets(
                self.schedule,
                (BodyForceSystems::Pointer, BodyForceSystems::External)
                    .chain()
                    .in_set(ParticleSystems::Bodies),
            );
        app.init_schedule(SphSubstep);
        let level = self.ambiguity_detection;
        for label in [self.schedule, SphSubstep.intern()] {
            app.edit_schedule(label, |schedule| {
                let mut settings = schedule.get_build_settings();
                if stricter(level, settings.ambiguity_detection) {
                    settings.ambiguity_detection = level;
                    schedule.set_build_settings(settings);
                }
            });
        }
    }
}

/// Whether `a` reports more than `b` (`Ignore` < `Warn` < `Error`).
fn stricter(a: LogLevel, b: LogLevel) -> bool {
    let rank = |level: LogLevel| match level {
        LogLevel::Ignore => 0,
        LogLevel::Warn => 1,
        LogLevel::Error => 2,
    };
    rank(a) > rank(b)
}
