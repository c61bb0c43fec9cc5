//! Same seed, same run (a fluid with a still solid and a moving one): bit for bit, across repeated runs, across thread counts (through the
//! ECS and on plain slices), and different for a different seed. Built without the `parallel`
//! feature (one thread), the ECS checks across thread counts do not apply; `.ci/run` compares
//! that build's fingerprints with the threaded build's instead.

use crate::common::*;
use bevy::prelude::*;
use bevy_sph2d::fluid::{PressureSolver, Solid, SolidShape, SolidVelocity, SphParams, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::slices::SliceFluid;

fn params() -> SphParams {
    params_for(PressureSolver::Wcsph)
}

fn params_for(solver: PressureSolver) -> SphParams {
    let base = match solver {
        PressureSolver::Wcsph => SphParams::water_wcsph(),
        PressureSolver::Dfsph => SphParams::water(),
    };
    SphParams {
        particle_spacing: 0.01,
        tank: Some(Tank::new(0.6, 0.4)),
        speed_of_sound: SphParams::speed_of_sound_for_height(0.25),
        ..base
    }
}

/// DFSPH at a spacing fine enough (over 8,192 particles) for its solver passes and the ECS's
/// light passes to run in parallel chunks.
fn dfsph_fine() -> SphParams {
    SphParams {
        particle_spacing: 0.0022,
        ..params_for(PressureSolver::Dfsph)
    }
}

/// What a helper process runs (`SPH_TEST_CASE`: `wcsph`, the default, or `dfsph-fine`).
fn case_from_env() -> (SphParams, usize) {
    match std::env::var("SPH_TEST_CASE").as_deref() {
        Ok("dfsph-fine") => (dfsph_fine(), 4),
        _ => (params(), 25),
    }
}

fn block(seed: u64) -> FluidBlock {
    FluidBlock::dam_break(0.2, 0.25)
        .with_jitter(0.05)
        .with_seed(seed)
}

/// A fingerprint of every bit of the final state.
fn fingerprint(states: &[State]) -> u64 {
    use std::hash::{DefaultHasher, Hash, Hasher};
    let mut hasher = DefaultHasher::new();
    for s in states {
        for v in [
            s.position.x,
            s.position.y,
            s.velocity.x,
            s.velocity.y,
            s.acceleration.x,
            s.acceleration.y,
            s.density,
            s.pressure,
        ] {
            v.to_bits().hash(&mut hasher);
        }
    }
    hasher.finish()
}

fn run_ecs(seed: u64, app: &mut App) -> u64 {
    run_ecs_ticks(seed, app, 25)
}

fn run_ecs_ticks(seed: u64, app: &mut App, ticks: usize) -> u64 {
    // A still solid (what an obstacle was).
    app.world_mut().spawn((
        Solid::new(SolidShape::circle(0.05)),
        Transform::from_xyz(0.4, 0.05, 0.0),
    ));
    // A kinematic paddle sweeping through the water: the solids' passes too.
    app.world_mut().spawn((
        Solid::new(SolidShape::rectangle(0.03, 0.12)),
        SolidVelocity {
            linear: Vec2::new(0.3, 0.0),
            angular: 0.5,
        },
        Transform::from_xyz(0.3, 0.1, 0.0),
    ));
    spawn(app, block(seed));
    run(app, ticks);
    fingerprint(&states(app))
}

#[test]
fn same_seed_same_run() {
    for solver in PressureSolver::ALL {
        let a = run_ecs(1, &mut create_app(params_for(solver)));
        let b = run_ecs(1, &mut create_app(params_for(solver)));
        let c = run_ecs(2, &mut create_app(params_for(solver)));
        assert_eq!(a, b, "{solver:?}: two runs with the same seed differ");
        assert_ne!(
            a, c,
            "{solver:?}: a different seed should give a different run"
        );
    }
}

/// Run by [`ecs_is_deterministic_across_thread_counts`] in a child process (Bevy's compute pool
/// is global, so each thread count needs a process of its own); prints the fingerprint.
#[test]
#[ignore = "helper, run by ecs_is_deterministic_across_thread_counts"]
fn fingerprint_with_threads_from_env() {
    let threads: usize = std::env::var("SPH_TEST_THREADS")
        .expect("SPH_TEST_THREADS")
        .parse()
        .expect("a thread count");
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
        bevy_sph2d::fluid::SphPlugin::default().with_params(case_from_env().0),
    ))
    .insert_resource(Time::<Fixed>::from_duration(
        std::time::Duration::from_secs_f64(TICK),
    ))
    .insert_resource(bevy::time::TimeUpdateStrategy::FixedTimesteps(1));
    let actual = bevy::tasks::ComputeTaskPool::get().thread_num();
    let ticks = case_from_env().1;
    println!(
        "fingerprint={} threads={actual}",
        run_ecs_ticks(1, &mut app, ticks)
    );
}

