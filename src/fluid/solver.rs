//! The SPH maths of one sub-step on plain data: density, equation of state, wall pressure,
//! forces, time-step limits and integration. Pure, no ECS: the systems in
//! [`systems`](super::systems) and the slice solver in [`slices`](super::slices) both call these
//! functions, so the two paths compute the same numbers.
//!
//! Weakly compressible SPH (Monaghan 1994, 2005):
//! - density by summation, `ρᵢ = Σⱼ m W(rᵢⱼ)`, over fluid and wall particles, `i` itself included;
//! - Tait equation of state `p = B((ρ/ρ₀)^γ − 1)`, `B = ρ₀c₀²/γ`, clamped at zero so the free
//!   surface (where summation under-counts) feels no tension;
//! - the symmetric pressure force `aᵢ = −Σⱼ m (pᵢ/ρᵢ² + pⱼ/ρⱼ² + Πᵢⱼ) ∇W`, which conserves momentum
//!   pair by pair, with Monaghan's artificial viscosity `Πᵢⱼ` and the Lo & Shao (2002) laminar
//!   viscosity term for a kinematic viscosity `ν`;
//! - walls as fixed boundary particles whose pressure is extrapolated from the fluid with the
//!   hydrostatic correction of Adami, Hu & Adams (2012); they take part in pressure and laminar
//!   viscosity, not in the artificial viscosity (which would act as wall friction);
//! - symplectic Euler sub-steps bounded by the CFL, force and viscous limits.
//!
//! See [`SphPlugin`](crate::fluid::SphPlugin).

use super::boundary::{Obstacle, Tank};
use super::grid::NeighborGrid;
use super::kernels::{KernelKind, RadialKernel};
use super::parallel::{Parallel, chunk_size};
use bevy::math::{Mat4, Vec2, Vec4};
use core::sync::atomic::{AtomicU64, Ordering};

/// Everything the sub-step maths needs, derived once from validated
/// [`SphParams`](crate::fluid::SphParams) by
/// [`SphParams::constants`](crate::fluid::SphParams::constants).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphConstants {
    /// Kernel choice.
    pub kernel: KernelKind,
    /// Initial particle spacing, m.
    pub spacing: f32,
    /// Kernel support radius `H`, m.
    pub support: f32,
    /// `H²`, m².
    pub support_sq: f32,
    /// Smoothing length `h = H/2`, m (the length in the time-step limits and viscosity terms).
    pub smoothing_length: f32,
    /// Mass of every particle, kg per metre of depth.
    pub mass: f32,
    /// Rest density `ρ₀`, kg/m³.
    pub rest_density: f32,
    /// Speed of sound `c₀`, m/s.
    pub speed_of_sound: f32,
    /// Tait exponent `γ`.
    pub eos_exponent: f32,
    /// Tait stiffness `B = ρ₀c₀²/γ`, Pa.
    pub stiffness: f32,
    /// Background pressure added to the equation of state, Pa.
    pub background_pressure: f32,
    /// Monaghan artificial viscosity `α`.
    pub artificial_viscosity: f32,
    /// Kinematic viscosity `ν`, m²/s.
    pub kinematic_viscosity: f32,
    /// Gravity, m/s².
    pub gravity: Vec2,
    /// Courant number of the acoustic time-step limit.
    pub cfl_number: f32,
    /// Speeds are capped here, m/s: beyond `c₀` the weakly compressible model is meaningless.
    pub speed_limit: f32,
    /// Restitution of the collision safety net, 0..1.
    pub wall_restitution: f32,
    /// The tank, if any.
    pub tank: Option<Tank>,
    /// Layers of boundary particles behind each wall.
    pub wall_layers: u32,
    /// Sub-steps allowed per tick.
    pub max_substeps: u32,
}

