//! Reusable physical checks, headless on [`SliceFluid`]: the Martin & Moyce (1952) dam break
//! (the experiment's surge-front data, the scene in SPH units, a run that records the front),
//! a resting layer of any depth and spacing measured against hydrostatics, and a floating box.
//! The physics tests assert on them (`#[path]` from `tests/`) and the `validate` and `resting`
//! examples print and chart them (`mod validation;`). Not part of the library: it runs on the
//! crate's public plain-vector driver, as any user's check would. No ECS.

#![allow(dead_code, reason = "each example uses a different part")]

use bevy::math::Vec2;
use bevy_sph2d::fluid::{STANDARD_GRAVITY, SphParams, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::slices::SliceFluid;

/// The largest length among `vectors`.
fn max_length(vectors: &[Vec2]) -> f32 {
    vectors
        .iter()
        .fold(0.0f32, |m, a| m.max(a.length_squared()))
        .sqrt()
}

/// Martin & Moyce (1952), Phil. Trans. R. Soc. A 244, fig. 3, a column of width `a` and height
/// `2a` (n² = 2, a = 2.25 in): dimensionless time `t √(2g/a)` and surge front position `Z/a`.
pub const MARTIN_MOYCE: [(f32, f32); 8] = [
    (0.832, 1.217),
    (1.219, 1.474),
    (1.997, 2.292),
    (2.547, 2.995),
    (3.345, 4.134),
    (4.034, 4.944),
    (4.418, 5.881),
    (5.091, 6.980),
];

/// The dam break of the comparison: a water column `a` wide and `2a` high against the left wall
/// of a tank `10a × 3a`, `a / spacing` particles across.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MartinMoyce {
    /// Column width `a`, m.
    pub column_width: f32,
    /// Particles across the column.
    pub particles_across: u32,
}

impl Default for MartinMoyce {
    /// `a = 5 cm`, 20 particles across (800 particles).
    fn default() -> Self {
        Self {
            column_width: 0.05,
            particles_across: 20,
        }
    }
}

impl MartinMoyce {
    /// The run ends at this dimensionless time, past the experiment's last point.
    pub const END: f32 = 5.2;

    /// `base` with this scene's spacing, tank and speed of sound (for WCSPH, `20 √(2ga)`).
    pub fn params(&self, base: SphParams) -> SphParams {
        let a = self.column_width;
        SphParams {
            particle_spacing: a / self.particles_across as f32,
            speed_of_sound: SphParams::speed_of_sound_for_height(2.0 * a),
            tank: Some(Tank::new(10.0 * a, 3.0 * a)),
            ..base
        }
    }

    /// The water column.
    pub fn block(&self) -> FluidBlock {
        let a = self.column_width;
        FluidBlock::dam_break(a, 2.0 * a).with_seed(7)
    }

    /// `√(2g/a)`, 1/s: simulated seconds times this is the experiment's time.
    pub fn time_scale(&self) -> f32 {
        (2.0 * STANDARD_GRAVITY / self.column_width).sqrt()
    }

    /// The surge front `Z/a` of `positions`: the farthest particle along the floor.
    pub fn front(&self, positions: impl IntoIterator<Item = bevy::math::Vec2>) -> f32 {
        positions.into_iter().map(|p| p.x).fold(0.0, f32::max) / self.column_width
    }

    /// Runs the scene on `base` (headless, on plain slices) until [`END`](Self::END), ticking
    /// at `tick` seconds, and returns the front after every tick as `(t*, Z/a)`. `None` if
    /// `base` does not validate.
    pub fn run(&self, base: SphParams, tick: f64) -> Option<Vec<(f32, f32)>> {
        let params = self.params(base);
        let constants = params.constants().ok()?;
        let positions = self.block().positions_for(&params);
        let mut fluid = SliceFluid::new(constants, positions);
        let scale = self.time_scale();
        let mut history = Vec::new();
        while (fluid.clock().time as f32) * scale < Self::END {
            fluid.advance(tick);
            let front = self.front(fluid.position.iter().copied());
            history.push((fluid.clock().time as f32 * scale, front));
        }
        Some(history)
    }
}

/// `history`'s front (linear between samples) at dimensionless time `t`; the first sample's
/// before it, the last sample's after it.
pub fn front_at(history: &[(f32, f32)], t: f32) -> f32 {
    let Some(k) = history.iter().position(|&(ti, _)| ti >= t) else {
        return history.last().map_or(0.0, |h| h.1);
    };
    if k == 0 {
        return history[0].1;
    }
    let ((t0, z0), (t1, z1)) = (history[k - 1], history[k]);
    z0 + (z1 - z0) * (t - t0) / (t1 - t0)
}

