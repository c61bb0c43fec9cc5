//! A rotating disc of 20,000 bodies around a heavy centre, under Barnes-Hut gravity.
//!
//! Right button pushes bodies away, left pulls them (or spawns new ones with the "Spawn bodies"
//! tool, key `5`); the panel's gravity section sets G, θ and softening and shows energy and
//! momentum. `R` restarts the disc.
//!
//! `cargo run --example galaxy [-- BODIES]`

use bevy::prelude::*;
use bevy_sph2d::gameplay::{ScenarioKind, SphScenario};
use bevy_sph2d::gravity::GravityScenario;
use bevy_sph2d::prelude::*;

fn main() {
    let bodies = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20_000);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    App::new()
        .add_plugins((
            DefaultPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
            ParticlePlugins::default()
                .set(SphPlugin::default().with_params(SphParams {
                    tank: None,
                    ..default()
                }))
                .set(GravityPlugin::default().with_params(GravityParams {
                    gravitational_constant: 1.0,
                    theta: 0.7,
                    softening: 0.02,
                    ..default()
                })),
            ParticleUiPlugins,
        ))
        .insert_resource(ClearColor(Color::BLACK))
        .insert_resource(SphScenario::new(ScenarioKind::Empty, 0))
        .insert_resource(GravityScenario(GalaxyDisc::new(bodies)))
        .insert_resource(PointerSettings {
            radius: 0.15,
            strength: 20.0,
            body_mass: 1.0e-5,
            ..default()
        })
        .add_systems(Startup, setup)
        .run();
}

fn setup(mut commands: Commands, mut resets: MessageWriter<ResetSimulation>) {
    commands.spawn(ParticleCamera {
        region: Some(Rect::new(-1.05, -1.05, 1.05, 1.05)),
        ..default()
    });
    resets.write(ResetSimulation);
}
