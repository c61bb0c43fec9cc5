//! Feature `avian`: avian2d bodies in the fluid, headless. A crate lighter than water floats,
//! a stone sinks and rests on the tank's floor, a crate dropped from half a metre splashes in
//! and settles, and no particle gets inside any of them.

use crate::common::*;
use avian2d::prelude::{
    Collider, ColliderDensity, Gravity, LinearVelocity, PhysicsPlugins, RigidBody,
};
use bevy::log::tracing::{
    self,
    field::{Field, Visit},
};
use bevy::log::tracing_subscriber::layer::{Context, Layer, SubscriberExt};
use bevy::log::tracing_subscriber::registry::Registry;
use bevy::prelude::*;
use bevy_sph2d::coupling::{FluidCoupled, FluidCouplingPlugin, TankWall};
use bevy_sph2d::fluid::PressureSolver;
use bevy_sph2d::fluid::{
    FluidForce, FluidParticle, Position, Solid, SphParams, SphSolver, SphStats, SphSystems,
    Submerged, Tank,
};
use bevy_sph2d::gameplay::FluidBlock;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

/// A resting layer 0.2 m deep in a 0.8 m wide tank `height` m high with the coupling and avian.
fn harbour_app(height: f32) -> App {
    harbour_app_with(height, 0.01, FluidCouplingPlugin::with_tank_walls())
}

