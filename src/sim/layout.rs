//! The solver's data layout, shared by both pressure solvers: cell-sorted points padded for
//! lane loads, the fluid snapshot (kinematics, densities and pressures by sorted slot), the wall
//! particles, per-particle neighbour lists, and slot-indexed values that parallel loops over
//! particles in any order can fill. Plain data, no physics and no ECS.
//!

use super::config::SphConstants;
use super::grid::NeighborGrid;
use super::parallel::{Parallel, chunk_size};
use super::solid::{MovingSolid, SolidMotion};
use bevy::math::{Mat4, Vec2, Vec4};
use core::sync::atomic::{AtomicU64, Ordering};

/// Width of the lane batches the neighbour loops work in: four `f32` lanes (one SSE or NEON
/// register).
pub(crate) const LANES: usize = 4;

/// Coordinate given to the padding after the last point: far from everything, yet small enough
/// that its square stays finite, so padded lanes compute finite garbage that masks discard.
const FAR: f32 = 1.0e18;

/// Points in cell-sorted order, with their cell list: the x and y coordinates as separate
/// arrays (so a run of neighbours loads as lane vectors), each padded with [`LANES`] far points
/// so lane loads never read past the end.
#[derive(Debug, Clone, Default)]
pub(crate) struct SortedPoints {
    /// The cell list; its sorted order is the order of `x` and `y`.
    pub grid: NeighborGrid,
    /// x coordinates, sorted, m (plus padding).
    pub x: Vec<f32>,
    /// y coordinates, sorted, m (plus padding).
    pub y: Vec<f32>,
}

impl SortedPoints {
    /// Rebuilds the cell list over `points` (input order) with cells of `cell_size` and at most
    /// `max_cells` cells (see [`NeighborGrid::rebuild_with_budget`]), and copies the points into
    /// sorted order.
    pub fn rebuild(&mut self, cell_size: f32, points: &[Vec2], max_cells: usize) {
        self.grid.set_cell_size(cell_size);
        self.grid.rebuild_with_budget(points, max_cells);
        let n = points.len();
        self.x.resize(n + LANES, FAR);
        self.y.resize(n + LANES, FAR);
        for ((x, y), &i) in self.x.iter_mut().zip(&mut self.y).zip(self.grid.order()) {
            let p = points[i as usize];
            (*x, *y) = (p.x, p.y);
        }
        self.x[n..].fill(FAR);
        self.y[n..].fill(FAR);
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.grid.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.grid.is_empty()
    }

    /// The point at sorted `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> Vec2 {
        Vec2::new(self.x[slot], self.y[slot])
    }

    /// Calls `visit(first_slot, dx, dy, r²)` for the candidate neighbours of `p` (see
    /// [`NeighborGrid::for_each_run`]) in batches of [`LANES`] consecutive slots, with the offsets
    /// `(dx, dy)` from `p` to each candidate; lanes past the end of a run have `r² = ∞`.
    #[inline(always)]
    pub fn for_each_batch(&self, p: Vec2, mut visit: impl FnMut(usize, Vec4, Vec4, Vec4)) {
        const LANE: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);
        let (px, py) = (Vec4::splat(p.x), Vec4::splat(p.y));
        self.grid.for_each_run(p, |run| {
            // The padding after the last point makes whole lane batches readable.
            let padded = run.len().next_multiple_of(LANES);
            let xs = &self.x[run.start..run.start + padded];
            let ys = &self.y[run.start..run.start + padded];
            let mut start = run.start;
            for (x4, y4) in xs.chunks_exact(LANES).zip(ys.chunks_exact(LANES)) {
                let dx = Vec4::from_slice(x4) - px;
                let dy = Vec4::from_slice(y4) - py;
                let mut r2 = dx * dx + dy * dy;
                let left = run.end - start;
                if left < LANES {
                    // The last batch runs into the next cell's points: mask them out.
                    r2 = Vec4::select(LANE.cmplt(Vec4::splat(left as f32)), r2, Vec4::INFINITY);
                }
                visit(start, dx, dy, r2);
                start += LANES;
            }
        });
    }
}

/// What neighbours contribute to forces besides their positions, in sorted order, as separate
/// arrays padded like [`SortedPoints`] so they load as lane vectors.
#[derive(Debug, Clone, Default)]
pub(crate) struct NeighborData {
    /// Velocity x, m/s (zero for walls).
    pub vx: Vec<f32>,
    /// Velocity y, m/s (zero for walls).
    pub vy: Vec<f32>,
    /// Density, kg/m³.
    pub density: Vec<f32>,
    /// `p/ρ²`, Pa·m⁶/kg².
    pub pressure_term: Vec<f32>,
}

