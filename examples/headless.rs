//! Headless recorder: runs a fluid scenario with `MinimalPlugins` (no window, no GPU) and writes
//! CSV frames `time,id,x,y,vx,vy,ax,ay,mass,density,pressure` in SI units, origin at the tank's
//! inner bottom-left corner, y up. `--scenario galaxy` runs Barnes-Hut gravity on a disc of
//! bodies around a heavy centre instead (G = 1, disc radius 1 m, centre at the origin; `ax, ay`
//! are the gravitational accelerations, density and pressure are 0).
//!
//! ```text
//! cargo run --release --example headless -- --scenario dam-break --column-width 0.1 \
//!     --column-height 0.2 --tank-width 0.8 --tank-height 0.3 --spacing 0.0025 \
//!     --duration 1 --every 0.01 --seed 1 --out dam_break.csv
//! ```

mod support;

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{
    FluidBlock, PressureSolver, SphParams, SphSolver, Tank, refresh_fluid_state,
};
use bevy_sph2d::gravity::GravityAcceleration;
use bevy_sph2d::prelude::*;
use std::io::{BufWriter, Write};
use std::time::Duration;
use support::{Args, fail};

const USAGE: &str = "\
usage: headless [options]
  --scenario dam-break|tank|galaxy   what to simulate (default dam-break)
  --column-width W            dam-break column width, m (default 0.1)
  --column-height H           dam-break column height, m (default 0.2)
  --tank-width L              tank inner width, m (default 0.8)
  --tank-height M             tank inner height, m (default 0.4)
  --depth D                   tank scenario: water depth, m (default 0.2)
  --spacing S                 particle spacing, m (default: column width / 40, or depth / 40)
  --duration T                simulated time, s (default 1)
  --every DT                  time between frames, s (default 0.01)
  --seed N                    jitter seed (default 0)
  --out FILE.csv              output file (default headless.csv)
  --jitter J                  spawn jitter, fraction of the spacing (default 0.0001)
  --solver dfsph|wcsph        pressure solver (default dfsph, incompressible)
  --support-ratio R           kernel support / spacing (default 3 for wcsph, 2 for dfsph)
  --kernel wendland|cubic|muller   (default wendland)
  --speed-of-sound C          m/s (default 20 sqrt(g * fluid height))
  --viscosity NU              kinematic viscosity, m^2/s (default 1e-6)
  --alpha A                   artificial viscosity (default 0.02)
  --threads T                 compute threads (default: all cores)
galaxy options:
  --bodies N                  bodies, the central one included (default 20000)
  --theta X                   Barnes-Hut opening angle (default 0.7)
  --steps K                   fixed steps of --dt seconds (default 100)
  --dt S                      step, s (default 0.002)
  --frame-steps F             steps between frames (default: K, so the first and last frame)
  --softening E               m (default 0.01)";

const VALUED: &[&str] = &[
    "solver",
    "scenario",
    "column-width",
    "column-height",
    "tank-width",
    "tank-height",
    "depth",
    "spacing",
    "duration",
    "every",
    "seed",
    "out",
    "jitter",
    "support-ratio",
    "kernel",
    "speed-of-sound",
    "viscosity",
    "alpha",
    "threads",
    "bodies",
    "theta",
    "steps",
    "dt",
    "frame-steps",
    "softening",
];

struct Config {
    params: SphParams,
    block: FluidBlock,
    duration: f64,
    every: f64,
    out: String,
    threads: usize,
}

