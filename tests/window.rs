//! The demo app in a real window: runs the `dam_break` app's plugin (with the resting-tank
//! scenario, so the only motion is the mouse's). First in the liquid view the demo starts in:
//! counts frames, takes a screenshot with Bevy's `Screenshot` and checks from its pixels that
//! the resting layer is one body of water without holes whose surface line lies within two
//! particle spacings of the highest particles. Then in the sprite view: counts frames, holds the
//! left mouse button above the water with `xdotool` (or, without it, by warping the pointer and
//! pressing the button in Bevy's input), takes a screenshot, and checks that the water rose
//! towards the cursor and that the picture is not blank. Prints the frame rates of both views.
//! With feature `avian` it then runs the `harbour` app in a child process (`window/harbour.rs`:
//! bodies float, the stone rests on the floor, no particle inside a body, a screenshot).
//!
//! Needs an X display: CI runs it under `xvfb-run` (Mesa's lavapipe renders on the CPU). Without
//! `DISPLAY` it prints why and passes. The screenshot is kept in the target's temp folder.

#[path = "../examples/demo/mod.rs"]
mod demo;

use bevy::ecs::schedule::{LogLevel, ScheduleLabel};
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::window::PrimaryWindow;
use bevy::winit::WinitPlugin;
use bevy_sph2d::SphSubstep;
use bevy_sph2d::fluid::SphParams;
use bevy_sph2d::fluid::{FluidParticle, Position, SphStats};
use bevy_sph2d::gameplay::{ScenarioKind, SphScenario};
use bevy_sph2d::interact::PointerSettings;
use bevy_sph2d::render::{ParticleCamera, ParticleDraw, ParticleView};
use demo::SphDemoPlugin;
use std::process::Command;
use std::sync::Mutex;

/// The outcome, kept outside the app: `App::run` hands the world to the window runner, which does
/// not give it back.
static VERDICT: Mutex<Option<Result<String, String>>> = Mutex::new(None);

const TITLE: &str = "bevy_sph2d window test";
/// Where the cursor pulls, m: 0.14 m above the middle of a 0.36 m deep layer in the
/// 1.6 m × 0.9 m tank, so the tool's 0.2 m radius reaches into the water.
const TARGET: Vec2 = Vec2::new(0.8, 0.5);
/// Water above this height near the cursor has been lifted by the tool, m.
const LIFTED: f32 = 0.42;
/// Real seconds before giving up.
const TIMEOUT: f32 = 240.0;
/// Real seconds each view's frames are counted over.
const COUNT_FOR: f32 = 3.0;

#[derive(Resource, Default)]
struct Script {
    phase: Phase,
    started: f32,
    lifted_before: usize,
    sim_time_at_press: f64,
    xdotool: bool,
    verdict: Option<Result<String, String>>,
    /// Frames, real time (s) and simulated time (s) since the layer settled.
    frames: u64,
    measured_from: Option<(f32, f64)>,
    /// Frames counted in each view and over how long (real s).
    counted: u64,
    counting_since: f32,
    liquid_fps: f32,
    sprite_fps: f32,
    /// Where the liquid screenshot's columns are checked.
    columns: Vec<Column>,
    /// Screen pixels per world metre, and the particle spacing (m).
    pixels_per_metre: f32,
    spacing: f32,
}

/// A column of the liquid screenshot: screen x, the screen y of the tank floor and of the
/// highest particle near it (px, y down).
#[derive(Debug, Clone, Copy)]
struct Column {
    x: u32,
    floor: f32,
    top: f32,
}

#[derive(Default, PartialEq, Debug, Clone, Copy)]
enum Phase {
    #[default]
    Settle,
    /// Counting the liquid view's frames, then its screenshot.
    Liquid,
    LiquidShot,
    /// Counting the sprite view's frames.
    Sprites,
    Press,
    Pulling,
    Shot,
    Done,
}

/// Set in the child process that runs the harbour.
#[cfg(feature = "avian")]
const HARBOUR_ENV: &str = "SPH_WINDOW_TEST_HARBOUR";

#[cfg(feature = "avian")]
#[path = "window/harbour.rs"]
mod harbour;

