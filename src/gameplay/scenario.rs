//! Ready-made starting states (dam break, double dam break, a drop into a pool, a resting tank)
//! that [`ResetSimulation`] respawns. See
//! [`SphPlugin`](crate::fluid::SphPlugin).

use super::sources::{EmitterRate, FluidDrain, FluidEmitter};
use super::spawn::FluidBlock;
use crate::control::ResetSimulation;
use crate::fluid::FluidParticle;
use crate::fluid::SphParams;
use crate::sim::boundary::Tank;
use crate::sim::region::FluidRegion;
use bevy::prelude::*;

/// Which starting state a [`SphScenario`] spawns.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[reflect(Debug, Default, PartialEq)]
pub enum ScenarioKind {
    /// A column of water against the left wall, 0.3 of the tank wide and 0.6 high.
    #[default]
    DamBreak,
    /// Two columns, one against each side wall, that meet in the middle.
    DoubleDamBreak,
    /// A square block falling into a pool a quarter of the tank deep.
    DropIntoPool,
    /// A resting layer 0.4 of the tank deep, to tilt and stir.
    Tank,
    /// A pool a quarter of the tank deep fed by a nozzle high on the left wall, with an overflow
    /// drain at the right wall that keeps its level ([`FluidEmitter`], [`FluidDrain`]).
    Fountain,
    /// No fluid (for scenes of gravity bodies alone).
    Empty,
}

impl ScenarioKind {
    /// Every kind, in menu order.
    pub const ALL: [ScenarioKind; 6] = [
        ScenarioKind::DamBreak,
        ScenarioKind::DoubleDamBreak,
        ScenarioKind::DropIntoPool,
        ScenarioKind::Tank,
        ScenarioKind::Fountain,
        ScenarioKind::Empty,
    ];

    /// A human-readable name.
    pub fn label(self) -> &'static str {
        match self {
            ScenarioKind::DamBreak => "Dam break",
            ScenarioKind::DoubleDamBreak => "Double dam break",
            ScenarioKind::DropIntoPool => "Drop into a pool",
            ScenarioKind::Tank => "Tank",
            ScenarioKind::Fountain => "Fountain",
            ScenarioKind::Empty => "No fluid",
        }
    }
}

/// The scenario that [`ResetSimulation`] respawns: its kind and about how many particles.
///
/// The fluid blocks are laid out in fractions of [`SphParams::tank`], and the particle spacing is
/// chosen so that they hold about `particles` particles; a reset writes that spacing into
/// [`SphParams`].
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Default, Debug, PartialEq)]
pub struct SphScenario {
    /// The starting state.
    pub kind: ScenarioKind,
    /// About how many particles to spawn (at least 16).
    pub particles: u32,
    /// Seed of the lattice jitter.
    pub seed: u64,
}

impl Default for SphScenario {
    fn default() -> Self {
        Self {
            kind: ScenarioKind::DamBreak,
            particles: 3000,
            seed: 0,
        }
    }
}

/// Tank used by scenarios when the parameters have none, m.
pub const SCENARIO_TANK: Tank = Tank {
    width: 1.6,
    height: 0.9,
};

impl SphScenario {
    /// A scenario of `kind` with about `particles` particles.
    pub fn new(kind: ScenarioKind, particles: u32) -> Self {
        Self {
            kind,
            particles,
            seed: 0,
        }
    }

    /// The fluid blocks in `tank`, before the spacing is known.
    pub fn blocks(&self, tank: &Tank) -> Vec<FluidBlock> {
        let (w, h) = (tank.width, tank.height);
        let block = |x: f32, y: f32, width: f32, height: f32| {
            FluidBlock::new(Vec2::new(x * w, y * h), Vec2::new(width * w, height * h))
        };
        let blocks = match self.kind {
            ScenarioKind::DamBreak => vec![block(0.0, 0.0, 0.3, 0.6)],
            ScenarioKind::DoubleDamBreak => {
                vec![block(0.0, 0.0, 0.2, 0.6), block(0.8, 0.0, 0.2, 0.6)]
            }
            ScenarioKind::DropIntoPool => {
                let side = 0.3 * h.min(w);
                vec![
                    block(0.0, 0.0, 1.0, 0.25),
                    FluidBlock::new(
                        Vec2::new(0.5 * w - 0.5 * side, 0.85 * h - side),
                        Vec2::splat(side),
                    )
                    .with_hydrostatic(false),
                ]
            }
            ScenarioKind::Tank => vec![block(0.0, 0.0, 1.0, 0.4)],
            ScenarioKind::Fountain => vec![block(0.0, 0.0, 1.0, 0.25)],
            ScenarioKind::Empty => Vec::new(),
        };
        blocks
            .into_iter()
            .enumerate()
            .map(|(i, b)| b.with_seed(self.seed.wrapping_add(i as u64)))
            .collect()
    }

