//! Feature `avian`: avian2d bodies in the fluid, headless. A crate lighter than water floats,
//! a stone sinks and rests on the tank's floor, and no particle gets inside either.

use crate::common::*;
use avian2d::prelude::{Collider, ColliderDensity, PhysicsPlugins, RigidBody};
use bevy::prelude::*;
use bevy_sph2d::coupling::{FluidCoupled, FluidCouplingPlugin};
use bevy_sph2d::fluid::{FluidForce, FluidParticle, Position, SphParams, Submerged, Tank};
use bevy_sph2d::gameplay::FluidBlock;

/// A resting layer 0.2 m deep in a 0.8 m × 0.4 m tank with the coupling and avian.
fn harbour_app() -> App {
    let tank = Tank::new(0.8, 0.4);
    let params = SphParams {
        particle_spacing: 0.01,
        tank: Some(tank),
        ..SphParams::water()
    };
    let mut app = create_app(params);
    app.add_plugins((
        TransformPlugin,
        PhysicsPlugins::default(),
        FluidCouplingPlugin,
    ));
    // avian registers some of its resources in `Plugin::finish`, which `App::run` calls.
    app.finish();
    app.cleanup();
    spawn(&mut app, FluidBlock::resting_layer(&tank, 0.2).with_seed(3));
    app
}

/// Spawns a `width` × `height` box of `density` (kg/m³) with its centre at `(x, y)`.
fn drop_box(app: &mut App, x: f32, y: f32, width: f32, height: f32, density: f32) -> Entity {
    app.world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(width, height),
            ColliderDensity(density),
            Transform::from_xyz(x, y, 0.0),
            FluidCoupled,
        ))
        .id()
}

/// Despawns the fluid particles within `margin` of the `size` box centred at `center`.
fn clear_box(app: &mut App, center: Vec2, size: Vec2, margin: f32) {
    let world = app.world_mut();
    let mut particles = world.query_filtered::<(Entity, &Position), With<FluidParticle>>();
    let inside: Vec<Entity> = particles
        .iter(world)
        .filter(|(_, p)| ((p.0 - center).abs() - 0.5 * size).max_element() < margin)
        .map(|(e, _)| e)
        .collect();
    for entity in inside {
        world.despawn(entity);
    }
}

/// The still-water level of the 0.8 m wide tank, m, from the volume the fluid's particles fill
/// at rest (a spacing squared each), the stone's (`stone`, m², resting under water) and the
/// upright crate's part under that level (`width` wide, its bottom at `bottom`, m). Waves
/// sloshing in the short tank move the free surface at its ends by several millimetres; the
/// volume does not move.
fn still_level(app: &mut App, stone: f32, width: f32, bottom: f32) -> f32 {
    let fluid = states(app).len() as f32 * 0.01 * 0.01;
    (fluid + stone - width * bottom) / (0.8 - width)
}

/// A crate of half the water's density released at its Archimedes draft floats through avian,
/// upright and in the water, at Archimedes' draft within 5% over the last second; a stone five
/// times as dense dropped beside it sinks and rests on the tank's floor (avian's static walls).
#[test]
fn a_light_crate_floats_and_a_stone_rests_on_the_floor() {
    let mut app = harbour_app();
    let (size, at) = (Vec2::new(0.16, 0.08), Vec2::new(0.3, 0.2));
    clear_box(&mut app, at, size, 0.005);
    let crate_ = drop_box(&mut app, at.x, at.y, size.x, size.y, 500.0);
    let stone = drop_box(&mut app, 0.65, 0.26, 0.06, 0.06, 5000.0);
    let mut drafts = Vec::new();
    for tick in 0..240 {
        run(&mut app, 1);
        if tick >= 180 {
            let y = app.world().get::<Transform>(crate_).unwrap().translation.y;
            let bottom = y - 0.5 * size.y;
            drafts.push(still_level(&mut app, 0.06 * 0.06, size.x, bottom) - bottom);
        }
    }
    let draft = drafts.iter().sum::<f32>() / drafts.len() as f32;
    let world = app.world_mut();
    let floating = *world.get::<Submerged>(crate_).unwrap();
    let force = *world.get::<FluidForce>(crate_).unwrap();
    let angle = world
        .get::<Transform>(crate_)
        .unwrap()
        .rotation
        .to_euler(EulerRot::ZYX)
        .0;
    let stone_y = world.get::<Transform>(stone).unwrap().translation.y;
    println!("crate draft {draft} m at {angle} rad, {floating:?}, {force:?}; stone at {stone_y} m");
    assert!(
        (draft - 0.04).abs() < 0.05 * 0.04,
        "crate draft {draft} m, Archimedes 0.04 m"
    );
    assert!(
        angle.abs() < 0.1 && floating.in_water,
        "{angle} rad, {floating:?}"
    );
    assert!(
        (stone_y - 0.03).abs() < 0.005,
        "the stone should rest on the floor: {stone_y} m"
    );
    assert!(all_finite(&states(&mut app)));
}
