//! Emitters, drains, sensors and the point probe, headless with the default (DFSPH) solver: an
//! emitter pours at its set rate, a drain removes what enters and counts it, a sensor reads the
//! fill of a resting layer and sends one message per crossing, the probe reads hydrostatic
//! pressure, and bad settings are refused without losing anything.

use crate::common;

use crate::common::{TICK, create_app, run, spawn};
use bevy::ecs::message::Messages;
use bevy::ecs::system::SystemState;
use bevy::prelude::*;
use bevy_sph2d::fluid::{
    ContactAngle, FluidMaterial, FluidParticle, Liquid, Solid, SolidShape, SphParams, SphSolver,
    SphStats, Tank,
};
use bevy_sph2d::gameplay::{
    EmitterRate, FluidBlock, FluidDrain, FluidEmitter, FluidEntered, FluidLeft, FluidQuery,
    FluidRegion, FluidSensor,
};

const SPACING: f32 = 0.01;

fn params() -> SphParams {
    SphParams {
        particle_spacing: SPACING,
        tank: Some(Tank::new(1.0, 0.6)),
        ..SphParams::water()
    }
}

fn particles(app: &mut App) -> usize {
    app.world_mut()
        .query_filtered::<(), With<FluidParticle>>()
        .iter(app.world())
        .count()
}

/// A 1 m × 0.6 m tank with a resting layer 0.2 m deep, settled for a quarter second.
fn resting_layer() -> App {
    let mut app = create_app(params());
    spawn(
        &mut app,
        FluidBlock::resting_layer(&Tank::new(1.0, 0.6), 0.2).with_seed(3),
    );
    run(&mut app, 15);
    app
}

#[test]
fn emitter_pours_at_its_volume_rate() {
    emitter_rate(params());
}

#[test]
fn emitter_pours_at_its_volume_rate_wcsph() {
    emitter_rate(SphParams {
        support_ratio: 2.5,
        speed_of_sound: 20.0,
        ..SphParams {
            solver: bevy_sph2d::fluid::PressureSolver::Wcsph,
            ..params()
        }
    });
}

fn emitter_rate(params: SphParams) {
    let mut app = create_app(params);
    app.update();
    let rate = 0.01; // m²/s: a fifth of the nozzle's full 0.05 m × 1 m/s
    let emitter = app
        .world_mut()
        .spawn((
            FluidEmitter::new(0.05, Vec2::new(0.0, -1.0), 1.0, EmitterRate::Volume(rate)),
            Transform::from_xyz(0.5, 0.5, 0.0),
        ))
        .id();
    let seconds = 1.5;
    let ticks = (seconds / TICK).round() as usize;
    run(&mut app, ticks);
    let emitted = app.world().get::<FluidEmitter>(emitter).unwrap().emitted;
    assert_eq!(particles(&mut app), emitted as usize);
    let measured = emitted as f64 * (SPACING * SPACING) as f64 / (ticks as f64 * TICK);
    assert!(
        (measured / rate as f64 - 1.0).abs() < 0.05,
        "poured {measured:.5} m²/s against {rate} ({emitted} particles)"
    );
    // A budget stops it.
    app.world_mut()
        .get_mut::<FluidEmitter>(emitter)
        .unwrap()
        .budget = Some(emitted + 20);
    run(&mut app, 60);
    let emitter = app.world().get::<FluidEmitter>(emitter).unwrap();
    assert_eq!(emitter.emitted, emitted + 20);
    assert!(!emitter.active);
}

#[test]
fn a_paused_simulation_pours_nothing() {
    let mut app = create_app(params());
    app.update();
    app.world_mut()
        .resource_mut::<bevy_sph2d::SimulationControl>()
        .toggle_pause();
    let emitter = app
        .world_mut()
        .spawn((
            FluidEmitter::new(0.05, Vec2::NEG_Y, 1.0, EmitterRate::Volume(0.01)),
            Transform::from_xyz(0.5, 0.5, 0.0),
        ))
        .id();
    run(&mut app, 30);
    assert_eq!(particles(&mut app), 0, "poured while paused");
    app.world_mut()
        .resource_mut::<bevy_sph2d::SimulationControl>()
        .toggle_pause();
    run(&mut app, 30);
    let emitted = app.world().get::<FluidEmitter>(emitter).unwrap().emitted;
    assert!(emitted > 0 && particles(&mut app) == emitted as usize);
}