/// [`harbour_app`] at a particle spacing of `spacing` m, with `coupling`.
fn harbour_app_with(height: f32, spacing: f32, coupling: FluidCouplingPlugin) -> App {
    let tank = Tank::new(0.8, height);
    let params = SphParams {
        particle_spacing: spacing,
        tank: Some(tank),
        ..SphParams::water()
    };
    let mut app = create_app(params);
    app.add_plugins((TransformPlugin, PhysicsPlugins::default(), coupling));
    // avian registers some of its resources in `Plugin::finish`, which `App::run` calls.
    app.finish();
    app.cleanup();
    app.init_resource::<MostInside>()
        .add_systems(FixedUpdate, count_inside.after(SphSystems::Finish));
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

/// The most fluid particles found more than half a spacing inside a solid right after a fluid
/// step, with the solid where the step left it (avian moves it on after, and may cover
/// particles until the next step pushes them out).
#[derive(Resource, Default)]
struct MostInside(usize);

fn count_inside(
    mut most: ResMut<MostInside>,
    params: Res<SphParams>,
    solver: Res<SphSolver>,
    solids: Query<(Entity, &Solid)>,
    particles: Query<&Position, With<FluidParticle>>,
) {
    let depth = 0.5 * params.particle_spacing;
    let inside = solids
        .iter()
        .filter_map(|(entity, solid)| Some((solid, solver.solid_motion(entity)?.pose)))
        .map(|(solid, pose)| {
            particles
                .iter()
                .filter(|p| solid.shape.distance(pose.to_local(p.0)).0 < -depth)
                .count()
        })
        .sum();
    most.0 = most.0.max(inside);
}

fn most_inside(app: &App) -> usize {
    app.world().resource::<MostInside>().0
}

/// The still-water level of the 0.8 m wide tank, m, from the volume the fluid's particles fill
/// at rest (a spacing squared each), a sunk body's (`stone`, m², resting under water) and the
/// upright crate's part under that level (`width` wide, its bottom at `bottom`, m). Waves
/// sloshing in the short tank move the free surface at its ends by several millimetres; the
/// volume does not move.
fn still_level(app: &mut App, stone: f32, width: f32, bottom: f32) -> f32 {
    let spacing = app.world().resource::<SphParams>().particle_spacing;
    let fluid = states(app).len() as f32 * spacing * spacing;
    (fluid + stone - width * bottom) / (0.8 - width)
}

/// A crate of half the water's density released at its Archimedes draft floats through avian,
/// upright and in the water, at Archimedes' draft within 5% (mean over the last 1.6 s of 5 s),
/// with no particle ever inside it.
#[test]
fn a_light_crate_floats_at_archimedes_draft() {
    let mut app = harbour_app(0.4);
    let (size, at) = (Vec2::new(0.16, 0.08), Vec2::new(0.4, 0.2));
    clear_box(&mut app, at, size, 0.005);
    let crate_ = drop_box(&mut app, at.x, at.y, size.x, size.y, 500.0);
    let mut drafts = Vec::new();
    for tick in 0..320 {
        run(&mut app, 1);
        if tick >= 216 {
            let y = app.world().get::<Transform>(crate_).unwrap().translation.y;
            let bottom = y - 0.5 * size.y;
            drafts.push(still_level(&mut app, 0.0, size.x, bottom) - bottom);
        }
    }
    let draft = drafts.iter().sum::<f32>() / drafts.len() as f32;
    let world = app.world();
    let floating = *world.get::<Submerged>(crate_).unwrap();
    let force = *world.get::<FluidForce>(crate_).unwrap();
    let angle = world
        .get::<Transform>(crate_)
        .unwrap()
        .rotation
        .to_euler(EulerRot::ZYX)
        .0;
    println!("crate draft {draft} m at {angle} rad, {floating:?}, {force:?}");
    assert!(
        (draft - 0.04).abs() < 0.05 * 0.04,
        "crate draft {draft} m, Archimedes 0.04 m"
    );
    assert!(
        angle.abs() < 0.1 && floating.in_water,
        "{angle} rad, {floating:?}"
    );
    assert_eq!(most_inside(&app), 0, "particles inside the crate");
    assert!(all_finite(&states(&mut app)));
}

/// A stone five times as dense as the water dropped into it sinks and rests on the tank's
/// floor (avian's static walls) under water, with no particle ever inside it.
#[test]
fn a_stone_sinks_and_rests_on_the_floor() {
    let mut app = harbour_app(0.4);
    let size = Vec2::splat(0.06);
    let stone = drop_box(&mut app, 0.4, 0.26, size.x, size.y, 5000.0);
    run(&mut app, 150);
    let world = app.world();
    let y = world.get::<Transform>(stone).unwrap().translation.y;
    let under = *world.get::<Submerged>(stone).unwrap();
    println!("stone at {y} m, {under:?}");
    assert!(
        (y - 0.03).abs() < 0.005,
        "the stone should rest on the floor: {y} m"
    );
    assert!(
        under.fraction > 0.99,
        "the stone should be under water: {under:?}"
    );
    assert_eq!(most_inside(&app), 0, "particles inside the stone");
    assert!(all_finite(&states(&mut app)));
}

/// A stone of 2.5 times the water's density (a 10 × 6 cm box) released at the surface of the
/// 0.2 m layer at 5 mm spacing, ticks of 100 Hz, carried by the fluid at its velocity through
/// each tick (`FluidCouplingPlugin::carried`), sinks onto the floor, and the fluid keeps
/// stepping: every tick within a quarter of the sub-step budget (no time dropped), no particle
/// ever inside the stone, everything finite.
///
/// Before pinned particles were left out of the solves (`PINNED_DIAGONAL` in the core), a
/// particle caught in the closing gap, whose density no pressure could change, took a stiffness
/// that grew without bound and the step shrank with it (to 10⁻⁷ s): here 400 sub-steps a tick,
/// time dropped. Measured since: at most 27.
///
/// That it comes to rest is not asserted: carried, the stone squeezes the film under it until
/// the film throws it back (up to 6,400 N/m at 60 ticks a second, 79,000 at 100, against a
/// weight of 147 N/m), tumbling.
#[test]
fn a_stone_landing_on_the_floor_keeps_the_fluid_stepping() {
    let coupling = FluidCouplingPlugin {
        carried: true,
        ..FluidCouplingPlugin::with_tank_walls()
    };
    let mut app = harbour_app_with(0.4, 0.005, coupling);
    app.world_mut()
        .resource_mut::<Time<Fixed>>()
        .set_timestep(Duration::from_millis(10));
    let (size, at) = (Vec2::new(0.1, 0.06), Vec2::new(0.4, 0.2));
    clear_box(&mut app, at, size, 0.0025);
    let stone = drop_box(&mut app, at.x, at.y, size.x, size.y, 2500.0);
    let (mut most_substeps, mut lowest) = (0, f32::INFINITY);
    for _ in 0..200 {
        run(&mut app, 1);
        let world = app.world();
        most_substeps = most_substeps.max(world.resource::<SphStats>().substeps);
        lowest = lowest.min(world.get::<Transform>(stone).unwrap().translation.y);
    }
    let stats = app.world().resource::<SphStats>();
    let budget = SphParams::water().max_substeps;
    println!(
        "stone: lowest centre {lowest} m, at most {most_substeps} sub-steps a tick of {budget}, \
         {} s dropped",
        stats.dropped_time
    );
    assert_eq!(stats.dropped_time, 0.0, "the fluid fell behind");
    assert!(
        most_substeps <= budget / 4,
        "{most_substeps} sub-steps in a tick"
    );
    assert!(
        lowest < 0.06,
        "the stone never reached the floor: {lowest} m"
    );
    assert_eq!(most_inside(&app), 0, "particles inside the stone");
    assert!(all_finite(&states(&mut app)));
}

/// A stone of 2.5 times the water's density (a 10 × 6 cm box) dropped flat with its bottom
/// 0.3 m above the 0.2 m layer (5 mm spacing, ticks of 100 Hz) splashes in, sinks, lands flat
/// on the floor and rests there with the water's weight over it pressing it down (no film left
/// under it: ρ₀ g (D − h) w within 10%, `D` the still-water level); from the first tick it is
/// within a centimetre of the floor the fluid's force stays under eight times its weight
/// (measured: 5.9); every tick within a quarter of
/// the sub-step budget (no time dropped), no particle ever inside it, everything finite.
///
/// Before pinned particles were left out of the solves (`PINNED_DIAGONAL` in the core), a
/// particle caught in the closing gap, whose density no pressure could change, took a stiffness
/// that grew without bound and the step shrank with it (to 10⁻⁷ s): 400 sub-steps a tick, time
/// dropped. Carried at its speed through the whole tick (`FluidCouplingPlugin::carried`, the
/// exchange of earlier versions), the stone squeezes the film under it until the film throws it
/// back (79,000 N/m at 100 ticks a second, held to 10 g), tumbling, to rest on its narrow side.
#[test]
fn a_stone_dropped_into_the_water_lands_flat_and_rests_under_it() {
    let mut app = harbour_app_with(0.7, 0.005, FluidCouplingPlugin::with_tank_walls());
    app.world_mut()
        .resource_mut::<Time<Fixed>>()
        .set_timestep(Duration::from_millis(10));
    let size = Vec2::new(0.1, 0.06);
    let stone = drop_box(&mut app, 0.4, 0.5 + 0.5 * size.y, size.x, size.y, 2500.0);
    let weight = 2500.0 * 9.81 * size.x * size.y;
    let (mut most_substeps, mut landing_force, mut last) = (0, 0.0f32, Vec::new());
    for tick in 0..200 {
        run(&mut app, 1);
        let world = app.world();
        most_substeps = most_substeps.max(world.resource::<SphStats>().substeps);
        let pose = world.get::<Transform>(stone).unwrap();
        let y = pose.translation.y;
        let force = world.get::<FluidForce>(stone).unwrap().force;
        if y - 0.5 * size.y < 0.01 {
            landing_force = landing_force.max(force.length());
        }
        if tick >= 150 {
            let angle = pose.rotation.to_euler(EulerRot::ZYX).0;
            let speed = world.get::<LinearVelocity>(stone).unwrap().0.length();
            last.push((y, angle.abs(), speed, force.y));
        }
    }
    let level = still_level(&mut app, size.x * size.y, 0.0, 0.0);
    let stats = app.world().resource::<SphStats>();
    let mean =
        |f: fn(&(f32, f32, f32, f32)) -> f32| last.iter().map(f).sum::<f32>() / last.len() as f32;
    let (y, angle, speed, force) = (mean(|r| r.0), mean(|r| r.1), mean(|r| r.2), mean(|r| r.3));
    let over = -1000.0 * 9.81 * (level - size.y) * size.x;
    let budget = SphParams::water().max_substeps;
    println!(
        "stone at {y} m, {angle} rad, {speed} m/s, fluid force {force} N/m (the water over it \
         {over}); landing: at most {landing_force} N/m ({} weights); at most {most_substeps} \
         sub-steps a tick of {budget}, {} s dropped",
        landing_force / weight,
        stats.dropped_time
    );
    assert_eq!(stats.dropped_time, 0.0, "the fluid fell behind");
    assert!(
        most_substeps <= budget / 4,
        "{most_substeps} sub-steps in a tick"
    );
    assert!(
        (y - 0.03).abs() < 0.001 && angle < 0.01 && speed < 0.005,
        "the stone should rest flat on the floor: {y} m, {angle} rad, {speed} m/s"
    );
    assert!(
        (force - over).abs() < 0.1 * over.abs(),
        "the fluid's force {force} N/m, the water over the stone {over} N/m"
    );
    assert!(
        landing_force < 8.0 * weight,
        "the landing took {landing_force} N/m, its weight {weight}"
    );
    assert_eq!(most_inside(&app), 0, "particles inside the stone");
    assert!(all_finite(&states(&mut app)));
}

/// Coupling a body under WCSPH, which throws bodies lighter than water out of it (relative
/// densities 0.3 and 0.5 measured), warns once and names the solver.
#[test]
fn coupling_a_body_under_wcsph_warns_naming_the_solver() {
    let warnings = warnings();
    let mut app = harbour_app(0.4);
    {
        let mut params = app.world_mut().resource_mut::<SphParams>();
        params.solver = PressureSolver::Wcsph;
        params.support_ratio = 2.5;
    }
    run(&mut app, 1);
    let named = |w: &String| w.contains("FluidCouplingPlugin") && w.contains("WCSPH");
    assert!(!warnings.lock().unwrap().iter().any(named));
    drop_box(&mut app, 0.4, 0.25, 0.1, 0.1, 500.0);
    run(&mut app, 3);
    let found = warnings.lock().unwrap().iter().filter(|w| named(w)).count();
    assert_eq!(found, 1, "{:?}", warnings.lock().unwrap());
}

/// Every warning logged in this test binary, from the first call on (a global subscriber:
/// systems log from the task pool's threads).
fn warnings() -> Arc<Mutex<Vec<String>>> {
    static STORE: OnceLock<Arc<Mutex<Vec<String>>>> = OnceLock::new();
    STORE
        .get_or_init(|| {
            let store = Arc::new(Mutex::new(Vec::new()));
            let subscriber = Registry::default().with(Capture(store.clone()));
            tracing::subscriber::set_global_default(subscriber)
                .expect("no other subscriber in the test binary");
            store
        })
        .clone()
}

/// A tracing layer that keeps the message of every warning.
struct Capture(Arc<Mutex<Vec<String>>>);

impl<S: tracing::Subscriber> Layer<S> for Capture {
    fn on_event(&self, event: &tracing::Event<'_>, _: Context<'_, S>) {
        if *event.metadata().level() == tracing::Level::WARN {
            let mut message = Message(String::new());
            event.record(&mut message);
            self.0.lock().unwrap().push(message.0);
        }
    }
}

/// An event's message field.
struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

/// A 10 cm crate of half the water's density dropped with its bottom half a metre above the
/// water (3.1 m/s at impact) splashes in, plunges without going through the floor and settles
/// afloat within five seconds: in the water, its centre near the water level, under 0.08 m/s
/// on average over the last half second (it rides the tank's sloshing), and no particle ever
/// inside it.
#[test]
fn a_crate_dropped_from_half_a_metre_splashes_and_settles() {
    let mut app = harbour_app(0.9);
    let size = Vec2::splat(0.1);
    let crate_ = drop_box(&mut app, 0.4, 0.2 + 0.5 + 0.05, size.x, size.y, 500.0);
    let (mut lowest, mut speeds) = (f32::INFINITY, Vec::new());
    for tick in 0..300 {
        run(&mut app, 1);
        let world = app.world();
        lowest = lowest.min(world.get::<Transform>(crate_).unwrap().translation.y);
        if tick >= 270 {
            speeds.push(world.get::<LinearVelocity>(crate_).unwrap().0.length());
        }
    }
    let world = app.world();
    let y = world.get::<Transform>(crate_).unwrap().translation.y;
    let floating = *world.get::<Submerged>(crate_).unwrap();
    let speed = speeds.iter().sum::<f32>() / speeds.len() as f32;
    println!(
        "dropped crate: lowest centre {lowest} m, now {y} m, mean speed {speed} m/s, {floating:?}"
    );
    assert!(
        floating.in_water && (0.17..0.25).contains(&y),
        "{y} m, {floating:?}"
    );
    assert!(
        lowest >= 0.05,
        "the crate went into the floor: lowest centre {lowest} m"
    );
    assert!(speed < 0.08, "still moving at {speed} m/s");
    assert_eq!(most_inside(&app), 0, "particles inside the crate");
    assert!(all_finite(&states(&mut app)));
}

/// Gravity is set in one place: avian's follows `SphParams::gravity`, tilted or not (not to a
/// refused value). Tank walls for avian come only when asked for (and a second `App::finish`
/// does no harm).
#[test]
fn avian_takes_the_fluids_gravity_and_tank_walls_are_opt_in() {
    let walls = |app: &mut App| {
        let world = app.world_mut();
        world.query::<&TankWall>().iter(world).count()
    };
    let mut app = harbour_app(0.4);
    run(&mut app, 1);
    assert_eq!(walls(&mut app), 4);
    let tilted = Vec2::new(1.0, -9.7);
    app.world_mut().resource_mut::<SphParams>().gravity = tilted;
    run(&mut app, 1);
    assert_eq!(app.world().resource::<Gravity>().0, tilted);
    // Refused parameters: the fluid keeps its last valid ones, and so does avian.
    app.world_mut().resource_mut::<SphParams>().gravity = Vec2::NAN;
    run(&mut app, 1);
    assert_eq!(app.world().resource::<Gravity>().0, tilted);

    let mut bare = create_app(SphParams {
        tank: Some(Tank::new(0.8, 0.4)),
        ..SphParams::water()
    });
    bare.add_plugins((
        TransformPlugin,
        PhysicsPlugins::default(),
        FluidCouplingPlugin::default(),
    ));
    bare.finish();
    bare.finish();
    bare.cleanup();
    run(&mut bare, 2);
    assert_eq!(walls(&mut bare), 0);
    assert_eq!(
        bare.world().resource::<Gravity>().0,
        SphParams::water().gravity
    );
}
