//! Feature `avian`: the `harbour` example's app. Water in a tank with a wave-maker paddle at
//! the left, and floating crates, a boat, a barrel and a stone of different densities, coupled
//! two ways with avian2d rigid bodies. See [`HarbourDemoPlugin`] (the window) and
//! [`HarbourScene`] (the scene alone, headless too).

use super::limit_catch_up;
use avian2d::prelude::{
    AngularVelocity, Collider, ColliderDensity, LinearVelocity, PhysicsPlugins, RigidBody,
};
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use bevy_sph2d::ParticleSystems;
use bevy_sph2d::coupling::{FluidCoupled, FluidCouplingPlugin};
use bevy_sph2d::fluid::{FluidForce, SphParams, SphPlugin, Submerged, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::render::{ParticleCamera, ParticleDraw, ParticleView, RenderMode};
use bevy_sph2d::{ParticlePlugins, ParticleUiPlugins};

/// The harbour's tank, m.
pub const HARBOUR_TANK: Vec2 = Vec2::new(1.6, 0.8);
/// Still-water depth, m.
pub const HARBOUR_DEPTH: f32 = 0.3;
/// The paddle's period, s.
const PADDLE_PERIOD: f32 = 1.2;
/// Longest stroke the keys set, m.
const MAX_STROKE: f32 = 0.1;
/// Where the paddle stands at rest, m from the left wall.
const PADDLE_X: f32 = 0.2;

/// The whole `harbour` app on top of `DefaultPlugins`: the fluid ([`harbour_params`]) with
/// sprites, mouse tools and the panel, avian with [`FluidCouplingPlugin`], the
/// [`HarbourScene`], a camera, the keys (`Up`/`Down` set the paddle's stroke, `Space` drops a
/// crate) and a "Bodies" window with each body's submerged fraction and fluid force.
#[derive(Debug, Clone, Copy, Default)]
pub struct HarbourDemoPlugin;

/// The harbour's scene alone: the water, the paddle (kinematic, driven by [`PaddleStroke`])
/// and the floating bodies. Needs the fluid (`SphPlugin` with [`harbour_params`]), avian's
/// `PhysicsPlugins` and [`FluidCouplingPlugin`]; runs headless with `MinimalPlugins` and
/// `TransformPlugin`.
#[derive(Debug, Clone, Copy, Default)]
pub struct HarbourScene;

/// The wave maker's stroke (amplitude of its sway), m.
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Debug)]
pub struct PaddleStroke(pub f32);

/// Marks the harbour's wave-maker paddle.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Paddle;

/// The harbour's water: [`SphParams::water`] at a 2 cm spacing (about 1,100 particles) in the
/// [`HARBOUR_TANK`], with the demo's speed of sound and sub-step cap (see
/// [`demo_params`](super::demo_params)). The default solve's fixed budget needs no cap with the
/// five bodies in the water (the strict solve's largest-error stop was seldom met there, and it
/// ran to 300 iterations a sub-step).
pub fn harbour_params() -> SphParams {
    SphParams {
        tank: Some(Tank::new(HARBOUR_TANK.x, HARBOUR_TANK.y)),
        particle_spacing: 0.02,
        speed_of_sound: 30.0,
        max_substeps: 40,
        ..SphParams::water()
    }
}

impl Plugin for HarbourScene {
    fn build(&self, app: &mut App) {
        app.insert_resource(PaddleStroke(0.04))
            .add_systems(Startup, spawn_harbour)
            .add_systems(FixedUpdate, drive_paddle.before(ParticleSystems::Prepare));
    }
}

impl Plugin for HarbourDemoPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((
            ParticlePlugins::default().set(SphPlugin::default().with_params(harbour_params())),
            ParticleUiPlugins,
            PhysicsPlugins::default(),
            FluidCouplingPlugin::with_tank_walls(),
            HarbourScene,
        ))
        .insert_resource(ClearColor(Color::srgb(0.04, 0.05, 0.07)))
        .insert_resource(ParticleView {
            draw: ParticleDraw::Liquid,
            mode: RenderMode::Solid,
            ..default()
        })
        .add_systems(Startup, (spawn_camera, limit_catch_up))
        .add_systems(Update, (set_stroke, drop_crate))
        .add_systems(EguiPrimaryContextPass, bodies_window);
    }
}

