//! The `harbour` app in a window (feature `avian`), run in a child process of the window test
//! (one window per process): lets the bodies settle for 3 simulated seconds, counts frames and
//! simulated time over 3 real seconds, checks that the boat, the crate and the barrel float
//! (partly in the water, not sunk), that the stone rests on the floor and that no
//! particle is inside a body, then takes a screenshot and checks it is not blank.

use super::{COUNT_FOR, TIMEOUT};
use crate::demo::{HARBOUR_DEPTH, HarbourDemoPlugin};
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy_sph2d::fluid::{FluidParticle, Position, Solid, SphParams, SphStats, Submerged};
use std::sync::Mutex;

/// The verdict, kept outside the app (the window runner keeps the world).
static VERDICT: Mutex<Option<Result<String, String>>> = Mutex::new(None);

/// Simulated seconds the bodies get to settle.
const SETTLE: f64 = 3.0;

#[derive(Resource, Default)]
struct Script {
    /// Real time (s), simulated time (s) and frames when counting began.
    counting: Option<(f32, f64, u64)>,
    frames: u64,
    verdict: Option<Result<String, String>>,
    shot: bool,
}

/// Runs the harbour in a window and exits with the verdict.
pub fn main() {
    let mut app = App::new();
    app.add_plugins((
        super::test_window_plugins("bevy_sph2d harbour window test"),
        HarbourDemoPlugin,
    ))
    .init_resource::<Script>()
    .add_systems(Update, script);
    let exit = app.run();
    match VERDICT.lock().map(|mut v| v.take()).unwrap_or(None) {
        Some(Ok(message)) if exit.is_success() => println!("harbour window test passed: {message}"),
        other => {
            eprintln!("harbour window test FAILED: {other:?} (exit {exit:?})");
            std::process::exit(1);
        }
    }
}

fn script(
    mut script: ResMut<Script>,
    time: Res<Time<Real>>,
    (stats, params): (Res<SphStats>, Res<SphParams>),
    bodies: Query<(&Name, &Submerged, &Solid, &Transform)>,
    particles: Query<&Position, With<FluidParticle>>,
    mut commands: Commands,
    mut exit: MessageWriter<AppExit>,
) {
    let now = time.elapsed_secs();
    script.frames += 1;
    if now > TIMEOUT && script.verdict.is_none() {
        let verdict = Err(format!("timed out at sim time {:.2} s", stats.time));
        finish(&mut script, verdict, &mut exit);
        return;
    }
    if script.shot || stats.time < SETTLE {
        return;
    }
    let Some((real, sim, frames)) = script.counting else {
        script.counting = Some((now, stats.time, script.frames));
        return;
    };
    if now - real < COUNT_FOR {
        return;
    }
    let elapsed = now - real;
    let speed = format!(
        "fps={:.1} sim_speed={:.2} particles={}",
        (script.frames - frames) as f32 / elapsed,
        (stats.time - sim) as f32 / elapsed,
        stats.particles
    );
    let positions: Vec<Vec2> = particles.iter().map(|p| p.0).collect();
    let verdict = bodies_verdict(&bodies, &positions, params.particle_spacing)
        .map(|bodies| format!("{speed}; {bodies}"));
    script.verdict = Some(verdict);
    script.shot = true;
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("window_harbour.png");
    commands
        .spawn(Screenshot::primary_window())
        .observe(save_to_disk(path))
        .observe(check_screenshot);
}

/// Each body's state; an error if a floater is out of the water or sunk, the stone is off the
/// floor, or a particle is more than half a spacing inside a body.
fn bodies_verdict(
    bodies: &Query<(&Name, &Submerged, &Solid, &Transform)>,
    particles: &[Vec2],
    spacing: f32,
) -> Result<String, String> {
    let mut report = Vec::new();
    for (name, submerged, solid, transform) in bodies {
        let at = transform.translation.truncate();
        let turn = Rot2::radians(transform.rotation.to_euler(EulerRot::ZYX).0);
        let inside = particles
            .iter()
            .filter(|&&p| solid.shape.distance(turn.inverse() * (p - at)).0 < -0.5 * spacing)
            .count();
        let line = format!(
            "{name} at ({:.3}, {:.3}) m {:.0}% under, {inside} particles inside",
            at.x,
            at.y,
            100.0 * submerged.fraction
        );
        // Afloat: in the water (a wave may wash over it) and not sunk below half the depth.
        let floating =
            submerged.in_water && submerged.fraction >= 0.1 && at.y > 0.5 * HARBOUR_DEPTH;
        let ok = inside == 0
            && match name.as_str() {
                "stone" => submerged.fraction > 0.9 && at.y < 0.06,
                "paddle" => true,
                _ => floating,
            };
        if !ok {
            return Err(line);
        }
        report.push(line);
    }
    Ok(report.join(", "))
}

/// Not blank: some water-blue and some lit pixels.
fn check_screenshot(
    captured: On<ScreenshotCaptured>,
    mut script: ResMut<Script>,
    mut exit: MessageWriter<AppExit>,
) {
    let picture = match captured.image.clone().try_into_dynamic() {
        Ok(image) => {
            let rgb = image.to_rgb8();
            let total = (rgb.width() * rgb.height()) as f32;
            let blue = rgb.pixels().filter(|p| super::is_water(p.0)).count() as f32 / total;
            if blue > 0.05 {
                Ok(format!("{:.0}% water-blue", 100.0 * blue))
            } else {
                Err(format!(
                    "harbour screenshot looks blank: {:.1}% blue",
                    100.0 * blue
                ))
            }
        }
        Err(error) => Err(format!("harbour screenshot unreadable: {error:?}")),
    };
    let verdict = match (script.verdict.take(), picture) {
        (Some(Ok(a)), Ok(b)) => Ok(format!("{a}; {b}")),
        (Some(Err(a)), _) | (_, Err(a)) => Err(a),
        (None, Ok(b)) => Ok(b),
    };
    finish(&mut script, verdict, &mut exit);
}

fn finish(script: &mut Script, verdict: Result<String, String>, exit: &mut MessageWriter<AppExit>) {
    script.verdict = Some(verdict.clone());
    if let Ok(mut slot) = VERDICT.lock() {
        *slot = Some(verdict);
    }
    exit.write(AppExit::Success);
}
