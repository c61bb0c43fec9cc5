//! The fluid's statistics, at the end of the tick ([`SphSystems::Finish`](super::SphSystems::Finish)).

use super::components::{Density, FluidParticle, Velocity};
use super::liquids::FluidMaterial;
use super::resources::{SphSolver, SphStats};
use bevy::prelude::*;

/// Fills [`SphStats`] after the tick.
pub(crate) fn update_stats(
    solver: Res<SphSolver>,
    particles: Query<(&Velocity, &Density, Option<&FluidMaterial>), With<FluidParticle>>,
    mut stats: ResMut<SphStats>,
) {
    let c = solver.constants();
    let mut count = 0usize;
    let mut max_speed_sq = 0.0f32;
    let mut max_error = 0.0f32;
    let mut sum_error = 0.0f64;
    for (velocity, density, material) in &particles {
        count += 1;
        max_speed_sq = max_speed_sq.max(velocity.length_squared());
        // Against the particle's own liquid's rest density.
        let ratio = super::driver::liquid_of(&solver.liquids, material).ratio;
        let error = (density.0 / (ratio * c.rest_density) - 1.0).max(0.0);
        max_error = max_error.max(error);
        sum_error += error as f64;
    }
    let shared = &solver.step.shared;
    let (clock, iterations) = (shared.clock, shared.iterations);
    *stats = SphStats {
        particles: count,
        wall_particles: shared.walls.len(),
        substeps: clock.substeps,
        total_substeps: clock.total_substeps,
        dt: clock.dt,
        time: clock.time,
        dropped_time: clock.dropped,
        tick_ms: stats.tick_ms,
        max_speed: max_speed_sq.sqrt(),
        max_density_error: 100.0 * max_error,
        mean_density_error: if count > 0 {
            (100.0 * sum_error / count as f64) as f32
        } else {
            0.0
        },
        non_finite_resets: shared.non_finite,
        removed_non_finite: solver.removed_non_finite,
        removed_escaped: solver.removed_escaped,
        slow_motion: clock.dropped > stats.dropped_time,
        solver: c.solver,
        density_iterations: iterations.density,
        divergence_iterations: iterations.divergence,
        total_iterations: iterations.total,
        solver_density_error: 100.0 * solver.dfsph_report().density_error,
    };
}
