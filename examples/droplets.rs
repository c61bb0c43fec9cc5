//! Droplets: water with surface tension (σ = 0.072 N/m) at a millimetre's spacing, dripping from
//! three taps onto three tilted plates that it wets differently: at 20° the drops spread and run
//! down the plate as a film, at 90° they sit as half-discs and slide, at 150° they bead and roll
//! off. A drain in the floor keeps the box from filling.
//!
//! Left mouse button: pull (pick a drop up and let it go: it rounds and oscillates); right:
//! push; wheel: the tool's radius. The panel edits the surface tension and the box's contact
//! angle (the plates keep their own); Reset clears the water; `T` stops and restarts the taps.
//!
//! `cargo run --example droplets` (a window), `cargo run --example droplets -- --headless 5`
//! to run 5 simulated seconds without one and print the speed relative to real time, or
//! `-- --screenshot droplets.png 8` to save the window after 8 simulated seconds and quit.

mod demo;

use bevy::prelude::*;
use bevy_sph2d::fluid::{ContactAngle, Solid, SolidShape, SphParams, Tank};
use bevy_sph2d::gameplay::{EmitterRate, FluidDrain, FluidEmitter, FluidRegion};
use demo::{ScreenshotAt, headless_seconds, liquid_window, run_scene_headless};

/// The box, m.
const BOX: Vec2 = Vec2::new(0.09, 0.05);

/// The plates: centre (m), tilt (degrees, counter-clockwise) and the water's contact angle on
/// each (degrees).
const PLATES: [(Vec2, f32, f32); 3] = [
    (Vec2::new(0.017, 0.024), -15.0, 20.0),
    (Vec2::new(0.045, 0.018), 15.0, 90.0),
    (Vec2::new(0.073, 0.024), -15.0, 150.0),
];

/// The plates' size, m.
const PLATE: Vec2 = Vec2::new(0.024, 0.003);

/// Each tap opens for this long every [`DRIP_PERIOD`], s: a burst of about 50 particles that
/// rounds into a drop some 8 mm across as it falls.
const DRIP_OPEN: f32 = 0.2;

/// The taps' period, s (each a third of it after the last).
const DRIP_PERIOD: f32 = 1.0;

/// Water at 1 mm spacing with surface tension, on the default solver: the capillary length
/// (2.7 mm) is almost three spacings, so drops of a few millimetres bead; the sub-step keeps
/// under the capillary limit (1.5 ms) and at most 40 run a tick. The speed of sound is
/// water's default: under DFSPH it only scales the artificial viscosity, which damps the
/// surface's noise at the scale of a particle (at 10 m/s drops shed stray particles).
fn droplet_params() -> SphParams {
    SphParams {
        tank: Some(Tank::new(BOX.x, BOX.y)),
        particle_spacing: 0.001,
        surface_tension: 0.072,
        contact_angle: 90.0,
        max_substeps: 40,
        ..SphParams::water()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match headless_seconds(&args) {
        Some(seconds) => run_scene_headless("droplets", droplet_params(), DropletScene, seconds),
        None => window(ScreenshotAt::from_args(&args, "droplets.png", 8.0)),
    }
}

/// The example in a window, drawn as liquid, with the mouse tools and the panel.
fn window(shot: Option<ScreenshotAt>) {
    liquid_window("bevy_sph2d: droplets", droplet_params(), DropletScene, shot)
        .add_systems(Update, toggle_taps)
        .run();
}

/// The scene: the plates, a tap over each and the drain.
struct DropletScene;

impl Plugin for DropletScene {
    fn build(&self, app: &mut App) {
        app.insert_resource(TapsOn(true))
            .add_systems(Startup, spawn_scene)
            .add_systems(FixedUpdate, drip);
    }
}

/// A tap and its phase in the drip cycle, s.
#[derive(Component)]
struct Tap(f32);

/// Whether the taps drip (`T`).
#[derive(Resource)]
struct TapsOn(bool);

/// Opens each tap for [`DRIP_OPEN`] every [`DRIP_PERIOD`].
fn drip(on: Res<TapsOn>, time: Res<Time>, mut taps: Query<(&Tap, &mut FluidEmitter)>) {
    for (tap, mut emitter) in &mut taps {
        let open = on.0 && (time.elapsed_secs() + tap.0).rem_euclid(DRIP_PERIOD) < DRIP_OPEN;
        if emitter.active != open {
            emitter.active = open;
        }
    }
}

fn spawn_scene(mut commands: Commands) {
    for (k, (centre, tilt, angle)) in PLATES.into_iter().enumerate() {
        commands.spawn((
            Solid::new(SolidShape::rectangle(PLATE.x, PLATE.y)),
            ContactAngle(angle),
            Transform::from_translation(centre.extend(0.0))
                .with_rotation(Quat::from_rotation_z(tilt.to_radians())),
        ));
        // A tap over the plate's upper half.
        let over = centre + Vec2::new(-0.004 * tilt.signum(), 0.018);
        commands.spawn((
            Tap(k as f32 * DRIP_PERIOD / 3.0),
            FluidEmitter::new(0.003, Vec2::NEG_Y, 0.1, EmitterRate::Particles(250.0)),
            Transform::from_translation(over.extend(0.0)),
        ));
    }
    // What reaches the floor drains away.
    commands.spawn(FluidDrain::new(FluidRegion::rect(
        Vec2::new(BOX.x / 2.0, 0.002),
        Vec2::new(BOX.x / 2.0, 0.002),
    )));
}

/// `T` stops and restarts the taps.
fn toggle_taps(keys: Res<ButtonInput<KeyCode>>, mut on: ResMut<TapsOn>) {
    if keys.just_pressed(KeyCode::KeyT) {
        on.0 = !on.0;
    }
}