#[test]
fn emitter_never_spawns_into_occupied_space() {
    // Pouring straight into the resting layer's surface: every new particle keeps its distance.
    let mut app = resting_layer();
    let before = particles(&mut app);
    app.world_mut().spawn((
        FluidEmitter::new(
            0.1,
            Vec2::new(0.0, -1.0),
            0.5,
            EmitterRate::Particles(400.0),
        ),
        Transform::from_xyz(0.5, 0.19, 0.0),
    ));
    run(&mut app, 3);
    let world = app.world_mut();
    let positions: Vec<Vec2> = world
        .query_filtered::<&bevy_sph2d::fluid::Position, With<FluidParticle>>()
        .iter(world)
        .map(|p| p.0)
        .collect();
    assert!(positions.len() >= before);
    for (i, a) in positions.iter().enumerate() {
        for b in &positions[i + 1..] {
            assert!(a.distance(*b) > 0.5 * SPACING, "{a} and {b} overlap");
        }
    }
}

#[test]
fn drain_removes_what_enters_and_counts_it() {
    let mut app = create_app(params());
    let ids = spawn(&mut app, FluidBlock::dam_break(0.2, 0.3).with_seed(1));
    let drain = app
        .world_mut()
        .spawn(FluidDrain::new(FluidRegion::rect(
            Vec2::new(0.9, 0.1),
            Vec2::new(0.1, 0.1),
        )))
        .id();
    run(&mut app, 90);
    let remaining = particles(&mut app);
    let drain = app.world().get::<FluidDrain>(drain).unwrap();
    assert!(
        drain.removed > 100,
        "the surge should reach the drain: {}",
        drain.removed
    );
    assert_eq!(remaining + drain.removed as usize, ids.len());
    assert!((drain.removed_volume - drain.removed as f32 * SPACING * SPACING).abs() < 1e-6);
    assert_eq!(app.world().resource::<SphStats>().particles, remaining);
}

/// An emitter of oil pours onto a resting layer of water: every particle it pours is oil, the
/// oil floats up to the surface, and sensors for each liquid over the surface rows and the
/// bottom read oil on top and none at the floor, water at the floor.
#[test]
fn an_oil_emitter_pours_oil_that_floats_and_per_liquid_sensors_tell_them_apart() {
    let mut app = create_app(SphParams {
        liquids: vec![Liquid::new("oil", 700.0)],
        ..params()
    });
    spawn(
        &mut app,
        FluidBlock::resting_layer(&Tank::new(1.0, 0.6), 0.2).with_seed(3),
    );
    let oil = FluidMaterial(1);
    let emitter = app
        .world_mut()
        .spawn((
            FluidEmitter::new(0.1, Vec2::new(0.0, -1.0), 0.5, EmitterRate::Volume(0.02))
                .with_material(oil)
                .with_budget(200),
            Transform::from_xyz(0.5, 0.4, 0.0),
        ))
        .id();
    let floor = FluidRegion::rect(Vec2::new(0.5, 0.03), Vec2::new(0.45, 0.03));
    let sensors = [FluidMaterial(0), oil].map(|m| {
        app.world_mut()
            .spawn(FluidSensor::new(floor).for_material(m))
            .id()
    });
    run(&mut app, (3.0 / TICK).round() as usize);
    assert_eq!(
        app.world().get::<FluidEmitter>(emitter).unwrap().emitted,
        200
    );
    let world = app.world_mut();
    let heights: Vec<f32> = world
        .query::<(&bevy_sph2d::fluid::Position, &FluidMaterial)>()
        .iter(world)
        .filter(|(_, m)| **m == oil)
        .map(|(p, _)| p.0.y)
        .collect();
    assert_eq!(heights.len(), 200, "every poured particle is oil");
    let mean = heights.iter().sum::<f32>() / heights.len() as f32;
    assert!(
        mean > 0.18,
        "the oil floats on the water: mean height {mean} m"
    );
    let reading = |app: &App, k: usize| app.world().get::<FluidSensor>(sensors[k]).unwrap().reading;
    let (water, oil) = (reading(&app, 0), reading(&app, 1));
    assert!(water.fill > 0.9, "water at the floor: {water:?}");
    assert_eq!(oil.particles, 0, "no oil at the floor: {oil:?}");
}

