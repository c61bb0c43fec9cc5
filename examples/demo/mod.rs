//! The examples' ready-made demo apps, shared by the `dam_break`, `record_gif`, `harbour` and
//! `droplets` examples and the window test (`mod demo;`, or `#[path]` from `tests/`): a
//! scenario in a tank, sprites, mouse tools and the panel (`SphDemoPlugin`), with feature
//! `avian` the harbour (`HarbourDemoPlugin`), and the headless runner (`run_headless`). Not
//! part of the library: it is what a game built on the crate's public API looks like.

#![allow(dead_code, reason = "each example uses a different part")]

use bevy::prelude::*;
use bevy_sph2d::ResetSimulation;
use bevy_sph2d::fluid::{SphParams, SphPlugin};
use bevy_sph2d::gameplay::{ScenarioKind, SphScenario};
use bevy_sph2d::render::{ParticleCamera, ParticleDraw, ParticleView, RenderMode};
use bevy_sph2d::{ParticlePlugins, ParticleUiPlugins};

#[cfg(feature = "avian")]
mod harbour;
#[cfg(feature = "avian")]
#[allow(unused_imports, reason = "each example uses a different part")]
pub use harbour::{
    HARBOUR_DEPTH, HARBOUR_TANK, HarbourDemoPlugin, HarbourScene, Paddle, PaddleStroke,
    harbour_params,
};

/// Everything the demo needs on top of `DefaultPlugins`: [`ParticlePlugins`] with
/// [`demo_params`], [`ParticleUiPlugins`] drawing the liquid ([`ParticleDraw::Liquid`]; `L`
/// switches to the particles), a [`ParticleCamera`], and the scenario spawned at start.
#[derive(Debug, Clone)]
pub struct SphDemoPlugin {
    /// The scenario spawned at start and on every reset.
    pub scenario: SphScenario,
    /// The fluid's parameters.
    pub params: SphParams,
}

impl SphDemoPlugin {
    /// A dam break of about `particles` particles.
    pub fn dam_break(particles: u32) -> Self {
        Self {
            scenario: SphScenario::new(ScenarioKind::DamBreak, particles),
            params: demo_params(),
        }
    }
}

/// `DefaultPlugins` for a demo window: a 1280 × 720 window titled `title`, and Bevy's compute
/// pool on every core ([`task_pool_plugin`](bevy_sph2d::task_pool_plugin)).
pub fn window_plugins(title: &str) -> impl PluginGroup {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    DefaultPlugins
        .set(WindowPlugin {
            primary_window: Some(Window {
                title: title.into(),
                resolution: (1280, 720).into(),
                ..default()
            }),
            ..default()
        })
        .set(bevy_sph2d::task_pool_plugin(threads))
}

/// Water tuned for interactive use in the scenario tank (1.6 m × 0.9 m), on the default
/// incompressible solver:
/// - the default support of 2 spacings (about 12 neighbours);
/// - speed of sound 30 m/s, about six times the fastest flow of its dam break (4.6 m/s): what
///   WCSPH steps at if you pick it in the panel (the accurate `20 √(g H)` = 46 m/s costs it 1.5
///   times the sub-steps); DFSPH only scales its artificial viscosity with it;
/// - at most 40 sub-steps per tick, so a slow machine runs the fluid in slow motion instead of
///   dropping frames (the panel shows the speed relative to real time).
pub fn demo_params() -> SphParams {
    SphParams {
        tank: Some(bevy_sph2d::gameplay::SCENARIO_TANK),
        speed_of_sound: 30.0,
        max_substeps: 40,
        ..SphParams::water()
    }
}

/// At most this much virtual time per frame, s: four fixed ticks at Bevy's 64 Hz, so the fluid
/// keeps real time down to 16 frames per second (a software renderer draws the demo at about
/// 20). A frame that falls further behind runs four ticks, not a growing pile of them.
pub const MAX_FRAME_TIME: f64 = 4.0 / 64.0;

impl Plugin for SphDemoPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((
            ParticlePlugins::default().set(SphPlugin::default().with_params(self.params.clone())),
            ParticleUiPlugins,
        ))
        .insert_resource(ClearColor(Color::srgb(0.04, 0.05, 0.07)))
        .insert_resource(ParticleView {
            draw: ParticleDraw::Liquid,
            mode: RenderMode::Solid,
            ..default()
        })
        .insert_resource(self.scenario)
        .add_systems(Startup, (start_demo, limit_catch_up));
    }
}

fn start_demo(mut commands: Commands, mut resets: MessageWriter<ResetSimulation>) {
    commands.spawn(ParticleCamera::default());
    resets.write(ResetSimulation);
}

/// Holds each frame to [`MAX_FRAME_TIME`] of virtual time (a `Startup` system).
pub fn limit_catch_up(mut time: ResMut<Time<Virtual>>) {
    time.set_max_delta(core::time::Duration::from_secs_f64(MAX_FRAME_TIME));
}

