//! Spawners: a rectangular block of fluid on a jittered square lattice, with the dam-break and
//! resting-layer set-ups as special cases. See [`SphPlugin`](crate::fluid::SphPlugin).
//!
//! The lattice and its jitter are pure ([`FluidBlock::positions`]); the block is also a
//! [`Command`], so `commands.queue(FluidBlock::dam_break(0.6, 1.2))` spawns it at the spacing in
//! [`SphParams`].

use crate::fluid::SphParams;
use crate::fluid::{FluidParticle, Position};
use crate::sim::boundary::Tank;
use bevy::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A rectangle of fluid particles on a square lattice, each nudged by seeded random jitter.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct FluidBlock {
    /// Bottom-left corner of the rectangle the particles fill, m.
    pub min: Vec2,
    /// Width and height of the rectangle, m.
    pub size: Vec2,
    /// Largest random offset per axis, as a fraction of the spacing (0 gives a perfect lattice).
    pub jitter: f32,
    /// Seed of the jitter: the same seed gives the same particles, bit for bit.
    pub seed: u64,
    /// Start at hydrostatic pressure rather than at rest density: rows are packed closer with
    /// depth, as the equation of state requires under gravity, so the block does not first
    /// fall into its own compression and ring with pressure waves. Applies when gravity points
    /// straight down.
    pub hydrostatic: bool,
}

impl FluidBlock {
    /// Default jitter, as a fraction of the spacing: enough to break the lattice's symmetry,
    /// small enough not to disturb the initial pressure. A weakly compressible fluid turns
    /// density noise into pressure noise of `c₀² δρ`: a jitter `j` gives about `0.3 j` relative
    /// density noise, which with `c₀ = 20 √(g H)` is `120 j` times the hydrostatic pressure at
    /// the bottom of a column `H` high; this default keeps it near 1%.
    pub const DEFAULT_JITTER: f32 = 1.0e-4;

    /// A block filling the rectangle from `min` with `size`, m.
    pub fn new(min: Vec2, size: Vec2) -> Self {
        Self {
            min,
            size,
            jitter: Self::DEFAULT_JITTER,
            seed: 0,
            hydrostatic: true,
        }
    }

    /// A dam-break column of `width` × `height` (m) against the tank's left wall and floor.
    pub fn dam_break(width: f32, height: f32) -> Self {
        Self::new(Vec2::ZERO, Vec2::new(width, height))
    }

    /// A resting layer filling `tank` to `depth` (m).
    pub fn resting_layer(tank: &Tank, depth: f32) -> Self {
        Self::new(Vec2::ZERO, Vec2::new(tank.width, depth.min(tank.height)))
    }

    /// With this jitter (fraction of the spacing).
    pub fn with_jitter(mut self, jitter: f32) -> Self {
        self.jitter = jitter;
        self
    }

    /// With this seed.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// With or without the hydrostatic start (see [`hydrostatic`](Self::hydrostatic)).
    pub fn with_hydrostatic(mut self, hydrostatic: bool) -> Self {
        self.hydrostatic = hydrostatic;
        self
    }

    /// Number of particles along each axis at `spacing` (m): as many whole cells as fit.
    pub fn lattice_size(&self, spacing: f32) -> (u32, u32) {
        if spacing.is_nan() || spacing <= 0.0 || !self.size.is_finite() {
            return (0, 0);
        }
        let count =
            |length: f32| ((length / spacing + 1e-4).floor().max(0.0) as u64).min(1 << 24) as u32;
        (count(self.size.x), count(self.size.y))
    }

    /// Particle positions, row by row from the bottom: cell centres of a lattice of `spacing`
    /// (m) plus jitter. Empty for a non-positive spacing or size.
    pub fn positions(&self, spacing: f32) -> Vec<Vec2> {
        let (columns, rows) = self.lattice_size(spacing);
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let amplitude = self.jitter.clamp(0.0, 0.45) * spacing;
        let mut out = Vec::with_capacity(columns as usize * rows as usize);
        for j in 0..rows {
            for i in 0..columns {
                let mut p = self.min + (Vec2::new(i as f32, j as f32) + 0.5) * spacing;
                if amplitude > 0.0 {
                    p += Vec2::new(
                        rng.random_range(-amplitude..=amplitude),
                        rng.random_range(-amplitude..=amplitude),
                    );
                }
                out.push(p);
            }
        }
        out
    }