/// Runs `$body` with `$w` bound to the density kernel and `$g` to the gradient kernel of
/// `$kind`, monomorphised per kernel so the neighbour loops have no dynamic dispatch.
macro_rules! with_kernels {
    ($kind:expr, $support:expr, |$w:ident, $g:ident| $body:expr) => {{
        use $crate::fluid::kernels as k;
        match $kind {
            k::KernelKind::WendlandC2 => {
                let $w = k::WendlandC2::new($support);
                let $g = $w;
                $body
            }
            k::KernelKind::CubicSpline => {
                let $w = k::CubicSpline::new($support);
                let $g = $w;
                $body
            }
            k::KernelKind::Muller => {
                let $w = k::Poly6::new($support);
                let $g = k::Spiky::new($support);
                $body
            }
        }
    }};
}
pub(crate) use with_kernels;

/// Width of the lane batches the neighbour loops work in: four `f32` lanes (one SSE or NEON
/// register).
pub const LANES: usize = 4;

/// Coordinate given to the padding after the last point: far from everything, yet small enough
/// that its square stays finite, so padded lanes compute finite garbage that masks discard.
const FAR: f32 = 1.0e18;

/// Points in cell-sorted order, with their cell list: the x and y coordinates as separate
/// arrays (so a run of neighbours loads as lane vectors), each padded with [`LANES`] far points
/// so lane loads never read past the end.
#[derive(Debug, Clone, Default)]
pub struct SortedPoints {
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
pub struct NeighborData {
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

/// Density and `p/ρ²` of every fluid particle by sorted slot, one atomic word each, so that the
/// density pass, running in parallel over particles in any order, can store each particle's
/// values at its slot while nothing else writes there. Relaxed atomic loads and stores compile
/// to plain moves.
#[derive(Debug, Default)]
pub struct PressureSlots(Vec<AtomicU64>);

impl Clone for PressureSlots {
    fn clone(&self) -> Self {
        Self(
            self.0
                .iter()
                .map(|v| AtomicU64::new(v.load(Ordering::Relaxed)))
                .collect(),
        )
    }
}

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
        self.0[slot].store(pack(density, term), Ordering::Relaxed);
    }

    /// Density (kg/m³) and `p/ρ²` at `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> (f32, f32) {
        let word = self.0[slot].load(Ordering::Relaxed);
        (
            f32::from_bits(word as u32),
            f32::from_bits((word >> 32) as u32),
        )
    }
}

/// Two `f32` in one `u64`, the first in the low half.
#[inline]
fn pack(low: f32, high: f32) -> u64 {
    u64::from(low.to_bits()) | (u64::from(high.to_bits()) << 32)
}

/// A cell-sorted copy of the fluid particles for neighbour reads: positions and velocities
/// from the start of the sub-step, then densities and pressures once they are known.
#[derive(Debug, Clone, Default)]
pub struct FluidSnapshot {
    /// Positions and cell list (for scanning candidates).
    pub points: SortedPoints,
    /// `[x, y, vx, vy]` per sorted slot (m, m/s), padded with [`LANES`] far entries: a
    /// neighbour's kinematics in one vector load.
    pub kinematics: Vec<[f32; 4]>,
    /// Density and pressure term per sorted slot, padded like `kinematics`.
    pub pressure: PressureSlots,
    /// Largest speed in the snapshot, m/s.
    pub max_speed: f32,
}

