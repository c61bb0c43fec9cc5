//! Headless benchmark: a dam break of N particles, stepped K times on plain slices (rayon) and
//! through the ECS, in the same process, on T threads; or, with `--gravity`,
//! Barnes-Hut gravity on a disc of N bodies around a heavy centre.
//!
//! ```text
//! cargo run --release --example bench -- --particles 100000 --steps 200 --threads 2
//! cargo run --release --example bench -- --gravity --bodies 1000000 --steps 5 --threads 2 --theta 1
//! ```
//! With `--realtime`, the demo's dam break runs through the ECS for one simulated second and the
//! last line reads
//! `realtime solver=S particles=N threads=T sim_s=X wall_s=Y realtime_x=Z substeps_per_sim_s=K iterations_per_substep=I ns_per_particle_substep=C`
//! (`realtime_x` is simulated seconds per wall second; iterations count both DFSPH solves and are
//! 0 for WCSPH; `C` is core time, wall time × threads, per particle and sub-step). With
//! `--density-iterations N --divergence-iterations M` the DFSPH solves run exactly that many
//! iterations each sub-step (a fixed budget, no tolerance stop); with `--breakdown` a line per
//! part of a sub-step comes before the last one,
//! `breakdown part=P wall_s=X ns_per_particle_substep=C share=S%`, the part `driver` being the
//! fluid's tick around its sub-steps (the copies between the components and the solver) and
//! `app` the rest of the wall time (Bevy's schedules and the fluid's other systems).
//!
//! The fluid's last two lines (three with `--hook`, the ECS again with a game system between the
//! stages of every sub-step) read
//! `path=slices|ecs|ecs_hook particles=N steps=K threads=T neighbours=X ms_per_step=Y particle_steps_per_s=Z iterations_per_step=I`,
//! where a step is one solver sub-step and `neighbours` the mean number of particles within the
//! kernel support (the particle itself and wall particles included).
//!
//! Gravity's last line reads
//! `bodies=N steps=K threads=T theta=X ms_per_step=Y body_steps_per_s=Z`, a step being one fixed
//! tick through the ECS: leapfrog kick and drift, tree build, field evaluation, kick. Up to 20,000
//! bodies a line starting `direct` gives exact direct summation on the same bodies before it.

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{
    DfsphSettings, Pose, Position, PressureSolver, SphParams, SphSolver, Tank,
};
use bevy_sph2d::gameplay::SCENARIO_TANK;
use bevy_sph2d::gameplay::{FluidBlock, ScenarioKind, SphScenario};
use bevy_sph2d::gravity::Multipole;
use bevy_sph2d::prelude::*;
use bevy_sph2d::slices::{
    MovingSolid, SliceFluid, SolidMotion, SphConstants, StageProfile, SubstepPart,
};
use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, ValueEnum};
use std::time::{Duration, Instant};

/// Headless benchmark. By default a dam break (column 1:2, tank 4 columns wide) of about
/// --particles at 5 mm spacing, --steps sub-steps on plain slices and through the ECS after 10
/// warm-up steps; with --realtime the demo's dam break (tank 1.6 m x 0.9 m, column 0.48 m x
/// 0.54 m, spacing from --particles) with the solver's default settings through the ECS at 64
/// ticks/s for 1 simulated second; with --gravity Barnes-Hut gravity on a disc of --bodies
/// around a heavy centre (G = 1, radius 1 m), --steps fixed ticks after one warm-up tick.
#[derive(Parser, Debug)]
#[command(name = "bench", allow_negative_numbers = true)]
struct Cli {
    /// Run the demo's dam break against the clock.
    #[arg(long, conflicts_with = "gravity")]
    realtime: bool,
    /// Benchmark Barnes-Hut gravity instead of the fluid.
    #[arg(long)]
    gravity: bool,
    /// Fluid particles [default: 100000, or 2500 with --realtime].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    particles: Option<u32>,
    /// Sub-steps (fluid) or ticks (gravity) [default: 100, or 10 with --gravity].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    steps: Option<u32>,
    /// Threads.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..))]
    threads: u32,
    /// Kernel support / spacing.
    #[arg(long, default_value_t = 2.0)]
    support_ratio: f32,
    /// Smoothing kernel.
    #[arg(long, value_enum, default_value_t = Kernel::Wendland)]
    kernel: Kernel,
    /// Pressure solver.
    #[arg(long, value_enum, default_value_t = Solver::Dfsph)]
    solver: Solver,
    /// Gravity bodies.
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u32).range(1..))]
    bodies: u32,
    /// Barnes-Hut opening angle.
    #[arg(long, default_value_t = 1.0)]
    theta: f32,
    /// Also run the ECS with a (do-nothing) game system in `SphSubstep`, as a game that adds
    /// forces between sub-steps does: every sub-step then reads and writes the components
    /// (one more line, `path=ecs_hook`).
    #[arg(long, conflicts_with_all = ["gravity", "realtime"])]
    hook: bool,
    /// Solids in the fluid's plain-slices run: boxes six spacings wide on the water's surface,
    /// sinking at 1 cm/s, so their boundary particles move every sub-step (prints
    /// `solids=N` on the slices line).
    #[arg(long, default_value_t = 0, conflicts_with_all = ["gravity", "realtime"])]
    solids: u32,
    /// Gravity's far field: point masses, or with quadrupole moments.
    #[arg(long, value_enum, default_value_t = Expansion::Monopole)]
    multipole: Expansion,
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
    /// With --realtime: where a sub-step's time goes, a line per part before the last line.
    #[arg(long, requires = "realtime")]
    breakdown: bool,
    /// Surface tension, N/m (0: none), to measure what its pass costs.
    #[arg(long, default_value_t = 0.0, conflicts_with = "gravity")]
    surface_tension: f32,
    /// With --realtime: the right half of the column a second liquid this many times the
    /// water's density (0.25-4), to measure what two liquids cost.
    #[arg(long, requires = "realtime")]
    second_liquid: Option<f32>,
}

