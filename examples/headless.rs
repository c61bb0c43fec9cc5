//! Headless recorder: runs a fluid scenario with `MinimalPlugins` (no window, no GPU) and writes
//! CSV frames `time,id,x,y,vx,vy,ax,ay,mass,density,pressure` in SI units, origin at the tank's
//! inner bottom-left corner, y up. `--scenario galaxy` runs Barnes-Hut gravity on a disc of
//! bodies around a heavy centre instead (G = 1, disc radius 1 m, centre at the origin; `ax, ay`
//! are the gravitational accelerations, density and pressure are 0).
//!
//! ```text
//! cargo run --release --features avian --example headless -- --scenario float \
//!     --body-shape box --body-width 0.1 --body-height 0.05 --body-density 500 --depth 0.2 \
//!     --bodies-out bodies.csv --out float.csv
//! cargo run --release --example headless -- --scenario dam-break --column-width 0.1 \
//!     --column-height 0.2 --tank-width 0.8 --tank-height 0.3 --spacing 0.0025 \
//!     --duration 1 --every 0.01 --seed 1 --out dam_break.csv
//! cargo run --release --example headless -- --scenario drop --gravity 0 --column-width 0.05 \
//!     --column-height 0.025 --tank-width 0.2 --tank-height 0.2 --spacing 0.001 --out drop.csv
//! cargo run --release --example headless -- --scenario sessile --surface-tension 0.072 \
//!     --contact-angle 45 --column-width 0.003 --tank-width 0.012 --tank-height 0.006 \
//!     --out sessile.csv
//! ```

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{
    DfsphSettings, FluidMaterial, Liquid, PressureSolver, STANDARD_GRAVITY, SphParams, SphSolver,
    Tank, refresh_fluid_state,
};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::gravity::GravityAcceleration;
use bevy_sph2d::particle::{Mass, Position, Velocity};
use bevy_sph2d::prelude::*;
use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{BufWriter, Write};
use std::time::Duration;

