//! Feature `render`: the mouse and keyboard tools — pull, push, drag, pour and erase fluid
//! under the cursor; pause, step, reset and tilt the tank from the keyboard. See
//! [`ParticleInteractPlugin`].

mod tools;

use crate::control::{ResetSimulation, SimulationControl, simulation_running};
use crate::fluid::SubstepHooks;
use crate::fluid::{
    Acceleration, FluidMaterial, FluidParticle, SphParams, SphSubstep, SphSubstepSystems,
};
use crate::gameplay::{EmitterRate, FluidEmitter, LoadSlot, SaveSlot};
use crate::gravity::{GravityAcceleration, Mass};
use crate::particle::{Position, Velocity};
use crate::render::{ParticleCamera, ParticleDraw, ParticleView, cursor_to_world};
use crate::schedule::{BodyForceSystems, ParticleSchedule, ParticleSystems};
use bevy::input::mouse::AccumulatedMouseScroll;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

pub(crate) use tools::{PointerAction, PointerForce, tilted_gravity};

/// Mouse and keyboard tools for the fluid.
///
/// Mouse (over the tank, not over UI): the left button uses the [`PointerTool`] in
/// [`PointerSettings`] (pull, drag, pour or erase); the right button always pushes; the wheel
/// changes the radius. The tool's circle is drawn with gizmos.
///
/// Keyboard: `Space` pauses, `.` runs a single tick, `R` resets the scenario, `L` switches
/// between the liquid and the particles ([`ParticleView::draw`]), `F5` saves the fluid into the
/// [`SnapshotSlot`](crate::gameplay::SnapshotSlot) and `F9` loads it, `←`/`→` tilt the tank (turn
/// gravity), `↑` levels it, `1`–`5` pick the tool.
///
/// The cursor is read each frame before the fixed steps
/// ([`RunFixedMainLoopSystems::BeforeFixedMainLoop`]) into [`Pointer`]; the fixed step applies
/// its force in [`SphSubstepSystems::PointerForces`] (on bodies in
/// [`BodyForceSystems::Pointer`]) and pours, erases or spawns bodies in
/// [`ParticleInteractSystems`], in [`ParticleSystems::Input`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ParticleInteractPlugin;

/// What the left mouse button does.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum PointerTool {
    /// Pull fluid towards the cursor (the right button pushes it away).
    #[default]
    Pull,
    /// Move the fluid under the cursor with the cursor's velocity.
    Drag,
    /// Pour new particles from the cursor.
    Pour,
    /// Remove particles under the cursor.
    Erase,
    /// Spawn gravity bodies at the cursor, moving with it.
    Bodies,
}

impl PointerTool {
    /// Every tool, in menu order (keys `1`–`5`).
    pub const ALL: [PointerTool; 5] = [
        PointerTool::Pull,
        PointerTool::Drag,
        PointerTool::Pour,
        PointerTool::Erase,
        PointerTool::Bodies,
    ];

    /// The tool's name.
    pub fn label(self) -> &'static str {
        match self {
            PointerTool::Pull => "Pull / push",
            PointerTool::Drag => "Drag",
            PointerTool::Pour => "Pour",
            PointerTool::Erase => "Erase",
            PointerTool::Bodies => "Spawn bodies",
        }
    }
}

/// Tool settings; edit them live (the panel does).
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct PointerSettings {
    /// The left button's tool.
    pub tool: PointerTool,
    /// Radius of every tool, m.
    pub radius: f32,
    /// Peak acceleration of pull and push, m/s².
    pub strength: f32,
    /// How fast pull damps and drag matches the cursor's velocity, 1/s.
    pub rate: f32,
    /// Speed of the poured jet, m/s.
    pub pour_speed: f32,
    /// Pouring stops at this many particles.
    pub max_particles: usize,
    /// The liquid the pour tool pours (see [`FluidMaterial`]; `M` cycles through them).
    pub pour_material: FluidMaterial,
    /// How fast the arrow keys tilt the tank, rad/s.
    pub tilt_rate: f32,
    /// Largest tilt, rad.
    pub max_tilt: f32,
    /// Mass of each spawned body, kg.
    pub body_mass: f32,
    /// Bodies spawned per fixed tick while the button is held.
    pub bodies_per_tick: u32,
}

