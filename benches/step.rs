//! Criterion benchmarks of one solver sub-step: the same dam break on plain slices and through
//! the ECS, and the neighbour grid on its own. Throughput is in particle-steps.
//!
//! `cargo bench --bench step`; the headless `bench` example measures the 100,000-particle case.

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_sph2d::fluid::{SphParams, SphPlugin, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::slices::{NeighborGrid, SliceFluid};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::time::Duration;

const SPACING: f32 = 0.005;

fn dam_break(particles: usize, support_ratio: f32) -> (SphParams, FluidBlock) {
    let columns = ((particles as f32 / 2.0).sqrt().round() as usize).max(1);
    let rows = particles.div_ceil(columns);
    let column = Vec2::new(columns as f32, rows as f32) * SPACING;
    let params = SphParams {
        particle_spacing: SPACING,
        support_ratio,
        speed_of_sound: SphParams::speed_of_sound_for_height(column.y),
        tank: Some(Tank::new(4.0 * column.x, 1.25 * column.y)),
        max_substeps: 1,
        ..default()
    };
    (
        params,
        FluidBlock::dam_break(column.x + 1e-4, column.y + 1e-4),
    )
}

fn substep(c: &mut Criterion) {
    let mut group = c.benchmark_group("substep");
    for (particles, ratio) in [(20_000, 2.0), (20_000, 2.6)] {
        let (params, block) = dam_break(particles, ratio);
        let positions = block.positions_for(&params);
        let n = positions.len() as u64;
        group.throughput(Throughput::Elements(n));

        let mut fluid = SliceFluid::new(params.constants().unwrap(), positions);
        group.bench_function(format!("slices/{n}/R{ratio}"), |b| b.iter(|| fluid.step()));

        // One sub-step per update: max_substeps = 1 and a tick longer than a stable step. As
        // many compute threads as rayon uses for the slices.
        let threads = rayon::current_num_threads();
        let mut app = App::new();
        app.add_plugins((
            MinimalPlugins.set(bevy_sph2d::task_pool_plugin(threads)),
            SphPlugin::default().with_params(params),
        ))
        .insert_resource(Time::<Fixed>::from_duration(Duration::from_millis(100)))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
        block.spawn(app.world_mut());
        app.update();
        group.bench_function(format!("ecs/{n}/R{ratio}"), |b| b.iter(|| app.update()));
    }
    group.finish();
}

fn grid(c: &mut Criterion) {
    let (params, block) = dam_break(100_000, 2.0);
    let positions = block.positions_for(&params);
    let mut grid = NeighborGrid::new(params.support_radius());
    let mut group = c.benchmark_group("grid");
    group.throughput(Throughput::Elements(positions.len() as u64));
    group.bench_function("rebuild/100k", |b| b.iter(|| grid.rebuild(&positions)));
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(4));
    targets = substep, grid
}
criterion_main!(benches);
