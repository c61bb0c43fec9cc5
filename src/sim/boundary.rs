//! The walls: the rectangular tank, sampled into fixed boundary particles, and the collision
//! projection that keeps fluid particles in it. Solids inside the fluid, still or moving, are
//! [`solid`](super::solid)'s.
//!
//! Boundary particles sit on the same lattice spacing as the fluid, in as many layers as the
//! kernel support needs, so a fluid particle next to a wall sees a full neighbourhood: its summed
//! density stays at rest density, and the wall's pressure (extrapolated from the fluid each
//! sub-step, Adami et al. 2012) pushes back exactly as hard as hydrostatics requires. The
//! geometric projection in [`Tank::confine`] is only a safety net.

use bevy::math::Vec2;
use bevy::reflect::Reflect;

/// The fluid's container: inner corners at `(0, 0)` and `(width, height)`, m, y up; closed on
/// all four sides.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct Tank {
    /// Inner width, m.
    pub width: f32,
    /// Inner height, m.
    pub height: f32,
}

impl Tank {
    /// A tank of the given inner width and height, m.
    pub const fn new(width: f32, height: f32) -> Self {
        Self { width, height }
    }

    /// Whether `p` lies inside the tank or within `margin` (m) of it.
    pub fn contains(&self, p: Vec2, margin: f32) -> bool {
        p.x >= -margin
            && p.y >= -margin
            && p.x <= self.width + margin
            && p.y <= self.height + margin
    }

    /// Inner size as a vector, m.
    pub fn size(&self) -> Vec2 {
        Vec2::new(self.width, self.height)
    }

    /// Samples the walls, lid and corners into boundary particles: `layers` layers of spacing
    /// `spacing` (m) outside the inner rectangle, the first half a spacing from the wall surface.
    /// Along each wall the particles are spread evenly, so their spacing is the nearest to
    /// `spacing` that fits the wall's length.
    pub fn sample(&self, spacing: f32, layers: u32, out: &mut Vec<Vec2>) {
        let (columns, rows) = self.wall_counts(spacing);
        let dx = self.width / columns as f32;
        let dy = self.height / rows as f32;
        let outside = |k: u32| (k as f32 + 0.5) * spacing;
        for k in 0..layers {
            let (below, above) = (-outside(k), self.height + outside(k));
            let xs = (0..columns)
                .map(|i| (i as f32 + 0.5) * dx)
                .chain((0..layers).flat_map(|c| [-outside(c), self.width + outside(c)]));
            for x in xs {
                out.push(Vec2::new(x, below));
                out.push(Vec2::new(x, above));
            }
            let (left, right) = (-outside(k), self.width + outside(k));
            for j in 0..rows {
                let y = (j as f32 + 0.5) * dy;
                out.push(Vec2::new(left, y));
                out.push(Vec2::new(right, y));
            }
        }
    }

    fn wall_counts(&self, spacing: f32) -> (u64, u64) {
        let columns = (self.width / spacing).round().max(1.0) as u64;
        let rows = (self.height / spacing).round().max(1.0) as u64;
        (columns, rows)
    }

    /// Number of boundary particles [`sample`](Self::sample) produces.
    pub fn sample_count(&self, spacing: f32, layers: u32) -> u64 {
        let (columns, rows) = self.wall_counts(spacing);
        let layers = layers as u64;
        2 * layers * (columns + 2 * layers) + 2 * layers * rows
    }

    /// Keeps a particle inside the tank: a position outside is put back on the wall and the
    /// outward part of the velocity is reflected with `restitution` (0 = stops, 1 = bounces).
    #[inline]
    pub fn confine(&self, position: &mut Vec2, velocity: &mut Vec2, restitution: f32) {
        confine_axis(&mut position.x, &mut velocity.x, self.width, restitution);
        confine_axis(&mut position.y, &mut velocity.y, self.height, restitution);
    }
}

/// [`Tank::confine`] along one axis, between 0 and `max`.
#[inline]
fn confine_axis(position: &mut f32, velocity: &mut f32, max: f32, restitution: f32) {
    let (limit, outward) = if *position < 0.0 {
        (0.0, -1.0)
    } else if *position > max {
        (max, 1.0)
    } else {
        return;
    };
    *position = limit;
    if *velocity * outward > 0.0 {
        *velocity *= -restitution;
    }
}

/// Most boundary particles one tank or one solid may need: a larger one is refused rather
/// than sampled (4 million particles are about 200 MB of walls).
pub const MAX_BOUNDARY_PARTICLES: u64 = 4_000_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tank_samples_every_layer_outside_the_walls() {
        let tank = Tank::new(1.0, 0.5);
        let mut pts = Vec::new();
        tank.sample(0.1, 3, &mut pts);
        assert_eq!(pts.len() as u64, tank.sample_count(0.1, 3));
        for p in &pts {
            let inside = p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 0.5;
            assert!(!inside, "{p} is inside the tank");
            assert!(p.x > -0.3 && p.x < 1.3 && p.y > -0.3 && p.y < 0.8);
        }
        // No two boundary particles coincide.
        for (i, a) in pts.iter().enumerate() {
            for b in &pts[i + 1..] {
                assert!(a.distance(*b) > 0.05, "{a} and {b} overlap");
            }
        }
    }

    #[test]
    fn confine_keeps_particles_inside_and_stops_them() {
        let tank = Tank::new(2.0, 1.0);
        let mut p = Vec2::new(-0.1, 1.3);
        let mut v = Vec2::new(-3.0, 2.0);
        tank.confine(&mut p, &mut v, 0.0);
        assert_eq!(p, Vec2::new(0.0, 1.0));
        assert_eq!(v, Vec2::ZERO);
        let mut p = Vec2::new(2.5, -0.2);
        let mut v = Vec2::new(1.0, -1.0);
        tank.confine(&mut p, &mut v, 0.5);
        assert_eq!(p, Vec2::new(2.0, 0.0));
        assert_eq!(v, Vec2::new(-0.5, 0.5));
    }
}
