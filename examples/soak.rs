//! Headless soak: a resting tank stirred for a given wall time by everything a game does to the
//! fluid at random — pull, push and drag forces around a wandering point (the mouse tools'
//! profiles), pouring and erasing (emitters and drains that come and go), obstacles that appear
//! and vanish, a paddle that sweeps and turns through the water, parameter edits from the
//! validated ranges, tilting gravity, and save/restore round trips; with feature `avian`, also
//! three avian bodies (a crate, a barrel and a stone) tossed about in it and dropped from high
//! up now and then — checking after every tick that every particle and body is finite and
//! inside the tank (a non-finite or escaped body counts as one). Prints last
//! `soak: minutes=M ticks=T particles_min=A particles_max=B nonfinite=0 escaped=0 recovered=R`
//! (`recovered`: updates the solver held back plus particles the stability guard removed) and
//! exits with status 1 if a particle was ever non-finite or outside the tank.
//!
//! ```text
//! cargo run --release --no-default-features --example soak -- --minutes 2
//! cargo run --release --example soak -- --minutes 2   # with avian bodies
//! ```

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{
    Acceleration, FluidParticle, Position, PressureSolver, Solid, SolidShape, SphParams, SphStats,
    SphSubstep, SphSubstepSystems,
};
use bevy_sph2d::gameplay::{
    EmitterRate, FluidDrain, FluidEmitter, FluidRegion, ScenarioKind, SphScenario, load_fluid,
    save_fluid,
};
use bevy_sph2d::prelude::*;
use clap::Parser;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng as StdRng;
use std::time::{Duration, Instant};

/// Headless soak of the fluid under random stirring, sources, obstacles, edits and save/restore.
#[derive(Parser, Debug)]
#[command(name = "soak")]
struct Cli {
    /// Wall time to run, minutes.
    #[arg(long, default_value_t = 2.0)]
    minutes: f64,
    /// Particles of the starting tank.
    #[arg(long, default_value_t = 2_000)]
    particles: u32,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Compute threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
}

/// The wandering "mouse": a force around `center` (a pull, push or drag, as the tools do).
#[derive(Resource, Debug, Clone, Copy, Default)]
struct Stir {
    center: Vec2,
    velocity: Vec2,
    radius: f32,
    /// Positive pulls towards the centre, negative pushes away, m/s².
    strength: f32,
    /// Drag instead: the fluid follows `velocity`.
    drag: bool,
}

/// The stirring force, in every sub-step, with the tools' smooth falloff `(1 − (d/r)²)²`.
fn stir(
    stir: Res<Stir>,
    mut particles: Query<(&Position, &mut Acceleration), With<FluidParticle>>,
) {
    if stir.strength == 0.0 {
        return;
    }
    for (position, mut acceleration) in &mut particles {
        let offset = stir.center - position.0;
        let d2 = offset.length_squared() / (stir.radius * stir.radius);
        if d2 >= 1.0 {
            continue;
        }
        let falloff = (1.0 - d2) * (1.0 - d2);
        acceleration.0 += if stir.drag {
            falloff * 20.0 * stir.velocity
        } else {
            falloff * stir.strength * offset.normalize_or_zero()
        };
    }
}

/// Moves the paddle by its velocity for one tick, turning it back at the tank's walls.
fn sweep(world: &mut World, paddle: Entity, tank: &Tank) {
    let mut entity = world.entity_mut(paddle);
    let mut velocity = *entity
        .get::<SolidVelocity>()
        .expect("the paddle has a velocity");
    let mut transform = entity
        .get_mut::<Transform>()
        .expect("the paddle has a transform");
    let at = transform.translation.truncate() + velocity.linear / 64.0;
    if !(0.15..tank.width - 0.15).contains(&at.x) {
        velocity.linear.x = -velocity.linear.x;
    }
    if !(0.15..tank.height - 0.15).contains(&at.y) {
        velocity.linear.y = -velocity.linear.y;
    }
    transform.translation = at.extend(0.0);
    transform.rotate_z(velocity.angular / 64.0);
    entity.insert(velocity);
}