impl FluidSnapshot {
    /// Rebuilds the grid over `positions` (input order) and copies positions and velocities into
    /// sorted order, in parallel chunks on `parallel`; densities are left at rest until
    /// [`set_pressure`](Self::set_pressure).
    pub fn rebuild(
        &mut self,
        c: &SphConstants,
        positions: &[Vec2],
        velocities: &[Vec2],
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
            .resize_with(n + LANES, || AtomicU64::new(at_rest));
        let chunk = chunk_size(n, 16, 4096);
        let order = points.grid.order();
        let mut pieces: Vec<_> = order
            .chunks(chunk)
            .zip(points.x.chunks_mut(chunk))
            .zip(points.y.chunks_mut(chunk))
            .zip(self.kinematics.chunks_mut(chunk))
            .zip(self.pressure.0.chunks(chunk))
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
        for padding in &self.pressure.0[n..] {
            padding.store(at_rest, Ordering::Relaxed);
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
    fn gather(&self, slots: [usize; LANES]) -> ([Vec4; 2], [Vec4; 4]) {
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

/// Fixed boundary particles of the tank and obstacles, cell-sorted, with the pressure the fluid
/// currently exerts on each.
#[derive(Debug, Clone, Default)]
pub struct Walls {
    /// Positions and cell list (rebuilt only when the geometry changes).
    pub points: SortedPoints,
    /// Densities and pressure terms (velocities stay zero), sorted.
    pub data: NeighborData,
    /// The obstacles the walls were sampled from, for the collision safety net.
    pub obstacles: Vec<Obstacle>,
    /// Scratch for the parallel wall-pressure pass.
    states: Vec<WallState>,
}

/// Density (kg/m³) and pressure (Pa) of one wall particle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WallState {
    /// Density, kg/m³.
    pub density: f32,
    /// Pressure, Pa.
    pub pressure: f32,
}

impl Walls {
    /// Samples the tank and `obstacles` into wall particles for spacing and support of `c`.
    pub fn rebuild(&mut self, c: &SphConstants, obstacles: &[Obstacle]) {
        let mut points = Vec::new();
        if let Some(tank) = &c.tank {
            tank.sample(c.spacing, c.wall_layers, &mut points);
        }
        for obstacle in obstacles.iter().filter(|o| o.is_valid()) {
            obstacle.sample(c.spacing, c.wall_layers, &mut points);
        }
        self.obstacles = obstacles
            .iter()
            .copied()
            .filter(Obstacle::is_valid)
            .collect();
        // Wall particles outline the whole tank: budget cells for its area, not their number.
        self.points
            .rebuild(c.support, &points, NeighborGrid::STATIC_BUDGET);
        // Most fluid particles are far from every wall; let their wall queries end at once.
        self.points.grid.mark_occupied_blocks();
        self.data.reset(points.len(), c.rest_density);
        self.states.clear();
        self.states.resize(points.len(), WallState::default());
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

    /// Whether there are no wall particles.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// Most fluid neighbours a [`NeighborList`] holds; a particle with more (a support ratio above
/// about 3.5, or a strongly compressed fluid) is evaluated straight from the grid instead.
pub const NEIGHBOR_LIST_CAPACITY: usize = 48;

/// The sorted slots of a particle's fluid neighbours (inside the support, itself excluded), as
/// found by [`density_and_neighbors_at`] and reused by [`acceleration_at`], so the force pass
/// neither searches the grid for fluid neighbours nor evaluates candidates outside the support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NeighborList {
    len: u32,
    // Room for a whole lane batch past the capacity: compaction writes four slots at a time.
    slots: [u32; NEIGHBOR_LIST_CAPACITY + LANES],
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

    /// The neighbours' sorted slots, or `None` if there were too many to list.
    pub fn slots(&self) -> Option<&[u32]> {
        self.slots.get(..self.len as usize)
    }

    /// The slots padded to whole lane batches with the snapshot's padding slot (a far point).
    fn padded_slots(&self) -> Option<&[u32]> {
        self.slots
            .get(..(self.len as usize).checked_next_multiple_of(LANES)?)
    }
}

/// Summed density at `x` (kg/m³): fluid particles (the one at `x` itself included) and wall
/// particles, summed lane by lane in a fixed order so the result does not depend on threads.
/// Also records the fluid neighbours inside the support, in candidate order, in `list`.
#[inline]
pub fn density_and_neighbors_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    x: Vec2,
    fluid: &FluidSnapshot,
    walls: &Walls,
    list: &mut NeighborList,
) -> f32 {
    let support_sq = Vec4::splat(c.support_sq);
    let tiny = Vec4::splat(1e-12 * c.support_sq);
    let mut sum = Vec4::ZERO;
    let mut len = 0usize;
    fluid.points.for_each_batch(x, |start, _, _, r2| {
        // No branch on the support: the kernels are zero beyond it.
        sum += kernel.value_sq_x4(r2);
        let inside = (r2.cmplt(support_sq) & r2.cmpgt(tiny)).bitmask() as usize;
        // Write all four slots, the inside ones first, and advance by how many are inside.
        if len <= NEIGHBOR_LIST_CAPACITY {
            let start = start as u32;
            let [a, b, c, d] = COMPACT[inside];
            list.slots[len..len + LANES].copy_from_slice(&[
                start + a,
                start + b,
                start + c,
                start + d,
            ]);
        }
        len += inside.count_ones() as usize;
    });
    walls
        .points
        .for_each_batch(x, |_, _, _, r2| sum += kernel.value_sq_x4(r2));
    list.len = if len <= NEIGHBOR_LIST_CAPACITY {
        // Pad the last lane batch with the padding slot after the last particle (far away).
        list.slots[len..len + LANES].fill(fluid.len() as u32);
        len as u32
    } else {
        u32::MAX
    };
    c.mass * sum.element_sum()
}

/// For each 4-bit lane mask, the lanes in the order "set lanes first": compaction by table.
const COMPACT: [[u32; LANES]; 16] = {
    let mut table = [[0u32; LANES]; 16];
    let mut mask = 0;
    while mask < 16 {
        let (mut next, mut lane) = (0, 0);
        while lane < LANES {
            if mask & (1 << lane) != 0 {
                table[mask][next] = lane as u32;
                next += 1;
            }
            lane += 1;
        }
        lane = 0;
        while lane < LANES {
            if mask & (1 << lane) == 0 {
                table[mask][next] = lane as u32;
                next += 1;
            }
            lane += 1;
        }
        mask += 1;
    }
    table
};

/// Mean number of particles, fluid and wall, within the kernel support of each fluid particle
/// (the particle itself included), over the snapshot's positions.
pub fn mean_neighbors(c: &SphConstants, fluid: &FluidSnapshot, walls: &Walls) -> f64 {
    if fluid.is_empty() {
        return 0.0;
    }
    let mut total = 0usize;
    for slot in 0..fluid.len() {
        let x = fluid.points.get(slot);
        for points in [&fluid.points, &walls.points] {
            points.for_each_batch(x, |_, _, _, r2| {
                total += r2.cmplt(Vec4::splat(c.support_sq)).bitmask().count_ones() as usize;
            });
        }
    }
    total as f64 / fluid.len() as f64
}

/// Tait equation of state plus the background pressure, clamped at zero: pressure (Pa) at
/// `density` (kg/m³).
#[inline]
pub fn pressure_from_density(c: &SphConstants, density: f32) -> f32 {
    let ratio = density / c.rest_density;
    let powered = if c.eos_exponent == 7.0 {
        let r2 = ratio * ratio;
        r2 * r2 * r2 * ratio
    } else if c.eos_exponent == 1.0 {
        ratio
    } else {
        ratio.powf(c.eos_exponent)
    };
    (c.stiffness * (powered - 1.0) + c.background_pressure).max(0.0)
}

/// Inverse of [`pressure_from_density`] for non-negative pressure, kg/m³.
#[inline]
pub fn density_from_pressure(c: &SphConstants, pressure: f32) -> f32 {
    let excess = (pressure.max(0.0) - c.background_pressure) / c.stiffness;
    c.rest_density * (1.0 + excess).max(0.0).powf(1.0 / c.eos_exponent)
}

/// Pressure and density of the wall particle at `x` (Adami et al. 2012): the kernel-weighted
/// fluid pressure around it plus the hydrostatic head `ρ g·(x_w − x_f)` between fluid and wall.
/// A wall particle with no fluid near it gets zero pressure.
#[inline]
pub fn wall_state_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    x: Vec2,
    fluid: &FluidSnapshot,
) -> WallState {
    let (mut weight, mut pressure) = (Vec4::ZERO, Vec4::ZERO);
    let (mut head_x, mut head_y) = (Vec4::ZERO, Vec4::ZERO);
    fluid.points.for_each_batch(x, |start, dx, dy, r2| {
        let w = kernel.value_sq_x4(r2); // zero outside the support and in masked lanes
        let (_, [_, _, rho, term]) = fluid.gather([start, start + 1, start + 2, start + 3]);
        weight += w;
        pressure += term * rho * rho * w;
        // x_w − x_f = −(dx, dy).
        head_x -= rho * w * dx;
        head_y -= rho * w * dy;
    });
    let weight = weight.element_sum();
    if weight <= 0.0 {
        return WallState {
            density: c.rest_density,
            pressure: 0.0,
        };
    }
    let head = Vec2::new(head_x.element_sum(), head_y.element_sum());
    let p = ((pressure.element_sum() + c.gravity.dot(head)) / weight).max(0.0);
    WallState {
        density: density_from_pressure(c, p),
        pressure: p,
    }
}

/// Acceleration (m/s²) of a particle at `x` with velocity `v`, density `rho` and pressure `p`:
/// pressure, artificial and laminar viscosity from fluid and wall neighbours, plus gravity.
///
/// Fluid neighbours come from `list` (filled by [`density_and_neighbors_at`] this sub-step), or
/// from the grid if it overflowed; wall neighbours always come from the wall grid, and add
/// pressure and laminar viscosity (no-slip) but no artificial viscosity. Lanes are
/// evaluated four at a time and those outside the support masked, so there is no branch per
/// neighbour.
#[inline]
#[expect(
    clippy::too_many_arguments,
    reason = "the particle's own state, spelled out"
)]
pub fn acceleration_at<K: RadialKernel>(
    kernel: &K,
    c: &SphConstants,
    x: Vec2,
    v: Vec2,
    rho: f32,
    p: f32,
    list: &NeighborList,
    fluid: &FluidSnapshot,
    walls: &Walls,
) -> Vec2 {
    let pair = PairTerms::new(c, v, rho, p);
    let mut sum = (Vec4::ZERO, Vec4::ZERO);
    match list.padded_slots() {
        Some(slots) => {
            for batch in slots.chunks_exact(LANES) {
                let lanes = [0, 1, 2, 3].map(|lane| batch[lane] as usize);
                let ([px, py], neighbor) = fluid.gather(lanes);
                let (dx, dy) = (px - Vec4::splat(x.x), py - Vec4::splat(x.y));
                pair.accumulate(kernel, dx, dy, neighbor, &mut sum);
            }
        }
        None => fluid.points.for_each_batch(x, |start, dx, dy, _| {
            let (_, neighbor) = fluid.gather([start, start + 1, start + 2, start + 3]);
            pair.accumulate(kernel, dx, dy, neighbor, &mut sum);
        }),
    }
    // Artificial viscosity is a numerical damping of the fluid's own noise; against a wall it
    // would act as friction (measured: a dam-break front slowing by a fifth, where experiments
    // show none), so walls only take the physical laminar term.
    let wall_pair = PairTerms {
        artificial: Vec4::ZERO,
        ..pair
    };
    walls.points.for_each_batch(x, |start, dx, dy, _| {
        wall_pair.accumulate(kernel, dx, dy, walls.data.lanes(start), &mut sum);
    });
    c.mass * Vec2::new(sum.0.element_sum(), sum.1.element_sum()) + c.gravity
}