fn main() {
    if std::env::var_os("DISPLAY").is_none() {
        eprintln!("window test SKIPPED: no DISPLAY; run it under xvfb-run (see .ci/run)");
        return;
    }
    #[cfg(feature = "avian")]
    if std::env::var_os(HARBOUR_ENV).is_some() {
        harbour::main();
        return;
    }
    let xdotool = Command::new("xdotool").arg("version").output().is_ok();
    if !xdotool {
        eprintln!("xdotool not found: injecting the mouse input into Bevy instead");
    }
    let mut demo = SphDemoPlugin::dam_break(1500);
    demo.scenario = SphScenario::new(ScenarioKind::Tank, 1500);
    let mut app = App::new();
    app.add_plugins((test_window_plugins(TITLE), demo))
        .insert_resource(PointerSettings {
            radius: 0.2,
            ..default()
        })
        .insert_resource(Script {
            xdotool,
            ..default()
        })
        .add_systems(Update, script);
    // The whole demo (fluid, gravity, render, mouse tools, panel) with no ambiguous order in the
    // particle schedules: a build error panics the first tick.
    for label in [FixedUpdate.intern(), SphSubstep.intern()] {
        app.edit_schedule(label, |schedule| {
            let mut settings = schedule.get_build_settings();
            settings.ambiguity_detection = LogLevel::Error;
            schedule.set_build_settings(settings);
        });
    }
    let exit = app.run();
    let verdict = VERDICT.lock().map(|mut v| v.take()).unwrap_or(None);
    match verdict {
        Some(Ok(message)) if exit.is_success() => {
            println!("window test passed: {message}");
            #[cfg(feature = "avian")]
            run_harbour();
        }
        Some(Err(message)) => {
            eprintln!("window test FAILED: {message}");
            std::process::exit(1);
        }
        other => {
            eprintln!("window test FAILED: app ended with {exit:?} before a verdict ({other:?})");
            std::process::exit(1);
        }
    }
}

/// `DefaultPlugins` for a test window titled `title`: 1024 × 576, the event loop on the test's
/// thread, two compute threads.
fn test_window_plugins(title: &str) -> impl PluginGroup {
    DefaultPlugins
        .set(WindowPlugin {
            primary_window: Some(Window {
                title: title.into(),
                resolution: (1024, 576).into(),
                ..default()
            }),
            ..default()
        })
        .set(WinitPlugin {
            run_on_any_thread: true,
        })
        .set(bevy_sph2d::task_pool_plugin(2))
}

/// Runs the harbour's window test in a child process (a process opens one event loop) and
/// fails if it does.
#[cfg(feature = "avian")]
fn run_harbour() {
    // The dam break's pull has let go, and the cursor is out of the harbour's way.
    let _ = Command::new("xdotool")
        .args(["mouseup", "1", "mousemove", "0", "0"])
        .status();
    let status =
        std::env::current_exe().and_then(|exe| Command::new(exe).env(HARBOUR_ENV, "1").status());
    match status {
        Ok(status) if status.success() => {}
        other => {
            eprintln!("window test FAILED: the harbour's run ended with {other:?}");
            std::process::exit(1);
        }
    }
}

/// How many particles the tool has lifted above the layer near the cursor, and their centroid.
fn lifted_near_target(particles: &Query<&Position, With<FluidParticle>>) -> (usize, Vec2) {
    let lifted: Vec<Vec2> = particles
        .iter()
        .map(|p| p.0)
        .filter(|p| p.y > LIFTED && (p.x - TARGET.x).abs() < 0.3)
        .collect();
    let centroid = lifted.iter().sum::<Vec2>() / lifted.len().max(1) as f32;
    (lifted.len(), centroid)
}

/// Runs `xdotool` with `args` against the test window.
fn xdotool(args: &[String]) -> bool {
    let mut command = Command::new("xdotool");
    command.args(["search", "--sync", "--name", TITLE]);
    command.args(args);
    command.status().map(|s| s.success()).unwrap_or(false)
}