/// For each point of [`MARTIN_MOYCE`]: `(t*, simulated Z/a, measured Z/a, simulated/measured)`.
pub fn compare(history: &[(f32, f32)]) -> Vec<(f32, f32, f32, f32)> {
    MARTIN_MOYCE
        .iter()
        .map(|&(t, measured)| {
            let z = front_at(history, t);
            (t, z, measured, z / measured)
        })
        .collect()
}

/// A layer of water at rest in a tank, `depth` deep and `width` wide, at `spacing`: what the
/// pressure solve must hold at every depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestingLayer {
    /// Water depth `D`, m.
    pub depth: f32,
    /// Tank width, m.
    pub width: f32,
    /// Particle spacing, m.
    pub spacing: f32,
}

/// How a [`RestingLayer`] settled: per-particle pressure and density averaged over the last
/// part of the run, the speeds at its end.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LayerReport {
    /// Particles.
    pub particles: usize,
    /// Particles from the floor to the surface.
    pub particles_deep: u32,
    /// The least-squares slope of the averaged pressure against height below the surface layer,
    /// as a multiple of `ρ₀g` (hydrostatic: 1).
    pub slope: f32,
    /// The largest compression `ρ/ρ₀ − 1` of the averaged density below the surface layer,
    /// fraction (a free surface reads below rest density by design of summation density, so
    /// only compression counts, as in the fluid's stats).
    pub compression: f32,
    /// The fastest particle at the end, as a fraction of the gravity-wave speed `√(gD)`.
    pub fastest: f32,
    /// Mean iterations of the density solve per sub-step.
    pub density_iterations: f32,
    /// Mean iterations of the divergence solve per sub-step.
    pub divergence_iterations: f32,
}

impl RestingLayer {
    /// A layer `depth` deep (m), `width` wide (m), at `spacing` (m).
    pub fn new(depth: f32, width: f32, spacing: f32) -> Self {
        Self {
            depth,
            width,
            spacing,
        }
    }

    /// Particles from the floor to the surface.
    pub fn particles_deep(&self) -> u32 {
        self.block().lattice_size(self.spacing).1
    }

    /// `base` with this layer's spacing, a tank 1.6 times as high as the water, and (for WCSPH)
    /// the speed of sound for the depth.
    pub fn params(&self, base: SphParams) -> SphParams {
        SphParams {
            particle_spacing: self.spacing,
            speed_of_sound: SphParams::speed_of_sound_for_height(self.depth),
            tank: Some(Tank::new(self.width, 1.6 * self.depth)),
            ..base
        }
    }

    /// The water.
    pub fn block(&self) -> FluidBlock {
        FluidBlock::new(
            bevy::math::Vec2::ZERO,
            bevy::math::Vec2::new(self.width, self.depth),
        )
        .with_seed(2)
    }

    /// Runs the layer on `base` for `duration` seconds in ticks of `tick` seconds, averaging
    /// pressure and density over the last `average` seconds. `None` if `base` does not validate.
    pub fn run(
        &self,
        base: SphParams,
        duration: f64,
        average: f64,
        tick: f64,
    ) -> Option<LayerReport> {
        let params = self.params(base);
        let constants = params.constants().ok()?;
        let positions = self.block().positions_for(&params);
        let fluid = SliceFluid::new(constants, positions);
        let mut report = settle(fluid, duration, average, tick);
        report.particles_deep = self.particles_deep();
        Some(report)
    }
}

/// The demo's dam break settling: a column 0.3 of the tank wide and 0.6 high against the left
/// wall of [`SphParams::water`]'s 2 m × 1.2 m tank, about `particles` particles, run until the
/// water rests (its settled depth is about 32 spacings at 10,000 particles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamBreakSettling {
    /// About how many particles.
    pub particles: u32,
}

impl DamBreakSettling {
    /// `base` with the spacing that gives about [`particles`](Self::particles) particles.
    pub fn params(&self, base: SphParams) -> SphParams {
        let tank = base.tank.unwrap_or(Tank::new(2.0, 1.2));
        let area = 0.3 * tank.width * 0.6 * tank.height;
        let spacing = (area / self.particles.max(1) as f32).sqrt();
        SphParams {
            particle_spacing: spacing,
            speed_of_sound: SphParams::speed_of_sound_for_height(0.6 * tank.height),
            tank: Some(tank),
            ..base
        }
    }

