//! Validation you can see: the Martin & Moyce (1952) dam break run headless with both pressure
//! solvers, the surge front charted against the experiment as a PNG, and the ratios printed.
//!
//! ```sh
//! cargo run --release --no-default-features --example validate -- --out assets/validate.png
//! ```

mod validation;

use bevy_sph2d::fluid::{PressureSolver, SphParams};
use clap::Parser;
use plotters::prelude::*;
use std::path::PathBuf;
use validation::{MARTIN_MOYCE, MartinMoyce, compare};

/// Runs the Martin & Moyce dam break with DFSPH and WCSPH and charts the surge front.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Where to write the chart (PNG).
    #[arg(long, default_value = "validate.png")]
    out: PathBuf,
    /// Particles across the water column (20 gives 800 particles).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(4..=200))]
    particles_across: u32,
    /// DFSPH: the strict reference solve (`SphParams::reference`) instead of the default.
    #[arg(long)]
    reference: bool,
}

const SIZE: (u32, u32) = (900, 560);
const TICK: f64 = 1.0 / 60.0;

fn main() {
    let args = Args::parse();
    let scene = MartinMoyce {
        particles_across: args.particles_across,
        ..MartinMoyce::default()
    };
    let mut runs = Vec::new();
    for (solver, base) in [
        (
            PressureSolver::Dfsph,
            if args.reference {
                SphParams::reference()
            } else {
                SphParams::water()
            },
        ),
        (PressureSolver::Wcsph, SphParams::water_wcsph()),
    ] {
        let started = std::time::Instant::now();
        let history = scene.run(base, TICK).expect("the presets validate");
        let wall = started.elapsed().as_secs_f64();
        let worst = compare(&history)
            .into_iter()
            .map(|(t, z, measured, ratio)| {
                println!(
                    "{} t*={t:.3} front={z:.3} experiment={measured:.3} ratio={ratio:.3}",
                    solver.label()
                );
                (ratio - 1.0).abs()
            })
            .fold(0.0f32, f32::max);
        println!(
            "{}: largest front error {:.1}% ({:.1} s wall)",
            solver.label(),
            100.0 * worst,
            wall
        );
        runs.push((solver, history));
    }
    if let Err(error) = draw(&args.out, &runs) {
        eprintln!("validate: could not write {}: {error}", args.out.display());
        std::process::exit(1);
    }
    println!("chart written to {}", args.out.display());
}

/// Draws the experiment's points and each run's front into an RGB buffer and writes a PNG.
fn draw(out: &PathBuf, runs: &[(PressureSolver, Vec<(f32, f32)>)]) -> Result<(), String> {
    plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| "the chart font did not load".to_string())?;
    let mut pixels = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Dam break surge front: Martin & Moyce (1952), column a x 2a",
                ("sans-serif", 24),
            )
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(52)
            .build_cartesian_2d(0.0f32..MartinMoyce::END, 1.0f32..7.5)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("t √(2g/a)")
            .y_desc("front Z / a")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| e.to_string())?;
        let colours = [RGBColor(30, 110, 200), RGBColor(220, 110, 30)];
        for ((solver, history), colour) in runs.iter().zip(colours) {
            chart
                .draw_series(LineSeries::new(
                    history.iter().copied(),
                    colour.stroke_width(3),
                ))
                .map_err(|e| e.to_string())?
                .label(format!("SPH, {}", solver.label()))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 24, y)], colour.stroke_width(3))
                });
        }
        chart
            .draw_series(
                MARTIN_MOYCE
                    .iter()
                    .map(|&(t, z)| Circle::new((t, z), 6, BLACK.filled())),
            )
            .map_err(|e| e.to_string())?
            .label("experiment")
            .legend(|(x, y)| Circle::new((x + 12, y), 6, BLACK.filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 18))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    let file = std::fs::File::create(out).map_err(|e| e.to_string())?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), SIZE.0, SIZE.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(&pixels).map_err(|e| e.to_string())
}
