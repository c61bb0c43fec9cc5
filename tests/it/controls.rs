//! Pause, single step and reset ([`SimulationControl`], [`ResetSimulation`], [`SphScenario`]),
//! the gas preset's background pressure, and the mouse tools' force applied through the
//! fixed step — all headless.

use crate::common;

use crate::common::{create_app, run, states};
use bevy::prelude::*;
use bevy_sph2d::fluid::{SphParams, SphStats};
use bevy_sph2d::gameplay::{ScenarioKind, SphScenario};
use bevy_sph2d::prelude::*;

fn scenario_app(kind: ScenarioKind, particles: u32) -> App {
    let mut app = create_app(SphParams {
        speed_of_sound: 25.0,
        support_ratio: 2.0,
        ..SphParams::water()
    });
    app.insert_resource(SphScenario::new(kind, particles));
    app.world_mut().write_message(ResetSimulation);
    // The first update only starts the clocks; the second runs the first tick, which resets.
    app.update();
    app.update();
    app
}

fn sim_time(app: &App) -> f64 {
    app.world().resource::<SphStats>().time
}

#[test]
fn pause_stops_the_fluid_and_step_runs_one_tick() {
    let mut app = scenario_app(ScenarioKind::DamBreak, 400);
    run(&mut app, 3);
    let running = sim_time(&app);
    assert!(running > 0.0);

    app.world_mut().resource_mut::<SimulationControl>().paused = true;
    let before = states(&mut app);
    run(&mut app, 5);
    assert_eq!(sim_time(&app), running, "paused time must not advance");
    assert_eq!(states(&mut app), before, "paused particles must not move");

    app.world_mut().resource_mut::<SimulationControl>().step();
    run(&mut app, 3);
    let stepped = sim_time(&app) - running;
    assert!(
        (stepped - common::TICK).abs() < 1e-6,
        "one step is one tick: advanced {stepped} s"
    );
    assert!(app.world().resource::<SimulationControl>().paused);

    app.world_mut()
        .resource_mut::<SimulationControl>()
        .toggle_pause();
    run(&mut app, 2);
    assert!(sim_time(&app) > running + 2.5 * common::TICK);
}

#[test]
fn reset_respawns_the_scenario_at_its_particle_count() {
    let mut app = scenario_app(ScenarioKind::DamBreak, 500);
    let first = states(&mut app);
    assert!(
        (450..=550).contains(&first.len()),
        "{} particles",
        first.len()
    );
    run(&mut app, 20);
    assert_ne!(states(&mut app), first);

    // The same scenario again: the very same particles, and the clock back at zero.
    app.world_mut().write_message(ResetSimulation);
    app.update();
    let again = states(&mut app);
    assert_eq!(
        again.iter().map(|s| s.position).collect::<Vec<_>>(),
        first.iter().map(|s| s.position).collect::<Vec<_>>()
    );
    assert!(sim_time(&app) <= common::TICK + 1e-9);

    // Another kind and count: the spacing follows the count.
    *app.world_mut().resource_mut::<SphScenario>() = SphScenario::new(ScenarioKind::Tank, 1200);
    app.world_mut().write_message(ResetSimulation);
    app.update();
    let tank = states(&mut app);
    assert!(
        (1100..=1300).contains(&tank.len()),
        "{} particles",
        tank.len()
    );
    let spacing = app.world().resource::<SphParams>().particle_spacing;
    let expected = SphScenario::new(ScenarioKind::Tank, 1200)
        .spacing(&SphScenario::tank(app.world().resource::<SphParams>()));
    assert!((spacing - expected).abs() < 1e-7);
    assert!(tank.iter().all(|s| s.position.y < 0.4 * 1.2 + 0.01));
}

#[test]
fn gas_fills_its_container_and_water_does_not() {
    let rise = |params: SphParams| {
        let mut app = create_app(SphParams {
            tank: Some(Tank::new(0.4, 0.4)),
            particle_spacing: 0.01,
            max_substeps: 2000,
            ..params
        });
        app.insert_resource(SphScenario::new(ScenarioKind::Tank, 400));
        app.world_mut().write_message(ResetSimulation);
        app.update();
        app.update();
        let top = |app: &mut App| {
            states(app)
                .iter()
                .map(|s| s.position.y)
                .fold(0.0f32, f32::max)
        };
        let start = top(&mut app);
        run(&mut app, 30);
        assert!(states(&mut app).iter().all(|s| s.position.is_finite()));
        top(&mut app) - start
    };
    let water = rise(SphParams {
        speed_of_sound: 10.0,
        ..SphParams::water()
    });
    let gas = rise(SphParams::gas());
    assert!(water.abs() < 0.02, "water rose {water} m");
    assert!(gas > 0.08, "gas rose only {gas} m");
}
