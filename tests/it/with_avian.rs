//! Features `avian` and `render`: the `with_avian` example, which glob-imports bevy's, avian2d's
//! and this crate's preludes together, builds and plays headless; avian's plugins, the crate's
//! and the coupling give the same app in every order, and the app's fixed rate stays the app's.

#[allow(dead_code, reason = "the example's window is not opened here")]
#[path = "../../examples/with_avian.rs"]
mod example;

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::prelude::*;
use std::hash::{Hash, Hasher};

/// An app without a window, one fixed tick (1/64 s) an update.
fn headless() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app
}

/// Finishes building `app` (as `App::run` does) and runs `ticks` fixed ticks.
fn play(app: &mut App, ticks: u32) {
    app.finish();
    app.cleanup();
    for _ in 0..ticks {
        app.update();
    }
}

/// Each body's name and pose, by name.
fn bodies(app: &mut App) -> Vec<(String, Vec2, f32)> {
    let world = app.world_mut();
    let mut query = world.query::<(&Name, &Position, &Rotation)>();
    let mut bodies: Vec<_> = query
        .iter(world)
        .map(|(name, position, rotation)| (name.to_string(), position.0, rotation.as_radians()))
        .collect();
    bodies.sort_by(|a, b| a.0.cmp(&b.0));
    bodies
}

/// The fluid particles' positions.
fn particles(app: &mut App) -> Vec<Vec2> {
    let world = app.world_mut();
    let mut query = world.query_filtered::<&particle::Position, With<FluidParticle>>();
    query.iter(world).map(|p| p.0).collect()
}

/// A hash of every bit of the particles' positions (in entity order) and the bodies' poses.
fn fingerprint(app: &mut App) -> u64 {
    let mut hasher = std::hash::DefaultHasher::new();
    let world = app.world_mut();
    let mut query = world.query_filtered::<(Entity, &particle::Position), With<FluidParticle>>();
    let mut positions: Vec<_> = query.iter(world).map(|(e, p)| (e, p.0)).collect();
    positions.sort_by_key(|&(e, _)| e);
    for (_, p) in positions {
        p.to_array().map(f32::to_bits).hash(&mut hasher);
    }
    for (name, at, angle) in bodies(app) {
        (name, at.to_array().map(f32::to_bits), angle.to_bits()).hash(&mut hasher);
    }
    hasher.finish()
}

/// The example's game plays: after 10 s the stream has poured all its water (the pool rises
/// from 0.2 m to about 0.5 m) and the crate, the ball and the plank, all lighter than water,
/// float on it, nearly still, with every particle in the tank.
#[test]
fn the_glob_imported_game_pours_and_floats() {
    let mut app = headless();
    example::game(&mut app);
    play(&mut app, 640);
    let particles = particles(&mut app);
    let tank = example::params().tank.unwrap();
    let spacing = example::params().particle_spacing;
    let inside = |p: &Vec2| p.is_finite() && tank.contains(*p, 0.0);
    assert!(particles.iter().all(inside), "a particle left the tank");
    let pool = (tank.width / spacing).round() * (0.2 / spacing).round();
    assert_eq!(particles.len(), pool as usize + example::POURED as usize);
    let level = particles.len() as f32 * spacing * spacing / tank.width;
    let world = app.world_mut();
    let mut query = world.query::<(&Name, &Position, &LinearVelocity)>();
    for (name, position, velocity) in query.iter(world) {
        println!(
            "{name} at {:?}, {:?} m/s; water level {level} m",
            position.0, velocity.0
        );
        assert!(
            (position.y - level).abs() < 0.05 && velocity.length() < 0.1,
            "{name} should float still on water {level} m deep: at {:?}, {:?} m/s",
            position.0,
            velocity.0
        );
    }
}

/// avian's `PhysicsPlugins`, `ParticlePlugins` and `FluidCouplingPlugin` added in each of the
/// six orders make the same app: the same particles and bodies, bit for bit, after a second of
/// water poured on a crate; the fixed rate the app set first is kept.
#[test]
fn the_plugins_make_the_same_app_in_every_order() {
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let fingerprints: Vec<u64> = orders
        .iter()
        .map(|order| {
            let mut app = headless();
            app.insert_resource(Time::<Fixed>::from_hz(50.0));
            for &plugin in order {
                match plugin {
                    0 => app.add_plugins(PhysicsPlugins::default()),
                    1 => app.add_plugins(
                        ParticlePlugins::default()
                            .set(SphPlugin::default().with_params(example::params())),
                    ),
                    _ => app.add_plugins(FluidCouplingPlugin::with_tank_walls()),
                };
            }
            example::scene(&mut app);
            play(&mut app, 50);
            assert_eq!(
                app.world()
                    .resource::<Time<Fixed>>()
                    .timestep()
                    .as_secs_f64(),
                0.02
            );
            // The pool and three particles a tick but the first (which starts the clock).
            assert_eq!(particles(&mut app).len(), 600 + 3 * 49, "order {order:?}");
            fingerprint(&mut app)
        })
        .collect();
    assert!(
        fingerprints.iter().all(|&f| f == fingerprints[0]),
        "{fingerprints:?}"
    );
}
