//! A harbour: water in a tank with a wave-maker paddle at the left, and floating crates, a boat,
//! a barrel and a stone of different densities, coupled two ways with avian2d rigid bodies (the
//! water pushes them, they push the water).
//!
//! Keys: `Up`/`Down` lengthen or shorten the paddle's stroke, `Space` drops a new crate. The
//! mouse tools and the panel work as in `dam_break`; the "Bodies" window lists each body's
//! submerged fraction and the fluid's force on it.
//!
//! `cargo run --example harbour`

use avian2d::prelude::{
    AngularVelocity, Collider, ColliderDensity, LinearVelocity, PhysicsPlugins, RigidBody,
};
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::prelude::*;

/// The tank, m.
const TANK: Vec2 = Vec2::new(1.6, 0.8);
/// Still-water depth, m.
const DEPTH: f32 = 0.3;

fn main() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let params = SphParams {
        tank: Some(Tank::new(TANK.x, TANK.y)),
        ..SphParams::water()
    };
    App::new()
        .add_plugins((
            DefaultPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
            ParticlePlugins::default().set(SphPlugin::default().with_params(params)),
            ParticleUiPlugins,
            PhysicsPlugins::default(),
            FluidCouplingPlugin,
        ))
        .insert_resource(Stroke(0.06))
        .add_systems(Startup, setup)
        .add_systems(Update, (set_stroke, drop_crate))
        .add_systems(EguiPrimaryContextPass, bodies_window)
        .add_systems(FixedUpdate, drive_paddle.before(ParticleSystems::Prepare))
        .run();
}

/// The paddle's stroke (amplitude), m.
#[derive(Resource)]
struct Stroke(f32);

/// The wave maker.
#[derive(Component)]
struct Paddle;

fn setup(mut commands: Commands) {
    commands.spawn(ParticleCamera::default());
    commands.queue(FluidBlock::new(
        Vec2::new(0.15, 0.0),
        Vec2::new(TANK.x - 0.15, DEPTH),
    ));
    commands.spawn((
        Name::new("paddle"),
        Paddle,
        RigidBody::Kinematic,
        Collider::rectangle(0.04, 0.5),
        Transform::from_xyz(0.08, 0.3, 0.0),
        FluidCoupled,
    ));
    let hull = [(-0.2, 0.04), (0.2, 0.04), (0.13, -0.04), (-0.13, -0.04)];
    let hull = Collider::convex_hull(hull.map(|(x, y)| Vec2::new(x, y)).to_vec());
    let bodies = [
        ("boat", hull.expect("a convex hull"), 300.0, 0.75),
        ("crate", Collider::rectangle(0.1, 0.1), 500.0, 0.45),
        ("barrel", Collider::circle(0.05), 700.0, 1.05),
        ("stone", Collider::rectangle(0.07, 0.07), 2500.0, 1.3),
    ];
    for (name, collider, density, x) in bodies {
        spawn_body(
            &mut commands,
            name,
            collider,
            density,
            Vec2::new(x, DEPTH + 0.06),
        );
    }
}

fn spawn_body(commands: &mut Commands, name: &str, collider: Collider, density: f32, at: Vec2) {
    commands.spawn((
        Name::new(name.to_owned()),
        RigidBody::Dynamic,
        collider,
        ColliderDensity(density),
        Transform::from_translation(at.extend(0.0)),
        FluidCoupled,
    ));
}

/// Moves the paddle back and forth (`x = x₀ + A sin ωt`, 1.2 s period) by its velocity.
fn drive_paddle(
    time: Res<Time>,
    stroke: Res<Stroke>,
    mut paddle: Single<(&mut LinearVelocity, &mut AngularVelocity), With<Paddle>>,
) {
    let omega = core::f32::consts::TAU / 1.2;
    let t = time.elapsed_secs();
    paddle.0.0 = Vec2::new(stroke.0 * omega * (omega * t).cos(), 0.0);
    paddle.1.0 = 0.0;
}

fn set_stroke(keys: Res<ButtonInput<KeyCode>>, mut stroke: ResMut<Stroke>) {
    if keys.just_pressed(KeyCode::ArrowUp) {
        stroke.0 = (stroke.0 + 0.02).min(0.14);
    }
    if keys.just_pressed(KeyCode::ArrowDown) {
        stroke.0 = (stroke.0 - 0.02).max(0.0);
    }
}

fn drop_crate(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut commands: Commands) {
    if keys.just_pressed(KeyCode::Space) {
        let x = 0.4 + (time.elapsed_secs() * 0.37).fract() * (TANK.x - 0.6);
        let at = Vec2::new(x, TANK.y - 0.1);
        spawn_body(
            &mut commands,
            "crate",
            Collider::rectangle(0.1, 0.1),
            500.0,
            at,
        );
    }
}

/// Each body's submerged fraction and the fluid's force on it.
fn bodies_window(
    mut contexts: EguiContexts,
    stroke: Res<Stroke>,
    bodies: Query<(&Name, &Submerged, &FluidForce)>,
) -> Result {
    egui::Window::new("Bodies")
        .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
        .show(contexts.ctx_mut()?, |ui| {
            ui.label(format!(
                "paddle stroke {:.2} m (Up/Down), Space drops a crate",
                stroke.0
            ));
            for (name, submerged, force) in &bodies {
                ui.label(format!(
                    "{name}: {:3.0}% under, force ({:6.1}, {:6.1}) N/m",
                    100.0 * submerged.fraction,
                    force.force.x,
                    force.force.y
                ));
            }
        });
    Ok(())
}