impl Cli {
    /// `params` with the surface tension of --surface-tension, the strict solve of --reference
    /// and the DFSPH budget of --density-iterations and --divergence-iterations, if given.
    fn budgeted(&self, mut params: SphParams) -> SphParams {
        params.surface_tension = self.surface_tension;
        if let Some(ratio) = self.second_liquid {
            params.liquids = vec![Liquid::new("second", ratio * params.rest_density)];
        }
        if self.reference {
            params.dfsph = DfsphSettings::reference();
        }
        if let (Some(density), Some(divergence)) =
            (self.density_iterations, self.divergence_iterations)
        {
            params.dfsph = params.dfsph.with_budget(density, divergence);
        }
        params
    }
}

/// Gravity's far-field expansion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Expansion {
    Monopole,
    Quadrupole,
}

/// The fluid's pressure solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Solver {
    /// Incompressible (divergence-free SPH).
    Dfsph,
    /// Weakly compressible.
    Wcsph,
}

impl Solver {
    fn solver(self) -> PressureSolver {
        match self {
            Solver::Dfsph => PressureSolver::Dfsph,
            Solver::Wcsph => PressureSolver::Wcsph,
        }
    }
}

/// The smoothing kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Kernel {
    Wendland,
    Cubic,
    Muller,
}

/// Exits with `message`, the usage and status 2, as for any other bad argument.
fn refuse(message: impl std::fmt::Display) -> ! {
    Cli::command()
        .error(ErrorKind::ValueValidation, message)
        .exit()
}

/// Largest body count for which the direct-sum comparison runs.
const DIRECT_LIMIT: usize = 20_000;

/// Sub-steps per ECS tick: enough that per-tick work (statistics) is amortised as in a game.
const SUBSTEPS_PER_TICK: u32 = 10;
const WARM_UP: usize = 10;

