//! [`SphSystems::Prepare`](super::SphSystems::Prepare): the stability guard and the wall
//! particles, before the tick's sub-steps.

use super::components::{FluidParticle, Position, Velocity};
use super::resources::SphSolver;
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

/// Re-samples the tank's wall particles when the tank or the spacing changes.
pub(crate) fn rebuild_walls(mut solver: ResMut<SphSolver>) {
    if solver.walls_dirty {
        solver.step.rebuild_walls();
        solver.walls_dirty = false;
    }
}
