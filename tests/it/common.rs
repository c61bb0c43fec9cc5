//! Headless test harness: `MinimalPlugins`, a fixed tick per `App::update`, and helpers to read
//! particle state.

#![allow(dead_code, reason = "each test file uses a different part of it")]

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{SphParams, SphSolver};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::prelude::*;
use std::time::Duration;

/// Fixed tick of the test apps, s (a whole number of nanoseconds, as `Time<Fixed>` keeps it).
pub const TICK: f64 = 0.016_666_666;

/// A headless app with the fluid plugin on `params`, where each `App::update` runs exactly one
/// fixed tick of [`TICK`] seconds (after a first update that only starts the clocks).
pub fn create_app(params: SphParams) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, SphPlugin::default().with_params(params)))
        .insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f64(TICK)))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app
}

/// Spawns `block`, runs the clock-starting update, and returns the particles in lattice order.
pub fn spawn(app: &mut App, block: FluidBlock) -> Vec<Entity> {
    let ids = block.spawn(app.world_mut());
    app.update();
    ids
}

/// Runs `ticks` fixed ticks.
pub fn run(app: &mut App, ticks: usize) {
    for _ in 0..ticks {
        app.update();
    }
}

/// One particle's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    pub position: Vec2,
    pub velocity: Vec2,
    pub acceleration: Vec2,
    pub density: f32,
    pub pressure: f32,
}

/// Every fluid particle's state, in query order.
pub fn states(app: &mut App) -> Vec<State> {
    let world = app.world_mut();
    let mut query = world.query_filtered::<(
        &particle::Position,
        &particle::Velocity,
        &Acceleration,
        &Density,
        &Pressure,
    ), With<FluidParticle>>();
    query
        .iter(world)
        .map(|(x, v, a, rho, p)| State {
            position: x.0,
            velocity: v.0,
            acceleration: a.0,
            density: rho.0,
            pressure: p.0,
        })
        .collect()
}

/// Simulated time so far, s.
pub fn sim_time(app: &App) -> f64 {
    app.world().resource::<SphSolver>().clock().time
}

/// Whether every component of every particle is finite.
pub fn all_finite(states: &[State]) -> bool {
    states.iter().all(|s| {
        s.position.is_finite()
            && s.velocity.is_finite()
            && s.acceleration.is_finite()
            && s.density.is_finite()
            && s.pressure.is_finite()
    })
}
