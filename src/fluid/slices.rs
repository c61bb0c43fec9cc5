//! The whole fluid solver on plain vectors, without the ECS: the reference the ECS path is
//! measured and tested against, and a way to run SPH outside Bevy. It calls the same functions in
//! [`solver`](super::solver), [`wcsph`](super::wcsph) and [`dfsph`](super::dfsph) as the systems
//! do, in the same order, and drives the same [`SubstepClock`], so for the same particles in the
//! same order both paths produce the same numbers bit for bit.
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin) for the ECS version.

use super::boundary::Obstacle;
use super::clock::SubstepClock;
use super::dfsph::{Dfsph, divergence_step};
use super::layout::{FluidSnapshot, NeighborList, Walls};
use super::parallel::Rayon;
use super::params::PressureSolver;
use super::solver::{
    SphConstants, advance_particle, density_and_neighbors_at, max_length, mean_neighbors,
    move_particle, with_kernels,
};
use super::wcsph::{acceleration_at, pressure_from_density, stable_time_step, wall_state_at};
use bevy::math::Vec2;
use rayon::prelude::*;

/// Smallest number of particles a rayon task takes (keeps scheduling overhead low).
const MIN_PARTICLES_PER_TASK: usize = 512;

/// Fluid particles as a structure of arrays, stepped with rayon on the caller's current pool
/// (on the calling thread without the `parallel` feature).
#[derive(Debug, Clone)]
pub struct SliceFluid {
    constants: SphConstants,
    /// Positions, m.
    pub position: Vec<Vec2>,
    /// Velocities, m/s.
    pub velocity: Vec<Vec2>,
    /// Accelerations of the last sub-step, m/s² (DFSPH: without pressure).
    pub acceleration: Vec<Vec2>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// Pressures, Pa.
    pub pressure: Vec<f32>,
    /// DFSPH stiffness `[κ, κᵛ]`, m²/s², carried to the next sub-step.
    pub stiffness: Vec<Vec2>,
    neighbors: Vec<NeighborList>,
    snapshot: FluidSnapshot,
    walls: Walls,
    dfsph: Dfsph,
    /// The sub-step clock: simulated time, sub-steps, dropped time.
    pub clock: SubstepClock,
    /// Solver iterations (both DFSPH solves) since the start.
    pub iterations: u64,
    /// Of those, the density solve's.
    pub density_iterations: u64,
}

impl SliceFluid {
    /// Fluid particles at rest at `positions`, in the tank of `constants` with `obstacles`.
    pub fn new(constants: SphConstants, positions: Vec<Vec2>, obstacles: &[Obstacle]) -> Self {
        let n = positions.len();
        let mut walls = Walls::default();
        walls.rebuild(&constants, obstacles);
        Self {
            constants,
            position: positions,
            velocity: vec![Vec2::ZERO; n],
            acceleration: vec![Vec2::ZERO; n],
            density: vec![constants.rest_density; n],
            pressure: vec![0.0; n],
            stiffness: vec![Vec2::ZERO; n],
            neighbors: vec![NeighborList::default(); n],
            snapshot: FluidSnapshot::default(),
            walls,
            dfsph: Dfsph::default(),
            clock: SubstepClock::default(),
            iterations: 0,
            density_iterations: 0,
        }
    }