/// What one particle brings to each of its pair interactions, splatted across lanes.
struct PairTerms {
    support_sq: Vec4,
    tiny: Vec4,
    eta_sq: Vec4,
    own_term: Vec4,
    rho: Vec4,
    vx: Vec4,
    vy: Vec4,
    /// `2 α c₀ h`: Monaghan's `Π = −α c₀ h μ / ρ̄` with `μ = (v·r)/(r²+η²)` for approaching
    /// pairs and `ρ̄ = (ρᵢ+ρⱼ)/2`.
    artificial: Vec4,
    /// `4 ν`: Lo & Shao's laminar term `4ν (r·∇W)/((ρᵢ+ρⱼ)(r²+η²)) vᵢⱼ`.
    laminar: Vec4,
}

impl PairTerms {
    #[inline]
    fn new(c: &SphConstants, v: Vec2, rho: f32, p: f32) -> Self {
        let h = c.smoothing_length;
        Self {
            support_sq: Vec4::splat(c.support_sq),
            tiny: Vec4::splat(1e-12 * c.support_sq),
            eta_sq: Vec4::splat(0.01 * h * h),
            own_term: Vec4::splat(p / (rho * rho)),
            rho: Vec4::splat(rho),
            vx: Vec4::splat(v.x),
            vy: Vec4::splat(v.y),
            artificial: Vec4::splat(2.0 * c.artificial_viscosity * c.speed_of_sound * h),
            laminar: Vec4::splat(4.0 * c.kinematic_viscosity),
        }
    }