impl NeighborData {
    /// `n` entries at rest (zero velocity and pressure, density `rest_density`) plus padding.
    fn reset(&mut self, n: usize, rest_density: f32) {
        for (values, fill) in [
            (&mut self.vx, 0.0),
            (&mut self.vy, 0.0),
            (&mut self.density, rest_density),
            (&mut self.pressure_term, 0.0),
        ] {
            values.clear();
            values.resize(n + LANES, fill);
        }
    }

    /// `[vx, vy, density, pressure term]` of the four slots from `start`.
    #[inline(always)]
    pub fn lanes(&self, start: usize) -> [Vec4; 4] {
        let load = |values: &[f32]| Vec4::from_slice(&values[start..start + LANES]);
        [
            load(&self.vx),
            load(&self.vy),
            load(&self.density),
            load(&self.pressure_term),
        ]
    }

    /// Sets density (kg/m³) and pressure (Pa) at `slot`; a non-positive density counts as
    /// no pressure.
    #[inline]
    pub fn set_pressure(&mut self, slot: usize, density: f32, pressure: f32) {
        self.density[slot] = density;
        self.pressure_term[slot] = if density > 0.0 {
            pressure / (density * density)
        } else {
            0.0
        };
    }
}

/// Density and `p/ρ²` of every fluid particle by sorted slot (a [`SlotVectors`]), so that the
/// density pass, running in parallel over particles in any order, can store each particle's
/// values at its slot while nothing else writes there.
#[derive(Debug, Clone, Default)]
pub(crate) struct PressureSlots(SlotVectors);

impl PressureSlots {
    /// Stores density (kg/m³) and pressure (Pa) at `slot`; a non-positive density counts as no
    /// pressure.
    #[inline]
    pub fn set(&self, slot: usize, density: f32, pressure: f32) {
        let term = if density > 0.0 {
            pressure / (density * density)
        } else {
            0.0
        };
        self.0.set(slot, Vec2::new(density, term));
    }

    /// Density (kg/m³) and `p/ρ²` at `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> (f32, f32) {
        self.0.get(slot).into()
    }
}

/// Two `f32` in one `u64`, the first in the low half.
#[inline]
fn pack(low: f32, high: f32) -> u64 {
    u64::from(low.to_bits()) | (u64::from(high.to_bits()) << 32)
}

/// A `Vec2` per sorted slot, one atomic word each: a parallel loop over particles in any order
/// stores each particle's value at its own slot while nothing else writes there. Relaxed atomic
/// loads and stores compile to plain moves.
#[derive(Debug, Default)]
pub(crate) struct SlotVectors(Vec<AtomicU64>);

impl Clone for SlotVectors {
    fn clone(&self) -> Self {
        Self(
            self.0
                .iter()
                .map(|v| AtomicU64::new(v.load(Ordering::Relaxed)))
                .collect(),
        )
    }
}

impl SlotVectors {
    /// Stores `value` at `slot`.
    #[inline]
    pub fn set(&self, slot: usize, value: Vec2) {
        self.0[slot].store(pack(value.x, value.y), Ordering::Relaxed);
    }

    /// The value at `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> Vec2 {
        let word = self.0[slot].load(Ordering::Relaxed);
        Vec2::new(
            f32::from_bits(word as u32),
            f32::from_bits((word >> 32) as u32),
        )
    }
}

/// A cell-sorted copy of the fluid particles for neighbour reads: positions and velocities
/// from the start of the sub-step, then densities and pressures once they are known.
#[derive(Debug, Clone, Default)]
pub(crate) struct FluidSnapshot {
    /// Positions and cell list (for scanning candidates).
    pub points: SortedPoints,
    /// `[x, y, vx, vy]` per sorted slot (m, m/s), padded with [`LANES`] far entries: a
    /// neighbour's kinematics in one vector load.
    pub kinematics: Vec<[f32; 4]>,
    /// Density and pressure term per sorted slot, padded like `kinematics`.
    pub pressure: PressureSlots,
    /// Largest speed in the snapshot, m/s.
    pub max_speed: f32,
    /// Rest density over [`SphConstants::rest_density`] per sorted slot (a particle's mass over
    /// the base liquid's), padded with ones like `kinematics`.
    pub rest_ratio: Vec<f32>,
    /// Kinematic viscosity per sorted slot, m²/s, padded with zeros like `kinematics`; empty
    /// when every particle has [`SphConstants::kinematic_viscosity`].
    pub viscosity: Vec<f32>,
    /// The largest of [`viscosity`](Self::viscosity) and the constants' kinematic viscosity,
    /// m²/s: the viscous step limit's.
    pub max_viscosity: f32,
}