#[test]
fn sensor_reads_the_fill_of_a_resting_layer_and_messages_once_per_crossing() {
    let mut app = resting_layer();
    // Half in the 0.2 m layer, half above it.
    let inside = FluidRegion::rect(Vec2::new(0.5, 0.2), Vec2::new(0.2, 0.1));
    let sensor = app
        .world_mut()
        .spawn(FluidSensor::new(inside).with_thresholds(0.3, 0.1))
        .id();
    let mut events = Vec::new();
    // Cursors kept across ticks: each message is read once.
    let mut entered_cursor = app
        .world()
        .resource::<Messages<FluidEntered>>()
        .get_cursor();
    let mut left_cursor = app.world().resource::<Messages<FluidLeft>>().get_cursor();
    let mut record = |app: &mut App, events: &mut Vec<&'static str>| {
        let world = app.world();
        let entered = world.resource::<Messages<FluidEntered>>();
        for message in entered_cursor.read(entered) {
            assert_eq!(message.sensor, sensor);
            events.push("entered");
        }
        let left = world.resource::<Messages<FluidLeft>>();
        for _ in left_cursor.read(left) {
            events.push("left");
        }
    };
    run(&mut app, 1);
    record(&mut app, &mut events);
    let reading = app.world().get::<FluidSensor>(sensor).unwrap().reading;
    assert!(
        (reading.fill - 0.5).abs() < 0.05 * 0.5,
        "fill {} against the geometric 0.5",
        reading.fill
    );
    // The surface rows, with half a neighbourhood, sum a little less than rest density.
    assert!(
        (reading.mean_density / 1000.0 - 1.0).abs() < 0.03,
        "{reading:?}"
    );
    assert!(reading.mean_velocity.length() < 0.05, "{reading:?}");
    // Mean depth of the particles inside is 0.05 m: about 490 Pa.
    assert!(
        (reading.mean_pressure - 490.0).abs() < 0.2 * 490.0,
        "{reading:?}"
    );
    // Lift it out of the water, leave it a while, put it back.
    for (center, ticks) in [(0.5, 20), (0.2, 20)] {
        app.world_mut()
            .get_mut::<FluidSensor>(sensor)
            .unwrap()
            .region = FluidRegion::rect(Vec2::new(0.5, center), Vec2::new(0.2, 0.1));
        for _ in 0..ticks {
            run(&mut app, 1);
            record(&mut app, &mut events);
        }
    }
    assert_eq!(events, ["entered", "left", "entered"]);
}

#[test]
fn the_fluid_query_reads_hydrostatic_pressure_and_nothing_outside() {
    let mut app = resting_layer();
    // Settled as in the physics tests' resting layer (1.5 s).
    run(&mut app, 75);
    let near: Vec<(Vec2, f32)> = {
        let world = app.world_mut();
        world
            .query_filtered::<(&bevy_sph2d::fluid::Position, &bevy_sph2d::fluid::Pressure), With<FluidParticle>>()
            .iter(world)
            .map(|(x, p)| (x.0, p.0))
            .collect()
    };
    let floor = 1000.0 * 9.81 * 0.2;
    let mut state = SystemState::<FluidQuery>::new(app.world_mut());
    let fluid = state.get(app.world()).expect("the fluid is there");
    for depth in [0.05f32, 0.1, 0.15] {
        let at = Vec2::new(0.5, 0.2 - depth);
        let sample = fluid.sample(at).expect("inside the fluid");
        // What the particles around the point carry, and what the depth says (the wide tank
        // still sloshes a little after 1.5 s).
        let around: Vec<f32> = near
            .iter()
            .filter(|(x, _)| x.distance(at) < 1.5 * SPACING)
            .map(|(_, p)| *p)
            .collect();
        let mean = around.iter().sum::<f32>() / around.len() as f32;
        let hydrostatic = 1000.0 * 9.81 * depth;
        assert!(
            (sample.pressure - mean).abs() < 0.03 * floor,
            "at {depth} m: {sample:?}, the particles around carry {mean:.0} Pa"
        );
        assert!(
            (sample.pressure - hydrostatic).abs() < 0.1 * floor,
            "at {depth} m: {sample:?} against {hydrostatic:.0} Pa"
        );
        assert!((sample.density / 1000.0 - 1.0).abs() < 0.01, "{sample:?}");
        assert!(sample.velocity.length() < 0.05, "{sample:?}");
        assert!((sample.coverage - 1.0).abs() < 0.1, "{sample:?}");
    }
    assert_eq!(fluid.sample(Vec2::new(0.5, 0.5)), None);
    assert_eq!(fluid.sample(Vec2::NAN), None);
    // The particles in a region: exactly those whose positions lie in it.
    let region = FluidRegion::rect(Vec2::new(0.3, 0.1), Vec2::new(0.05, 0.03));
    let inside: Vec<Vec2> = fluid.particles_in(region).map(|(_, x)| x).collect();
    let expected = near.iter().filter(|(x, _)| region.contains(*x)).count();
    assert!(expected > 20, "{expected} particles in the region");
    assert_eq!(inside.len(), expected);
    assert!(
        fluid
            .particles_in(FluidRegion::circle(Vec2::new(0.5, 0.5), 0.05))
            .next()
            .is_none()
    );
}

#[test]
fn a_solid_too_big_to_sample_is_refused_and_the_fluid_runs_on() {
    let mut app = resting_layer();
    let before = particles(&mut app);
    let walls = app.world().resource::<SphStats>().wall_particles;
    // Sampled, this disc would need some 10¹² boundary particles (terabytes).
    app.world_mut().spawn((
        Solid::new(SolidShape::circle(1.0e9)),
        Transform::from_xyz(0.5, 0.3, 0.0),
    ));
    run(&mut app, 10);
    assert_eq!(particles(&mut app), before);
    assert_eq!(app.world().resource::<SphStats>().wall_particles, walls);
    assert_eq!(app.world().resource::<SphStats>().removed_escaped, 0);
}