/// Headless recorder: runs a fluid scenario (or a galaxy of gravity bodies) with
/// `MinimalPlugins` and writes CSV frames `time,id,x,y,vx,vy,ax,ay,mass,density,pressure` in SI
/// units. Shows a progress bar on stderr when it is a terminal.
#[derive(Parser, Debug)]
#[command(name = "headless", allow_negative_numbers = true)]
struct Cli {
    /// What to simulate.
    #[arg(long, value_enum, default_value_t = Scenario::DamBreak)]
    scenario: Scenario,
    /// Dam-break column (drop: block) width, m.
    #[arg(long, default_value_t = 0.1, value_parser = positive)]
    column_width: f32,
    /// Dam-break column (drop: block) height, m.
    #[arg(long, default_value_t = 0.2, value_parser = positive)]
    column_height: f32,
    /// Gravity, m/s², downward (0: weightless).
    #[arg(long, default_value_t = STANDARD_GRAVITY, value_parser = non_negative)]
    gravity: f32,
    /// Tank inner width, m.
    #[arg(long, default_value_t = 0.8, value_parser = positive)]
    tank_width: f32,
    /// Tank inner height, m.
    #[arg(long, default_value_t = 0.4, value_parser = positive)]
    tank_height: f32,
    /// Tank, float and lock-exchange scenarios: the liquid's depth, m.
    #[arg(long, default_value_t = 0.2, value_parser = positive)]
    depth: f32,
    /// Particle spacing, m [default: column width / 40, or depth / 40].
    #[arg(long, value_parser = positive)]
    spacing: Option<f32>,
    /// Simulated time, s.
    #[arg(long, default_value_t = 1.0)]
    duration: f64,
    /// Time between frames, s.
    #[arg(long, default_value_t = 0.01)]
    every: f64,
    /// Jitter (or galaxy) seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output file.
    #[arg(long, default_value = "headless.csv")]
    out: String,
    /// Spawn jitter, fraction of the spacing (0 to 0.45).
    #[arg(long, default_value_t = FluidBlock::DEFAULT_JITTER)]
    jitter: f32,
    /// Pressure solver.
    #[arg(long, value_enum, default_value_t = Solver::Dfsph)]
    solver: Solver,
    /// Kernel support / spacing [default: 3 for wcsph and for the lock exchange, 2 for dfsph].
    #[arg(long, value_parser = positive)]
    support_ratio: Option<f32>,
    /// Smoothing kernel.
    #[arg(long, value_enum, default_value_t = Kernel::Wendland)]
    kernel: Kernel,
    /// Speed of sound, m/s [default: 20 sqrt(g * fluid height)].
    #[arg(long, value_parser = positive)]
    speed_of_sound: Option<f32>,
    /// Kinematic viscosity, m²/s.
    #[arg(long, default_value_t = 1.0e-6)]
    viscosity: f32,
    /// Artificial viscosity.
    #[arg(long, default_value_t = 0.02)]
    alpha: f32,
    /// Surface tension, N/m (water: 0.072; 0: none; experimental).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    surface_tension: f32,
    /// Contact angle of the liquid on the tank's walls, degrees through the liquid (0–180;
    /// under 90 it wets, over 90 it beads; acts with --surface-tension).
    #[arg(long, default_value_t = 90.0, value_parser = angle)]
    contact_angle: f32,
    /// Lock exchange: the right half's liquid's rest density over the base liquid's (0.25–4).
    #[arg(long, default_value_t = 2.0, value_parser = positive)]
    density_ratio: f32,
    /// Compute threads [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    /// Galaxy: bodies, the central one included.
    #[arg(long, default_value_t = 20_000)]
    bodies: usize,
    /// Galaxy: Barnes-Hut opening angle.
    #[arg(long, default_value_t = 0.7)]
    theta: f32,
    /// Galaxy: fixed steps of --dt seconds.
    #[arg(long, default_value_t = 100)]
    steps: usize,
    /// Galaxy: step, s.
    #[arg(long, default_value_t = 0.002)]
    dt: f64,
    /// Galaxy: steps between frames [default: --steps, so the first and last frame].
    #[arg(long)]
    frame_steps: Option<usize>,
    /// Galaxy: softening, m.
    #[arg(long, default_value_t = 0.01)]
    softening: f32,
    /// Float: the body's shape.
    #[arg(long, value_enum, default_value_t = BodyShape::Box)]
    body_shape: BodyShape,
    /// Float: the body's width (a circle's diameter), m.
    #[arg(long, default_value_t = 0.1, value_parser = positive)]
    body_width: f32,
    /// Float: the body's height, m (a box's).
    #[arg(long, default_value_t = 0.05, value_parser = positive)]
    body_height: f32,
    /// Float: the body's density, kg/m³.
    #[arg(long, default_value_t = 500.0, value_parser = positive)]
    body_density: f32,
    /// Float: the body's angle at release, degrees.
    #[arg(long, default_value_t = 0.0)]
    body_angle: f32,
    /// Float: the bodies' CSV, `time,id,x,y,angle,vx,vy,omega,fx,fy,torque`.
    #[arg(long, default_value = "bodies.csv")]
    bodies_out: String,
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

/// The floating body's shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BodyShape {
    Box,
    Circle,
}

/// The float scenario's body: an avian body centred at the still-water level, released.
#[derive(Clone, Debug)]
#[cfg_attr(
    not(feature = "avian"),
    expect(dead_code, reason = "the float scenario is built with avian")
)]
struct Body {
    shape: SolidShape,
    /// The still water's level, m.
    level: f32,
    density: f32,
    angle: f32,
    out: String,
}

/// What the recorder simulates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Scenario {
    /// A water column collapsing in a tank.
    DamBreak,
    /// A resting layer.
    Tank,
    /// Barnes-Hut gravity on a disc of bodies around a heavy centre (G = 1, radius 1 m).
    Galaxy,
    /// A resting layer with one avian body released at its surface (built with `--features
    /// avian`; writes `--bodies-out` too).
    Float,
    /// A block `--column-width` by `--column-height` centred in the tank, released (with
    /// `--gravity 0`, a weightless drop).
    Drop,
    /// A round drop `--column-width` across resting on the middle of the tank's floor,
    /// released (with --surface-tension and --contact-angle, it spreads or beads to the angle).
    Sessile,
    /// The tank's left half filled to `--depth` with the base liquid (water), its right half
    /// with a liquid `--density-ratio` times as dense, released: each runs under or over the
    /// other as a gravity current (at three spacings' support unless `--support-ratio` says
    /// otherwise). The CSV gains a last column, `material` (0 the base liquid, 1 the other).
    LockExchange,
}

