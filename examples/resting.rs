//! Hydrostatics at every depth: resting layers 20 to 100 particles deep, at spacings from 2 to
//! 20 mm, run headless on plain slices; prints how each settled (pressure slope against ρ₀g,
//! the largest interior compression, the fastest particle against √(gD), solver iterations).
//!
//! ```sh
//! cargo run --release --no-default-features --example resting
//! cargo run --release --no-default-features --example resting -- --solver wcsph \
//!     --layer 0.1,0.2,0.002
//! ```

mod validation;

use bevy_sph2d::fluid::{DfsphSettings, SphParams};
use clap::{Parser, ValueEnum};
use validation::{DamBreakSettling, LayerReport, RestingLayer};

/// Runs resting layers and prints how close each comes to hydrostatic.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// A layer as `depth,width,spacing` in metres (repeatable); default: the depth issue's set.
    #[arg(long, value_parser = layer)]
    layer: Vec<RestingLayer>,
    /// Instead of layers: the demo's dam break with about this many particles, settling
    /// (use `--duration 6` or more).
    #[arg(long)]
    dam_break: Option<u32>,
    /// Pressure solver.
    #[arg(long, value_enum, default_value_t = Solver::Dfsph)]
    solver: Solver,
    /// Simulated time, s.
    #[arg(long, default_value_t = 2.0)]
    duration: f64,
    /// Averaging window at the end, s.
    #[arg(long, default_value_t = 0.5)]
    average: f64,
    /// Fixed tick, Hz.
    #[arg(long, default_value_t = 64.0)]
    hz: f64,
    /// DFSPH: longest sub-step, s [default: the preset's].
    #[arg(long)]
    max_time_step: Option<f32>,
    /// DFSPH: mean density error the density solve stops at [default: the preset's].
    #[arg(long)]
    density_tolerance: Option<f32>,
    /// DFSPH: mean density change per step the divergence solve stops at [default: the preset's].
    #[arg(long)]
    divergence_tolerance: Option<f32>,
    /// DFSPH: most iterations of each solve per sub-step [default: the preset's].
    #[arg(long)]
    max_iterations: Option<u32>,
    /// DFSPH: start each solve from zero pressure instead of the last sub-step's.
    #[arg(long)]
    cold_start: bool,
    /// DFSPH: exactly this many density-solve iterations per sub-step (a fixed budget, no
    /// tolerance stop; with --divergence-iterations).
    #[arg(long, requires = "divergence_iterations", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    density_iterations: Option<u32>,
    /// DFSPH: exactly this many divergence-solve iterations per sub-step (0: none; with
    /// --density-iterations).
    #[arg(long, requires = "density_iterations", value_parser = clap::value_parser!(u32).range(0..=10_000))]
    divergence_iterations: Option<u32>,
    /// DFSPH: the strict reference solve (`DfsphSettings::reference`: each solve to its
    /// tolerance, no grid start) instead of the default's fixed budget from the grid.
    #[arg(long)]
    reference: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Solver {
    Dfsph,
    Wcsph,
}

fn layer(text: &str) -> Result<RestingLayer, String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>().map_err(|e| format!("{v}: {e}")))
        .collect::<Result<_, _>>()?;
    match values[..] {
        [depth, width, spacing] if depth > 0.0 && width > 0.0 && spacing > 0.0 => {
            Ok(RestingLayer::new(depth, width, spacing))
        }
        _ => Err("expected three positive numbers: depth,width,spacing (m)".into()),
    }
}

fn main() {
    let args = Args::parse();
    let layers = if args.layer.is_empty() {
        vec![
            RestingLayer::new(0.1, 0.3, 0.004),
            RestingLayer::new(0.1, 0.2, 0.002),
            RestingLayer::new(0.2, 0.3, 0.002),
            RestingLayer::new(0.5, 0.4, 0.01),
            RestingLayer::new(0.4, 0.6, 0.02),
        ]
    } else {
        args.layer
    };
    let mut base = match args.solver {
        Solver::Dfsph => SphParams::water(),
        Solver::Wcsph => SphParams::water_wcsph(),
    };
    if args.reference {
        base.dfsph = DfsphSettings::reference();
    }
    let d = &mut base.dfsph;
    d.max_time_step = args.max_time_step.unwrap_or(d.max_time_step);
    d.density_tolerance = args.density_tolerance.unwrap_or(d.density_tolerance);
    d.divergence_tolerance = args.divergence_tolerance.unwrap_or(d.divergence_tolerance);
    if let Some(most) = args.max_iterations {
        (d.max_density_iterations, d.max_divergence_iterations) = (most, most);
    }
    d.warm_start &= !args.cold_start;
    if let (Some(density), Some(divergence)) = (args.density_iterations, args.divergence_iterations)
    {
        *d = d.with_budget(density, divergence);
    }
    let tick = 1.0 / args.hz;
    if let Some(particles) = args.dam_break {
        let started = std::time::Instant::now();
        let scene = DamBreakSettling { particles };
        let Some(r) = scene.run(base.clone(), args.duration, args.average, tick) else {
            eprintln!("the parameters do not validate");
            std::process::exit(2);
        };
        print_report("dam-break", &base, &r, started);
        return;
    }
    for layer in layers {
        let started = std::time::Instant::now();
        let Some(r) = layer.run(base.clone(), args.duration, args.average, tick) else {
            eprintln!("{layer:?}: the parameters do not validate");
            std::process::exit(2);
        };
        let scene = format!(
            "layer depth={} width={} spacing={}",
            layer.depth, layer.width, layer.spacing
        );
        print_report(&scene, &base, &r, started);
    }
}

/// One machine-readable line per scene.
fn print_report(scene: &str, base: &SphParams, r: &LayerReport, started: std::time::Instant) {
    println!(
        "resting solver={} {scene} particles={} deep={} slope={:.3} compression={:.4} \
         fastest={:.4} density_iterations={:.1} divergence_iterations={:.1} wall_s={:.1}",
        base.solver.label(),
        r.particles,
        r.particles_deep,
        r.slope,
        r.compression,
        r.fastest,
        r.density_iterations,
        r.divergence_iterations,
        started.elapsed().as_secs_f64()
    );
}
