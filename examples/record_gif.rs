//! Records the README's animation from real frames: the dam break example in the liquid view,
//! one screenshot (Bevy's `Screenshot`) every `1/fps` simulated seconds, scaled down and encoded
//! as a looping GIF whose frame delays are the simulated time between them, so it plays at the
//! speed of the water whatever speed the machine drew it at.
//!
//! `cargo run --example record_gif [-- --out assets/dam_break.gif --seconds 3 --fps 12]`. Needs a
//! display (`xvfb-run -a -s "-screen 0 1280x800x24"` on a server).

mod demo;

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy_sph2d::panel::PanelState;
use clap::Parser;
use demo::SphDemoPlugin;
use image::codecs::gif::{GifEncoder, Repeat};
use std::path::PathBuf;

/// Records the dam break as an animated GIF.
#[derive(Parser, Resource, Debug, Clone)]
struct Cli {
    /// The GIF to write.
    #[arg(long, default_value = "assets/dam_break.gif")]
    out: PathBuf,
    /// Simulated seconds to record.
    #[arg(long, default_value_t = 3.0)]
    seconds: f32,
    /// Frames per simulated second.
    #[arg(long, default_value_t = 12.0)]
    fps: f32,
    /// Width of the GIF, pixels (the window is 1280 × 720).
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// Fluid particles.
    #[arg(long, default_value_t = 2500)]
    particles: u32,
}

/// The frames asked for and those captured, by index.
#[derive(Resource, Default)]
struct Recording {
    requested: usize,
    frames: Vec<Option<image::RgbaImage>>,
    started: Option<std::time::Instant>,
}

fn main() {
    let cli = Cli::parse();
    App::new()
        .add_plugins((
            demo::window_plugins("bevy_sph2d: recording"),
            SphDemoPlugin::dam_break(cli.particles),
        ))
        .insert_resource(cli)
        .init_resource::<Recording>()
        .add_systems(Update, (hide_panel, request_frames, finish).chain())
        .run();
}

/// The animation shows the water alone.
fn hide_panel(panel: Option<ResMut<PanelState>>) {
    if let Some(mut panel) = panel {
        panel.open = false;
    }
}

/// Asks for a screenshot whenever the simulation passes the next frame's time.
fn request_frames(
    mut commands: Commands,
    time: Res<Time<Fixed>>,
    cli: Res<Cli>,
    mut recording: ResMut<Recording>,
) {
    let total = (cli.seconds * cli.fps).round() as usize;
    recording
        .started
        .get_or_insert_with(std::time::Instant::now);
    while recording.requested < total && time.elapsed_secs() >= recording.requested as f32 / cli.fps
    {
        let index = recording.requested;
        recording.requested += 1;
        recording.frames.push(None);
        let width = cli.width;
        commands.spawn(Screenshot::primary_window()).observe(
            move |captured: On<ScreenshotCaptured>, mut recording: ResMut<Recording>| {
                recording.frames[index] =
                    captured
                        .image
                        .clone()
                        .try_into_dynamic()
                        .ok()
                        .map(|picture| {
                            let height = width * picture.height() / picture.width().max(1);
                            picture
                                .resize_exact(width, height, image::imageops::FilterType::Triangle)
                                .to_rgba8()
                        });
            },
        );
    }
}

/// Once every frame is in: encodes the GIF, prints what it recorded and quits.
fn finish(
    cli: Res<Cli>,
    time: Res<Time<Fixed>>,
    recording: Res<Recording>,
    mut exit: MessageWriter<AppExit>,
) {
    let total = (cli.seconds * cli.fps).round() as usize;
    if recording.requested < total || recording.frames.iter().any(Option::is_none) {
        return;
    }
    let wall = recording.started.map_or(0.0, |t| t.elapsed().as_secs_f32());
    match encode(&cli, &recording) {
        Ok(bytes) => println!(
            "recorded frames={total} sim_s={:.2} wall_s={wall:.1} sim_speed={:.2} out={} bytes={bytes}",
            time.elapsed_secs(),
            time.elapsed_secs() / wall.max(1e-3),
            cli.out.display()
        ),
        Err(error) => {
            eprintln!("{}: {error}", cli.out.display());
            exit.write(AppExit::error());
            return;
        }
    }
    exit.write(AppExit::Success);
}

/// Writes the frames as a looping GIF; returns its size in bytes.
fn encode(cli: &Cli, recording: &Recording) -> Result<u64, Box<dyn std::error::Error>> {
    let file = std::fs::File::create(&cli.out)?;
    let mut encoder = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    encoder.set_repeat(Repeat::Infinite)?;
    let delay = image::Delay::from_numer_denom_ms(1000, cli.fps.round().max(1.0) as u32);
    for frame in recording.frames.iter().flatten() {
        encoder.encode_frame(image::Frame::from_parts(frame.clone(), 0, 0, delay))?;
    }
    drop(encoder);
    Ok(std::fs::metadata(&cli.out)?.len())
}