impl Default for PointerSettings {
    fn default() -> Self {
        Self {
            tool: PointerTool::Pull,
            radius: 0.12,
            strength: 60.0,
            rate: 12.0,
            pour_speed: 1.5,
            max_particles: 20_000,
            pour_material: FluidMaterial(0),
            tilt_rate: 0.8,
            max_tilt: 1.0,
            body_mass: 1.0e-4,
            bodies_per_tick: 4,
        }
    }
}

/// The pointer as the simulation sees it, updated every frame.
#[derive(Resource, Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct Pointer {
    /// The cursor in world space, m (`None` outside the window).
    pub world: Option<Vec2>,
    /// The cursor's velocity, m/s.
    pub velocity: Vec2,
    /// The force the fixed step applies this frame.
    pub(crate) force: PointerForce,
    /// The left button is held with the pour or erase tool.
    pub tool_active: bool,
    /// UI has the pointer (set by the panel): the tools ignore the mouse.
    pub over_ui: bool,
    /// UI has the keyboard (set by the panel): the key bindings are ignored.
    pub ui_has_keyboard: bool,
    /// Current tilt of the tank, rad.
    pub tilt: f32,
}

/// The pour, erase and spawn systems, in [`ParticleSystems::Input`] of the particle schedule.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ParticleInteractSystems;

impl Plugin for ParticleInteractPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<PointerSettings>()
            .register_type::<Pointer>()
            .init_resource::<PointerSettings>()
            .init_resource::<Pointer>()
            .add_systems(
                RunFixedMainLoop,
                track_pointer.in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop),
            )
            .add_systems(
                SphSubstep,
                apply_pointer_force.in_set(SphSubstepSystems::PointerForces),
            )
            .add_systems(Update, (keyboard_controls, draw_pointer));
        SubstepHooks::register(app, 1, |world| {
            world.resource::<Pointer>().force.action != PointerAction::None
        });
    }

    /// The fixed-step systems go into the particle schedule once every plugin is built, so the
    /// tools follow [`ParticlePlugins`](crate::ParticlePlugins) added before or after them.
    fn finish(&self, app: &mut App) {
        let schedule = ParticleSchedule::of(app);
        app.configure_sets(
            schedule,
            ParticleInteractSystems.in_set(ParticleSystems::Input),
        )
        .add_systems(
            schedule,
            (
                (aim_pour_nozzle, erase_particles, spawn_bodies)
                    .chain()
                    .run_if(simulation_running)
                    .in_set(ParticleInteractSystems),
                push_bodies
                    .run_if(simulation_running)
                    .in_set(BodyForceSystems::Pointer),
            ),
        );
    }
}

