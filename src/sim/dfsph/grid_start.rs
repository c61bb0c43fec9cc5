//! The density solve's start from a coarse grid ([`DfsphSettings::grid_start`]): the pressure
//! that makes the predicted velocities divergence-free on a grid under the particles
//! ([`grid_pressure`](crate::sim::grid_pressure)), read back at each particle as its starting
//! stiffness `κ = p/ρ₀`, plus most of what the warm start had above it. The grid carries the
//! smooth, fluid-wide part of the pressure (a column's weight), which the local iterations remove
//! slowest; the iterations that follow correct what the grid cannot see (under two cells, near
//! the surface and in splashes).
//!
//! [`DfsphSettings::grid_start`]: crate::sim::config::DfsphSettings::grid_start

use super::Dfsph;
use crate::sim::config::SphConstants;
use crate::sim::grid_pressure::{GridInput, GridPressure, GridPressureSettings, GridReport};
use crate::sim::layout::{FluidSnapshot, Walls};
use crate::sim::parallel::{Parallel, Sequential, for_each_slot};
use bevy::math::Vec2;

/// The grid's solve: cells of two spacings, solved until the largest residual is a
/// thousandth of the largest divergence (the iterations after it correct the rest; measured on
/// the demo's surge and the resting layers, a ten-thousandth gained nothing but a V-cycle).
const SETTINGS: GridPressureSettings = GridPressureSettings {
    cell_ratio: 2.0,
    tolerance: 1e-3,
    max_iterations: 50,
};

/// The most compressed a particle may be (its density over the rest density) to start from
/// the grid's pressure. The grid carries the smooth pressure of water near its rest density; a
/// particle compressed further (spawned too densely, pressed into a clump at a wall) has an
/// error of its own that the iterations remove, and the grid's pressure on top of it threw
/// particles of a block spawned at four times the rest density out of the water at the speed
/// limit. Measured: at 1.05 and 1.2 a crate dropped into the water from half a metre lost the
/// grid's push where it hit and rode low, still rocking at 0.09-0.2 m/s after four seconds;
/// at 1.5 it floats at its draft, and the block stays under 5 m/s.
const MAX_START_DENSITY: f32 = 1.5;

/// The share of the warm start's excess over the grid's pressure a particle starts from: its
/// starting stiffness is the grid's plus this much of what the last sub-step's stiffness (the
/// warm start) had above it, so a peak the grid cannot resolve (an impact under two cells) is
/// kept for the iterations to refine, and an excess nothing renews fades, by a tenth a sub-step.
/// Measured (4 + 1 iterations, release): with the whole excess kept (the larger of the two), a
/// resting layer 1.5 m deep at 1 cm spacing blew up after 0.6 s, 1 m deep at 1 cm after
/// 0.8–2.2 s (the floor's second row swayed sideways, growing about twofold a tick); the excess
/// the iterations left at one sub-step came back at the next and grew. At 0.9 every layer tried
/// (0.2 m at 2 mm to 2 m at 1 cm and at 2 cm) rests for 8 s (1 m and 1.5 m at 1 cm for 20 s)
/// with no particle faster than 0.3% of `√(gD)`, and the demo's surge keeps 99% of its
/// particles within 1.05% of the rest density (1.15% with the whole excess kept, 1.05% at 0.8,
/// 1.44% at 0.7, 2.1% at 0.5, 4.4% from the grid's pressure alone); at 0.8 a layer 25 deep at
/// 1 cm still rippled at 1.04% of `√(gD)` after 2 s, against 0.70% at 0.9.
const WARM_EXCESS_KEPT: f32 = 0.9;

/// The grid and what it reads, kept from sub-step to sub-step (the grid warm-starts from its
/// last pressure within a tick).
#[derive(Debug, Clone)]
pub(super) struct GridStart {
    grid: GridPressure,
    /// The particles' positions by sorted slot.
    positions: Vec<Vec2>,
    /// Their rest density ratios by sorted slot, with two liquids (empty with one).
    ratios: Vec<f32>,
}

impl GridStart {
    /// The grid of this sub-step's particles, from their positions (and the walls' solids)
    /// alone, before their velocities are known: [`GridPressure::prepare`], on the calling
    /// thread. Runs beside the neighbour pass ([`Dfsph::prepare_with_grid`]).
    pub(super) fn prepare(&mut self, c: &SphConstants, (fluid, walls): (&FluidSnapshot, &Walls)) {
        let Self {
            grid,
            positions,
            ratios,
        } = self;
        positions.clear();
        positions.extend((0..fluid.len()).map(|slot| fluid.points.get(slot)));
        ratios.clear();
        let sorted = &fluid.rest_ratio[..fluid.len()];
        if sorted.iter().any(|&r| r != 1.0) {
            ratios.extend_from_slice(sorted);
        }
        let input = grid_input(c, positions, ratios);
        grid.prepare(&input, |x| solid_velocity(walls, x), &Sequential);
    }
}