fn main() {
    let cli = Cli::parse();
    let mut rng = StdRng::seed_from_u64(cli.seed);
    let scenario = SphScenario::new(ScenarioKind::Tank, cli.particles);
    let tank = bevy_sph2d::gameplay::SCENARIO_TANK;
    let base = SphParams {
        tank: Some(tank),
        particle_spacing: scenario.spacing(&tank),
        max_substeps: 60,
        ..SphParams::water()
    };
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(cli.threads.max(1))),
        SphPlugin::default().with_params(base.clone()),
    ))
    .insert_resource(Time::<Fixed>::from_hz(64.0))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
    .insert_resource(scenario)
    .init_resource::<Stir>()
    .add_systems(SphSubstep, stir.in_set(SphSubstepSystems::ExternalForces));
    #[cfg(feature = "avian")]
    let bodies = bodies::add(&mut app, &tank);
    for block in scenario.blocks(&tank) {
        block.spawn(app.world_mut());
    }
    let paddle = app
        .world_mut()
        .spawn((
            Solid::new(SolidShape::rectangle(0.04, 0.3)),
            SolidVelocity {
                linear: Vec2::new(0.4, 0.25),
                angular: 1.5,
            },
            Transform::from_xyz(0.3 * tank.width, 0.4 * tank.height, 0.0),
        ))
        .id();
    app.update();
    let spacing = base.particle_spacing;
    let start_count = cli.particles as usize;
    let (mut low, mut high) = (usize::MAX, 0usize);
    let (mut nonfinite, mut escaped, mut ticks) = (0u64, 0u64, 0u64);
    let (mut sources, mut drains, mut obstacles): (Vec<Entity>, Vec<Entity>, Vec<Entity>) =
        (Vec::new(), Vec::new(), Vec::new());
    let started = Instant::now();
    let budget = Duration::from_secs_f64(cli.minutes.max(0.0) * 60.0);
    let random_point = |rng: &mut StdRng, margin: f32| {
        Vec2::new(
            rng.random_range(margin..tank.width - margin),
            rng.random_range(margin..tank.height - margin),
        )
    };
    while started.elapsed() < budget {
        // The mouse wanders, and now and then changes tool.
        {
            let mut s = app.world_mut().resource_mut::<Stir>();
            if ticks % 32 == 0 {
                s.radius = rng.random_range(0.05..0.3);
                s.strength = rng.random_range(-60.0..60.0);
                s.drag = rng.random_bool(0.3);
                s.velocity = Vec2::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            }
            let next = s.center + s.velocity / 64.0;
            if next.x < 0.0 || next.x > tank.width {
                s.velocity.x = -s.velocity.x;
            }
            if next.y < 0.0 || next.y > tank.height {
                s.velocity.y = -s.velocity.y;
            }
            s.center = (s.center + s.velocity / 64.0).clamp(Vec2::ZERO, tank.size());
        }
        if ticks % 64 == 0 {
            let world = app.world_mut();
            let count = world.resource::<SphStats>().particles;
            // Erasing is brief: a drain lives one second.
            for drain in drains.drain(..) {
                world.despawn(drain);
            }
            // Pour or erase, leaning towards the starting count.
            match rng.random_range(0..4) {
                0 if count < 2 * start_count => {
                    let direction = Vec2::from_angle(rng.random_range(0.0..core::f32::consts::TAU));
                    sources.push(
                        world
                            .spawn((
                                FluidEmitter::new(
                                    rng.random_range(0.02..0.08),
                                    direction,
                                    rng.random_range(0.3..2.0),
                                    EmitterRate::Volume(rng.random_range(0.002..0.03)),
                                )
                                .with_budget(rng.random_range(50..400)),
                                Transform::from_translation(
                                    random_point(&mut rng, 0.05).extend(0.0),
                                ),
                            ))
                            .id(),
                    );
                }
                1 if count > start_count / 2 => {
                    let region = if rng.random_bool(0.5) {
                        FluidRegion::circle(
                            random_point(&mut rng, 0.0),
                            rng.random_range(0.02..0.1),
                        )
                    } else {
                        FluidRegion::rect(
                            random_point(&mut rng, 0.0),
                            Vec2::new(rng.random_range(0.02..0.1), rng.random_range(0.02..0.1)),
                        )
                    };
                    drains.push(world.spawn(FluidDrain::new(region)).id());
                }
                2 if !sources.is_empty() => {
                    let k = rng.random_range(0..sources.len());
                    world.despawn(sources.swap_remove(k));
                }
                _ => {}
            }
            // Obstacles appear and vanish.
            if rng.random_bool(0.3) {
                if obstacles.len() < 3 && rng.random_bool(0.6) {
                    // Still solids: a disc where it is put, or a segment in world coordinates.
                    let obstacle = if rng.random_bool(0.5) {
                        let radius = rng.random_range(0.02..0.08);
                        let at = random_point(&mut rng, 0.1);
                        (
                            Solid::new(SolidShape::circle(radius)),
                            Transform::from_translation(at.extend(0.0)),
                        )
                    } else {
                        let shape = SolidShape::capsule(
                            random_point(&mut rng, 0.1),
                            random_point(&mut rng, 0.1),
                            rng.random_range(0.005..0.03),
                        );
                        (Solid::new(shape), Transform::IDENTITY)
                    };
                    obstacles.push(world.spawn(obstacle).id());
                } else if let Some(obstacle) = obstacles.pop() {
                    world.despawn(obstacle);
                }
            }
            // A parameter edit from the validated ranges, or a tilt of gravity.
            let mut params = world.resource::<SphParams>().clone();
            match rng.random_range(0..6) {
                0 => params.kinematic_viscosity = 10f32.powf(rng.random_range(-6.0..-3.0)),
                1 => params.artificial_viscosity = rng.random_range(0.0..0.1),
                2 => params.dfsph.cfl_number = rng.random_range(0.3..0.8),
                3 => {
                    let angle = rng.random_range(-0.5f32..0.5);
                    params.gravity = Vec2::from_angle(angle).rotate(Vec2::new(0.0, -9.81));
                }
                4 if rng.random_bool(0.2) => {
                    params.solver = match params.solver {
                        PressureSolver::Dfsph => PressureSolver::Wcsph,
                        PressureSolver::Wcsph => PressureSolver::Dfsph,
                    };
                    params.support_ratio = match params.solver {
                        PressureSolver::Dfsph => 2.0,
                        PressureSolver::Wcsph => 2.5,
                    };
                }
                _ => {}
            }
            if params.validate().is_ok() {
                *world.resource_mut::<SphParams>() = params;
            }
            #[cfg(feature = "avian")]
            if rng.random_bool(0.1) {
                let k = rng.random_range(0..bodies.len());
                let at = random_point(&mut rng, 0.1);
                bodies::drop_from(world, bodies[k], Vec2::new(at.x, tank.height - 0.1));
            }
        }
        // A save/restore round trip every ten simulated seconds.
        if ticks % 640 == 320 {
            let world = app.world_mut();
            match save_fluid(world).and_then(|text| load_fluid(world, &text)) {
                Ok(_) => {}
                Err(error) => {
                    eprintln!("soak: save/restore failed: {error}");
                    std::process::exit(1);
                }
            }
        }
        sweep(app.world_mut(), paddle, &tank);
        app.update();
        ticks += 1;
        // Every particle finite and in the tank (a spacing's margin for the wall's own layer).
        let world = app.world_mut();
        let mut count = 0usize;
        let mut query = world
            .query_filtered::<(&Position, &bevy_sph2d::fluid::Velocity), With<FluidParticle>>();
        for (position, velocity) in query.iter(world) {
            count += 1;
            if !position.is_finite() || !velocity.is_finite() {
                nonfinite += 1;
            } else if position.x < -spacing
                || position.y < -spacing
                || position.x > tank.width + spacing
                || position.y > tank.height + spacing
            {
                escaped += 1;
            }
        }
        low = low.min(count);
        high = high.max(count);
        #[cfg(feature = "avian")]
        {
            let (bad, out) = bodies::check(world, &bodies, &tank);
            nonfinite += bad;
            escaped += out;
        }
    }
    let stats = app.world().resource::<SphStats>();
    let recovered = stats.non_finite_resets + stats.removed_non_finite + stats.removed_escaped;
    println!(
        "soak: minutes={:.1} ticks={ticks} particles_min={low} particles_max={high} \
         nonfinite={nonfinite} escaped={escaped} recovered={recovered}",
        started.elapsed().as_secs_f64() / 60.0
    );
    if nonfinite > 0 || escaped > 0 {
        std::process::exit(1);
    }
}