/// A solid's [`ContactAngle`] reaches the fluid, changes with the component, and falls back
/// to the tank's when it is removed or out of range.
#[test]
fn a_solids_contact_angle_follows_its_component() {
    let mut app = resting_layer();
    let plate = app
        .world_mut()
        .spawn((
            Solid::new(SolidShape::rectangle(0.2, 0.04)),
            ContactAngle(30.0),
            Transform::from_xyz(0.5, 0.45, 0.0),
        ))
        .id();
    let angle = |app: &App| {
        let angle = app
            .world()
            .resource::<SphSolver>()
            .solid_contact_angle(plate);
        angle.expect("the fluid holds the plate")
    };
    run(&mut app, 1);
    assert!((angle(&app) - 30.0).abs() < 1e-4);
    app.world_mut()
        .entity_mut(plate)
        .insert(ContactAngle(150.0));
    run(&mut app, 1);
    assert!((angle(&app) - 150.0).abs() < 1e-4);
    // The tank's, SphParams::contact_angle (90° by default).
    app.world_mut()
        .entity_mut(plate)
        .insert(ContactAngle(200.0));
    run(&mut app, 1);
    assert!((angle(&app) - 90.0).abs() < 1e-3);
    app.world_mut().entity_mut(plate).insert(ContactAngle(10.0));
    run(&mut app, 1);
    app.world_mut().entity_mut(plate).remove::<ContactAngle>();
    run(&mut app, 1);
    assert!((angle(&app) - 90.0).abs() < 1e-3);
}

#[test]
fn bad_emitters_drains_and_sensors_change_nothing() {
    let mut app = resting_layer();
    let before = particles(&mut app);
    app.world_mut().spawn((
        Solid::new(SolidShape::circle(0.05)),
        Transform::from_xyz(0.8, 0.45, 0.0),
    ));
    let world = app.world_mut();
    world.spawn((
        FluidEmitter::new(f32::NAN, Vec2::X, 1.0, EmitterRate::Volume(0.01)),
        Transform::from_xyz(0.3, 0.4, 0.0),
    ));
    world.spawn((
        FluidEmitter::new(0.05, Vec2::ZERO, 1.0, EmitterRate::Volume(0.01)),
        Transform::from_xyz(0.3, 0.4, 0.0),
    ));
    // Inside the solid, and outside the tank.
    world.spawn((
        FluidEmitter::new(0.02, Vec2::X, 0.2, EmitterRate::Volume(0.001)),
        Transform::from_xyz(0.8, 0.45, 0.0),
    ));
    world.spawn((
        FluidEmitter::new(0.05, Vec2::X, 1.0, EmitterRate::Volume(0.01)),
        Transform::from_xyz(2.0, 0.4, 0.0),
    ));
    world.spawn(FluidDrain::new(FluidRegion::circle(
        Vec2::new(0.5, 0.1),
        -1.0,
    )));
    let sensor = world
        .spawn(FluidSensor::new(FluidRegion::rect(
            Vec2::new(0.5, 0.1),
            Vec2::ZERO,
        )))
        .id();
    run(&mut app, 20);
    assert_eq!(particles(&mut app), before);
    let sensor = app.world().get::<FluidSensor>(sensor).unwrap();
    assert_eq!(sensor.reading, Default::default());
    assert!(sensor.check().is_err());
}

#[test]
fn the_guard_removes_a_poisoned_particle_and_the_rest_stays_finite() {
    let mut app = resting_layer();
    let before = particles(&mut app);
    let world = app.world_mut();
    let mut query = world.query_filtered::<(
        &mut bevy_sph2d::fluid::Position,
        &mut bevy_sph2d::fluid::Velocity,
    ), With<FluidParticle>>();
    let mut poisoned = 0;
    for (i, (mut position, mut velocity)) in query.iter_mut(world).enumerate() {
        match i {
            100 => velocity.0 = Vec2::new(f32::NAN, 0.0),
            200 => position.0 = Vec2::new(0.5, f32::INFINITY),
            300 => position.0 = Vec2::new(5.0, 0.1),
            _ => continue,
        }
        poisoned += 1;
    }
    assert_eq!(poisoned, 3);
    run(&mut app, 30);
    assert_eq!(particles(&mut app), before - 3);
    let stats = app.world().resource::<SphStats>();
    assert_eq!((stats.removed_non_finite, stats.removed_escaped), (2, 1));
    let states = common::states(&mut app);
    assert!(common::all_finite(&states));
    assert!(
        states.iter().all(|s| s.velocity.length() < 0.5),
        "the layer stays at rest"
    );
}
