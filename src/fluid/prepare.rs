//! [`SphSystems::Prepare`](super::SphSystems::Prepare): the stability guard and the wall
//! particles, before the tick's sub-steps.

use super::components::{FluidParticle, Obstacle, Position, Velocity};
use super::params::MAX_WALL_PARTICLES;
use super::resources::SphSolver;
use crate::sim::boundary::Shape;
use bevy::prelude::*;

/// The stability guard, before each tick's sub-steps: despawns every particle whose position or
/// velocity is not finite, or that lies outside the tank by more than a spacing (a game's own
/// system put it there), with a warning naming the cause, and counts them in
/// [`SphStats`](super::SphStats), so one bad particle never reaches its neighbours' sums. The
/// solver itself never produces such a particle (it holds back an update that would), so this
/// changes nothing in a stable run.
pub(crate) fn guard_particles(
    mut commands: Commands,
    mut solver: ResMut<SphSolver>,
    particles: Query<(Entity, &Position, &Velocity), With<FluidParticle>>,
) {
    let c = *solver.constants();
    let (mut non_finite, mut escaped) = (0u64, 0u64);
    for (entity, position, velocity) in &particles {
        let cause = if !position.is_finite() || !velocity.is_finite() {
            non_finite += 1;
            "not finite"
        } else if c
            .tank
            .is_some_and(|tank| !tank.contains(position.0, c.spacing))
        {
            escaped += 1;
            "outside the tank"
        } else {
            continue;
        };
        if non_finite + escaped <= 3 {
            warn!(
                "fluid particle {entity} at position {} with velocity {}: {cause}, removed",
                position.0, velocity.0
            );
        }
        commands.entity(entity).despawn();
    }
    if non_finite + escaped > 3 {
        warn!(
            "{} more fluid particles removed this tick",
            non_finite + escaped - 3
        );
    }
    if non_finite + escaped > 0 {
        solver.removed_non_finite += non_finite;
        solver.removed_escaped += escaped;
    }
}

/// Re-samples the wall particles when the tank, spacing or obstacles change.
pub(crate) fn rebuild_walls(
    mut solver: ResMut<SphSolver>,
    obstacles: Query<&Obstacle>,
    changed: Query<(), Changed<Obstacle>>,
    mut removed: RemovedComponents<Obstacle>,
) {
    let removed_any = removed.read().count() > 0;
    if !(solver.walls_dirty || removed_any || !changed.is_empty()) {
        return;
    }
    let shapes: Vec<Shape> = obstacles.iter().map(|o| o.0).collect();
    let (spacing, layers) = {
        let c = solver.step.constants();
        (c.spacing, c.wall_layers)
    };
    for shape in &shapes {
        if !shape.is_valid() {
            warn!("ignoring obstacle {shape:?}: coordinates must be finite and radii positive");
        } else if !shape.fits(spacing, layers) {
            warn!(
                "ignoring obstacle {shape:?}: at {spacing} m spacing it needs {} boundary \
                 particles (limit {MAX_WALL_PARTICLES}); make it smaller or the spacing coarser",
                shape.sample_count(spacing, layers)
            );
        }
    }
    solver.step.rebuild_walls(&shapes);
    solver.walls_dirty = false;
}