impl FluidSnapshot {
    /// Rebuilds the grid over `positions` (input order) and copies positions, velocities, rest
    /// density ratios and viscosities (each empty for the base liquid's everywhere: see
    /// [`Particles`](super::step::Particles)) into sorted order, in parallel chunks on
    /// `parallel`; densities are left at rest until [`set_pressure`](Self::set_pressure).
    pub fn rebuild(
        &mut self,
        c: &SphConstants,
        (positions, velocities, ratios, viscosities): (&[Vec2], &[Vec2], &[f32], &[f32]),
        parallel: &impl Parallel,
    ) {
        debug_assert_eq!(positions.len(), velocities.len());
        let n = positions.len();
        let points = &mut self.points;
        points.grid.set_cell_size(c.support);
        points
            .grid
            .rebuild_with(positions, NeighborGrid::max_cells(n), parallel);
        let far = [FAR, FAR, 0.0, 0.0];
        let at_rest = pack(c.rest_density, 0.0);
        points.x.resize(n + LANES, FAR);
        points.y.resize(n + LANES, FAR);
        self.kinematics.resize(n + LANES, far);
        self.pressure
            .0
            .0
            .resize_with(n + LANES, || AtomicU64::new(at_rest));
        let chunk = chunk_size(n, 16, 4096);
        let order = points.grid.order();
        let mut pieces: Vec<_> = order
            .chunks(chunk)
            .zip(points.x.chunks_mut(chunk))
            .zip(points.y.chunks_mut(chunk))
            .zip(self.kinematics.chunks_mut(chunk))
            .zip(self.pressure.0.0.chunks(chunk))
            .map(|((((order, x), y), kinematics), pressure)| {
                (order, x, y, kinematics, pressure, 0.0f32)
            })
            .collect();
        parallel.for_each(
            &mut pieces,
            |(order, xs, ys, kinematics, pressure, max_speed_sq)| {
                for (k, &i) in order.iter().enumerate() {
                    let (p, v) = (positions[i as usize], velocities[i as usize]);
                    (xs[k], ys[k]) = (p.x, p.y);
                    kinematics[k] = [p.x, p.y, v.x, v.y];
                    pressure[k].store(at_rest, Ordering::Relaxed);
                    *max_speed_sq = max_speed_sq.max(v.length_squared());
                }
            },
        );
        let max_speed_sq = pieces.iter().fold(0.0f32, |m, piece| m.max(piece.5));
        self.max_speed = max_speed_sq.sqrt();
        points.x[n..].fill(FAR);
        points.y[n..].fill(FAR);
        self.kinematics[n..].fill(far);
        for padding in &self.pressure.0.0[n..] {
            padding.store(at_rest, Ordering::Relaxed);
        }
        self.rest_ratio.clear();
        if ratios.is_empty() {
            self.rest_ratio.resize(n + LANES, 1.0);
        } else {
            let sorted = order.iter().map(|&i| ratios[i as usize]);
            self.rest_ratio.extend(sorted.chain([1.0; LANES]));
        }
        self.viscosity.clear();
        self.max_viscosity = c.kinematic_viscosity;
        if !viscosities.is_empty() {
            let sorted = order.iter().map(|&i| viscosities[i as usize]);
            self.viscosity.extend(sorted.chain([0.0; LANES]));
            self.max_viscosity = (self.viscosity.iter()).fold(self.max_viscosity, |m, &v| m.max(v));
        }
    }