    /// Adds, per lane, the pressure and viscosity terms (per unit mass) of four neighbours at
    /// offsets `(dx, dy)` with `[vx, vy, density, pressure term]`; lanes outside the support
    /// (or at the particle itself) add nothing.
    #[inline(always)]
    fn accumulate<K: RadialKernel>(
        &self,
        kernel: &K,
        dx: Vec4,
        dy: Vec4,
        [vx_j, vy_j, rho_j, term_j]: [Vec4; 4],
        sum: &mut (Vec4, Vec4),
    ) {
        let r2 = dx * dx + dy * dy;
        let inside = r2.cmplt(self.support_sq) & r2.cmpgt(self.tiny);
        let r2 = r2.min(self.support_sq); // finite in masked lanes
        let (rx, ry) = (-dx, -dy); // rᵢⱼ = xᵢ − xⱼ
        let (vx, vy) = (self.vx - vx_j, self.vy - vy_j);
        let slope = kernel.derivative_over_r_x4(r2.sqrt()); // ∇W = slope · r
        let inv = Vec4::ONE / ((r2 + self.eta_sq) * (self.rho + rho_j));
        let approach = (vx * rx + vy * ry).min(Vec4::ZERO);
        let scalar = self.own_term + term_j - self.artificial * approach * inv;
        let viscous = self.laminar * r2 * inv;
        let fx = slope * (viscous * vx - scalar * rx);
        let fy = slope * (viscous * vy - scalar * ry);
        sum.0 += Vec4::select(inside, fx, Vec4::ZERO);
        sum.1 += Vec4::select(inside, fy, Vec4::ZERO);
    }
}