/// `MinimalPlugins` on every core, for a scene run without a window by [`run_headless`].
pub fn headless_plugins() -> (impl PluginGroup, TransformPlugin) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    (
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        TransformPlugin,
    )
}

/// Runs `app` (a scene on [`headless_plugins`]) for `seconds` of simulated time at 64 ticks a
/// second, as fast as it goes, and prints `name`'s speed relative to real time.
pub fn run_headless(name: &str, mut app: App, seconds: f64) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    app.insert_resource(bevy::time::TimeUpdateStrategy::FixedTimesteps(1));
    app.finish();
    app.cleanup();
    app.update();
    let ticks = (seconds * 64.0).ceil() as u32;
    let started = std::time::Instant::now();
    for _ in 0..ticks {
        app.update();
    }
    let wall = started.elapsed().as_secs_f64();
    let stats = app.world().resource::<bevy_sph2d::fluid::SphStats>();
    let sim = f64::from(ticks) / 64.0;
    println!(
        "{name} headless particles={} threads={threads} sim_s={sim:.2} wall_s={wall:.2} \
         realtime_x={:.2} substeps={} iterations={}",
        stats.particles,
        sim / wall,
        stats.total_substeps,
        stats.total_iterations
    );
}

/// Where and when (simulated seconds) to save the window, then quit (`--screenshot FILE S`).
#[derive(Resource)]
pub struct ScreenshotAt {
    path: String,
    after: f64,
    /// Frames since it was taken.
    taken: Option<u32>,
}

impl ScreenshotAt {
    /// From `--screenshot [FILE [SECONDS]]` in `args`, with defaults `path` and `after`.
    pub fn from_args(args: &[String], path: &str, after: f64) -> Option<Self> {
        args.iter().position(|a| a == "--screenshot").map(|i| Self {
            path: args.get(i + 1).cloned().unwrap_or(path.into()),
            after: args
                .get(i + 2)
                .and_then(|s| s.parse().ok())
                .unwrap_or(after),
            taken: None,
        })
    }
}

/// Saves the window once the simulation reaches the [`ScreenshotAt`] time, and quits a few
/// frames later (once it is written).
pub fn take_screenshot(
    mut commands: Commands,
    mut shot: ResMut<ScreenshotAt>,
    stats: Res<bevy_sph2d::fluid::SphStats>,
    time: Res<Time<Virtual>>,
    real: Res<Time<Real>>,
    mut exit: MessageWriter<AppExit>,
) {
    use bevy::render::view::screenshot::{Screenshot, save_to_disk};
    match shot.taken {
        None if time.elapsed_secs_f64() >= shot.after => {
            info!(
                "screenshot at {:.1} simulated s after {:.1} s: {} particles",
                stats.time,
                real.elapsed_secs_f64(),
                stats.particles,
            );
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(shot.path.clone()));
            shot.taken = Some(0);
        }
        Some(frames) if frames > 10 => {
            exit.write(AppExit::Success);
        }
        Some(frames) => shot.taken = Some(frames + 1),
        None => {}
    }
}

/// A scene's app in a window, drawn as liquid in the liquid's own colours on a dark
/// background, with the mouse tools and the panel: `scene` adds the scene, `params` the fluid,
/// `shot` a screenshot to take and quit (`--screenshot`). Reset clears the fluid (an empty
/// scenario): the scene refills it, if it wants.
pub fn liquid_window(
    title: &str,
    params: SphParams,
    scene: impl Plugin,
    shot: Option<ScreenshotAt>,
) -> App {
    let mut app = App::new();
    if let Some(shot) = shot {
        app.insert_resource(shot)
            .add_systems(Update, take_screenshot);
    }
    app.add_plugins((
        window_plugins(title),
        ParticlePlugins::default().set(SphPlugin::default().with_params(params)),
        ParticleUiPlugins,
        scene,
    ))
    .insert_resource(ClearColor(Color::srgb(0.04, 0.05, 0.07)))
    .insert_resource(SphScenario::new(ScenarioKind::Empty, 0))
    .insert_resource(ParticleView {
        draw: ParticleDraw::Liquid,
        mode: RenderMode::Solid,
        ..default()
    })
    .add_systems(Startup, (spawn_particle_camera, limit_catch_up));
    app
}

fn spawn_particle_camera(mut commands: Commands) {
    commands.spawn(ParticleCamera::default());
}

/// The simulated seconds of `--headless [SECONDS]` in `args` (5 when none is given), if the
/// flag is there.
pub fn headless_seconds(args: &[String]) -> Option<f64> {
    let i = args.iter().position(|a| a == "--headless")?;
    Some(args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(5.0))
}

/// `scene` on `params` without a window for `seconds` ([`run_headless`]), printing `name`'s
/// speed.
pub fn run_scene_headless(name: &str, params: SphParams, scene: impl Plugin, seconds: f64) {
    let mut app = App::new();
    app.add_plugins((
        headless_plugins(),
        SphPlugin::default().with_params(params),
        scene,
    ));
    run_headless(name, app, seconds);
}