    /// The cell list.
    pub fn grid(&self) -> &NeighborGrid {
        &self.points.grid
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Records density (kg/m³) and pressure (Pa) of the particle at sorted `slot`; a
    /// non-positive density counts as no pressure. Takes `&self`: particles store their own
    /// slots from a parallel loop.
    #[inline]
    pub fn set_pressure(&self, slot: usize, density: f32, pressure: f32) {
        self.pressure.set(slot, density, pressure);
    }

    /// Positions `[x, y]` and `[vx, vy, ρ, p/ρ²]` of the particles at four sorted slots, as
    /// lanes.
    #[inline(always)]
    pub(crate) fn gather(&self, slots: [usize; LANES]) -> ([Vec4; 2], [Vec4; 4]) {
        let [a, b, c, d] = slots.map(|j| Vec4::from_array(self.kinematics[j]));
        let m = Mat4::from_cols(a, b, c, d).transpose();
        let [pa, pb, pc, pd] = slots.map(|j| self.pressure.get(j));
        (
            [m.x_axis, m.y_axis],
            [
                m.z_axis,
                m.w_axis,
                Vec4::new(pa.0, pb.0, pc.0, pd.0),
                Vec4::new(pa.1, pb.1, pc.1, pd.1),
            ],
        )
    }
}

/// Boundary particles of the tank and the solids (still or moving), cell-sorted,
/// with the pressure the fluid currently exerts on each and (solids) their velocity.
#[derive(Debug, Clone, Default)]
pub(crate) struct Walls {
    /// Positions and cell list (rebuilt when the geometry changes or a solid moves).
    pub points: SortedPoints,
    /// Velocities (zero but on solids), densities and pressure terms, sorted.
    pub data: NeighborData,
    /// The solids, whose boundary particles follow the tank's in input order.
    pub solids: Vec<MovingSolid>,
    /// `cos θ` of each wall particle's contact angle, sorted; NaN where it is the tank's
    /// ([`SphConstants::wetting`]).
    pub wetting: Vec<f32>,
    /// Whether any wall particle has an angle of its own (a solid's).
    pub own_wetting: bool,
    /// Boundary particles of the tank, in input order.
    fixed: Vec<Vec2>,
    /// The solids' motions when they were last placed (`None`: place them again).
    placed: Option<Vec<SolidMotion>>,
    /// Scratch: every boundary particle in input order.
    scratch: Vec<Vec2>,
    /// Scratch for the parallel wall-pressure pass.
    states: Vec<WallState>,
}

/// Density (kg/m³) and pressure (Pa) of one wall particle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct WallState {
    /// Density, kg/m³.
    pub density: f32,
    /// Pressure, Pa.
    pub pressure: f32,
}

impl Walls {
    /// Samples the tank into wall particles for spacing and support of `c`.
    pub fn rebuild(&mut self, c: &SphConstants) {
        self.fixed.clear();
        if let Some(tank) = &c.tank {
            tank.sample(c.spacing, c.wall_layers, &mut self.fixed);
        }
        self.placed = None;
        self.place(c);
    }

    /// Places the solids' boundary particles at their poses with their point velocities, and
    /// sorts every wall particle, unless nothing moved since the last time.
    pub fn place(&mut self, c: &SphConstants) {
        let motions = self.solids.iter().map(MovingSolid::motion);
        if self
            .placed
            .as_ref()
            .is_some_and(|placed| placed.iter().copied().eq(motions))
        {
            return;
        }
        self.placed = Some(self.solids.iter().map(MovingSolid::motion).collect());
        let mut points = core::mem::take(&mut self.scratch);
        points.clear();
        points.extend_from_slice(&self.fixed);
        for solid in &self.solids {
            let pose = solid.motion().pose;
            points.extend(solid.local_points().iter().map(|&p| pose.apply(p)));
        }
        // Wall particles outline the whole tank: budget cells for its area, not their number.
        self.points
            .rebuild(c.support, &points, NeighborGrid::STATIC_BUDGET);
        // Most fluid particles are far from every wall; let their wall queries end at once.
        self.points.grid.mark_occupied_blocks();
        self.data.reset(points.len(), c.rest_density);
        self.wetting.clear();
        self.wetting.resize(points.len(), f32::NAN);
        let mut first = self.fixed.len();
        for solid in &self.solids {
            let range = first..first + solid.len();
            let slots = &self.points.grid.slot_of()[range.clone()];
            let wetting = solid
                .contact_angle()
                .map_or(f32::NAN, |a| a.to_radians().cos());
            for (&slot, &x) in slots.iter().zip(&points[range]) {
                let v = solid.point_velocity(x);
                (self.data.vx[slot as usize], self.data.vy[slot as usize]) = (v.x, v.y);
                self.wetting[slot as usize] = wetting;
            }
            first += solid.len();
        }
        self.own_wetting = self.solids.iter().any(|s| s.contact_angle().is_some());
        self.states.clear();
        self.states.resize(points.len(), WallState::default());
        self.scratch = points;
    }

    /// Forgets where the solids were placed, so the next [`place`](Self::place) sorts again
    /// (after solids were added, removed or re-sampled).
    pub fn solids_changed(&mut self) {
        self.placed = None;
    }