/// Feature `avian`: three coupled avian bodies in the soak's tank.
#[cfg(feature = "avian")]
mod bodies {
    use avian2d::prelude::{Collider, ColliderDensity, PhysicsPlugins, RigidBody};
    use bevy::prelude::*;
    use bevy_sph2d::prelude::*;

    /// Adds avian and the coupling, and spawns a crate, a barrel and a stone.
    pub fn add(app: &mut App, tank: &Tank) -> Vec<Entity> {
        app.add_plugins((
            TransformPlugin,
            PhysicsPlugins::default(),
            FluidCouplingPlugin::with_tank_walls(),
        ));
        app.finish();
        app.cleanup();
        let bodies = [
            (Collider::rectangle(0.1, 0.1), 500.0, 0.55),
            (Collider::circle(0.05), 700.0, 0.75),
            (Collider::rectangle(0.06, 0.06), 3000.0, 0.9),
        ];
        bodies
            .into_iter()
            .map(|(collider, density, x)| {
                let at = Vec2::new(x * tank.width, 0.8 * tank.height);
                app.world_mut()
                    .spawn((
                        RigidBody::Dynamic,
                        collider,
                        ColliderDensity(density),
                        Transform::from_translation(at.extend(0.0)),
                        FluidCoupled,
                    ))
                    .id()
            })
            .collect()
    }

    /// Lifts `body` to `at` and lets it fall.
    pub fn drop_from(world: &mut World, body: Entity, at: Vec2) {
        if let Some(mut transform) = world.get_mut::<Transform>(body) {
            transform.translation = at.extend(0.0);
        }
        if let Some(mut position) = world.get_mut::<avian2d::prelude::Position>(body) {
            position.0 = at;
        }
    }

    /// How many bodies are not finite, and how many are outside the tank.
    pub fn check(world: &World, bodies: &[Entity], tank: &Tank) -> (u64, u64) {
        let (mut bad, mut out) = (0, 0);
        for &body in bodies {
            let Some(transform) = world.get::<Transform>(body) else {
                continue;
            };
            let at = transform.translation.truncate();
            if !at.is_finite() || !transform.rotation.is_finite() {
                bad += 1;
            } else if at.x < 0.0 || at.y < 0.0 || at.x > tank.width || at.y > tank.height {
                out += 1;
            }
        }
        (bad, out)
    }
}