fn main() {
    let cli = Cli::parse();
    if cli.gravity {
        gravity_bench(&cli);
        return;
    }
    if cli.realtime {
        realtime_bench(&cli);
        return;
    }
    let particles = cli.particles.unwrap_or(100_000) as usize;
    let steps = cli.steps.unwrap_or(100) as usize;
    let threads = cli.threads as usize;
    let kernel = match cli.kernel {
        Kernel::Wendland => KernelKind::WendlandC2,
        Kernel::Cubic => KernelKind::CubicSpline,
        Kernel::Muller => KernelKind::Muller,
    };
    let spacing = 0.005f32;
    let columns = ((particles as f32 / 2.0).sqrt().round() as usize).max(1);
    let rows = particles.div_ceil(columns);
    let column = Vec2::new(columns as f32, rows as f32) * spacing;
    let params = cli.budgeted(SphParams {
        particle_spacing: spacing,
        support_ratio: cli.support_ratio,
        kernel,
        solver: cli.solver.solver(),
        speed_of_sound: SphParams::speed_of_sound_for_height(column.y),
        tank: Some(Tank::new(4.0 * column.x, 1.25 * column.y)),
        max_substeps: SUBSTEPS_PER_TICK,
        ..default()
    });
    if let Err(error) = params.validate() {
        refuse(error);
    }
    let particles = columns * rows;
    let tank = params.tank.expect("the bench has a tank");
    let column = Vec2::new(tank.width / 4.0, tank.height / 1.25);
    let block = FluidBlock::dam_break(column.x + 1e-4, column.y + 1e-4);
    let positions = block.positions(params.particle_spacing);
    assert_eq!(positions.len(), particles);
    let constants = params.constants().expect("validated above");
    let solids = boxes(&constants, column, cli.solids as usize);
    eprintln!(
        "dam break: {particles} particles, column {:.2} m x {:.2} m, tank {:.2} m x {:.2} m, \
         support ratio {}, {} kernel, {} solver, {threads} threads",
        column.x,
        column.y,
        tank.width,
        tank.height,
        params.support_ratio,
        params.kernel.label(),
        params.solver.label()
    );

    // Plain slices on a rayon pool of `threads` threads.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    let (slices_seconds, neighbours, slices_iterations) = pool.install(|| {
        let mut fluid = SliceFluid::new(constants, positions.clone());
        fluid.solids_mut().extend(solids);
        for _ in 0..WARM_UP {
            fluid.step();
        }
        let before = fluid.iterations().total;
        let started = Instant::now();
        for _ in 0..steps {
            fluid.step();
        }
        let seconds = started.elapsed().as_secs_f64();
        (
            seconds,
            fluid.mean_neighbors(),
            fluid.iterations().total - before,
        )
    });
    drop(pool);

    let (ecs_steps, ecs_seconds, ecs_iterations) = ecs_run(&params, &block, steps, threads, false);
    let hooked = cli
        .hook
        .then(|| ecs_run(&params, &block, steps, threads, true));

    let line = |path: &str, steps: usize, seconds: f64, iterations: u64| {
        println!(
            "path={path} particles={particles} steps={steps} threads={threads} \
             neighbours={neighbours:.1} ms_per_step={:.3} particle_steps_per_s={:.0} \
             iterations_per_step={:.2}",
            1000.0 * seconds / steps as f64,
            (particles * steps) as f64 / seconds,
            iterations as f64 / steps as f64
        );
    };
    eprintln!(
        "ecs / slices time per step: {:.3}",
        (ecs_seconds / ecs_steps as f64) / (slices_seconds / steps as f64)
    );
    if cli.solids > 0 {
        line(
            &format!("slices solids={}", cli.solids),
            steps,
            slices_seconds,
            slices_iterations,
        );
    } else {
        line("slices", steps, slices_seconds, slices_iterations);
    }
    line("ecs", ecs_steps, ecs_seconds, ecs_iterations);
    if let Some((steps, seconds, iterations)) = hooked {
        line("ecs_hook", steps, seconds, iterations);
    }
}

/// `count` boxes six spacings wide sitting on the surface of the water column, spread along it
/// and sinking slowly.
fn boxes(c: &SphConstants, column: Vec2, count: usize) -> Vec<MovingSolid> {
    let size = 6.0 * c.spacing;
    (0..count)
        .filter_map(|k| {
            let shape = SolidShape::rectangle(size, size);
            let mut solid = MovingSolid::new(shape, Vec2::ZERO, c.spacing, c.wall_layers)?;
            let x = (k as f32 + 0.5) / count as f32 * column.x;
            solid.set_motion(SolidMotion {
                pose: Pose {
                    position: Vec2::new(x, column.y + 0.5 * size + 0.5 * c.spacing),
                    angle: 0.0,
                },
                velocity: Vec2::new(0.0, -0.01),
                angular_velocity: 0.0,
            });
            Some(solid)
        })
        .collect()
}