    /// Runs it for `duration` seconds in ticks of `tick`, averaging over the last `average`.
    /// `None` if `base` does not validate.
    pub fn run(
        &self,
        base: SphParams,
        duration: f64,
        average: f64,
        tick: f64,
    ) -> Option<LayerReport> {
        let params = self.params(base);
        let tank = params.tank?;
        let constants = params.constants().ok()?;
        let block = FluidBlock::dam_break(0.3 * tank.width, 0.6 * tank.height).with_seed(7);
        let fluid = SliceFluid::new(constants, block.positions_for(&params));
        Some(settle(fluid, duration, average, tick))
    }
}

/// A box released at the still-water level of a [`RestingLayer`], free to heave, sway and roll
/// under gravity and the fluid's force and torque ([`MovingSolid::load`](bevy_sph2d::slices::MovingSolid::load)), stepped with them
/// once a tick (semi-implicit Euler, as a rigid-body engine would): Archimedes says it floats
/// with its bottom `relative_density × height` under the water.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloatingBox {
    /// The water.
    pub layer: RestingLayer,
    /// Box width and height, m.
    pub size: bevy::math::Vec2,
    /// Density over the fluid's rest density.
    pub relative_density: f32,
    /// Angle at release, rad.
    pub angle: f32,
}

/// How a [`FloatingBox`] settled, averaged over the last part of the run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FloatReport {
    /// How deep the box's lowest corner lies under the water level, m (the level of the free
    /// surface away from the box, [`water_level`]).
    pub draft: f32,
    /// Archimedes' draft of the box upright, `relative_density × height`, m.
    pub expected_draft: f32,
    /// Angle at the end, rad.
    pub angle: f32,
    /// Submerged fraction the fluid reports at the end.
    pub submerged_fraction: f32,
    /// Largest box speed over the averaging, m/s.
    pub body_speed: f32,
    /// Fluid particles inside the box at the end.
    pub inside: usize,
}

impl FloatingBox {
    /// Runs it on `base` for `duration` seconds in ticks of `tick`, averaging over the last
    /// `average`. `None` if `base` does not validate or the box cannot be sampled.
    pub fn run(
        &self,
        base: SphParams,
        duration: f64,
        average: f64,
        tick: f64,
    ) -> Option<FloatReport> {
        use bevy_sph2d::fluid::{Pose, SolidShape, coupled_acceleration};
        use bevy_sph2d::slices::{MovingSolid, SolidMotion};
        let params = self.layer.params(base);
        let c = params.constants().ok()?;
        let shape = SolidShape::rectangle(self.size.x, self.size.y);
        let mut solid = MovingSolid::new(shape, bevy::math::Vec2::ZERO, c.spacing, c.wall_layers)?;
        let width = self.layer.width;
        let start = Pose {
            position: bevy::math::Vec2::new(0.5 * width, self.layer.depth),
            angle: self.angle,
        };
        solid.set_motion(SolidMotion {
            pose: start,
            ..Default::default()
        });
        let clear = |p: &bevy::math::Vec2| solid.distance(*p).0 > 0.5 * c.spacing;
        let positions: Vec<_> = self
            .layer
            .block()
            .positions_for(&params)
            .into_iter()
            .filter(clear)
            .collect();
        let mut fluid = SliceFluid::new(c, positions);
        fluid.solids_mut().push(solid);
        let (w, h) = (self.size.x, self.size.y);
        let mass = self.relative_density * c.rest_density * w * h;
        let inertia = mass * (w * w + h * h) / 12.0;
        let mut report = FloatReport {
            expected_draft: self.relative_density * h,
            ..Default::default()
        };
        let (mut drafts, mut samples) = (0.0f64, 0u32);
        while fluid.clock().time < duration - 1e-9 {
            fluid.advance(tick);
            let body = &fluid.solids()[0];
            let (load, mut motion) = (body.load(), body.motion());
            let dt = tick as f32;
            let (added, added_inertia) = body.added_mass(c.rest_density);
            let force = load.force + mass * c.gravity;
            let a = coupled_acceleration(mass, added, force);
            let alpha = coupled_acceleration(inertia, added_inertia, load.torque);
            motion.velocity += a * dt;
            motion.angular_velocity += alpha * dt;
            if !fluid.set_solid_motion(0, motion) || motion.velocity.length() > 100.0 {
                break; // Thrown out of the water: the report shows it.
            }
            if fluid.clock().time >= duration - average - 1e-9 {
                let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
                let bottom = corners
                    .map(|(x, y)| motion.pose.apply(bevy::math::Vec2::new(x * w, y * h)).y)
                    .into_iter()
                    .fold(f32::INFINITY, f32::min);
                let level = water_level(&fluid, motion.pose.position.x, w);
                drafts += (level - bottom) as f64;
                samples += 1;
                report.body_speed = report.body_speed.max(motion.velocity.length());
            }
        }
        let body = &fluid.solids()[0];
        report.draft = (drafts / samples.max(1) as f64) as f32;
        report.angle = body.motion().pose.angle;
        report.submerged_fraction = body.load().submerged_fraction;
        report.inside = fluid
            .position
            .iter()
            .filter(|p| body.distance(**p).0 < -0.1 * c.spacing)
            .count();
        Some(report)
    }
}