fn spawn_camera(mut commands: Commands) {
    commands.spawn(ParticleCamera::default());
}

/// The water (clear of the paddle), the paddle and four bodies: a boat (relative density 0.3),
/// a crate (0.5), a barrel (0.7) and a stone (2.5).
fn spawn_harbour(mut commands: Commands) {
    // Water on both sides of the paddle, which stands clear of the floor (the water flows under
    // it) and of the wall at its longest stroke (none is trapped behind it).
    let beside = PADDLE_X - 0.05;
    commands.queue(FluidBlock::new(
        Vec2::ZERO,
        Vec2::new(beside, HARBOUR_DEPTH),
    ));
    commands.queue(FluidBlock::new(
        Vec2::new(PADDLE_X + 0.05, 0.0),
        Vec2::new(HARBOUR_TANK.x - PADDLE_X - 0.05, HARBOUR_DEPTH),
    ));
    commands.spawn((
        Name::new("paddle"),
        Paddle,
        RigidBody::Kinematic,
        Collider::rectangle(0.04, 0.5),
        Transform::from_xyz(PADDLE_X, 0.3, 0.0),
        FluidCoupled,
    ));
    let hull = [(-0.2, 0.04), (0.2, 0.04), (0.13, -0.04), (-0.13, -0.04)];
    let hull = Collider::convex_hull(hull.map(|(x, y)| Vec2::new(x, y)).to_vec())
        .unwrap_or_else(|| Collider::rectangle(0.4, 0.08));
    let bodies = [
        ("crate", Collider::rectangle(0.1, 0.1), 500.0, 0.5),
        ("boat", hull, 300.0, 0.9),
        ("barrel", Collider::circle(0.06), 700.0, 1.3),
        ("stone", Collider::rectangle(0.07, 0.07), 2500.0, 1.5),
    ];
    for (name, collider, density, x) in bodies {
        let at = Vec2::new(x, HARBOUR_DEPTH + 0.06);
        commands.spawn(floating_body(name, collider, density, at));
    }
}

/// A dynamic coupled body named `name` of `density` (kg/m³) at `at`.
fn floating_body(name: &str, collider: Collider, density: f32, at: Vec2) -> impl Bundle {
    (
        Name::new(name.to_owned()),
        RigidBody::Dynamic,
        collider,
        ColliderDensity(density),
        Transform::from_translation(at.extend(0.0)),
        FluidCoupled,
    )
}

/// Sways the paddle back and forth (`x = x₀ + A sin ωt`) by setting its velocity.
fn drive_paddle(
    time: Res<Time>,
    stroke: Res<PaddleStroke>,
    mut paddle: Query<(&mut LinearVelocity, &mut AngularVelocity), With<Paddle>>,
) {
    let omega = core::f32::consts::TAU / PADDLE_PERIOD;
    let t = time.elapsed_secs();
    for (mut linear, mut angular) in &mut paddle {
        linear.0 = Vec2::new(stroke.0 * omega * (omega * t).cos(), 0.0);
        angular.0 = 0.0;
    }
}

fn set_stroke(keys: Res<ButtonInput<KeyCode>>, mut stroke: ResMut<PaddleStroke>) {
    if keys.just_pressed(KeyCode::ArrowUp) {
        stroke.0 = (stroke.0 + 0.02).min(MAX_STROKE);
    }
    if keys.just_pressed(KeyCode::ArrowDown) {
        stroke.0 = (stroke.0 - 0.02).max(0.0);
    }
}

fn drop_crate(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut commands: Commands) {
    if keys.just_pressed(KeyCode::Space) {
        let x = 0.4 + (time.elapsed_secs() * 0.37).fract() * (HARBOUR_TANK.x - 0.6);
        let at = Vec2::new(x, HARBOUR_TANK.y - 0.1);
        commands.spawn(floating_body(
            "crate",
            Collider::rectangle(0.1, 0.1),
            500.0,
            at,
        ));
    }
}

/// Each body's submerged fraction and the fluid's force on it.
fn bodies_window(
    mut contexts: EguiContexts,
    stroke: Res<PaddleStroke>,
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
