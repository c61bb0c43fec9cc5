//! Two self-gravitating blobs of fluid in empty space collide and merge into one "planet": SPH
//! pressure holds them up, Barnes-Hut gravity holds them together.
//!
//! Mouse tools and the panel work as in `dam_break`; `R` starts the collision again.
//!
//! `cargo run --example planet`

use bevy::prelude::*;
use bevy_sph2d::gameplay::{ScenarioKind, SphScenario};
use bevy_sph2d::prelude::*;

fn main() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    App::new()
        .add_plugins((
            DefaultPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
            ParticlePlugins::default()
                .set(SphPlugin::default().with_params(FluidPlanets::default().fluid_params()))
                .set(
                    GravityPlugin::default().with_params(FluidPlanets::default().gravity_params()),
                ),
            ParticleUiPlugins,
        ))
        .insert_resource(ClearColor(Color::srgb(0.01, 0.01, 0.03)))
        .insert_resource(SphScenario::new(ScenarioKind::Empty, 0))
        .add_systems(Startup, setup)
        .add_systems(
            FixedUpdate,
            respawn
                .after(SphSystems::Prepare)
                .before(SphSystems::Simulate),
        )
        .run();
}

fn setup(mut commands: Commands, mut resets: MessageWriter<ResetSimulation>) {
    commands.spawn(ParticleCamera {
        region: Some(Rect::new(-0.8, -0.45, 0.8, 0.45)),
        ..default()
    });
    resets.write(ResetSimulation);
}

/// On reset: two discs of fluid with a mass each, approaching off-centre.
fn respawn(
    mut resets: MessageReader<ResetSimulation>,
    params: Res<SphParams>,
    mut commands: Commands,
) {
    if resets.read().count() == 0 {
        return;
    }
    let mass = params.particle_mass();
    for (p, v) in FluidPlanets::default().particles(params.particle_spacing) {
        commands.spawn((
            FluidParticle,
            particle::Position(p),
            particle::Velocity(v),
            particle::Mass(mass),
        ));
    }
}