/// The free surface of a layer in a tank, m: the top particle of each column one spacing wide,
/// plus half a spacing (as a wall's surface lies half a spacing from its particles), averaged
/// over the columns farther than `width` from `x` (where a body floats).
pub fn water_level(fluid: &SliceFluid, x: f32, width: f32) -> f32 {
    let c = fluid.constants();
    let Some(tank) = c.tank else {
        return 0.0;
    };
    let columns = (tank.width / c.spacing).ceil().max(1.0) as usize;
    let mut top = vec![f32::NEG_INFINITY; columns];
    for p in &fluid.position {
        let k = ((p.x / c.spacing) as usize).min(columns - 1);
        top[k] = top[k].max(p.y);
    }
    let (sum, count) = top
        .iter()
        .enumerate()
        .filter(|(k, y)| {
            let centre = (*k as f32 + 0.5) * c.spacing;
            y.is_finite() && (centre - x).abs() > width
        })
        .fold((0.0f64, 0u32), |(s, n), (_, y)| (s + *y as f64, n + 1));
    (sum / count.max(1) as f64) as f32 + 0.5 * c.spacing
}

/// Runs `fluid` in a tank for `duration` seconds in ticks of `tick` seconds and measures how
/// close it came to hydrostatic rest, with pressure and density averaged per particle over the
/// last `average` seconds (see [`LayerReport`]; `particles_deep` is the settled depth in
/// spacings).
pub fn settle(mut fluid: SliceFluid, duration: f64, average: f64, tick: f64) -> LayerReport {
    let c = *fluid.constants();
    let n = fluid.len();
    let mut sums = vec![[0.0f64; 3]; n];
    let mut samples = 0u32;
    while fluid.clock().time < duration - 1e-9 {
        fluid.advance(tick);
        if fluid.clock().time >= duration - average - 1e-9 {
            samples += 1;
            for (sum, k) in sums.iter_mut().zip(0..n) {
                sum[0] += fluid.pressure[k] as f64;
                sum[1] += fluid.density[k] as f64;
                sum[2] += fluid.position[k].y as f64;
            }
        }
    }
    let samples = samples.max(1) as f64;
    let mean: Vec<[f64; 3]> = sums.iter().map(|s| s.map(|v| v / samples)).collect();
    let surface = fluid.position.iter().map(|p| p.y).fold(0.0, f32::max) as f64;
    let below = surface - 3.0 * c.spacing as f64;
    let interior: Vec<&[f64; 3]> = mean.iter().filter(|m| m[2] < below).collect();
    let rho_g = (c.rest_density * c.gravity.length()) as f64;
    let slope = -least_squares_slope(interior.iter().map(|m| (m[2], m[0]))) / rho_g;
    let compression = interior
        .iter()
        .map(|m| m[1] / c.rest_density as f64 - 1.0)
        .fold(0.0, f64::max);
    let fastest = max_length(&fluid.velocity);
    let depth = surface as f32 + 0.5 * c.spacing;
    let steps = fluid.clock().total_substeps.max(1) as f32;
    let density_iterations = fluid.iterations().total_density as f32 / steps;
    LayerReport {
        particles: n,
        particles_deep: (depth / c.spacing).round() as u32,
        slope: slope as f32,
        compression: compression as f32,
        fastest: fastest / (c.gravity.length() * depth).sqrt(),
        density_iterations,
        divergence_iterations: fluid.iterations().total as f32 / steps - density_iterations,
    }
}

/// The least-squares slope `dp/dy` of the points `(y, p)` (zero for fewer than two heights).
fn least_squares_slope(points: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let count = points.clone().count().max(1) as f64;
    let (my, mp) = points
        .clone()
        .fold((0.0, 0.0), |(a, b), (y, p)| (a + y / count, b + p / count));
    let (syy, syp) = points.fold((0.0, 0.0), |(a, b), (y, p)| {
        (a + (y - my) * (y - my), b + (y - my) * (p - mp))
    });
    if syy > 0.0 { syp / syy } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_at_interpolates_and_clamps() {
        let history = [(1.0, 2.0), (2.0, 4.0)];
        assert_eq!(front_at(&history, 1.5), 3.0);
        assert_eq!(front_at(&history, 0.0), 2.0);
        assert_eq!(front_at(&history, 9.0), 4.0);
    }
}