/// Reads the cursor, buttons and wheel into [`Pointer`].
fn track_pointer(
    window: Single<&Window, With<PrimaryWindow>>,
    camera: Single<(&Camera, &GlobalTransform, &Projection), With<ParticleCamera>>,
    buttons: Res<ButtonInput<MouseButton>>,
    scroll: Res<AccumulatedMouseScroll>,
    time: Res<Time<Real>>,
    mut settings: ResMut<PointerSettings>,
    mut pointer: ResMut<Pointer>,
) {
    let (camera, camera_transform, projection) = *camera;
    let projection: &Projection = projection;
    let world = match (
        window.cursor_position(),
        camera.logical_viewport_rect(),
        projection,
    ) {
        (Some(cursor), Some(viewport), Projection::Orthographic(ortho)) => Some(cursor_to_world(
            cursor - viewport.min,
            viewport.size(),
            ortho.area,
            camera_transform,
        )),
        _ => None,
    };
    let dt = time.delta_secs();
    let velocity = match (world, pointer.world) {
        (Some(now), Some(before)) if dt > 0.0 => (now - before) / dt,
        _ => Vec2::ZERO,
    };
    // Smooth over a few frames: cursor motion arrives in uneven steps.
    let smoothed = pointer.velocity.lerp(velocity, 0.5);
    pointer.world = world;
    pointer.velocity = if smoothed.is_finite() {
        smoothed
    } else {
        Vec2::ZERO
    };

    let free = world.is_some() && !pointer.over_ui;
    if free && scroll.delta.y != 0.0 {
        let radius = settings.radius * 1.1f32.powf(scroll.delta.y.clamp(-10.0, 10.0));
        settings.radius = radius.clamp(0.01, 10.0);
    }
    let left = free && buttons.pressed(MouseButton::Left);
    let right = free && buttons.pressed(MouseButton::Right);
    let action = match (left, right, settings.tool) {
        (_, true, _) => PointerAction::Push,
        (true, _, PointerTool::Pull) => PointerAction::Pull,
        (true, _, PointerTool::Drag) => PointerAction::Drag,
        _ => PointerAction::None,
    };
    pointer.tool_active = left
        && matches!(
            settings.tool,
            PointerTool::Pour | PointerTool::Erase | PointerTool::Bodies
        );
    pointer.force = PointerForce {
        action,
        center: world.unwrap_or_default(),
        velocity: pointer.velocity,
        radius: settings.radius,
        strength: settings.strength,
        rate: settings.rate,
    };
}

/// Adds the pointer's force to every particle it reaches (in each sub-step).
fn apply_pointer_force(
    pointer: Res<Pointer>,
    mut particles: Query<(&Position, &Velocity, &mut Acceleration), With<FluidParticle>>,
) {
    let force = pointer.force;
    if force.action == PointerAction::None {
        return;
    }
    particles
        .par_iter_mut()
        .for_each(|(position, velocity, mut acceleration)| {
            let a = force.acceleration(position.0, velocity.0);
            if a != Vec2::ZERO {
                acceleration.0 += a;
            }
        });
}

/// Most particles in one row of the pour tool's nozzle.
const MAX_POUR_ROW: u32 = 256;

/// Most rows the pour tool pours in one tick (a flick of the cursor must not fire a burst).
const MAX_POUR_ROWS_PER_TICK: f32 = 4.0;

/// The [`FluidEmitter`] the pour tool drives (spawned on first use, kept for the session).
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct PourNozzle;