fn configure(args: &Args) -> Result<Config, String> {
    let scenario = args.text("scenario").unwrap_or("dam-break");
    let tank = Tank::new(
        args.positive("tank-width", 0.8)?,
        args.positive("tank-height", 0.4)?,
    );
    let (block, height, default_spacing) = match scenario {
        "dam-break" => {
            let (w, h) = (
                args.positive("column-width", 0.1)?,
                args.positive("column-height", 0.2)?,
            );
            if w > tank.width || h > tank.height {
                return Err(format!("the {w} m × {h} m column does not fit the tank"));
            }
            (FluidBlock::dam_break(w, h), h, w / 40.0)
        }
        "tank" => {
            let depth = args.positive("depth", 0.2)?;
            if depth > tank.height {
                return Err(format!(
                    "depth {depth} m exceeds the tank height {} m",
                    tank.height
                ));
            }
            (FluidBlock::resting_layer(&tank, depth), depth, depth / 40.0)
        }
        other => return Err(format!("unknown scenario '{other}' (dam-break or tank)")),
    };
    let kernel = match args.text("kernel").unwrap_or("wendland") {
        "wendland" => KernelKind::WendlandC2,
        "cubic" => KernelKind::CubicSpline,
        "muller" => KernelKind::Muller,
        other => return Err(format!("unknown kernel '{other}'")),
    };
    let (solver, default_ratio) = match args.text("solver").unwrap_or("dfsph") {
        "wcsph" => (PressureSolver::Wcsph, 3.0),
        "dfsph" => (PressureSolver::Dfsph, 2.0),
        other => return Err(format!("unknown solver '{other}' (wcsph or dfsph)")),
    };
    let params = SphParams {
        particle_spacing: args.positive("spacing", default_spacing)?,
        support_ratio: args.positive("support-ratio", default_ratio)?,
        solver,
        kernel,
        speed_of_sound: args.positive(
            "speed-of-sound",
            SphParams::speed_of_sound_for_height(height),
        )?,
        kinematic_viscosity: args.get("viscosity", 1.0e-6)?,
        artificial_viscosity: args.get("alpha", 0.02)?,
        tank: Some(tank),
        max_substeps: 100_000,
        ..default()
    };
    params.validate().map_err(|e| e.to_string())?;
    let jitter: f32 = args.get("jitter", FluidBlock::DEFAULT_JITTER)?;
    if !(0.0..=0.45).contains(&jitter) {
        return Err(format!("--jitter must be within 0..=0.45, got {jitter}"));
    }
    if block.lattice_size(params.particle_spacing).0 == 0
        || block.lattice_size(params.particle_spacing).1 == 0
    {
        return Err("the spacing is larger than the fluid block: no particles".into());
    }
    let duration: f64 = args.get("duration", 1.0)?;
    let every: f64 = args.get("every", 0.01)?;
    if !(duration.is_finite() && duration >= 0.0 && every.is_finite() && every > 0.0) {
        return Err("--duration must be non-negative and --every positive".into());
    }
    let threads: usize = args.get(
        "threads",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
    )?;
    Ok(Config {
        params,
        block: block.with_jitter(jitter).with_seed(args.get("seed", 0)?),
        duration,
        every,
        out: args.text("out").unwrap_or("headless.csv").to_string(),
        threads: threads.max(1),
    })
}

fn main() {
    let args = Args::parse(VALUED, &[]).unwrap_or_else(|e| fail(&e, USAGE));
    if args.text("scenario") == Some("galaxy") {
        let galaxy = configure_galaxy(&args).unwrap_or_else(|e| fail(&e, USAGE));
        if let Err(e) = record_galaxy(&galaxy) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        return;
    }
    let config = configure(&args).unwrap_or_else(|e| fail(&e, USAGE));
    if let Err(e) = record(&config) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn record(config: &Config) -> std::io::Result<()> {
    // Whole ticks of at most 1/60 s per frame, so frames fall exactly on tick boundaries.
    let ticks_per_frame = (config.every * 60.0).ceil().max(1.0) as u32;
    let tick = Duration::from_secs_f64(config.every / ticks_per_frame as f64);
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(config.threads)),
        SphPlugin::default().with_params(config.params.clone()),
    ))
    .insert_resource(Time::<Fixed>::from_duration(tick))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    let ids = config.block.spawn(app.world_mut());
    app.update(); // the first update only starts the clocks
    refresh_fluid_state(app.world_mut());

    let mut out = BufWriter::new(std::fs::File::create(&config.out)?);
    writeln!(out, "time,id,x,y,vx,vy,ax,ay,mass,density,pressure")?;
    let mass = config.params.particle_mass();
    let frames = (config.duration / config.every + 1e-9).floor() as u64;
    let started = std::time::Instant::now();
    for frame in 0..=frames {
        if frame > 0 {
            for _ in 0..ticks_per_frame {
                app.update();
            }
        }
        let world = app.world_mut();
        let time = world.resource::<SphSolver>().clock().time;
        let mut query = world.query::<(&Position, &Velocity, &Acceleration, &Density, &Pressure)>();
        for (id, &entity) in ids.iter().enumerate() {
            let Ok((x, v, a, rho, p)) = query.get(world, entity) else {
                continue;
            };
            writeln!(
                out,
                "{time:.6},{id},{},{},{},{},{},{},{mass},{},{}",
                x.x, x.y, v.x, v.y, a.x, a.y, rho.0, p.0
            )?;
        }
    }
    out.flush()?;
    let stats = app.world().resource::<SphStats>();
    eprintln!(
        "{} particles, {} frames to {:.3} s in {:.1} s wall time -> {}",
        stats.particles,
        frames + 1,
        stats.time,
        started.elapsed().as_secs_f64(),
        config.out
    );
    Ok(())
}

