//! Headless benchmark: a dam break of N particles, stepped K times on plain slices (rayon) and
//! through the ECS (`par_iter_mut`), in the same process, on T threads; or, with `--gravity`,
//! Barnes-Hut gravity on a disc of N bodies around a heavy centre.
//!
//! ```text
//! cargo run --release --example bench -- --particles 100000 --steps 200 --threads 2
//! cargo run --release --example bench -- --gravity --bodies 1000000 --steps 5 --threads 2 --theta 1
//! ```
//! The fluid's last two lines read
//! `path=slices|ecs particles=N steps=K threads=T neighbours=X ms_per_step=Y particle_steps_per_s=Z`,
//! where a step is one solver sub-step and `neighbours` the mean number of particles within the
//! kernel support (the particle itself and wall particles included).
//!
//! Gravity's last line reads
//! `bodies=N steps=K threads=T theta=X ms_per_step=Y body_steps_per_s=Z`, a step being one fixed
//! tick through the ECS: leapfrog kick and drift, tree build, field evaluation, kick. Up to 20,000
//! bodies a line starting `direct` gives exact direct summation on the same bodies before it.

mod support;

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::slices::SliceFluid;
use bevy_sph2d::fluid::{FluidBlock, SphParams, SphSolver, Tank};
use bevy_sph2d::prelude::*;
use std::time::{Duration, Instant};
use support::{Args, fail};

const USAGE: &str = "\
usage: bench --particles N --steps K [--threads T] [--support-ratio R] [--kernel wendland|cubic|muller]
  a dam break (column 1:2, tank 4 columns wide) of about N particles at 5 mm spacing,
  K sub-steps on each path after 10 warm-up steps
usage: bench --gravity --bodies N --steps K [--threads T] [--theta X]
  Barnes-Hut gravity on a disc of N bodies around a heavy centre (G = 1, radius 1 m),
  K fixed ticks through the ECS after one warm-up tick";

/// Largest body count for which the direct-sum comparison runs.
const DIRECT_LIMIT: usize = 20_000;

/// Sub-steps per ECS tick: enough that per-tick work (statistics) is amortised as in a game.
const SUBSTEPS_PER_TICK: u32 = 10;
const WARM_UP: usize = 10;

