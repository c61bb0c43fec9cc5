//! The demo app in a real window: runs the `dam_break` app's plugin (with the resting-tank
//! scenario, so the only motion is the mouse's), holds the left mouse button above the water
//! with `xdotool` (or, without it, by warping the pointer and pressing the button in Bevy's
//! input), takes a screenshot with Bevy's `Screenshot`, and checks that the water rose towards
//! the cursor and that the picture is not blank.
//!
//! Needs an X display: CI runs it under `xvfb-run` (Mesa's lavapipe renders on the CPU). Without
//! `DISPLAY` it prints why and passes. The screenshot is kept in the target's temp folder.

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::window::PrimaryWindow;
use bevy::winit::WinitPlugin;
use bevy_sph2d::demo::SphDemoPlugin;
use bevy_sph2d::fluid::{FluidParticle, Position, ScenarioKind, SphScenario, SphStats};
use bevy_sph2d::interact::PointerSettings;
use bevy_sph2d::render::SphCamera;
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
}

#[derive(Default, PartialEq, Debug, Clone, Copy)]
enum Phase {
    #[default]
    Settle,
    Pulling,
    Shot,
    Done,
}

fn main() {
    if std::env::var_os("DISPLAY").is_none() {
        eprintln!("window test SKIPPED: no DISPLAY; run it under xvfb-run (see .ci/run)");
        return;
    }
    let xdotool = Command::new("xdotool").arg("version").output().is_ok();
    if !xdotool {
        eprintln!("xdotool not found: injecting the mouse input into Bevy instead");
    }
    let mut demo = SphDemoPlugin::dam_break(1500);
    demo.scenario = SphScenario::new(ScenarioKind::Tank, 1500);
    let mut app = App::new();
    app.add_plugins((
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: Some(Window {
                    title: TITLE.into(),
                    resolution: (1024, 576).into(),
                    ..default()
                }),
                ..default()
            })
            .set(WinitPlugin {
                run_on_any_thread: true,
            })
            .set(bevy_sph2d::task_pool_plugin(2)),
        demo,
    ))
    .insert_resource(PointerSettings {
        radius: 0.2,
        ..default()
    })
    .insert_resource(Script {
        xdotool,
        ..default()
    })
    .add_systems(Update, script);
    let exit = app.run();
    let verdict = VERDICT.lock().map(|mut v| v.take()).unwrap_or(None);
    match verdict {
        Some(Ok(message)) if exit.is_success() => println!("window test passed: {message}"),
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

#[allow(clippy::too_many_arguments)]
fn script(
    mut script: ResMut<Script>,
    time: Res<Time<Real>>,
    stats: Res<SphStats>,
    particles: Query<&Position, With<FluidParticle>>,
    camera: Single<(&Camera, &GlobalTransform), With<SphCamera>>,
    mut window: Single<&mut Window, With<PrimaryWindow>>,
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
    if script.phase != Phase::Settle {
        script.frames += 1;
    }
    match script.phase {
        // Let the window open, the shaders compile and the layer settle.
        Phase::Settle => {
            if now < 3.0 || stats.time < 0.3 || stats.particles == 0 {
                return;
            }
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