/// The fluid's pressure solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Solver {
    /// Incompressible (divergence-free SPH).
    Dfsph,
    /// Weakly compressible.
    Wcsph,
}

/// The smoothing kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Kernel {
    Wendland,
    Cubic,
    Muller,
}

/// `text` read as a number that passes `accept`; otherwise why not, `must` saying what it must be.
fn number(text: &str, accept: impl Fn(f32) -> bool, must: &str) -> Result<f32, String> {
    let value: f32 = text
        .parse()
        .map_err(|_| format!("cannot read '{text}' as a number"))?;
    if accept(value) {
        Ok(value)
    } else {
        Err(format!("must be {must}, got {value}"))
    }
}

/// A finite positive number.
fn positive(text: &str) -> Result<f32, String> {
    number(text, |v| v.is_finite() && v > 0.0, "a positive number")
}

/// A finite number, zero or more.
fn non_negative(text: &str) -> Result<f32, String> {
    number(
        text,
        |v| v.is_finite() && v >= 0.0,
        "zero or a positive number",
    )
}

/// An angle in degrees, 0 to 180.
fn angle(text: &str) -> Result<f32, String> {
    number(
        text,
        |v| (0.0..=180.0).contains(&v),
        "an angle from 0 to 180 degrees",
    )
}

/// Exits with `message`, the usage and status 2, as for any other bad argument.
fn refuse(message: impl std::fmt::Display) -> ! {
    Cli::command()
        .error(ErrorKind::ValueValidation, message)
        .exit()
}

/// A progress bar of `len` steps on stderr (drawn only when stderr is a terminal).
fn progress(len: u64, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit} ({{elapsed}}, {{eta}} left)");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}

struct Config {
    params: SphParams,
    block: FluidBlock,
    /// Only the disc inscribed in the block (sessile).
    round: bool,
    /// The block's right half is the second liquid (lock exchange).
    two_liquids: bool,
    #[cfg_attr(
        not(feature = "avian"),
        expect(dead_code, reason = "the float scenario is built with avian")
    )]
    body: Option<Body>,
    duration: f64,
    every: f64,
    out: String,
    threads: usize,
}

fn threads(cli: &Cli) -> usize {
    cli.threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1)
}