#[expect(
    clippy::too_many_arguments,
    reason = "a Bevy system: one parameter per resource and query it reads"
)]
fn script(
    mut script: ResMut<Script>,
    time: Res<Time<Real>>,
    stats: Res<SphStats>,
    particles: Query<&Position, With<FluidParticle>>,
    camera: Single<(&Camera, &GlobalTransform), With<ParticleCamera>>,
    mut window: Single<&mut Window, With<PrimaryWindow>>,
    view: Res<ParticleView>,
    params: Res<SphParams>,
    mut buttons: ResMut<ButtonInput<MouseButton>>,
    mut commands: Commands,
    mut exit: MessageWriter<AppExit>,
) {
    let now = time.elapsed_secs();
    if now > TIMEOUT && script.verdict.is_none() {
        script.verdict = Some(Err(format!(
            "timed out in phase {:?} (sim time {:.2} s)",
            script.phase, stats.time
        )));
        if let Ok(mut verdict) = VERDICT.lock() {
            *verdict = script.verdict.clone();
        }
        exit.write(AppExit::error());
        return;
    }
    let (camera, camera_transform) = *camera;
    if matches!(script.phase, Phase::Pulling | Phase::Shot | Phase::Done) {
        script.frames += 1;
    }
    script.counted += 1;
    match script.phase {
        // Let the window open, the shaders compile and the layer settle, in the liquid view.
        Phase::Settle => {
            if now < 3.0 || stats.time < 0.5 || stats.particles == 0 {
                return;
            }
            if view.draw != ParticleDraw::Liquid {
                script.verdict = Some(Err(format!("the demo starts in {:?}", view.draw)));
                script.phase = Phase::Done;
                return;
            }
            // The tool's circle follows the cursor: out of the picture, over the panel.
            let corner = Vec2::splat(2.0);
            let moved = script.xdotool
                && xdotool(&[
                    "mousemove".into(),
                    "--window".into(),
                    "%1".into(),
                    "2".into(),
                    "2".into(),
                ]);
            if !moved {
                window.set_cursor_position(Some(corner));
            }
            script.counted = 0;
            script.counting_since = now;
            script.phase = Phase::Liquid;
        }
        Phase::Liquid => {
            if now - script.counting_since < COUNT_FOR {
                return;
            }
            script.liquid_fps = script.counted as f32 / (now - script.counting_since);
            let scale = window.scale_factor();
            let Some((columns, pixels_per_metre)) =
                columns(&particles, camera, camera_transform, &params, scale)
            else {
                script.verdict = Some(Err("the tank is not in view".into()));
                script.phase = Phase::Done;
                return;
            };
            script.columns = columns;
            script.pixels_per_metre = pixels_per_metre;
            script.spacing = params.particle_spacing;
            let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("window_liquid.png");
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(path))
                .observe(check_liquid);
            script.phase = Phase::LiquidShot;
        }
        Phase::LiquidShot => {}
        Phase::Sprites => {
            if now - script.counting_since < COUNT_FOR {
                return;
            }
            script.sprite_fps = script.counted as f32 / (now - script.counting_since);
            script.phase = Phase::Press;
        }
        Phase::Press => {
            let Ok(cursor) = camera.world_to_viewport(camera_transform, TARGET.extend(0.0)) else {
                return;
            };
            script.lifted_before = lifted_near_target(&particles).0;
            script.sim_time_at_press = stats.time;
            script.measured_from = Some((now, stats.time));
            let (x, y) = (cursor.x.round() as i32, cursor.y.round() as i32);
            if script.xdotool {
                let moved = xdotool(&[
                    "mousemove".into(),
                    "--window".into(),
                    "%1".into(),
                    x.to_string(),
                    y.to_string(),
                    "mousedown".into(),
                    "1".into(),
                ]);
                if !moved {
                    eprintln!("xdotool failed; injecting the input instead");
                    script.xdotool = false;
                }
            }
            if !script.xdotool {
                window.set_cursor_position(Some(cursor));
                buttons.press(MouseButton::Left);
            }
            println!(
                "pressing at px ({x}, {y}) = world {TARGET} at sim time {:.2} s; {} particles \
                 lifted before",
                stats.time, script.lifted_before
            );
            script.started = now;
            script.phase = Phase::Pulling;
        }
        // Pull for 1 s of simulated time, then photograph the heap under the cursor.
        Phase::Pulling => {
            if stats.time - script.sim_time_at_press < 1.0 {
                return;
            }
            let (lifted, centroid) = lifted_near_target(&particles);
            let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("window_test.png");
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(path.clone()))
                .observe(check_screenshot);
            let gained = lifted.saturating_sub(script.lifted_before);
            let message = format!(
                "{lifted} particles above {LIFTED} m near the cursor after pulling (was {}), \
                 centred {:.3} m from it; screenshot {}",
                script.lifted_before,
                centroid.distance(TARGET),
                path.display()
            );
            script.verdict = Some(if gained >= 20 && centroid.distance(TARGET) < 0.1 {
                Ok(message)
            } else {
                Err(format!("the water did not rise to the cursor: {message}"))
            });
            script.phase = Phase::Shot;
        }
        Phase::Shot => {}
        Phase::Done => {
            if let Some((real, sim)) = script.measured_from {
                let elapsed = (now - real).max(1e-3);
                println!(
                    "window: fps={:.1} sim_speed={:.2} particles={}",
                    script.frames as f32 / elapsed,
                    (stats.time - sim) as f32 / elapsed,
                    stats.particles
                );
            }
            println!(
                "views at rest: liquid fps={:.1} sprites fps={:.1} (liquid frame time {:.2}x)",
                script.liquid_fps,
                script.sprite_fps,
                script.sprite_fps / script.liquid_fps.max(1e-3)
            );
            if let Ok(mut verdict) = VERDICT.lock() {
                *verdict = script.verdict.clone();
            }
            if script.xdotool {
                xdotool(&["mouseup".into(), "1".into()]);
            } else {
                buttons.release(MouseButton::Left);
            }
            exit.write(AppExit::Success);
        }
    }
}

