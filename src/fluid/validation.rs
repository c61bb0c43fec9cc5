//! The Martin & Moyce (1952) dam break as a reusable check: the experiment's surge-front data,
//! the scene in SPH units, and a headless run on [`SliceFluid`] that records the front. The
//! physics tests assert on it (through the ECS) and the `validate` example charts it. Pure, no
//! ECS.

use super::boundary::Tank;
use super::params::{STANDARD_GRAVITY, SphParams};
use super::slices::SliceFluid;
use super::spawn::FluidBlock;

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
        let mut fluid = SliceFluid::new(constants, positions, &[]);
        let scale = self.time_scale();
        let mut history = Vec::new();
        while (fluid.clock.time as f32) * scale < Self::END {
            fluid.advance(tick);
            let front = self.front(fluid.position.iter().copied());
            history.push((fluid.clock.time as f32 * scale, front));
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
