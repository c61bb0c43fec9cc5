//! The whole fluid solver on plain vectors, without the ECS: the reference the ECS path is
//! measured and tested against, and a way to run SPH outside Bevy. It calls the same functions in
//! [`solver`](super::solver) as the systems do, in the same order, so for the same particles in
//! the same order both paths produce the same numbers bit for bit.
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin) for the ECS version.

use super::boundary::Obstacle;
use super::parallel::Rayon;
use super::solver::{
    FluidSnapshot, NeighborList, SphConstants, Walls, acceleration_at, advance_particle,
    density_and_neighbors_at, mean_neighbors, plan_substep, pressure_from_density,
    stable_time_step, wall_state_at, with_kernels,
};
use bevy::math::Vec2;
use rayon::prelude::*;

/// Smallest number of particles a rayon task takes (keeps scheduling overhead low).
const MIN_PARTICLES_PER_TASK: usize = 512;

/// Fluid particles as a structure of arrays, stepped with rayon.
#[derive(Debug, Clone)]
pub struct SliceFluid {
    constants: SphConstants,
    /// Positions, m.
    pub position: Vec<Vec2>,
    /// Velocities, m/s.
    pub velocity: Vec<Vec2>,
    /// Accelerations of the last sub-step, m/s².
    pub acceleration: Vec<Vec2>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// Pressures, Pa.
    pub pressure: Vec<f32>,
    neighbors: Vec<NeighborList>,
    snapshot: FluidSnapshot,
    walls: Walls,
    /// Simulated time, s.
    pub time: f64,
    /// Sub-steps taken so far.
    pub substeps: u64,
    /// Simulated time dropped because a tick needed more than `max_substeps`, s.
    pub dropped_time: f64,
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
            neighbors: vec![NeighborList::default(); n],
            snapshot: FluidSnapshot::default(),
            walls,
            time: 0.0,
            substeps: 0,
            dropped_time: 0.0,
        }
    }

    /// The constants it runs on.
    pub fn constants(&self) -> &SphConstants {
        &self.constants
    }

    /// The cell-sorted snapshot of the last sub-step.
    pub fn snapshot(&self) -> &FluidSnapshot {
        &self.snapshot
    }

    /// The wall particles.
    pub fn walls(&self) -> &Walls {
        &self.walls
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
        let mut remaining = tick;
        let mut steps = 0;
        while remaining > 1e-9 * tick && steps < self.constants.max_substeps {
            let last = steps + 1 == self.constants.max_substeps;
            let dt = self.substep(remaining, last);
            remaining -= dt as f64;
            steps += 1;
        }
        if remaining > 1e-9 * tick {
            self.dropped_time += remaining;
        }
        steps
    }

    /// One sub-step of the largest stable length; returns it, s.
    pub fn step(&mut self) -> f32 {
        self.substep(f64::INFINITY, true)
    }

    /// Mean number of particles (fluid and wall, the particle itself included) within the kernel
    /// support of each fluid particle, as of the last sub-step.
    pub fn mean_neighbors(&self) -> f64 {
        mean_neighbors(&self.constants, &self.snapshot, &self.walls)
    }

    /// One sub-step: neighbours, density and pressure, wall pressure, forces, integration.
    /// Takes the largest stable step that divides `remaining` evenly (or just the largest
    /// stable step if `last`), and returns it, s.
    pub fn substep(&mut self, remaining: f64, last: bool) -> f32 {
        let c = self.constants;
        self.snapshot
            .rebuild(&c, &self.position, &self.velocity, &Rayon);
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
        let max_acceleration = self
            .acceleration
            .iter()
            .fold(0.0f32, |m, a| m.max(a.length_squared()))
            .sqrt();
        let stable = stable_time_step(&c, self.snapshot.max_speed, max_acceleration);
        let dt = if self.position.is_empty() {
            remaining.min(f32::MAX as f64) as f32
        } else if last {
            stable.min(remaining as f32)
        } else {
            plan_substep(remaining, stable)
        };
        let obstacles = &self.walls.obstacles;
        (&mut self.position, &mut self.velocity, &self.acceleration)
            .into_par_iter()
            .with_min_len(MIN_PARTICLES_PER_TASK)
            .for_each(|(x, v, a)| {
                advance_particle(&c, obstacles, x, v, *a, dt);
            });
        self.time += dt as f64;
        self.substeps += 1;
        dt
    }
}