/// The screen columns to check in the liquid view: twelve across the middle 70% of the tank,
/// with the floor and the highest particle within 1.5 spacings of each (physical px), and the
/// screen's pixels per metre.
fn columns(
    particles: &Query<&Position, With<FluidParticle>>,
    camera: &Camera,
    transform: &GlobalTransform,
    params: &SphParams,
    scale: f32,
) -> Option<(Vec<Column>, f32)> {
    let tank = params.tank?;
    let dx = params.particle_spacing;
    let to_screen = |p: Vec2| {
        camera
            .world_to_viewport(transform, p.extend(0.0))
            .ok()
            .map(|v| v * scale)
    };
    let pixels_per_metre = (to_screen(Vec2::X)? - to_screen(Vec2::ZERO)?).x.abs();
    let positions: Vec<Vec2> = particles.iter().map(|p| p.0).collect();
    (0..12)
        .map(|k| {
            let x = tank.width * (0.15 + 0.7 * k as f32 / 11.0);
            let top = positions
                .iter()
                .filter(|p| (p.x - x).abs() < 1.5 * dx)
                .map(|p| p.y)
                .fold(f32::NEG_INFINITY, f32::max);
            let floor = to_screen(Vec2::new(x, 0.0))?;
            Some(Column {
                x: floor.x.round() as u32,
                floor: floor.y,
                top: to_screen(Vec2::new(x, top.is_finite().then_some(top)?))?.y,
            })
        })
        .collect::<Option<Vec<_>>>()
        .map(|columns| (columns, pixels_per_metre))
}

/// A pixel of the water's body, rim included (bluish and bright enough), not the background,
/// the outline or the panel.
fn is_water([r, _, b]: [u8; 3]) -> bool {
    b > 80 && b as i32 > r as i32 + 30
}