/// What the grid reads of the particles at `positions` under the constants `c`.
fn grid_input<'a>(c: &SphConstants, positions: &'a [Vec2], ratios: &'a [f32]) -> GridInput<'a> {
    GridInput {
        positions,
        ratios,
        spacing: c.spacing,
        rest_density: c.rest_density,
        gravity: c.gravity,
        tank: c.tank,
    }
}

impl Default for GridStart {
    fn default() -> Self {
        Self {
            grid: GridPressure::new(SETTINGS),
            positions: Vec::new(),
            ratios: Vec::new(),
        }
    }
}

impl Dfsph {
    /// Step 1 and, beside it, the grid of [`start_from_grid`](Self::start_from_grid) from the
    /// positions alone (when `grid` is set): `prepare(self)`, the neighbour pass, runs its jobs
    /// on `parallel` while one thread builds the grid's cells and equations, which need no
    /// velocity, and then joins it (built after the pass instead, on one thread while the
    /// other waited, the grid took 22-27% of a default sub-step; measured beside it, 2
    /// threads: 2-5% less a sub-step at 2,491 and 9,964 particles). The same results in any
    /// order.
    pub(super) fn prepare_with_grid<P: Parallel>(
        &mut self,
        c: &SphConstants,
        (fluid, walls): (&FluidSnapshot, &Walls),
        grid: bool,
        parallel: &P,
        prepare: impl FnOnce(&mut Self) + Send,
    ) {
        let mut start = core::mem::take(&mut self.grid_start);
        parallel.join(
            || prepare(self),
            || {
                if grid {
                    start.prepare(c, (fluid, walls));
                }
            },
        );
        self.grid_start = start;
    }

    /// Step 4, between the prediction and the density solve: starts every particle's stiffness
    /// from the grid pressure of the predicted velocities over a step of `dt` seconds, plus
    /// [`WARM_EXCESS_KEPT`] of what its warm start had above that. The grid carries the smooth
    /// part the warm start loses (a column's weight, which the last sub-step's few iterations
    /// left short), the warm start's excess the peaks the grid cannot resolve (an impact under
    /// two cells). Measured on the demo's surge at 4 + 1 iterations: the 99th percentile of the
    /// density excess read 1.05% at worst, 2.9% (at 5 + 1) from the grid's alone. A particle
    /// compressed beyond [`MAX_START_DENSITY`] keeps its warm start. The grid's own solve
    /// starts from its last pressure, except on the `first_of_tick` sub-step, where it starts
    /// from zero: a tick then depends on the particles alone, so a run restored from a snapshot
    /// or reset between ticks repeats bit for bit. (Starting it from the particles' warm starts
    /// instead, averaged onto the cells, stopped the solve short on a biased start: a layer 100
    /// deep at 2 cm read a slope of 0.944.) The grid is the one [`Dfsph::prepare_with_grid`] built
    /// for this sub-step's particles. Returns what the grid's solve did.
    pub fn start_from_grid(
        &mut self,
        c: &SphConstants,
        (dt, first_of_tick): (f32, bool),
        parallel: &impl Parallel,
    ) -> GridReport {
        let GridStart {
            grid,
            positions,
            ratios,
        } = &mut self.grid_start;
        if first_of_tick {
            grid.forget();
        }
        if positions.len() != self.state.len() {
            // Not prepared for these particles (the density stage ran without the grid).
            debug_assert!(
                false,
                "the grid was not prepared for this sub-step's particles"
            );
            return GridReport::default();
        }
        let input = grid_input(c, positions, ratios);
        let report = grid.solve(&input, &self.velocity, dt, parallel);
        let (grid, positions) = (&*grid, &*positions);
        let to_stiffness = 1.0 / c.rest_density;
        let state = &self.state;
        for_each_slot(&mut self.kappa, parallel, |slot, kappa| {
            if state[slot].density > MAX_START_DENSITY {
                return 0.0;
            }
            let from_grid = to_stiffness * grid.pressure_at(positions[slot]);
            *kappa = from_grid + WARM_EXCESS_KEPT * (*kappa - from_grid).max(0.0);
            0.0
        });
        report
    }
}

/// The velocity of the solid at `x`, if `x` is inside one.
fn solid_velocity(walls: &Walls, x: Vec2) -> Option<Vec2> {
    walls
        .solids
        .iter()
        .find(|s| s.distance(x).0 < 0.0)
        .map(|s| s.point_velocity(x))
}
