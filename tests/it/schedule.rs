//! The plugin's schedule: no ambiguous system order, every plugin nested under the crate-wide
//! sets in one schedule the game picks, and a game's own force stage runs between the solver's
//! forces and integration.

use crate::common::*;
use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SystemSet};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{SphParams, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::prelude::*;
use std::time::Duration;

#[test]
fn systems_have_no_ambiguous_order() {
    let mut app = create_app(SphParams::default());
    // The gravity plugin shares the schedule and the fluid's sub-steps.
    app.add_plugins(GravityPlugin::default());
    let strict = ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..default()
    };
    app.edit_schedule(FixedUpdate, |s| {
        s.set_build_settings(strict.clone());
    });
    app.edit_schedule(SphSubstep, |s| {
        s.set_build_settings(strict.clone());
    });
    app.world_mut().commands().queue(GalaxyDisc::new(100));
    spawn(&mut app, FluidBlock::dam_break(0.3, 0.3));
    // Building a schedule with an ambiguity at LogLevel::Error panics here.
    run(&mut app, 2);
}

/// Cancels gravity: a game's own force, added after the solver's.
fn antigravity(params: Res<SphParams>, mut particles: Query<&mut Acceleration>) {
    for mut a in &mut particles {
        a.0 -= params.gravity;
    }
}

#[test]
fn external_forces_run_between_forces_and_integration() {
    let params = SphParams {
        particle_spacing: 0.02,
        tank: Some(Tank::new(1.0, 1.0)),
        speed_of_sound: 20.0,
        ..default()
    };
    let mut app = create_app(params);
    app.add_systems(
        SphSubstep,
        antigravity.in_set(SphSubstepSystems::ExternalForces),
    );
    // A blob floating mid-tank: without gravity it must stay put.
    spawn(
        &mut app,
        FluidBlock::new(Vec2::new(0.4, 0.5), Vec2::splat(0.2)).with_hydrostatic(false),
    );
    let before = states(&mut app);
    run(&mut app, 20);
    let after = states(&mut app);
    let mean_drop = before
        .iter()
        .zip(&after)
        .map(|(b, a)| b.position.y - a.position.y)
        .sum::<f32>()
        / before.len() as f32;
    // Free fall would have dropped it by g t²/2 = 0.54 m.
    assert!(
        mean_drop.abs() < 0.005,
        "the blob moved down by {mean_drop} m"
    );
}

/// Systems of `set` in the built `schedule` of `app`.
fn systems_in(app: &App, schedule: impl ScheduleLabel, set: impl SystemSet) -> Vec<String> {
    let schedules = app.world().resource::<Schedules>();
    let schedule = schedules.get(schedule).expect("the schedule exists");
    let keys = schedule
        .graph()
        .systems_in_set(set.intern())
        .expect("the set is in the schedule");
    schedule
        .systems()
        .expect("the schedule is built")
        .filter(|(key, _)| keys.contains(key))
        .map(|(_, system)| system.name().to_string())
        .collect()
}

#[test]
fn every_plugin_nests_under_the_crate_sets() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, ParticlePlugins::default()))
        .insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f64(TICK)))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.world_mut().commands().queue(GalaxyDisc::new(50));
    spawn(&mut app, FluidBlock::dam_break(0.3, 0.3));
    run(&mut app, 1);
    let nested = |inner: &dyn Fn(&App) -> Vec<String>, outer: ParticleSystems| {
        let outer = systems_in(&app, FixedUpdate, outer);
        let inner = inner(&app);
        assert!(!inner.is_empty());
        for system in &inner {
            assert!(outer.contains(system), "{system} is outside {outer:?}");
        }
    };
    nested(
        &|app| systems_in(app, FixedUpdate, SphSystems::Prepare),
        ParticleSystems::Prepare,
    );
    nested(
        &|app| systems_in(app, FixedUpdate, GravitySystems::Prepare),
        ParticleSystems::Prepare,
    );
    for stage in [
        GravitySystems::Drift,
        GravitySystems::Field,
        GravitySystems::Kick,
    ] {
        nested(
            &|app| systems_in(app, FixedUpdate, stage),
            ParticleSystems::Bodies,
        );
    }
    nested(
        &|app| systems_in(app, FixedUpdate, SphSystems::Simulate),
        ParticleSystems::Fluid,
    );
    nested(
        &|app| systems_in(app, FixedUpdate, SphSystems::Finish),
        ParticleSystems::Finish,
    );
    // Every system of the crate in the schedule sits in one of the crate's stages, apart from
    // the control's tick decision, which comes before them all.
    let staged: Vec<String> = [
        ParticleSystems::Prepare,
        ParticleSystems::Input,
        ParticleSystems::Bodies,
        ParticleSystems::Fluid,
        ParticleSystems::Finish,
    ]
    .into_iter()
    .flat_map(|stage| systems_in(&app, FixedUpdate, stage))
    .collect();
    let schedules = app.world().resource::<Schedules>();
    let built = schedules.get(FixedUpdate).unwrap().systems().unwrap();
    for (_, system) in built {
        let name = system.name().to_string();
        if name.starts_with("bevy_sph2d::") && !name.contains("begin_control_tick") {
            assert!(
                staged.contains(&name),
                "{name} is in no ParticleSystems stage"
            );
        }
    }
}

