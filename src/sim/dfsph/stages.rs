//! The divergence-free solver's part of the stages of a sub-step ([`step`](crate::sim::step)),
//! in the order of the module docs of [`dfsph`](super).

use super::{Dfsph, divergence_step};
use crate::sim::integrate::move_particle;
use crate::sim::parallel::{Parallel, for_each_slot};
use crate::sim::step::{ForcesWrite, Particles, PressureStages, Shared, for_each_particle};
use bevy::math::Vec2;

impl PressureStages for Dfsph {
    const FORCES_WRITE: ForcesWrite = ForcesWrite {
        pressure: false,
        velocity: true,
    };

    /// Step 1: caches neighbours and gradients, sums densities and factors (warm-started from
    /// each particle's stiffness).
    ///
    /// With the grid start, the grid's cells and equations are built beside it, from the
    /// positions.
    fn density(&mut self, s: &mut Shared, particles: &Particles, parallel: &impl Parallel) {
        let c = s.constants;
        let (order, stiffness) = (s.snapshot.grid().order(), &particles.stiffness);
        let (fluid, walls) = (&s.snapshot, &s.walls);
        let grid = c.dfsph.grid_start && !fluid.is_empty();
        self.prepare_with_grid(&c, (fluid, walls), grid, parallel, |dfsph| {
            dfsph.prepare(
                &c,
                fluid,
                walls,
                |slot| stiffness[order[slot] as usize],
                parallel,
            );
        });
    }

    /// Step 2: makes the velocity field divergence-free.
    fn correct_velocities(&mut self, s: &mut Shared, parallel: &impl Parallel) {
        let c = s.constants;
        let limits = c.with_largest_viscosity(s.snapshot.max_viscosity);
        let dt = divergence_step(&s.clock, &limits, s.snapshot.max_speed);
        let iterations = self.solve_divergence(&c, dt, parallel);
        s.iterations.divergence += iterations;
        s.iterations.total += iterations as u64;
    }

    /// Step 3, the solver's part: gravity and viscosity by sorted slot, then each particle's
    /// acceleration, divergence-free velocity and density.
    fn forces(&mut self, s: &mut Shared, particles: &mut Particles, parallel: &impl Parallel) {
        let c = s.constants;
        let n = self.len();
        s.accelerations.resize(n, Vec2::ZERO);
        let snapshot = &s.snapshot;
        let dfsph = &*self;
        for_each_slot(&mut s.accelerations, parallel, |slot, a| {
            *a = dfsph.non_pressure_acceleration(&c, snapshot, slot);
            0.0
        });
        dfsph.solid_forces(&c, snapshot, &mut s.walls);
        let (slot_of, accelerations) = (snapshot.grid().slot_of(), &s.accelerations);
        for_each_particle(particles, parallel, |i, p| {
            let slot = slot_of[i] as usize;
            *p.acceleration = accelerations[slot];
            *p.velocity = dfsph.velocity(slot);
            *p.density = dfsph.density(&c, slot);
            0
        });
    }

    fn step_limit(&self, s: &Shared, max_acceleration: f32) -> f32 {
        let limits = (s.constants).with_largest_viscosity(s.snapshot.max_viscosity);
        self.stable_time_step(&limits, max_acceleration)
    }

    /// Step 4, its start: the velocities predicted under every particle's acceleration
    /// (external forces included).
    fn start_pressure(
        &mut self,
        s: &mut Shared,
        particles: &Particles,
        dt: f32,
        _parallel: &impl Parallel,
    ) {
        let (order, acceleration) = (s.snapshot.grid().order(), &particles.acceleration);
        self.predicted_acceleration = self.predict(dt, |slot| acceleration[order[slot] as usize]);
    }

    /// Step 4, its start from the grid pressure, if the settings ask for it.
    fn grid_pressure(&mut self, s: &mut Shared, dt: f32, parallel: &impl Parallel) {
        let c = s.constants;
        self.report.grid_iterations = 0;
        if c.dfsph.grid_start && !self.is_empty() && dt > 0.0 {
            let first_of_tick = s.clock.substeps == 1;
            let grid = self.start_from_grid(&c, (dt, first_of_tick), parallel);
            self.report.grid_iterations = grid.iterations;
        }
    }

    /// Step 4: the density solve from that start.
    fn solve_pressure(
        &mut self,
        s: &mut Shared,
        _particles: &Particles,
        dt: f32,
        parallel: &impl Parallel,
    ) {
        let c = s.constants;
        let most = self.predicted_acceleration;
        let iterations = self.solve_density(&c, dt, most, parallel);
        s.iterations.density += iterations;
        s.iterations.total += iterations as u64;
        s.iterations.total_density += iterations as u64;
    }

    /// Step 5: each particle moves with its solved velocity and keeps its pressure and
    /// stiffness (its density is the force stage's).
    fn integrate(
        &mut self,
        s: &mut Shared,
        particles: &mut Particles,
        dt: f32,
        parallel: &impl Parallel,
    ) -> u64 {
        let c = s.constants;
        let slot_of = s.snapshot.grid().slot_of();
        let (dfsph, walls) = (&*self, &s.walls);
        // The densities were written in the force stage and the solve leaves them as they are.
        for_each_particle(particles, parallel, |i, p| {
            let slot = slot_of[i] as usize;
            *p.pressure = dfsph.pressure(&c, slot);
            *p.stiffness = dfsph.stiffness(slot);
            let solved = dfsph.velocity(slot);
            u64::from(!move_particle(
                &c, walls, p.position, p.velocity, solved, dt,
            ))
        })
    }

    /// Minus what the solids' boundary particles did to the fluid this sub-step.
    fn solid_impulses(&mut self, s: &mut Shared, dt: f32) {
        let c = s.constants;
        Dfsph::solid_impulses(self, &c, &s.snapshot, &mut s.walls, dt);
    }
}