/// Advances one particle by `dt` (symplectic Euler: velocity first, then position with the new
/// velocity), caps its speed, and keeps it inside the tank and out of obstacles. Returns `false`
/// (and leaves the particle where it was, at rest) if the result would not be finite.
#[inline]
pub fn advance_particle(
    c: &SphConstants,
    obstacles: &[Obstacle],
    position: &mut Vec2,
    velocity: &mut Vec2,
    acceleration: Vec2,
    dt: f32,
) -> bool {
    let mut v = *velocity + acceleration * dt;
    let speed_sq = v.length_squared();
    if speed_sq > c.speed_limit * c.speed_limit {
        v *= c.speed_limit / speed_sq.sqrt();
    }
    let mut x = *position + v * dt;
    for obstacle in obstacles {
        obstacle.push_out(&mut x, &mut v, c.wall_restitution);
    }
    if let Some(tank) = &c.tank {
        tank.confine(&mut x, &mut v, c.wall_restitution);
    }
    if x.is_finite() && v.is_finite() {
        *position = x;
        *velocity = v;
        true
    } else {
        *velocity = Vec2::ZERO;
        false
    }
}

/// The largest stable time step (s) for the given fastest speed (m/s) and largest acceleration
/// (m/s²): the acoustic CFL limit `C h/(c₀ + v)`, the force limit `¼√(h/a)` and the viscous
/// limit `⅛ h²/ν` (Monaghan 1992; Morris et al. 1997).
pub fn stable_time_step(c: &SphConstants, max_speed: f32, max_acceleration: f32) -> f32 {
    let h = c.smoothing_length;
    let mut dt = c.cfl_number * h / (c.speed_of_sound + max_speed);
    if max_acceleration > 0.0 {
        dt = dt.min(0.25 * (h / max_acceleration).sqrt());
    }
    if c.kinematic_viscosity > 0.0 {
        dt = dt.min(0.125 * h * h / c.kinematic_viscosity);
    }
    dt
}

/// Splits what is left of a tick into equal sub-steps no longer than `stable` and returns the
/// next one (s).
pub fn plan_substep(remaining: f64, stable: f32) -> f32 {
    if remaining <= 0.0 {
        return 0.0;
    }
    let stable = (stable as f64).max(1e-9);
    let count = (remaining / stable).ceil().max(1.0);
    (remaining / count) as f32
}