/// Aims the pour tool's [`FluidEmitter`] at the cursor and turns it on while the pour tool is
/// held: a jet of [`PointerSettings::pour_speed`] down plus half the cursor's velocity, as wide
/// as the tool's radius (at most [`MAX_POUR_ROW`] particles), one row per spacing of jet and at
/// most [`MAX_POUR_ROWS_PER_TICK`] a tick, never past
/// [`PointerSettings::max_particles`]. The emitter pours in [`SphSystems::Finish`] like any
/// other, on free spots only.
///
/// [`SphSystems::Finish`]: crate::fluid::SphSystems::Finish
fn aim_pour_nozzle(
    time: Res<Time>,
    pointer: Res<Pointer>,
    settings: Res<PointerSettings>,
    params: Res<SphParams>,
    particles: Query<(), With<FluidParticle>>,
    mut nozzle: Query<(&mut FluidEmitter, &mut Transform), With<PourNozzle>>,
    mut commands: Commands,
) {
    let pouring = settings.tool == PointerTool::Pour && pointer.tool_active;
    let Ok((mut emitter, mut transform)) = nozzle.single_mut() else {
        if pouring {
            let mut idle = FluidEmitter::new(1.0, Vec2::NEG_Y, 1.0, EmitterRate::Particles(0.0));
            idle.active = false;
            commands.spawn((PourNozzle, idle, Transform::default()));
        }
        return;
    };
    // Outside the tank the tool pours nothing (the emitter, kept off, does not warn).
    let inside = |p: Vec2| params.tank.is_none_or(|tank| tank.contains(p, 0.0));
    let (Some(center), true) = (pointer.world.filter(|&p| inside(p)), pouring) else {
        emitter.active = false;
        return;
    };
    let spacing = params.particle_spacing;
    let jet = Vec2::new(0.0, -settings.pour_speed.max(0.01)) + 0.5 * pointer.velocity;
    transform.translation = center.extend(0.0);
    emitter.width = settings
        .radius
        .clamp(spacing, MAX_POUR_ROW as f32 * spacing);
    emitter.direction = jet;
    emitter.speed = jet.length();
    emitter.material = settings.pour_material;
    // One row per spacing of jet, and a few a tick at most however fast the cursor flicks.
    let most = MAX_POUR_ROWS_PER_TICK / time.delta_secs().max(1e-6);
    let rows_per_second = (emitter.speed / spacing).min(most);
    emitter.rate = EmitterRate::Particles(rows_per_second * emitter.row_len(spacing) as f32);
    let room = settings
        .max_particles
        .saturating_sub(particles.iter().len());
    let room = u32::try_from(room).unwrap_or(u32::MAX);
    emitter.budget = Some(emitter.emitted.saturating_add(room));
    emitter.active = room > 0;
}

/// Despawns the particles under the cursor while the erase tool is held.
fn erase_particles(
    pointer: Res<Pointer>,
    settings: Res<PointerSettings>,
    particles: Query<(Entity, &Position), With<FluidParticle>>,
    mut commands: Commands,
) {
    let (Some(center), true) = (pointer.world, pointer.tool_active) else {
        return;
    };
    if settings.tool != PointerTool::Erase {
        return;
    }
    let radius_sq = settings.radius * settings.radius;
    for (entity, position) in &particles {
        if position.distance_squared(center) < radius_sq {
            commands.entity(entity).despawn();
        }
    }
}

/// Spawns bodies around the cursor while the body tool is held, moving with the cursor.
fn spawn_bodies(
    pointer: Res<Pointer>,
    settings: Res<PointerSettings>,
    mut tick: Local<u64>,
    mut commands: Commands,
) {
    let (Some(center), true) = (pointer.world, pointer.tool_active) else {
        return;
    };
    if settings.tool != PointerTool::Bodies {
        return;
    }
    *tick += 1;
    let count = settings.bodies_per_tick.min(1000);
    let velocity = pointer.velocity;
    let radius = settings.radius;
    let mass = settings.body_mass.max(0.0);
    let seed = *tick;
    commands.spawn_batch(
        (0..count)
            .map(move |i| {
                // A golden-angle spiral inside the radius, turned a little every tick.
                let k = i as f32 + 0.5;
                let r = radius * (k / count as f32).sqrt();
                let angle = k * 2.399_963 + seed as f32 * 0.618;
                (
                    Mass(mass),
                    Position(center + r * Vec2::from_angle(angle)),
                    Velocity(velocity),
                )
            })
            .collect::<Vec<_>>(),
    );
}

/// What the pointer pushes: gravity bodies' position, velocity and acceleration.
type PushedBody = (
    &'static Position,
    &'static Velocity,
    &'static mut GravityAcceleration,
);

/// The pointer's force on gravity bodies (fluid particles get it in the fluid's sub-steps).
fn push_bodies(
    pointer: Res<Pointer>,
    mut bodies: Query<PushedBody, (With<Mass>, Without<FluidParticle>)>,
) {
    let force = pointer.force;
    if force.action == PointerAction::None {
        return;
    }
    bodies
        .par_iter_mut()
        .for_each(|(position, velocity, mut acceleration)| {
            acceleration.0 += force.acceleration(position.0, velocity.0);
        });
}

