//! The whole fluid on plain vectors, without the ECS: the plain-vector driver of the one
//! sub-step order in [`step`](super::step). The benchmarks and tests run it, the ECS driver is
//! measured and tested against it, and it runs SPH outside Bevy. For the same particles in the
//! same order both drivers produce the same numbers bit for bit.

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
    /// Fluid particles at rest at `positions`, in the tank of `constants` (add solids with
    /// [`solids_mut`](Self::solids_mut)).
    pub fn new(constants: SphConstants, positions: Vec<Vec2>) -> Self {
        let mut step = FluidStep::new(constants);
        step.rebuild_walls();
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

    /// What 96 ticks (1.5 s) of a block of 3,000 particles at `lattice` (m) in a 0.4 × 0.3 m
    /// tank left: the fluid, the sub-steps of the last 32 ticks and the fastest particle, m/s.
    fn block_run(params: SphParams, at: Vec2, size: Vec2, lattice: f32) -> (SliceFluid, u32, f32) {
        let c = params.constants().unwrap();
        let positions = FluidBlock::new(at, size).positions(lattice);
        let mut fluid = SliceFluid::new(c, positions);
        let (mut fastest, mut substeps) = (0.0f32, 0);
        for tick in 0..96 {
            let taken = fluid.advance(1.0 / 64.0);
            assert!(fluid.position.iter().all(|p| p.is_finite()));
            fastest = fastest.max(max_length(&fluid.velocity));
            if tick >= 64 {
                substeps += taken;
            }
        }
        (fluid, substeps, fastest)
    }

    /// A block spawned at twice the lattice density along each axis (four times the rest
    /// density) pushes itself apart quickly but finitely and fills its tank at rest density
    /// (before the relief cap, every update of such a block was held back as non-finite), with
    /// the default solve and the strict one; once spread, it costs what the same particles
    /// spawned at rest cost: as many neighbours, as many sub-steps. (Before the walls mirrored
    /// the particles' density, a fifth of the particles stayed pressed into the floor in clumps
    /// of up to 48 times the rest density, and a sub-step took 2.5 to 4 times a calm one.)
    #[test]
    fn an_overpacked_block_expands_finitely() {
        let tank = Some(Tank::new(0.4, 0.3));
        let (calm, calm_substeps, _) = block_run(
            SphParams {
                particle_spacing: 0.005,
                tank,
                ..SphParams::water()
            },
            Vec2::ZERO,
            Vec2::new(0.4, 0.1875),
            0.005,
        );
        for (label, params) in [
            ("default", SphParams::water()),
            ("strict", SphParams::reference()),
        ] {
            let params = SphParams {
                particle_spacing: 0.005,
                tank,
                ..params
            };
            let at = Vec2::new(0.15, 0.0);
            let (fluid, substeps, fastest) = block_run(params, at, Vec2::new(0.1, 0.1875), 0.0025);
            assert_eq!(fluid.position.len(), 40 * 75);
            let rest = fluid.constants().rest_density;
            let densest = fluid.density.iter().copied().fold(0.0, f32::max);
            let width = fluid.position.iter().map(|p| p.x).fold(0.0, f32::max)
                - fluid.position.iter().map(|p| p.x).fold(1.0, f32::min);
            let mut density = fluid.density.clone();
            density.sort_by(f32::total_cmp);
            let median = density[density.len() / 2];
            let neighbours = fluid.mean_neighbors() / calm.mean_neighbors();
            eprintln!(
                "{label}: fastest {fastest} m/s, densest {densest} kg/m³, neighbours {neighbours}x calm, sub-steps {substeps} against {calm_substeps}"
            );
            // The run-up of the spreading block on the left wall at 0.13 s: 4.6-5.1 m/s (a block
            // asked to expand in one step flies apart at 3Δx/dt, 15 m/s and more).
            assert!(fastest < 6.0, "{label}: fastest particle {fastest} m/s");
            let dropped = fluid.clock().dropped;
            assert!(dropped < 0.01, "{label}: {dropped} s dropped");
            assert!(
                width > 0.38,
                "{label}: spread over {width} m of the 0.4 m tank"
            );
            assert!(
                (median / rest - 1.0).abs() < 0.05,
                "{label}: median density {median} kg/m³"
            );
            assert!(
                densest < 1.05 * rest,
                "{label}: densest particle {densest} kg/m³"
            );
            assert!(
                (neighbours - 1.0).abs() < 0.1,
                "{label}: {neighbours} times the calm neighbours"
            );
            assert!(
                substeps as f32 <= 1.25 * calm_substeps as f32,
                "{label}: {substeps} sub-steps in the last half second, {calm_substeps} calm"
            );
        }
    }

    /// A game that over-pours does not freeze: 12,000 particles spawned at four times the rest
    /// density (a 1.25 mm lattice at 2.5 mm spacing) spread over their tank with the default
    /// solve at the cost of the same particles spawned at rest: no tick near the cap of 400
    /// sub-steps, a sub-step's neighbours within 1.5 times the calm block's on average, and the
    /// sub-steps of the 1.75 s within 1.5 times. Before the push held the kernel's peak slope
    /// (`RadialKernel::push_slope`), pairs of particles met at the floor and formed clumps of 6
    /// to 8 at one point with no pressure, and from the 45th tick the step fell to the cap at
    /// 47 m/s (measured: 79-400 sub-steps a tick); now 8-52 a tick, and the clumps part within
    /// 1.5 s.
    #[test]
    fn an_over_poured_block_of_12000_particles_does_not_freeze() {
        let params = SphParams {
            particle_spacing: 0.0025,
            tank: Some(Tank::new(0.4, 0.3)),
            ..SphParams::water()
        };
        let c = params.constants().unwrap();
        let block =
            |at, width, lattice| FluidBlock::new(at, Vec2::new(width, 0.1875)).positions(lattice);
        let mut calm = SliceFluid::new(c, block(Vec2::ZERO, 0.4, 0.0025));
        let calm_substeps = (0..32).map(|_| calm.advance(1.0 / 64.0)).sum::<u32>() as f32 / 32.0;
        let calm_neighbours = calm.mean_neighbors();
        let mut fluid = SliceFluid::new(c, block(Vec2::new(0.15, 0.0), 0.1, 0.00125));
        assert_eq!(fluid.position.len(), 12_000);
        let (mut substeps, mut neighbours, mut busiest) = (0u32, 0.0, 0u32);
        for tick in 0..112 {
            let taken = fluid.advance(1.0 / 64.0);
            let fastest = max_length(&fluid.velocity);
            assert!(
                fastest < 6.0 && fluid.position.iter().all(|p| p.is_finite()),
                "tick {tick}: fastest particle {fastest} m/s"
            );
            substeps += taken;
            busiest = busiest.max(taken);
            neighbours += f64::from(taken) * fluid.mean_neighbors();
        }
        let neighbours = neighbours / f64::from(substeps) / calm_neighbours;
        let ratio = substeps as f32 / (112.0 * calm_substeps);
        let rest = c.rest_density;
        let densest = fluid.density.iter().copied().fold(0.0, f32::max) / rest;
        eprintln!(
            "over-pour: {substeps} sub-steps ({ratio}x calm, at most {busiest} a tick), {neighbours}x the calm neighbours, densest {densest}x rest"
        );
        assert!(busiest <= 64, "{busiest} sub-steps in one tick");
        assert!(ratio <= 1.5, "{ratio} times the calm block's sub-steps");
        assert!(neighbours <= 1.5, "{neighbours} times the calm neighbours");
        assert!(
            densest < 1.05,
            "densest particle at {densest} times the rest density"
        );
    }
}