fn main() {
    let args = Args::parse(
        &[
            "particles",
            "steps",
            "threads",
            "support-ratio",
            "kernel",
            "bodies",
            "theta",
        ],
        &["gravity"],
    )
    .unwrap_or_else(|e| fail(&e, USAGE));
    if args.flag("gravity") {
        gravity_bench(&args);
        return;
    }
    let run = || -> Result<(usize, usize, usize, SphParams), String> {
        let particles: usize = args.get("particles", 100_000)?;
        let steps: usize = args.get("steps", 100)?;
        let threads: usize = args.get("threads", 2)?;
        if particles == 0 || steps == 0 || threads == 0 {
            return Err("--particles, --steps and --threads must be positive".into());
        }
        let kernel = match args.text("kernel").unwrap_or("wendland") {
            "wendland" => KernelKind::WendlandC2,
            "cubic" => KernelKind::CubicSpline,
            "muller" => KernelKind::Muller,
            other => return Err(format!("unknown kernel '{other}'")),
        };
        let spacing = 0.005f32;
        let columns = ((particles as f32 / 2.0).sqrt().round() as usize).max(1);
        let rows = particles.div_ceil(columns);
        let column = Vec2::new(columns as f32, rows as f32) * spacing;
        let params = SphParams {
            particle_spacing: spacing,
            support_ratio: args.positive("support-ratio", 2.0)?,
            kernel,
            speed_of_sound: SphParams::speed_of_sound_for_height(column.y),
            tank: Some(Tank::new(4.0 * column.x, 1.25 * column.y)),
            max_substeps: SUBSTEPS_PER_TICK,
            ..default()
        };
        params.validate().map_err(|e| e.to_string())?;
        Ok((columns * rows, steps, threads, params))
    };
    let (particles, steps, threads, params) = run().unwrap_or_else(|e| fail(&e, USAGE));
    let tank = params.tank.expect("the bench has a tank");
    let column = Vec2::new(tank.width / 4.0, tank.height / 1.25);
    let block = FluidBlock::dam_break(column.x + 1e-4, column.y + 1e-4);
    let positions = block.positions(params.particle_spacing);
    assert_eq!(positions.len(), particles);
    eprintln!(
        "dam break: {particles} particles, column {:.2} m x {:.2} m, tank {:.2} m x {:.2} m, \
         support ratio {}, {} kernel, {threads} threads",
        column.x,
        column.y,
        tank.width,
        tank.height,
        params.support_ratio,
        params.kernel.label()
    );

    // Plain slices on a rayon pool of `threads` threads.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    let constants = params.constants().expect("validated above");
    let (slices_seconds, neighbours) = pool.install(|| {
        let mut fluid = SliceFluid::new(constants, positions.clone(), &[]);
        for _ in 0..WARM_UP {
            fluid.step();
        }
        let started = Instant::now();
        for _ in 0..steps {
            fluid.step();
        }
        (started.elapsed().as_secs_f64(), fluid.mean_neighbors())
    });
    drop(pool);

    // The ECS: each update is one tick of SUBSTEPS_PER_TICK stable sub-steps.
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        SphPlugin::default().with_params(params.clone()),
    ))
    // Ticks far longer than SUBSTEPS_PER_TICK stable steps, so each runs exactly that many; kept
    // under `Time<Virtual>`'s 0.25 s cap on one frame's delta.
    .insert_resource(Time::<Fixed>::from_duration(Duration::from_millis(200)))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    block.spawn(app.world_mut());
    app.update();
    let ticks = steps.div_ceil(SUBSTEPS_PER_TICK as usize);
    for _ in 0..WARM_UP.div_ceil(SUBSTEPS_PER_TICK as usize) {
        app.update();
    }
    let before = app.world().resource::<SphSolver>().clock().total_substeps;
    let started = Instant::now();
    for _ in 0..ticks {
        app.update();
    }
    let ecs_seconds = started.elapsed().as_secs_f64();
    let ecs_steps = (app.world().resource::<SphSolver>().clock().total_substeps - before) as usize;
    let stats = app.world().resource::<SphStats>();
    assert_eq!(stats.particles, particles, "the ECS lost particles");

    let line = |path: &str, steps: usize, seconds: f64| {
        println!(
            "path={path} particles={particles} steps={steps} threads={threads} \
             neighbours={neighbours:.1} ms_per_step={:.3} particle_steps_per_s={:.0}",
            1000.0 * seconds / steps as f64,
            (particles * steps) as f64 / seconds
        );
    };
    eprintln!(
        "ecs / slices time per step: {:.3}",
        (ecs_seconds / ecs_steps as f64) / (slices_seconds / steps as f64)
    );
    line("slices", steps, slices_seconds);
    line("ecs", ecs_steps, ecs_seconds);
}

/// Seconds per tick of the gravity plugin on a galaxy disc of `bodies` bodies.
fn time_gravity(bodies: usize, steps: usize, threads: usize, params: GravityParams) -> f64 {
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
        "{} bodies, {} nodes, field {:.1} ms of {:.1} ms per tick",
        stats.bodies,
        stats.nodes,
        stats.field_ms,
        1000.0 * seconds
    );
    seconds
}

fn gravity_bench(args: &Args) {
    let run = || -> Result<(usize, usize, usize, f32), String> {
        let bodies: usize = args.get("bodies", 100_000)?;
        let steps: usize = args.get("steps", 10)?;
        let threads: usize = args.get("threads", 2)?;
        let theta: f32 = args.get("theta", 1.0)?;
        if bodies == 0 || steps == 0 || threads == 0 {
            return Err("--bodies, --steps and --threads must be positive".into());
        }
        Ok((bodies, steps, threads, theta))
    };
    let (bodies, steps, threads, theta) = run().unwrap_or_else(|e| fail(&e, USAGE));
    let params = GravityParams {
        gravitational_constant: 1.0,
        theta,
        softening: 0.001,
        ..default()
    };
    if let Err(error) = params.validate() {
        fail(&error.to_string(), USAGE);
    }
    // The tree build and the field run on rayon from inside Bevy's systems, which run on Bevy's
    // threads, so they use rayon's global pool: give it the same thread count.
    if let Err(error) = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
    {
        eprintln!("rayon's global pool was already set up: {error}");
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