#[test]
#[cfg(feature = "parallel")]
fn ecs_is_deterministic_across_thread_counts() {
    ecs_across_thread_counts("wcsph", params(), 25);
}

#[test]
#[cfg(feature = "parallel")]
fn ecs_is_deterministic_across_thread_counts_dfsph() {
    let p = dfsph_fine();
    assert!(block(1).positions_for(&p).len() > bevy_sph2d::fluid::PARALLEL_SLOTS);
    ecs_across_thread_counts("dfsph-fine", p, 4);
}

#[cfg(feature = "parallel")]
fn ecs_across_thread_counts(case: &str, p: SphParams, ticks: usize) {
    let exe = std::env::current_exe().expect("test binary");
    let fingerprints: Vec<(String, String)> = [1, 2, 4]
        .iter()
        .map(|threads| {
            let out = std::process::Command::new(&exe)
                .args([
                    "determinism::fingerprint_with_threads_from_env",
                    "--exact",
                    "--ignored",
                    "--nocapture",
                ])
                .env("SPH_TEST_THREADS", threads.to_string())
                .env("SPH_TEST_CASE", case)
                .output()
                .expect("run the helper");
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(out.status.success(), "helper failed: {stdout}");
            let line = stdout
                .lines()
                .find(|l| l.starts_with("fingerprint="))
                .unwrap_or_else(|| panic!("no fingerprint in: {stdout}"));
            let mut parts = line.split_whitespace();
            let print = parts.next().unwrap().to_string();
            let used = parts.next().unwrap().to_string();
            assert_eq!(used, format!("threads={threads}"));
            (print, used)
        })
        .collect();
    assert!(
        fingerprints.windows(2).all(|w| w[0].0 == w[1].0),
        "results depend on the thread count: {fingerprints:?}"
    );
    // And they equal the in-process run, whatever its pool.
    let here = run_ecs_ticks(1, &mut create_app(p), ticks);
    assert_eq!(fingerprints[0].0, format!("fingerprint={here}"));
}

/// Runs `positions` on plain slices for `ticks` ticks on rayon pools of 1, 2 and 5 threads and
/// checks the final positions, velocities, densities and pressures agree bit for bit.
fn check_slices_across_thread_counts(p: &SphParams, positions: &[Vec2], ticks: usize) {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut fluid = SliceFluid::new(p.constants().unwrap(), positions.to_vec());
            for _ in 0..ticks {
                fluid.advance(TICK);
            }
            (
                fluid.position.clone(),
                fluid.velocity.clone(),
                fluid.density.clone(),
                fluid.pressure.clone(),
            )
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(5));
}

#[test]
fn slices_are_deterministic_across_thread_counts() {
    let p = params();
    check_slices_across_thread_counts(&p, &block(1).positions_for(&p), 25);
}

#[test]
fn dfsph_slices_are_deterministic_across_thread_counts() {
    // Fine enough for the solver's passes to run in parallel chunks.
    let p = dfsph_fine();
    let positions = block(1).positions_for(&p);
    assert!(positions.len() > bevy_sph2d::fluid::PARALLEL_SLOTS);
    check_slices_across_thread_counts(&p, &positions, 5);
}

#[test]
fn reference_slices_are_deterministic_across_thread_counts() {
    let p = SphParams {
        dfsph: bevy_sph2d::fluid::DfsphSettings::reference(),
        ..dfsph_fine()
    };
    let positions = block(1).positions_for(&p);
    check_slices_across_thread_counts(&p, &positions, 5);
}

#[test]
fn slices_with_surface_tension_are_deterministic_across_thread_counts() {
    let p = SphParams {
        surface_tension: 0.072,
        // The walls' wetted stress too.
        contact_angle: 60.0,
        ..dfsph_fine()
    };
    let positions = block(1).positions_for(&p);
    check_slices_across_thread_counts(&p, &positions, 5);
}