struct GalaxyConfig {
    disc: GalaxyDisc,
    params: GravityParams,
    steps: usize,
    dt: f64,
    frame_steps: usize,
    out: String,
    threads: usize,
}

fn configure_galaxy(args: &Args) -> Result<GalaxyConfig, String> {
    let bodies: usize = args.get("bodies", 20_000)?;
    let steps: usize = args.get("steps", 100)?;
    let dt: f64 = args.get("dt", 0.002)?;
    if bodies == 0 || !(dt.is_finite() && dt > 0.0) {
        return Err("--bodies and --dt must be positive".into());
    }
    let frame_steps: usize = args.get("frame-steps", steps.max(1))?;
    let params = GravityParams {
        gravitational_constant: 1.0,
        theta: args.get("theta", 0.7)?,
        softening: args.get("softening", 0.01)?,
        ..default()
    };
    params.validate().map_err(|e| e.to_string())?;
    let threads: usize = args.get(
        "threads",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
    )?;
    Ok(GalaxyConfig {
        disc: GalaxyDisc {
            seed: args.get("seed", 0)?,
            ..GalaxyDisc::new(bodies)
        },
        params,
        steps,
        dt,
        frame_steps: frame_steps.max(1),
        out: args.text("out").unwrap_or("headless.csv").to_string(),
        threads: threads.max(1),
    })
}

fn record_galaxy(config: &GalaxyConfig) -> std::io::Result<()> {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(config.threads)),
        GravityPlugin::default().with_params(config.params.clone()),
    ))
    .insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f64(
        config.dt,
    )))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    let bodies = config.disc.generate();
    let ids: Vec<Entity> = app
        .world_mut()
        .spawn_batch(
            bodies
                .positions
                .iter()
                .zip(&bodies.velocities)
                .zip(&bodies.masses)
                .map(|((p, v), m)| (Mass(*m), Position(*p), Velocity(*v)))
                .collect::<Vec<_>>(),
        )
        .collect();
    // The first update starts the clocks; the second runs the first step, whose start
    // evaluates the new bodies' field.
    app.update();
    let mut out = BufWriter::new(std::fs::File::create(&config.out)?);
    writeln!(out, "time,id,x,y,vx,vy,ax,ay,mass,density,pressure")?;
    let started = std::time::Instant::now();
    let mut write_frame = |app: &mut App, step: usize| -> std::io::Result<()> {
        let world = app.world_mut();
        let time = step as f64 * config.dt;
        let mut query = world.query::<(&Position, &Velocity, &GravityAcceleration, &Mass)>();
        for (id, &entity) in ids.iter().enumerate() {
            let Ok((x, v, a, m)) = query.get(world, entity) else {
                continue;
            };
            writeln!(
                out,
                "{time:.6},{id},{},{},{},{},{},{},{},0,0",
                x.x, x.y, v.x, v.y, a.x, a.y, m.0
            )?;
        }
        Ok(())
    };
    // Step 0 carries the field at the start, evaluated without moving anything.
    bevy_sph2d::gravity::refresh_gravity_field(app.world_mut());
    write_frame(&mut app, 0)?;
    for step in 1..=config.steps {
        app.update();
        if step % config.frame_steps == 0 || step == config.steps {
            write_frame(&mut app, step)?;
        }
    }
    out.flush()?;
    let stats = app.world().resource::<GravityStats>();
    eprintln!(
        "{} bodies, {} steps of {} s in {:.1} s wall time, energy {:.6e} J -> {}",
        stats.bodies,
        config.steps,
        config.dt,
        started.elapsed().as_secs_f64(),
        stats.total_energy(),
        config.out
    );
    Ok(())
}