    /// The emitters (with their nozzle positions) and drains of the scenario in `tank`.
    pub fn sources(&self, tank: &Tank) -> (Vec<(FluidEmitter, Vec2)>, Vec<FluidDrain>) {
        let (w, h) = (tank.width, tank.height);
        match self.kind {
            ScenarioKind::Fountain => (
                vec![(
                    // A nearly full jet: 80% of what the nozzle passes at its speed.
                    FluidEmitter::new(
                        0.03 * h,
                        Vec2::new(1.0, 0.35),
                        1.6,
                        EmitterRate::Volume(0.8 * 0.03 * h * 1.6),
                    ),
                    Vec2::new(0.04 * w, 0.6 * h),
                )],
                // An overflow just above the pool's level at the right wall.
                vec![FluidDrain::new(FluidRegion::Box {
                    min: Vec2::new(0.92 * w, 0.27 * h),
                    max: Vec2::new(w, 0.4 * h),
                })],
            ),
            _ => (Vec::new(), Vec::new()),
        }
    }

    /// The spacing (m) at which the blocks in `tank` hold about [`particles`](Self::particles).
    pub fn spacing(&self, tank: &Tank) -> f32 {
        let area: f32 = self.blocks(tank).iter().map(|b| b.size.x * b.size.y).sum();
        if area <= 0.0 {
            return tank.width.min(tank.height) / 50.0;
        }
        (area / self.particles.max(16) as f32).sqrt()
    }

    /// The tank the scenario fills: the parameters' tank, or [`SCENARIO_TANK`].
    pub fn tank(params: &SphParams) -> Tank {
        params.tank.unwrap_or(SCENARIO_TANK)
    }
}

/// Marks the emitters and drains a scenario spawned: the next reset removes them.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Default, Debug)]
pub struct ScenarioSource;

/// What a reset removes: fluid particles and the scenario's sources.
type ScenarioOwned = Or<(With<FluidParticle>, With<ScenarioSource>)>;

/// Despawns every fluid particle (and the scenario's own emitters and drains) and spawns the
/// [`SphScenario`] anew, at the spacing that gives its particle count, when a
/// [`ResetSimulation`] arrives.
pub(crate) fn reset_scenario(
    mut resets: MessageReader<ResetSimulation>,
    scenario: Option<Res<SphScenario>>,
    mut params: ResMut<SphParams>,
    particles: Query<Entity, ScenarioOwned>,
    mut commands: Commands,
) {
    if resets.read().count() == 0 {
        return;
    }
    let Some(scenario) = scenario else {
        warn!("ResetSimulation: there is no SphScenario resource to respawn; nothing reset");
        return;
    };
    for entity in &particles {
        commands.entity(entity).despawn();
    }
    if scenario.kind == ScenarioKind::Empty {
        return;
    }
    let tank = SphScenario::tank(&params);
    let spacing = scenario.spacing(&tank);
    let mut candidate = params.clone();
    candidate.tank = Some(tank);
    candidate.particle_spacing = spacing;
    if let Err(error) = candidate.validate() {
        error!("ResetSimulation: {error}; respawning at the current spacing instead");
    } else if *params != candidate {
        *params = candidate;
    }
    for block in scenario.blocks(&tank) {
        commands.queue(block);
    }
    let (emitters, drains) = scenario.sources(&tank);
    for (emitter, at) in emitters {
        commands.spawn((
            emitter,
            Transform::from_translation(at.extend(0.0)),
            ScenarioSource,
        ));
    }
    for drain in drains {
        commands.spawn((drain, ScenarioSource));
    }
    commands.queue(|world: &mut World| {
        world
            .resource_mut::<crate::fluid::SphSolver>()
            .restart_clock()
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_gives_the_particle_count() {
        let tank = SCENARIO_TANK;
        for kind in ScenarioKind::ALL
            .into_iter()
            .filter(|k| *k != ScenarioKind::Empty)
        {
            let scenario = SphScenario::new(kind, 3000);
            let spacing = scenario.spacing(&tank);
            let count: usize = scenario
                .blocks(&tank)
                .iter()
                .map(|b| b.positions(spacing).len())
                .sum();
            assert!(
                (2700..=3300).contains(&count),
                "{kind:?}: {count} particles at {spacing} m"
            );
            for block in scenario.blocks(&tank) {
                let max = block.min + block.size;
                assert!(
                    block.min.cmpge(Vec2::ZERO).all() && max.x <= 1.6 + 1e-5 && max.y <= 0.9 + 1e-5
                );
            }
        }
    }
}