    /// Particle positions for `params`: the lattice of [`positions`](Self::positions) at the
    /// particle spacing, with rows packed hydrostatically if [`hydrostatic`](Self::hydrostatic)
    /// is set and gravity points down. The bottom row keeps its place; each row's spacing is
    /// `Δx ρ₀/ρ(d)`, where `ρ(d)` is the density the Tait equation of state gives at the
    /// hydrostatic pressure `ρ₀ g d` of the row's depth `d`.
    pub fn positions_for(&self, params: &SphParams) -> Vec<Vec2> {
        let spacing = params.particle_spacing;
        let mut positions = self.positions(spacing);
        let g = params.gravity;
        let downward = g.y < 0.0 && g.x.abs() <= 1e-3 * g.y.abs();
        // An incompressible solver keeps rest density at any depth: nothing to pack.
        let compressible = params.solver == crate::sim::config::PressureSolver::Wcsph;
        if !(self.hydrostatic && downward && compressible && params.validate().is_ok()) {
            return positions;
        }
        let (columns, rows) = self.lattice_size(spacing);
        let stiffness = params.tait_stiffness();
        let row_spacing = |row: u32| {
            let depth = (rows - row) as f32 * spacing - 0.5 * spacing;
            let pressure = params.rest_density * -g.y * depth;
            spacing / (1.0 + pressure / stiffness).powf(1.0 / params.eos_exponent)
        };
        // Shift every row down by what the rows below it gave up.
        let mut shift = 0.0f32;
        let mut below = row_spacing(0);
        shift += 0.5 * (spacing - below);
        for row in 0..rows {
            if row > 0 {
                let here = row_spacing(row);
                shift += spacing - 0.5 * (below + here);
                below = here;
            }
            let start = (row * columns) as usize;
            for p in &mut positions[start..start + columns as usize] {
                p.y -= shift;
            }
        }
        positions
    }

    /// Spawns the block into `world` with the [`SphParams`] there (see
    /// [`positions_for`](Self::positions_for)) and returns the entities in lattice order.
    pub fn spawn(&self, world: &mut World) -> Vec<Entity> {
        let params = world
            .get_resource::<SphParams>()
            .cloned()
            .unwrap_or_default();
        let positions = self.positions_for(&params);
        world
            .spawn_batch(positions.into_iter().map(|p| (FluidParticle, Position(p))))
            .collect()
    }
}

impl Command for FluidBlock {
    type Out = ();

    fn apply(self, world: &mut World) {
        self.spawn(world);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_fills_the_rectangle() {
        let block = FluidBlock::dam_break(0.2, 0.4).with_jitter(0.0);
        let p = block.positions(0.01);
        assert_eq!(p.len(), 20 * 40);
        assert_eq!(p[0], Vec2::new(0.005, 0.005));
        assert!(
            p.iter()
                .all(|q| q.x > 0.0 && q.x < 0.2 && q.y > 0.0 && q.y < 0.4)
        );
    }

    #[test]
    fn jitter_is_seeded_and_bounded() {
        let block = FluidBlock::new(Vec2::new(1.0, 2.0), Vec2::splat(0.1)).with_jitter(0.2);
        let a = block.with_seed(5).positions(0.01);
        let b = block.with_seed(5).positions(0.01);
        let c = block.with_seed(6).positions(0.01);
        assert_eq!(a, b);
        assert_ne!(a, c);
        let perfect = block.with_jitter(0.0).positions(0.01);
        for (p, q) in a.iter().zip(&perfect) {
            let d = (*p - *q).abs();
            assert!(d.x <= 0.002 + 1e-6 && d.y <= 0.002 + 1e-6);
        }
    }

    #[test]
    fn hydrostatic_rows_pack_with_depth() {
        let params = SphParams {
            particle_spacing: 0.01,
            ..SphParams::water_wcsph()
        };
        let block = FluidBlock::dam_break(0.05, 0.5).with_jitter(0.0);
        let flat = block.with_hydrostatic(false).positions_for(&params);
        let packed = block.positions_for(&params);
        assert_eq!(flat, block.positions(0.01));
        assert_eq!(flat.len(), packed.len());
        let row_y = |p: &[Vec2], row: usize| p[row * 5].y;
        // The bottom row sits half a (packed) row above the floor, the rows get closer with
        // depth, and the top sinks by about the mean compression.
        assert!(row_y(&packed, 0) < 0.005 && row_y(&packed, 0) > 0.0049);
        let gap = |row: usize| row_y(&packed, row + 1) - row_y(&packed, row);
        assert!(gap(0) < gap(25) && gap(25) < gap(48));
        assert!(gap(48) < 0.01 && gap(0) > 0.0099 * (1.0 - 0.02));
        let sink = row_y(&flat, 49) - row_y(&packed, 49);
        // Mean pressure ρ₀ g H/2 over B = ρ₀c²/γ, divided by γ again for the strain.
        let c = params.speed_of_sound;
        let expected = 0.5 * 9.81 * 0.5 * 0.5 / (c * c);
        assert!(
            (sink / expected - 1.0).abs() < 0.1,
            "sank {sink} m, expected {expected} m"
        );
    }

    #[test]
    fn bad_sizes_give_no_particles() {
        assert!(FluidBlock::dam_break(-1.0, 1.0).positions(0.01).is_empty());
        assert!(FluidBlock::dam_break(1.0, 1.0).positions(0.0).is_empty());
        assert!(
            FluidBlock::dam_break(f32::NAN, 1.0)
                .positions(0.1)
                .is_empty()
        );
    }
}