/// The dam break of `block` through the ECS for about `steps` sub-steps after the warm-up, each
/// update one tick of [`SUBSTEPS_PER_TICK`] stable sub-steps; with `hook`, a game system in
/// [`SphSubstep`] (so every sub-step reads and writes the components). Returns the sub-steps,
/// the seconds and the solver iterations.
fn ecs_run(
    params: &SphParams,
    block: &FluidBlock,
    steps: usize,
    threads: usize,
    hook: bool,
) -> (usize, f64, u64) {
    let particles = block.positions(params.particle_spacing).len();
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        SphPlugin::default().with_params(params.clone()),
    ))
    // Ticks far longer than SUBSTEPS_PER_TICK stable steps, so each runs exactly that many; kept
    // under `Time<Virtual>`'s 0.25 s cap on one frame's delta.
    .insert_resource(Time::<Fixed>::from_duration(Duration::from_millis(200)))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    if hook {
        app.add_systems(
            SphSubstep,
            (|| {}).in_set(SphSubstepSystems::ExternalForces),
        );
    }
    block.spawn(app.world_mut());
    app.update();
    let ticks = steps.div_ceil(SUBSTEPS_PER_TICK as usize);
    for _ in 0..WARM_UP.div_ceil(SUBSTEPS_PER_TICK as usize) {
        app.update();
    }
    let solver_state = app.world().resource::<SphSolver>();
    let before = solver_state.clock().total_substeps;
    let iterations_before = solver_state.iterations().total;
    let started = Instant::now();
    for _ in 0..ticks {
        app.update();
    }
    let seconds = started.elapsed().as_secs_f64();
    let solver_state = app.world().resource::<SphSolver>();
    let ecs_steps = (solver_state.clock().total_substeps - before) as usize;
    let iterations = solver_state.iterations().total - iterations_before;
    let stats = app.world().resource::<SphStats>();
    assert_eq!(stats.particles, particles, "the ECS lost particles");
    (ecs_steps, seconds, iterations)
}

/// Makes the right half of the fluid (by position) the second liquid.
fn second_liquid_on_the_right(world: &mut World) {
    let mut query = world.query_filtered::<(Entity, &Position), With<FluidParticle>>();
    let mut xs: Vec<(Entity, f32)> = query.iter(world).map(|(e, p)| (e, p.0.x)).collect();
    xs.sort_by(|a, b| a.1.total_cmp(&b.1));
    for &(entity, _) in &xs[xs.len() / 2..] {
        world.entity_mut(entity).insert(FluidMaterial(1));
    }
}

/// The demo's dam break through the ECS for one simulated second: how fast it runs against the
/// clock.
fn realtime_bench(cli: &Cli) {
    let particles = cli.particles.unwrap_or(2_500);
    let threads = cli.threads as usize;
    let solver = cli.solver.solver();
    let scenario = SphScenario::new(ScenarioKind::DamBreak, particles);
    let tank = SCENARIO_TANK;
    // Each solver's own defaults (WCSPH needs the wider support).
    let base = match solver {
        PressureSolver::Wcsph => SphParams::water_wcsph(),
        PressureSolver::Dfsph => SphParams::water(),
    };
    let params = cli.budgeted(SphParams {
        tank: Some(tank),
        particle_spacing: scenario.spacing(&tank),
        // Every sub-step the flow needs: the measure is how long they take, not what a
        // step budget would drop.
        max_substeps: 100_000,
        ..base
    });
    if let Err(error) = params.validate() {
        refuse(error);
    }
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        SphPlugin::default().with_params(params.clone()),
    ))
    .insert_resource(Time::<Fixed>::from_hz(64.0))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    for block in scenario.blocks(&tank) {
        block.spawn(app.world_mut());
    }
    if cli.second_liquid.is_some() {
        second_liquid_on_the_right(app.world_mut());
    }
    app.update();
    eprintln!(
        "dam break at {:.4} m spacing, {} solver, {threads} threads, SIMD path {}",
        params.particle_spacing,
        solver.label(),
        bevy_sph2d::simd_path()
    );
    if cli.breakdown {
        let mut solver = app.world_mut().resource_mut::<SphSolver>();
        solver.set_stage_profile(Some(StageProfile::new(seconds_since_start)));
    }
    let started = Instant::now();
    let (mut density_iterations, mut divergence_iterations) = (0u64, 0u64);
    // The fluid's own tick (its sub-steps and the driver's work around them), s.
    let mut fluid_seconds = 0.0f64;
    while app.world().resource::<SphSolver>().clock().time < 1.0 {
        app.update();
        let stats = app.world().resource::<SphStats>();
        density_iterations += stats.density_iterations as u64;
        divergence_iterations += stats.divergence_iterations as u64;
        fluid_seconds += stats.tick_ms as f64 / 1000.0;
    }
    let wall = started.elapsed().as_secs_f64();
    let solver_state = app.world().resource::<SphSolver>();
    let clock = *solver_state.clock();
    let iterations = solver_state.iterations().total;
    let count = app.world().resource::<SphStats>().particles;
    if solver == PressureSolver::Dfsph {
        eprintln!(
            "iterations per sub-step: density {:.2}, divergence {:.2}",
            density_iterations as f64 / clock.total_substeps.max(1) as f64,
            divergence_iterations as f64 / clock.total_substeps.max(1) as f64
        );
    }
    let substeps = clock.total_substeps.max(1) as f64;
    // Core time per particle and sub-step, ns.
    let per_particle_substep =
        |seconds: f64| seconds * threads as f64 * 1e9 / (count.max(1) as f64 * substeps);
    if let Some(profile) = solver_state.stage_profile() {
        let parts = SubstepPart::ALL.map(|part| (part.label(), profile.seconds(part)));
        let driver = ("driver", fluid_seconds - profile.total_seconds());
        let app = ("app", wall - fluid_seconds);
        for (label, seconds) in parts.into_iter().chain([driver, app]) {
            println!(
                "breakdown part={label} wall_s={seconds:.3} ns_per_particle_substep={:.0} \
                 share={:.1}%",
                per_particle_substep(seconds),
                100.0 * seconds / wall
            );
        }
    }
    println!(
        "realtime solver={} particles={count} threads={threads} sim_s={:.3} wall_s={wall:.3} \
         realtime_x={:.3} substeps_per_sim_s={:.0} iterations_per_substep={:.2} \
         ns_per_particle_substep={:.0}",
        match solver {
            PressureSolver::Wcsph => "wcsph",
            PressureSolver::Dfsph => "dfsph",
        },
        clock.time,
        clock.time / wall,
        clock.total_substeps as f64 / clock.time,
        iterations as f64 / substeps,
        per_particle_substep(wall)
    );
}