/// Space, `.`, `R`, `L`, `F5`/`F9`, arrows and `1`–`5`.
#[expect(
    clippy::too_many_arguments,
    reason = "a Bevy system: one parameter per resource and query it reads"
)]
fn keyboard_controls(
    keys: Res<ButtonInput<KeyCode>>,
    view: Option<ResMut<ParticleView>>,
    time: Res<Time<Real>>,
    mut pointer: ResMut<Pointer>,
    mut settings: ResMut<PointerSettings>,
    mut control: ResMut<SimulationControl>,
    mut params: ResMut<SphParams>,
    mut resets: MessageWriter<ResetSimulation>,
    mut commands: Commands,
) {
    if pointer.ui_has_keyboard {
        return;
    }
    if keys.just_pressed(KeyCode::Space) {
        control.toggle_pause();
    }
    if keys.just_pressed(KeyCode::Period) {
        control.step();
    }
    if keys.just_pressed(KeyCode::KeyR) {
        resets.write(ResetSimulation);
    }
    if keys.just_pressed(KeyCode::F5) {
        commands.queue(SaveSlot);
    }
    if keys.just_pressed(KeyCode::F9) {
        commands.queue(LoadSlot);
    }
    if keys.just_pressed(KeyCode::KeyM) {
        let liquids = params.liquids.len() as u8 + 1;
        settings.pour_material = FluidMaterial((settings.pour_material.0 + 1) % liquids);
    }
    if keys.just_pressed(KeyCode::KeyL)
        && let Some(mut view) = view
    {
        view.draw = match view.draw {
            ParticleDraw::Sprites => ParticleDraw::Liquid,
            ParticleDraw::Liquid => ParticleDraw::Sprites,
        };
    }
    for (key, tool) in [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
    ]
    .into_iter()
    .zip(PointerTool::ALL)
    {
        if keys.just_pressed(key) {
            settings.tool = tool;
        }
    }
    let turn = match (
        keys.pressed(KeyCode::ArrowLeft),
        keys.pressed(KeyCode::ArrowRight),
    ) {
        (true, false) => 1.0,
        (false, true) => -1.0,
        _ => 0.0,
    };
    let mut tilt = pointer.tilt + turn * settings.tilt_rate * time.delta_secs();
    if keys.just_pressed(KeyCode::ArrowUp) {
        tilt = 0.0;
    }
    tilt = tilt.clamp(-settings.max_tilt, settings.max_tilt);
    if tilt != pointer.tilt {
        pointer.tilt = tilt;
        let gravity = tilted_gravity(params.gravity, tilt);
        if gravity.is_finite() && params.gravity != gravity {
            params.gravity = gravity;
        }
    }
}

/// The tool's circle at the cursor.
fn draw_pointer(pointer: Res<Pointer>, settings: Res<PointerSettings>, mut gizmos: Gizmos) {
    let Some(center) = pointer.world else {
        return;
    };
    if pointer.over_ui {
        return;
    }
    let color = match (pointer.force.action, settings.tool, pointer.tool_active) {
        (PointerAction::Pull, ..) => Color::srgb(0.3, 1.0, 0.5),
        (PointerAction::Push, ..) => Color::srgb(1.0, 0.4, 0.3),
        (PointerAction::Drag, ..) => Color::srgb(1.0, 0.85, 0.3),
        (_, PointerTool::Pour, true) => Color::srgb(0.4, 0.7, 1.0),
        (_, PointerTool::Erase, true) => Color::srgb(1.0, 0.3, 0.9),
        (_, PointerTool::Bodies, true) => Color::srgb(1.0, 0.7, 0.2),
        _ => Color::srgba(1.0, 1.0, 1.0, 0.6),
    };
    gizmos.circle_2d(Isometry2d::from_translation(center), settings.radius, color);
}