    /// The constants it runs on.
    pub fn constants(&self) -> &SphConstants {
        &self.constants
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Advances by one tick of `tick` seconds in as many stable sub-steps as it needs (at most
    /// `max_substeps`); returns the number of sub-steps.
    pub fn advance(&mut self, tick: f64) -> u32 {
        self.clock.begin_tick(tick);
        while self.clock.wants_substep(self.constants.max_substeps) {
            self.substep(|clock, c, stable, empty| {
                clock.take_substep(stable, c.max_substeps, empty)
            });
        }
        self.clock.end_tick();
        self.clock.substeps
    }

    /// One sub-step of the largest stable length, outside any tick; returns it, s.
    pub fn step(&mut self) -> f32 {
        self.substep(|clock, _, stable, _| clock.take_free_substep(stable))
    }

    /// What the last DFSPH sub-step's solves did (iterations and remaining errors).
    pub fn dfsph_report(&self) -> &super::dfsph::DfsphReport {
        &self.dfsph.report
    }

    /// Mean number of particles (fluid and wall, the particle itself included) within the kernel
    /// support of each fluid particle, as of the last sub-step.
    pub fn mean_neighbors(&self) -> f64 {
        mean_neighbors(&self.constants, &self.snapshot, &self.walls)
    }

    /// One sub-step with the configured solver; `take` turns the stability limit into the step
    /// through the clock.
    fn substep(
        &mut self,
        take: impl FnOnce(&mut SubstepClock, &SphConstants, f32, bool) -> f32 + Send,
    ) -> f32 {
        crate::compute::current(|| {
            self.snapshot
                .rebuild(&self.constants, &self.position, &self.velocity, &Rayon);
            match self.constants.solver {
                PressureSolver::Wcsph => self.wcsph_substep(take),
                PressureSolver::Dfsph => self.dfsph_substep(take),
            }
        })
    }

    /// WCSPH: density and pressure, wall pressure, forces, integration.
    fn wcsph_substep(
        &mut self,
        take: impl FnOnce(&mut SubstepClock, &SphConstants, f32, bool) -> f32,
    ) -> f32 {
        let c = self.constants;
        with_kernels!(c.kernel, c.support, |w, g| {
            let (snapshot, walls) = (&self.snapshot, &self.walls);
            let slots = snapshot.grid().slot_of();
            (
                &mut self.density,
                &mut self.pressure,
                &mut self.neighbors,
                &self.position,
                slots,
            )
                .into_par_iter()
                .with_min_len(MIN_PARTICLES_PER_TASK)
                .for_each(|(rho, p, list, x, &slot)| {
                    *rho = density_and_neighbors_at(&w, &c, *x, snapshot, walls, list);
                    *p = pressure_from_density(&c, *rho);
                    snapshot.set_pressure(slot as usize, *rho, *p);
                });
            let fluid = &self.snapshot;
            self.walls.update_pressure(|states, points| {
                states
                    .par_iter_mut()
                    .enumerate()
                    .with_min_len(MIN_PARTICLES_PER_TASK)
                    .for_each(|(slot, s)| *s = wall_state_at(&w, &c, points.get(slot), fluid));
            });
            let walls = &self.walls;
            (
                &mut self.acceleration,
                &self.position,
                &self.velocity,
                &self.density,
                &self.pressure,
                &self.neighbors,
            )
                .into_par_iter()
                .with_min_len(MIN_PARTICLES_PER_TASK)
                .for_each(|(a, x, v, rho, p, list)| {
                    *a = acceleration_at(&g, &c, *x, *v, *rho, *p, list, fluid, walls);
                });
        });
        let max_acceleration = max_length(&self.acceleration);
        let stable = stable_time_step(&c, self.snapshot.max_speed, max_acceleration);
        self.clock.max_acceleration = max_acceleration;
        let dt = take(&mut self.clock, &c, stable, self.position.is_empty());
        let obstacles = &self.walls.obstacles;
        (&mut self.position, &mut self.velocity, &self.acceleration)
            .into_par_iter()
            .with_min_len(MIN_PARTICLES_PER_TASK)
            .for_each(|(x, v, a)| {
                advance_particle(&c, obstacles, x, v, *a, dt);
            });
        dt
    }

    /// DFSPH: neighbours, densities and factors, divergence solve, non-pressure forces, step,
    /// density solve, move.
    fn dfsph_substep(
        &mut self,
        take: impl FnOnce(&mut SubstepClock, &SphConstants, f32, bool) -> f32,
    ) -> f32 {
        let c = self.constants;
        let order = self.snapshot.grid().order();
        let stiffness = &self.stiffness;
        self.dfsph.prepare(
            &c,
            &self.snapshot,
            &self.walls,
            |slot| stiffness[order[slot] as usize],
            &Rayon,
        );
        let last_dt = divergence_step(&self.clock, &c, self.snapshot.max_speed);
        self.dfsph.solve_divergence(&c, last_dt, &Rayon);
        let (dfsph, snapshot) = (&self.dfsph, &self.snapshot);
        let slots = snapshot.grid().slot_of();
        (&mut self.acceleration, &mut self.velocity, slots)
            .into_par_iter()
            .with_min_len(MIN_PARTICLES_PER_TASK)
            .for_each(|(a, v, &slot)| {
                *v = dfsph.velocity(slot as usize);
                *a = dfsph.non_pressure_acceleration(&c, snapshot, slot as usize);
                dfsph.set_acceleration(slot as usize, *a);
            });
        let max_acceleration = max_length(&self.acceleration);
        let stable = self.dfsph.stable_time_step(&c, max_acceleration);
        self.clock.max_acceleration = max_acceleration;
        let dt = take(&mut self.clock, &c, stable, self.position.is_empty());
        let density_iterations = self.dfsph.solve_density(&c, dt, &Rayon) as u64;
        self.density_iterations += density_iterations;
        self.iterations += density_iterations;
        self.iterations += self.dfsph.report.divergence_iterations as u64;
        let (dfsph, obstacles) = (&self.dfsph, &self.walls.obstacles);
        (
            &mut self.position,
            &mut self.velocity,
            &mut self.density,
            &mut self.pressure,
            &mut self.stiffness,
            slots,
        )
            .into_par_iter()
            .with_min_len(MIN_PARTICLES_PER_TASK)
            .for_each(|(x, v, rho, p, k, &slot)| {
                let slot = slot as usize;
                *rho = dfsph.density(&c, slot);
                *p = dfsph.pressure(&c, slot);
                *k = dfsph.stiffness(slot);
                move_particle(&c, obstacles, x, v, dfsph.velocity(slot), dt);
            });
        dt
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::boundary::Tank;
    use crate::fluid::params::SphParams;
    use crate::fluid::spawn::FluidBlock;

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
            fluid.clock.dropped < 0.01,
            "{} s dropped",
            fluid.clock.dropped
        );
        assert!(width > 0.38, "spread over {width} m of the 0.4 m tank");
        assert!(
            (median / c.rest_density - 1.0).abs() < 0.05,
            "median density {median} kg/m³"
        );
    }
}