/// Seconds since the first call: the clock of the sub-steps' [`StageProfile`].
fn seconds_since_start() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Seconds per tick of the gravity plugin on a galaxy disc of `bodies` bodies.
fn time_gravity(bodies: usize, steps: usize, threads: usize, params: GravityParams) -> f64 {
    let multipole = params.multipole;
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        GravityPlugin::default().with_params(params),
    ))
    .insert_resource(Time::<Fixed>::from_duration(Duration::from_millis(1)))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.world_mut().commands().queue(GalaxyDisc::new(bodies));
    // Start the clocks, then one warm-up tick (it also evaluates the new bodies' field).
    app.update();
    app.update();
    let started = Instant::now();
    for _ in 0..steps {
        app.update();
    }
    let seconds = started.elapsed().as_secs_f64() / steps as f64;
    let stats = app.world().resource::<GravityStats>();
    assert_eq!(stats.bodies, bodies, "the ECS lost bodies");
    eprintln!(
        "{} bodies, {} nodes, field {:.1} ms of {:.1} ms per tick, {} sums, {}",
        stats.bodies,
        stats.nodes,
        stats.field_ms,
        1000.0 * seconds,
        bevy_sph2d::simd_path(),
        multipole.label()
    );
    seconds
}

fn gravity_bench(cli: &Cli) {
    let bodies = cli.bodies as usize;
    let steps = cli.steps.unwrap_or(10) as usize;
    let threads = cli.threads as usize;
    let theta = cli.theta;
    let params = GravityParams {
        gravitational_constant: 1.0,
        theta,
        softening: 0.001,
        multipole: match cli.multipole {
            Expansion::Monopole => Multipole::Monopole,
            Expansion::Quadrupole => Multipole::Quadrupole,
        },
        ..default()
    };
    if let Err(error) = params.validate() {
        refuse(error);
    }
    {
        if bodies <= DIRECT_LIMIT {
            let direct_steps = steps.min(3);
            let direct = GravityParams {
                direct_sum: true,
                ..params.clone()
            };
            let seconds = time_gravity(bodies, direct_steps, threads, direct);
            println!(
                "direct bodies={bodies} steps={direct_steps} threads={threads} \
                 ms_per_step={:.3} body_steps_per_s={:.0}",
                1000.0 * seconds,
                bodies as f64 / seconds
            );
        }
        let seconds = time_gravity(bodies, steps, threads, params.clone());
        println!(
            "bodies={bodies} steps={steps} threads={threads} theta={theta} ms_per_step={:.3} \
             body_steps_per_s={:.0}",
            1000.0 * seconds,
            bodies as f64 / seconds
        );
    }
}
