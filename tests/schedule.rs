//! The plugin's schedule: no ambiguous system order, and a game's own force stage runs between
//! the solver's forces and integration.

mod common;

use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings};
use bevy::prelude::*;
use bevy_sph2d::fluid::{FluidBlock, SphParams, Tank};
use bevy_sph2d::prelude::*;
use common::*;

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
