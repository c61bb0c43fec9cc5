//! Two self-gravitating blobs of fluid in empty space collide and merge into one "planet": SPH
//! pressure holds them up, Barnes-Hut gravity holds them together.
//!
//! Mouse tools and the panel work as in `dam_break`; `R` starts the collision again.
//!
//! `cargo run --example planet`

use bevy::prelude::*;
use bevy_sph2d::fluid::{ScenarioKind, SphScenario};
use bevy_sph2d::prelude::*;

/// Blob radius, m, and the speed each blob approaches at, m/s.
const RADIUS: f32 = 0.15;
const SPEED: f32 = 0.25;

fn main() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    App::new()
        .add_plugins((
            DefaultPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
            ParticlePlugins::default()
                .set(SphPlugin::default().with_params(fluid()))
                .set(GravityPlugin::default().with_params(GravityParams {
                    // Surface gravity G M / R² of about 5 m/s² for these blobs.
                    gravitational_constant: 2.0e-3,
                    theta: 0.6,
                    softening: 0.01,
                    ..default()
                })),
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

/// Water without a tank or uniform gravity; a slow speed of sound suits the blobs' small
/// pressures (10 times their escape-free surface speed), and a little more artificial
/// viscosity calms the merger.
fn fluid() -> SphParams {
    SphParams {
        tank: None,
        gravity: Vec2::ZERO,
        particle_spacing: 0.01,
        support_ratio: 2.5,
        speed_of_sound: 10.0,
        artificial_viscosity: 0.1,
        max_substeps: 40,
        ..SphParams::water()
    }
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
    for (centre, velocity) in [
        (Vec2::new(-0.4, 0.03), Vec2::new(SPEED, 0.0)),
        (Vec2::new(0.4, -0.03), Vec2::new(-SPEED, 0.0)),
    ] {
        let square = FluidBlock::new(centre - Vec2::splat(RADIUS), Vec2::splat(2.0 * RADIUS))
            .with_hydrostatic(false);
        for p in square.positions(params.particle_spacing) {
            if p.distance(centre) < RADIUS {
                commands.spawn((FluidParticle, Position(p), Velocity(velocity), Mass(mass)));
            }
        }
    }
}