/// A game's own schedule, run from `Update`.
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct GameStep;

fn run_game_step(world: &mut World) {
    world.run_schedule(GameStep);
}

#[test]
fn particle_plugins_step_in_the_schedule_they_are_given() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, ParticlePlugins::new(GameStep)))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            TICK,
        )))
        .add_systems(Update, run_game_step);
    let fixed = app
        .world()
        .resource::<Schedules>()
        .get(FixedUpdate)
        .map_or(0, |schedule| schedule.systems_len());
    assert_eq!(fixed, 0, "nothing of the crate in FixedUpdate");
    for label in [GameStep.intern(), SphSubstep.intern()] {
        let level = app
            .world()
            .resource::<Schedules>()
            .get(label)
            .expect("the schedule exists")
            .get_build_settings()
            .ambiguity_detection;
        assert_eq!(level, LogLevel::Warn, "ambiguity detection in {label:?}");
    }
    let block = FluidBlock::dam_break(0.2, 0.2);
    block.spawn(app.world_mut());
    app.update();
    let start = states(&mut app);
    for _ in 0..20 {
        app.update();
    }
    let moved = start
        .iter()
        .zip(&states(&mut app))
        .any(|(a, b)| a.position != b.position);
    assert!(moved, "the fluid steps in the game's schedule");
    // Paused through the shared control, nothing moves.
    app.world_mut().resource_mut::<SimulationControl>().paused = true;
    let paused = states(&mut app);
    for _ in 0..5 {
        app.update();
    }
    let still = paused
        .iter()
        .zip(&states(&mut app))
        .all(|(a, b)| a.position == b.position);
    assert!(still, "pause holds in the game's schedule");
}

#[test]
fn a_stricter_ambiguity_level_set_first_is_kept() {
    let mut app = App::new();
    app.edit_schedule(FixedUpdate, |s| {
        s.set_build_settings(ScheduleBuildSettings {
            ambiguity_detection: LogLevel::Error,
            ..default()
        });
    });
    app.add_plugins((MinimalPlugins, ParticlePlugins::default()));
    let level = app
        .world()
        .resource::<Schedules>()
        .get(FixedUpdate)
        .unwrap()
        .get_build_settings()
        .ambiguity_detection;
    assert_eq!(level, LogLevel::Error);
}

/// A game's force on gravity bodies.
#[cfg(feature = "render")]
fn body_wind(mut bodies: Query<&mut bevy_sph2d::gravity::GravityAcceleration>) {
    for mut a in &mut bodies {
        a.0.x += 0.1;
    }
}

#[cfg(feature = "render")]
#[test]
fn the_mouse_tools_have_no_ambiguous_order_with_fluid_and_gravity() {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        ParticlePlugins::default(),
        ParticleInteractPlugin,
    ))
    // A game's own forces in the documented stages, next to the tools' and gravity's.
    .add_systems(
        SphSubstep,
        antigravity.in_set(SphSubstepSystems::ExternalForces),
    )
    .add_systems(FixedUpdate, body_wind.in_set(BodyForceSystems::External));
    app.finish();
    let strict = ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..default()
    };
    for label in [FixedUpdate.intern(), SphSubstep.intern()] {
        app.edit_schedule(label, |s| {
            s.set_build_settings(strict.clone());
        });
        // Builds the schedule without running it (the tools' frame systems need a window).
        let built = app
            .world_mut()
            .schedule_scope(label, |world, schedule| schedule.initialize(world));
        assert!(built.is_ok(), "{label:?}: {:?}", built.err());
    }
}