/// The liquid view of the resting layer: in every column, water all the way from just above
/// the floor to a surface within two spacings of the highest particle, and background just
/// above it; a row at half depth all water across the columns.
fn liquid_verdict(
    pixel: impl Fn(u32, u32) -> Option<[u8; 3]>,
    script: &Script,
) -> Result<String, String> {
    let limit = 2.0 * script.spacing * script.pixels_per_metre;
    let mut offsets = Vec::new();
    for column in &script.columns {
        let water = |y: f32| pixel(column.x, y.round().max(0.0) as u32).is_some_and(is_water);
        let start = column.floor - 3.0;
        let mut surface = start;
        while surface > 0.0 && water(surface) {
            surface -= 1.0;
        }
        // Screen y grows downwards: positive is above the highest particle.
        let above = column.top - surface;
        if above.abs() > limit {
            return Err(format!(
                "liquid column at px {}: water from the floor up to px {surface} but the highest \
                 particle is at px {:.0} ({:.1} spacings off; a hole or a misplaced surface)",
                column.x,
                column.top,
                above / (script.spacing * script.pixels_per_metre)
            ));
        }
        if (2..6).any(|k| water(surface - k as f32)) {
            return Err(format!(
                "liquid column at px {}: water again just above the surface at px {surface}",
                column.x
            ));
        }
        offsets.push(above / (script.spacing * script.pixels_per_metre));
    }
    let (first, last) = match (script.columns.first(), script.columns.last()) {
        (Some(first), Some(last)) => (first, last),
        _ => return Err("no liquid columns".into()),
    };
    let y = (0.5 * (first.floor + first.top)).round() as u32;
    if let Some(x) = (first.x..=last.x).find(|&x| !pixel(x, y).is_some_and(is_water)) {
        return Err(format!(
            "liquid row at half depth (px {y}) has a hole at px {x}"
        ));
    }
    let (low, high) = offsets
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &o| {
            (l.min(o), h.max(o))
        });
    Ok(format!(
        "{} columns of water without holes, the surface {low:.1}-{high:.1} spacings above the \
         highest particles; the half-depth row is water from px {} to {}",
        script.columns.len(),
        first.x,
        last.x
    ))
}

/// Checks the liquid view's screenshot, then switches to the sprite view and counts its frames.
fn check_liquid(
    captured: On<ScreenshotCaptured>,
    mut script: ResMut<Script>,
    mut view: ResMut<ParticleView>,
    time: Res<Time<Real>>,
) {
    let verdict = match captured.image.clone().try_into_dynamic() {
        Ok(image) => {
            let rgb = image.to_rgb8();
            liquid_verdict(|x, y| rgb.get_pixel_checked(x, y).map(|p| p.0), &script)
        }
        Err(error) => Err(format!("liquid screenshot unreadable: {error:?}")),
    };
    match verdict {
        Ok(message) => println!("liquid view: {message}"),
        Err(message) => {
            script.verdict = Some(Err(message));
            script.phase = Phase::Done;
            return;
        }
    }
    view.draw = ParticleDraw::Sprites;
    script.counted = 0;
    script.counting_since = time.elapsed_secs();
    script.phase = Phase::Sprites;
}

/// Not blank: most of the frame is not the clear colour's neighbourhood only, and it holds both
/// the dark background and lighter water and panel pixels.
fn check_screenshot(captured: On<ScreenshotCaptured>, mut script: ResMut<Script>) {
    let verdict = match captured.image.clone().try_into_dynamic() {
        Ok(image) => {
            let rgb = image.to_rgb8();
            let total = (rgb.width() * rgb.height()) as f32;
            let bright = rgb.pixels().filter(|p| p.0.iter().any(|&c| c > 60)).count() as f32;
            let blue = rgb
                .pixels()
                .filter(|p| p.0[2] > 80 && p.0[2] as i32 > p.0[0] as i32 + 30)
                .count() as f32;
            let (bright, blue) = (bright / total, blue / total);
            if bright > 0.05 && blue > 0.02 && bright < 0.98 {
                Ok(format!(
                    "{:.0}% lit pixels, {:.0}% water-blue",
                    100.0 * bright,
                    100.0 * blue
                ))
            } else {
                Err(format!(
                    "screenshot looks blank: {:.1}% lit, {:.1}% blue",
                    100.0 * bright,
                    100.0 * blue
                ))
            }
        }
        Err(error) => Err(format!("screenshot unreadable: {error:?}")),
    };
    script.verdict = match (script.verdict.take(), verdict) {
        (Some(Ok(a)), Ok(b)) => Some(Ok(format!("{a}; {b}"))),
        (Some(Err(a)), _) => Some(Err(a)),
        (_, Err(b)) => Some(Err(b)),
        (None, Ok(b)) => Some(Ok(b)),
    };
    script.phase = Phase::Done;
}