    /// Whether a wall particle lies within one and a half `spacing` of `x` and more than half
    /// a spacing beyond it along `normal`: another wall (the tank, another solid) touching the
    /// surface at `x`, whose own particles lie behind it.
    pub fn touches(&self, x: Vec2, normal: Vec2, spacing: f32) -> bool {
        let (reach_sq, beyond) = ((1.5 * spacing).powi(2), 0.5 * spacing);
        let mut found = false;
        self.points.for_each_batch(x, |_, dx, dy, r2| {
            let (dx, dy, r2) = (dx.to_array(), dy.to_array(), r2.to_array());
            for lane in 0..LANES {
                // dx, dy = wall − x.
                let outward = dx[lane] * normal.x + dy[lane] * normal.y;
                found |= r2[lane] < reach_sq && outward > beyond;
            }
        });
        found
    }

    /// Keeps a particle out of the solids (see [`MovingSolid::push_out`]).
    #[inline]
    pub fn push_out(&self, position: &mut Vec2, velocity: &mut Vec2, restitution: f32) {
        for solid in &self.solids {
            solid.push_out(position, velocity, restitution);
        }
    }

    /// Calls `visit(solid, x_b, wall_slot, fluid_slot, x_i − x_b, r²)` for every pair of a
    /// solid's boundary particle and a fluid particle within the support, solid by solid in
    /// the order of their particles (a fixed order: the sums are the same on any thread count).
    pub fn for_each_solid_pair(
        &self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        mut visit: impl FnMut(usize, Vec2, usize, usize, Vec2, f32),
    ) {
        let tiny = 1e-12 * c.support_sq;
        let mut first = self.fixed.len();
        let slot_of = self.points.grid.slot_of();
        for (k, solid) in self.solids.iter().enumerate() {
            for &wall in &slot_of[first..first + solid.len()] {
                let wall = wall as usize;
                let x = self.points.get(wall);
                fluid.points.for_each_batch(x, |start, dx, dy, r2| {
                    let (dx, dy, r2) = (dx.to_array(), dy.to_array(), r2.to_array());
                    for lane in 0..LANES {
                        if r2[lane] < c.support_sq && r2[lane] > tiny {
                            let r = Vec2::new(dx[lane], dy[lane]);
                            visit(k, x, wall, start + lane, r, r2[lane]);
                        }
                    }
                });
            }
            first += solid.len();
        }
    }

    /// Lets `compute` fill in every wall particle's state (given the slice of states, sorted,
    /// and the positions), then stores them for the force pass.
    pub fn update_pressure(&mut self, compute: impl FnOnce(&mut [WallState], &SortedPoints)) {
        compute(&mut self.states, &self.points);
        for (slot, s) in self.states.iter().enumerate() {
            self.data.set_pressure(slot, s.density, s.pressure);
        }
    }

    /// Number of wall particles.
    pub fn len(&self) -> usize {
        self.points.len()
    }
}

/// Most fluid neighbours a [`NeighborList`] holds; a particle with more (a support ratio above
/// about 3.5, or a strongly compressed fluid) is evaluated straight from the grid instead.
pub(crate) const NEIGHBOR_LIST_CAPACITY: usize = 48;

/// The sorted slots of a particle's fluid neighbours (inside the support, itself excluded), as
/// found by [`density_and_neighbors_at`](super::density::density_and_neighbors_at) and reused by
/// [`acceleration_at`](super::wcsph::acceleration_at), so the force pass
/// neither searches the grid for fluid neighbours nor evaluates candidates outside the support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NeighborList {
    pub(crate) len: u32,
    // Room for a whole lane batch past the capacity: compaction writes four slots at a time.
    pub(crate) slots: [u32; NEIGHBOR_LIST_CAPACITY + LANES],
}

impl Default for NeighborList {
    fn default() -> Self {
        Self::OVERFLOWED
    }
}

impl NeighborList {
    /// A list that holds nothing usable: forces fall back to the grid.
    pub const OVERFLOWED: Self = Self {
        len: u32::MAX,
        slots: [0; NEIGHBOR_LIST_CAPACITY + LANES],
    };

    /// The slots padded to whole lane batches with the snapshot's padding slot (a far point).
    pub(crate) fn padded_slots(&self) -> Option<&[u32]> {
        self.slots
            .get(..(self.len as usize).checked_next_multiple_of(LANES)?)
    }
}
