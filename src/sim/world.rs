//! The whole fluid on plain vectors, without the ECS: the plain-vector driver of the one
//! sub-step order in [`step`](super::step). The benchmarks and tests run it, the ECS driver is
//! measured and tested against it, and it runs SPH outside Bevy. For the same particles in the
//! same order both drivers produce the same numbers bit for bit.

use super::boundary::Shape;
use super::clock::SubstepClock;
use super::config::SphConstants;
use super::dfsph::DfsphReport;
use super::parallel::{Rayon, current};
use super::solid::{MovingSolid, SolidMotion};
use super::step::{FluidStep, Particles, SolverIterations, StepLength};
use bevy::math::Vec2;
use core::ops::{Deref, DerefMut};

/// Fluid particles as a structure of arrays ([`Particles`], which it dereferences to), stepped
/// with rayon on the caller's current pool (on the calling thread without the `parallel`
/// feature).
#[derive(Debug, Clone)]
pub struct SliceFluid {
    particles: Particles,
    step: FluidStep,
}

impl Deref for SliceFluid {
    type Target = Particles;

    fn deref(&self) -> &Particles {
        &self.particles
    }
}

impl DerefMut for SliceFluid {
    fn deref_mut(&mut self) -> &mut Particles {
        &mut self.particles
    }
}

impl SliceFluid {
    /// Fluid particles at rest at `positions`, in the tank of `constants` with solids of
    /// `shapes`.
    pub fn new(constants: SphConstants, positions: Vec<Vec2>, shapes: &[Shape]) -> Self {
        let mut step = FluidStep::new(constants);
        step.rebuild_walls(shapes);
        Self {
            particles: Particles::at_rest(positions, constants.rest_density),
            step,
        }
    }

    /// The constants it runs on.
    pub fn constants(&self) -> &SphConstants {
        self.step.constants()
    }

    /// The sub-step clock: simulated time, sub-steps, dropped time.
    pub fn clock(&self) -> &SubstepClock {
        &self.step.shared.clock
    }

    /// Pressure-solve iterations since the start.
    pub fn iterations(&self) -> &SolverIterations {
        &self.step.shared.iterations
    }

    /// Particle updates held back because they would not have been finite.
    pub fn non_finite(&self) -> u64 {
        self.step.shared.non_finite
    }

    /// Advances by one tick of `tick` seconds in as many stable sub-steps as it needs (at most
    /// `max_substeps`); returns the number of sub-steps.
    pub fn advance(&mut self, tick: f64) -> u32 {
        self.step.begin_tick(tick);
        while self.step.wants_substep() {
            self.substep(StepLength::InTick);
        }
        self.step.end_tick();
        self.step.shared.clock.substeps
    }

    /// One sub-step of the largest stable length, outside any tick; returns it, s.
    pub fn step(&mut self) -> f32 {
        self.substep(StepLength::Free)
    }

    /// What the last DFSPH sub-step's solves did (iterations and remaining errors); the
    /// default report under WCSPH.
    pub fn dfsph_report(&self) -> DfsphReport {
        self.step.dfsph().map(|d| d.report).unwrap_or_default()
    }

    /// Mean number of particles (fluid and wall, the particle itself included) within the kernel
    /// support of each fluid particle, as of the last sub-step.
    pub fn mean_neighbors(&self) -> f64 {
        self.step.mean_neighbors()
    }

    /// The solids in the fluid.
    pub fn solids(&self) -> &[MovingSolid] {
        self.step.solids()
    }

    /// The solids, to add, remove or re-sample; set a solid's pose and velocities with
    /// [`MovingSolid::set_motion`] before a step.
    pub fn solids_mut(&mut self) -> &mut Vec<MovingSolid> {
        self.step.solids_mut()
    }

    /// Sets solid `k`'s pose and velocities for the next tick; `false` if they are not finite
    /// or there is no such solid.
    pub fn set_solid_motion(&mut self, k: usize, motion: SolidMotion) -> bool {
        self.step.set_solid_motion(k, motion)
    }

    fn substep(&mut self, length: StepLength) -> f32 {
        let (step, particles) = (&mut self.step, &mut self.particles);
        current(|| step.substep(particles, length, &Rayon))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::SphParams;
    use crate::gameplay::FluidBlock;
    use crate::sim::boundary::Tank;
    use crate::sim::density::max_length;

    /// A block spawned at twice the lattice density along each axis (four times the rest
    /// density) pushes itself apart quickly but finitely and fills its tank at rest density
    /// (before the relief cap, every update of such a block was held back as non-finite).
    #[test]
    fn an_overpacked_block_expands_finitely() {
        let params = SphParams {
            particle_spacing: 0.005,
            tank: Some(Tank::new(0.4, 0.3)),
            ..SphParams::water()
        };
        let c = params.constants().unwrap();
        let positions =
            FluidBlock::new(Vec2::new(0.15, 0.0), Vec2::new(0.1, 0.1875)).positions(0.0025);
        assert_eq!(positions.len(), 40 * 75);
        let mut fluid = SliceFluid::new(c, positions, &[]);
        let mut fastest = 0.0f32;
        for _ in 0..96 {
            fluid.advance(1.0 / 64.0);
            assert!(fluid.position.iter().all(|p| p.is_finite()));
            fastest = fastest.max(max_length(&fluid.velocity));
        }
        let mut density = fluid.density.clone();
        density.sort_by(f32::total_cmp);
        let median = density[density.len() / 2];
        let width = fluid.position.iter().map(|p| p.x).fold(0.0, f32::max)
            - fluid.position.iter().map(|p| p.x).fold(1.0, f32::min);
        assert!(fastest < 5.0, "fastest particle {fastest} m/s");
        assert!(
            fluid.clock().dropped < 0.01,
            "{} s dropped",
            fluid.clock().dropped
        );
        assert!(width > 0.38, "spread over {width} m of the 0.4 m tank");
        assert!(
            (median / c.rest_density - 1.0).abs() < 0.05,
            "median density {median} kg/m³"
        );
    }
}
