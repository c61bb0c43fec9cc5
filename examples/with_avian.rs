//! Water and avian2d bodies in one game, written the way avian's own examples start: bevy's,
//! avian2d's and this crate's preludes glob-imported together. Water is poured particle by
//! particle into a tank (a particle is an entity with a `particle::Position`), and a crate, a
//! ball and a plank of different densities (avian rigid bodies marked `FluidCoupled`) fall in
//! and float, rising with the water.
//!
//! `cargo run --example with_avian` (a window: `Space` drops another crate, `W` blows a wind on
//! the water through the public force stage), or
//! `cargo run --example with_avian -- --headless 10` to run 10 simulated seconds without one
//! and print where each body ended.

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::prelude::*;

/// The tank, m (inner corner at the origin).
const TANK: Vec2 = Vec2::new(1.2, 0.8);

/// Particles the stream pours before it stops.
pub const POURED: u32 = 900;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut app = App::new();
    match args.iter().position(|a| a == "--headless") {
        Some(i) => {
            let seconds: f64 = args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(10.0);
            app.add_plugins((MinimalPlugins, TransformPlugin))
                .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
            game(&mut app);
            app.finish();
            app.cleanup();
            for _ in 0..(seconds * 64.0).ceil() as u32 {
                app.update();
            }
            let world = app.world_mut();
            let mut bodies = world.query::<(&Name, &Position, &LinearVelocity)>();
            for (name, position, velocity) in bodies.iter(world) {
                println!(
                    "{name}: at ({:.3}, {:.3}) m, moving {:.3} m/s",
                    position.x,
                    position.y,
                    velocity.length()
                );
            }
        }
        None => {
            app.add_plugins((DefaultPlugins, ParticleUiPlugins));
            game(&mut app);
            app.add_systems(Startup, |mut commands: Commands| {
                commands.spawn(ParticleCamera::default());
            })
            .add_systems(Update, (drop_on_space, blow))
            .run();
        }
    }
}

/// The game without its window: the plugins (in any order), the water and the bodies.
pub fn game(app: &mut App) {
    app.add_plugins((
        PhysicsPlugins::default(),
        ParticlePlugins::default().set(SphPlugin::default().with_params(params())),
        FluidCouplingPlugin::with_tank_walls(),
    ));
    scene(app);
}

/// Water at a 2 cm spacing in the tank.
pub fn params() -> SphParams {
    SphParams {
        tank: Some(Tank::new(TANK.x, TANK.y)),
        particle_spacing: 0.02,
        ..SphParams::water()
    }
}

/// The scene's systems: the pool and the bodies at start-up, the stream and the wind.
pub fn scene(app: &mut App) {
    app.init_resource::<Wind>()
        .add_systems(Startup, spawn_scene)
        .add_systems(FixedUpdate, pour.in_set(ParticleSystems::Input))
        .add_systems(SphSubstep, wind.in_set(SphSubstepSystems::ExternalForces));
}

/// A pool 0.2 m deep, and three bodies above it.
fn spawn_scene(mut commands: Commands) {
    commands.queue(FluidBlock::new(Vec2::ZERO, Vec2::new(TANK.x, 0.2)));
    commands.spawn(body("crate", Collider::rectangle(0.12, 0.12), 500.0, 0.3));
    commands.spawn(body("ball", Collider::circle(0.05), 300.0, 0.6));
    commands.spawn(body("plank", Collider::rectangle(0.3, 0.04), 700.0, 0.9));
}

/// A dynamic avian body of `density` (kg/m³), coupled with the fluid, at `x` m above the water.
fn body(name: &'static str, collider: Collider, density: f32, x: f32) -> impl Bundle {
    (
        Name::new(name),
        RigidBody::Dynamic,
        collider,
        ColliderDensity(density),
        FluidCoupled,
        Transform::from_xyz(x, 0.45, 0.0),
    )
}

/// A stream of water poured particle by particle from the left, two spacings apart, until
/// [`POURED`].
fn pour(mut commands: Commands, params: Res<SphParams>, mut poured: Local<u32>) {
    if *poured >= POURED {
        return;
    }
    let spacing = params.particle_spacing;
    for k in 0..3 {
        let at = Vec2::new(0.05 + k as f32 * spacing, 0.6);
        commands.spawn((
            FluidParticle,
            particle::Position(at),
            particle::Velocity(Vec2::new(1.0, -2.0)),
        ));
        *poured += 1;
    }
}

/// A wind from the left on the particles while `W` is held, m/s².
#[derive(Resource, Default)]
pub struct Wind(pub f32);

/// The wind on the particles, through the public force stage.
fn wind(wind: Res<Wind>, mut particles: Query<&mut Acceleration, With<FluidParticle>>) {
    for mut acceleration in &mut particles {
        acceleration.x += wind.0;
    }
}

/// `W` blows the wind.
fn blow(keys: Res<ButtonInput<KeyCode>>, mut wind: ResMut<Wind>) {
    wind.0 = if keys.pressed(KeyCode::KeyW) {
        2.0
    } else {
        0.0
    };
}

/// `Space` drops another crate.
fn drop_on_space(keys: Res<ButtonInput<KeyCode>>, mut commands: Commands) {
    if keys.just_pressed(KeyCode::Space) {
        commands.spawn(body("crate", Collider::rectangle(0.1, 0.1), 600.0, 0.5));
    }
}
