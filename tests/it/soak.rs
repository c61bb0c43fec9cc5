//! A long randomised soak: particles spawned and despawned at random, random external forces
//! through the public force stage, obstacles added and removed, gravity tilted. Everything
//! stays finite and inside the tank; the particles spawned outside it are exactly those the
//! stability guard removes.

use crate::common::*;
use bevy::prelude::*;
use bevy_sph2d::fluid::{Solid, SolidShape, SphParams, SphStats, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random force field, redrawn every tick: a game's stirring hand.
#[derive(Resource)]
struct Stirring {
    rng: ChaCha8Rng,
    centre: Vec2,
    strength: f32,
}

fn stir(stirring: Res<Stirring>, mut particles: Query<(&particle::Position, &mut Acceleration)>) {
    for (position, mut acceleration) in &mut particles {
        let d = position.0 - stirring.centre;
        let falloff = (1.0 - d.length() / 0.15).max(0.0);
        acceleration.0 += stirring.strength * falloff * d.perp().normalize_or_zero();
    }
}

#[test]
fn random_spawns_despawns_and_forces_stay_finite_and_inside() {
    soak(SphParams::water());
}

#[test]
fn random_spawns_despawns_and_forces_stay_finite_and_inside_wcsph() {
    soak(SphParams::water_wcsph());
}

fn soak(base: SphParams) {
    let tank = Tank::new(0.8, 0.5);
    let params = SphParams {
        particle_spacing: 0.015,
        tank: Some(tank),
        speed_of_sound: 20.0,
        max_substeps: 200,
        ..base
    };
    let mut app = create_app(params);
    app.insert_resource(Stirring {
        rng: ChaCha8Rng::seed_from_u64(42),
        centre: Vec2::new(0.3, 0.1),
        strength: 0.0,
    })
    .add_systems(SphSubstep, stir.in_set(SphSubstepSystems::ExternalForces));
    spawn(&mut app, FluidBlock::dam_break(0.3, 0.3));

    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut outside = 0u64;
    let mut obstacle = None;
    for tick in 0..400 {
        {
            let mut stirring = app.world_mut().resource_mut::<Stirring>();
            let centre = Vec2::new(
                stirring.rng.random_range(0.0..0.8),
                stirring.rng.random_range(0.0..0.5),
            );
            stirring.centre = centre;
            stirring.strength = stirring.rng.random_range(0.0..400.0);
        }
        match rng.random_range(0..10) {
            0 => {
                // Pour a few particles anywhere, some outside the tank (the guard removes those
                // more than a spacing out, and counts them).
                for _ in 0..rng.random_range(1..20) {
                    let p = Vec2::new(rng.random_range(-0.2..1.0), rng.random_range(-0.2..0.7));
                    let margin = 0.015;
                    if p.x < -margin
                        || p.y < -margin
                        || p.x > tank.width + margin
                        || p.y > tank.height + margin
                    {
                        outside += 1;
                    }
                    let v = Vec2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
                    app.world_mut().spawn((
                        FluidParticle,
                        particle::Position(p),
                        particle::Velocity(v),
                    ));
                }
            }
            1 => {
                // Despawn a random handful.
                let world = app.world_mut();
                let entities: Vec<Entity> = world
                    .query_filtered::<Entity, With<FluidParticle>>()
                    .iter(world)
                    .collect();
                for _ in 0..rng.random_range(1..30).min(entities.len()) {
                    let e = entities[rng.random_range(0..entities.len())];
                    if world.get_entity(e).is_ok() {
                        world.despawn(e);
                    }
                }
            }
            2 => {
                if let Some(e) = obstacle.take() {
                    app.world_mut().despawn(e);
                } else {
                    let c = Vec2::new(rng.random_range(0.1..0.7), rng.random_range(0.05..0.4));
                    let disc = (
                        Solid::new(SolidShape::circle(0.05)),
                        Transform::from_translation(c.extend(0.0)),
                    );
                    obstacle = Some(app.world_mut().spawn(disc).id());
                }
            }
            3 => {
                let angle: f32 = rng.random_range(-0.8..0.8);
                app.world_mut().resource_mut::<SphParams>().gravity =
                    Vec2::new(9.81 * angle.sin(), -9.81 * angle.cos());
            }
            _ => {}
        }
        run(&mut app, 1);
        if tick % 20 == 0 || tick == 399 {
            let s = states(&mut app);
            assert!(all_finite(&s), "non-finite state at tick {tick}");
            for p in &s {
                assert!(
                    (0.0..=tank.width).contains(&p.position.x)
                        && (0.0..=tank.height).contains(&p.position.y),
                    "particle escaped to {} at tick {tick}",
                    p.position
                );
            }
        }
    }
    let stats = app.world().resource::<SphStats>();
    assert!(stats.particles > 50, "{} particles left", stats.particles);
    assert_eq!(stats.non_finite_resets, 0);
    assert_eq!(stats.removed_non_finite, 0);
    assert_eq!(stats.removed_escaped, outside, "spawned outside the tank");
}