fn configure(cli: &Cli) -> Result<Config, String> {
    let tank = Tank::new(cli.tank_width, cli.tank_height);
    let (block, height, default_spacing) = match cli.scenario {
        Scenario::DamBreak => {
            let (w, h) = (cli.column_width, cli.column_height);
            if w > tank.width || h > tank.height {
                return Err(format!("the {w} m × {h} m column does not fit the tank"));
            }
            (FluidBlock::dam_break(w, h), h, w / 40.0)
        }
        Scenario::Drop => {
            let (w, h) = (cli.column_width, cli.column_height);
            if w >= tank.width || h >= tank.height {
                return Err(format!(
                    "the {w} m × {h} m block does not fit inside the tank"
                ));
            }
            let corner = Vec2::new(tank.width - w, tank.height - h) / 2.0;
            (FluidBlock::new(corner, Vec2::new(w, h)), h, w / 40.0)
        }
        Scenario::Sessile => {
            let d = cli.column_width;
            if d >= tank.width || d >= tank.height {
                return Err(format!("the {d} m drop does not fit inside the tank"));
            }
            let corner = Vec2::new((tank.width - d) / 2.0, 0.0);
            (FluidBlock::new(corner, Vec2::splat(d)), d, d / 20.0)
        }
        Scenario::Galaxy => return Err("the galaxy scenario has no fluid".into()),
        Scenario::Tank | Scenario::Float | Scenario::LockExchange => {
            let depth = cli.depth;
            if depth > tank.height {
                return Err(format!(
                    "depth {depth} m exceeds the tank height {} m",
                    tank.height
                ));
            }
            (FluidBlock::resting_layer(&tank, depth), depth, depth / 40.0)
        }
    };
    let kernel = match cli.kernel {
        Kernel::Wendland => KernelKind::WendlandC2,
        Kernel::Cubic => KernelKind::CubicSpline,
        Kernel::Muller => KernelKind::Muller,
    };
    // Two liquids of near-equal densities run as gravity currents only at three spacings'
    // support: at two, the particles' arrangement holds a stress of tens of pascals, and a
    // lock exchange at a density ratio of 1.05 does not move (`docs/physics.md`, "Two liquids").
    let (solver, default_ratio) = match cli.solver {
        Solver::Wcsph => (PressureSolver::Wcsph, 3.0),
        Solver::Dfsph if cli.scenario == Scenario::LockExchange => (PressureSolver::Dfsph, 3.0),
        Solver::Dfsph => (PressureSolver::Dfsph, 2.0),
    };
    let params = SphParams {
        particle_spacing: cli.spacing.unwrap_or(default_spacing),
        support_ratio: cli.support_ratio.unwrap_or(default_ratio),
        solver,
        kernel,
        speed_of_sound: cli
            .speed_of_sound
            .unwrap_or_else(|| SphParams::speed_of_sound_for_height(height)),
        kinematic_viscosity: cli.viscosity,
        artificial_viscosity: cli.alpha,
        surface_tension: cli.surface_tension,
        contact_angle: cli.contact_angle,
        gravity: Vec2::new(0.0, -cli.gravity),
        tank: Some(tank),
        max_substeps: 100_000,
        liquids: if cli.scenario == Scenario::LockExchange {
            vec![Liquid::new(
                "dense",
                cli.density_ratio * SphParams::water().rest_density,
            )]
        } else {
            Vec::new()
        },
        ..default()
    };
    let mut params = params;
    if cli.reference {
        params.dfsph = DfsphSettings::reference();
    }
    if let (Some(density), Some(divergence)) = (cli.density_iterations, cli.divergence_iterations) {
        params.dfsph = params.dfsph.with_budget(density, divergence);
    }
    params.validate().map_err(|e| e.to_string())?;
    if !(0.0..=0.45).contains(&cli.jitter) {
        return Err(format!(
            "--jitter must be within 0..=0.45, got {}",
            cli.jitter
        ));
    }
    let (columns, rows) = block.lattice_size(params.particle_spacing);
    if columns == 0 || rows == 0 {
        return Err("the spacing is larger than the fluid block: no particles".into());
    }
    if !(cli.duration.is_finite()
        && cli.duration >= 0.0
        && cli.every.is_finite()
        && cli.every > 0.0)
    {
        return Err("--duration must be non-negative and --every positive".into());
    }
    let body = (cli.scenario == Scenario::Float)
        .then(|| float_body(cli, &tank))
        .transpose()?;
    Ok(Config {
        params,
        body,
        block: block.with_jitter(cli.jitter).with_seed(cli.seed),
        round: cli.scenario == Scenario::Sessile,
        two_liquids: cli.scenario == Scenario::LockExchange,
        duration: cli.duration,
        every: cli.every,
        out: cli.out.clone(),
        threads: threads(cli),
    })
}

/// The float scenario's body from the command line.
fn float_body(cli: &Cli, tank: &Tank) -> Result<Body, String> {
    if !cfg!(feature = "avian") {
        return Err("the float scenario needs avian: build with --features avian".into());
    }
    let (w, h) = (cli.body_width, cli.body_height);
    if w >= tank.width || h >= tank.height || !cli.body_angle.is_finite() {
        return Err(format!(
            "the {w} m × {h} m body at {}° does not fit the tank",
            cli.body_angle
        ));
    }
    let shape = match cli.body_shape {
        BodyShape::Box => SolidShape::rectangle(w, h),
        BodyShape::Circle => SolidShape::circle(0.5 * w),
    };
    Ok(Body {
        shape,
        level: cli.depth,
        density: cli.body_density,
        angle: cli.body_angle.to_radians(),
        out: cli.bodies_out.clone(),
    })
}

fn main() {
    let cli = Cli::parse();
    let result = if cli.scenario == Scenario::Galaxy {
        let galaxy = configure_galaxy(&cli).unwrap_or_else(|e| refuse(e));
        record_galaxy(&galaxy)
    } else {
        let config = configure(&cli).unwrap_or_else(|e| refuse(e));
        record(&config)
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// The scenario's fluid particles: the block's, the disc inscribed in it, or the block with
/// its right half the second liquid.
fn spawn_fluid(config: &Config, world: &mut World) -> Vec<Entity> {
    if config.two_liquids {
        let block = &config.block;
        let middle = block.min.x + block.size.x / 2.0;
        let positions = block.positions_for(&config.params);
        return world
            .spawn_batch(positions.into_iter().map(move |p| {
                let material = FluidMaterial(u8::from(p.x > middle));
                (FluidParticle, Position(p), material)
            }))
            .collect();
    }
    if !config.round {
        return config.block.spawn(world);
    }
    let block = &config.block;
    let (centre, radius) = (block.min + block.size / 2.0, block.size.min_element() / 2.0);
    let positions = block.positions_for(&config.params);
    let inside = positions
        .into_iter()
        .filter(|p| p.distance(centre) < radius);
    world
        .spawn_batch(inside.map(|p| (FluidParticle, Position(p))))
        .collect()
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
    let ids = spawn_fluid(config, app.world_mut());
    #[cfg(feature = "avian")]
    let body = config
        .body
        .as_ref()
        .map(|body| float::add(&mut app, config, body, &ids));
    app.update(); // the first update only starts the clocks
    refresh_fluid_state(app.world_mut());

    #[cfg(feature = "avian")]
    let mut bodies_out = match &config.body {
        Some(body) => Some(float::csv(&body.out)?),
        None => None,
    };
    let mut out = BufWriter::new(std::fs::File::create(&config.out)?);
    let material_column = if config.two_liquids { ",material" } else { "" };
    writeln!(
        out,
        "time,id,x,y,vx,vy,ax,ay,mass,density,pressure{material_column}"
    )?;
    let base_mass = config.params.particle_mass();
    let frames = (config.duration / config.every + 1e-9).floor() as u64;
    let started = std::time::Instant::now();
    let bar = progress(frames + 1, "frames");
    for frame in 0..=frames {
        if frame > 0 {
            for _ in 0..ticks_per_frame {
                app.update();
            }
        }
        bar.inc(1);
        let world = app.world_mut();
        let time = world.resource::<SphSolver>().clock().time;
        #[cfg(feature = "avian")]
        if let (Some(entity), Some(file)) = (body, bodies_out.as_mut()) {
            float::row(world, entity, time, file)?;
        }
        let mut query = world.query::<(
            (&Position, &Velocity, &Acceleration, &Density, &Pressure),
            Option<&FluidMaterial>,
        )>();
        for (id, &entity) in ids.iter().enumerate() {
            let Ok(((x, v, a, rho, p), material)) = query.get(world, entity) else {
                continue;
            };
            let material = material.copied().unwrap_or_default();
            let mass = base_mass * config.params.density_ratio(material);
            write!(
                out,
                "{time:.6},{id},{},{},{},{},{},{},{mass},{},{}",
                x.x, x.y, v.x, v.y, a.x, a.y, rho.0, p.0
            )?;
            if config.two_liquids {
                write!(out, ",{}", material.0)?;
            }
            writeln!(out)?;
        }
    }
    out.flush()?;
    #[cfg(feature = "avian")]
    if let Some(file) = bodies_out.as_mut() {
        file.flush()?;
    }
    bar.finish_and_clear();
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

/// The float scenario's avian body.
#[cfg(feature = "avian")]
mod float {
    use super::{Body, Config};
    use avian2d::prelude::{
        AngularVelocity, Collider, ColliderDensity, LinearVelocity, PhysicsPlugins, RigidBody,
    };
    use bevy::prelude::*;
    use bevy_sph2d::fluid::{Part, Pose};
    use bevy_sph2d::prelude::*;
    use bevy_sph2d::slices::{MovingSolid, SolidMotion};
    use std::io::{BufWriter, Write};

    /// Adds avian and the coupling, removes the fluid particles where the body goes, and
    /// spawns it centred at the still-water level.
    pub fn add(app: &mut App, config: &Config, body: &Body, fluid: &[Entity]) -> Entity {
        let params = &config.params;
        let tank = params.tank.expect("the float scenario has a tank");
        let at = Vec2::new(0.5 * tank.width, body.level);
        app.add_plugins((
            TransformPlugin,
            PhysicsPlugins::default(),
            FluidCouplingPlugin::with_tank_walls(),
        ));
        // avian registers some of its resources in `Plugin::finish`, which `App::run` calls.
        app.finish();
        app.cleanup();
        let spacing = params.particle_spacing;
        let placed = MovingSolid::new(body.shape.clone(), Vec2::ZERO, spacing, 1).map(|mut s| {
            let pose = Pose {
                position: at,
                angle: body.angle,
            };
            s.set_motion(SolidMotion { pose, ..default() });
            s
        });
        let world = app.world_mut();
        for &particle in fluid {
            let x = world
                .get::<bevy_sph2d::particle::Position>(particle)
                .map(|p| p.0);
            if let (Some(x), Some(solid)) = (x, &placed)
                && solid.distance(x).0 < 0.5 * spacing
            {
                world.despawn(particle);
            }
        }
        let collider = match body.shape.parts.first() {
            Some(Part::Circle { radius, .. }) => Collider::circle(*radius),
            _ => {
                let size = body.shape.parts.first().map_or(Vec2::ONE, extent);
                Collider::rectangle(size.x, size.y)
            }
        };
        world
            .spawn((
                RigidBody::Dynamic,
                collider,
                ColliderDensity(body.density),
                Transform::from_translation(at.extend(0.0))
                    .with_rotation(Quat::from_rotation_z(body.angle)),
                FluidCoupled,
            ))
            .id()
    }

    /// A box part's width and height.
    fn extent(part: &Part) -> Vec2 {
        match part {
            Part::Polygon { vertices } => {
                let (lo, hi) = vertices.iter().fold(
                    (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
                    |(lo, hi), &v| (lo.min(v), hi.max(v)),
                );
                hi - lo
            }
            _ => Vec2::ONE,
        }
    }

    /// The bodies' CSV with its header.
    pub fn csv(path: &str) -> std::io::Result<BufWriter<std::fs::File>> {
        let mut file = BufWriter::new(std::fs::File::create(path)?);
        writeln!(file, "time,id,x,y,angle,vx,vy,omega,fx,fy,torque")?;
        Ok(file)
    }

    /// One row: the body's pose, velocities and the fluid's force and torque on it.
    pub fn row(
        world: &mut World,
        body: Entity,
        time: f64,
        file: &mut impl Write,
    ) -> std::io::Result<()> {
        // Before the first tick the body is at rest and not yet a solid of the fluid.
        let mut query = world.query::<(
            &Transform,
            Option<&LinearVelocity>,
            Option<&AngularVelocity>,
            Option<&FluidForce>,
        )>();
        let Ok((transform, v, omega, force)) = query.get(world, body) else {
            return Ok(());
        };
        let (v, omega) = (v.map_or(Vec2::ZERO, |v| v.0), omega.map_or(0.0, |w| w.0));
        let force = force.copied().unwrap_or_default();
        let angle = transform.rotation.to_euler(EulerRot::ZYX).0;
        let (x, y) = (transform.translation.x, transform.translation.y);
        writeln!(
            file,
            "{time:.6},0,{x},{y},{angle},{},{},{},{},{},{}",
            v.x, v.y, omega, force.force.x, force.force.y, force.torque
        )
    }
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

fn configure_galaxy(cli: &Cli) -> Result<GalaxyConfig, String> {
    if cli.bodies == 0 || !(cli.dt.is_finite() && cli.dt > 0.0) {
        return Err("--bodies and --dt must be positive".into());
    }
    let params = GravityParams {
        gravitational_constant: 1.0,
        theta: cli.theta,
        softening: cli.softening,
        ..default()
    };
    params.validate().map_err(|e| e.to_string())?;
    Ok(GalaxyConfig {
        disc: GalaxyDisc {
            seed: cli.seed,
            ..GalaxyDisc::new(cli.bodies)
        },
        params,
        steps: cli.steps,
        dt: cli.dt,
        frame_steps: cli.frame_steps.unwrap_or(cli.steps).max(1),
        out: cli.out.clone(),
        threads: threads(cli),
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
    let ids = config.disc.spawn(app.world_mut());
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
    let bar = progress(config.steps as u64, "steps");
    for step in 1..=config.steps {
        app.update();
        bar.inc(1);
        if step % config.frame_steps == 0 || step == config.steps {
            write_frame(&mut app, step)?;
        }
    }
    out.flush()?;
    bar.finish_and_clear();
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
