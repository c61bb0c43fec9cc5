//! Walls and solid shapes: the rectangular tank and static circle and capsule shapes, sampled
//! into fixed boundary particles, plus the collision projection that keeps fluid particles out
//! of them.
//!
//! Boundary particles sit on the same lattice spacing as the fluid, in as many layers as the
//! kernel support needs, so a fluid particle next to a wall sees a full neighbourhood: its summed
//! density stays at rest density, and the wall's pressure (extrapolated from the fluid each
//! sub-step, Adami et al. 2012) pushes back exactly as hard as hydrostatics requires. The
//! geometric projection in [`Shape::push_out`] and [`Tank::confine`] is only a safety net.

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

/// The shape of a static solid inside the fluid (the fluid plugin's `Obstacle` component holds
/// one).
///
/// Give shapes a radius of at least one kernel support radius where possible: thinner ones
/// cannot hold a full layer of boundary particles, so fluid near them sees a little less density
/// (the collision projection still keeps it out).
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub enum Shape {
    /// A disc.
    Circle {
        /// Centre, m.
        center: Vec2,
        /// Radius, m.
        radius: f32,
    },
    /// A capsule: every point within `radius` of the segment from `start` to `end`.
    Segment {
        /// One end of the centre line, m.
        start: Vec2,
        /// The other end of the centre line, m.
        end: Vec2,
        /// Half thickness, m (0 gives a single row of boundary particles).
        radius: f32,
    },
}

/// Most boundary particles one tank or one solid may need: a larger one is refused rather
/// than sampled (4 million particles are about 200 MB of walls).
pub const MAX_BOUNDARY_PARTICLES: u64 = 4_000_000;

impl Shape {
    /// A disc of `radius` (m) around `center`.
    pub const fn circle(center: Vec2, radius: f32) -> Self {
        Self::Circle { center, radius }
    }

    /// A capsule of half thickness `radius` (m) around the segment `start`–`end`.
    pub const fn segment(start: Vec2, end: Vec2, radius: f32) -> Self {
        Self::Segment { start, end, radius }
    }

    /// Whether the solid is valid and its sampling at `spacing` (m), `layers` deep, needs at
    /// most `MAX_BOUNDARY_PARTICLES` (4 million): the walls sample only solids that fit.
    pub fn fits(&self, spacing: f32, layers: u32) -> bool {
        self.is_valid() && self.sample_count(spacing, layers) <= MAX_BOUNDARY_PARTICLES
    }

    /// About how many boundary particles [`sample`](Self::sample) makes at `spacing` (m),
    /// `layers` deep, counted without making them (so a huge solid costs nothing to refuse).
    pub fn sample_count(&self, spacing: f32, layers: u32) -> u64 {
        use core::f64::consts::{PI, TAU};
        let (radius, length) = match *self {
            Self::Circle { radius, .. } => (radius as f64, 0.0),
            Self::Segment { start, end, radius } => (radius as f64, start.distance(end) as f64),
        };
        let spacing = spacing as f64;
        let rows = (length / spacing).round().max(1.0);
        let mut count = 0.0f64;
        let mut core = true;
        for k in 0..layers {
            let d = radius - (k as f64 + 0.5) * spacing;
            if d < 0.5 * spacing {
                break;
            }
            core = k + 1 < layers;
            count += if length > 0.0 {
                2.0 * (rows + 1.0) + 2.0 * ((PI * d / spacing).round().max(1.0) - 1.0)
            } else {
                (TAU * d / spacing).round().max(3.0)
            };
        }
        if core {
            count += if length > 0.0 { rows + 1.0 } else { 1.0 };
        }
        count.min(u64::MAX as f64) as u64
    }

    /// Whether every coordinate is finite and radii are non-negative (a circle's positive).
    pub fn is_valid(&self) -> bool {
        match *self {
            Self::Circle { center, radius } => {
                center.is_finite() && radius.is_finite() && radius > 0.0
            }
            Self::Segment { start, end, radius } => {
                start.is_finite() && end.is_finite() && radius.is_finite() && radius >= 0.0
            }
        }
    }

    /// Signed distance from `p` to the surface (negative inside) and the outward unit normal at
    /// the closest surface point.
    #[inline]
    pub fn distance(&self, p: Vec2) -> (f32, Vec2) {
        let (axis_point, radius) = match *self {
            Self::Circle { center, radius } => (center, radius),
            Self::Segment { start, end, radius } => {
                let along = end - start;
                let len2 = along.length_squared();
                let t = if len2 > 0.0 {
                    ((p - start).dot(along) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (start + t * along, radius)
            }
        };
        let d = p - axis_point;
        let len = d.length();
        let normal = if len > 0.0 { d / len } else { Vec2::Y };
        (len - radius, normal)
    }

    /// Moves a particle that has entered the obstacle back onto its surface and reflects the
    /// inward part of its velocity with `restitution`.
    #[inline]
    pub fn push_out(&self, position: &mut Vec2, velocity: &mut Vec2, restitution: f32) {
        let (distance, normal) = self.distance(*position);
        if distance < 0.0 {
            *position -= distance * normal;
            let vn = velocity.dot(normal);
            if vn < 0.0 {
                *velocity -= (1.0 + restitution) * vn * normal;
            }
        }
    }

    /// Samples the solid into boundary particles: rings (or parallel rows) `spacing` apart,
    /// from half a spacing under the surface inwards, at most `layers` deep; a solid thinner
    /// than that gets its centre point (or centre line) too.
    pub fn sample(&self, spacing: f32, layers: u32, out: &mut Vec<Vec2>) {
        use core::f32::consts::{PI, TAU};
        let (radius, start, end) = match *self {
            Self::Circle { center, radius } => (radius, center, center),
            Self::Segment { start, end, radius } => (radius, start, end),
        };
        let along = end - start;
        let length = along.length();
        let tangent = if length > 0.0 {
            along / length
        } else {
            Vec2::X
        };
        let normal_angle = tangent.perp().to_angle();
        let rows = (length / spacing).round().max(1.0) as usize;

        let mut offsets = Vec::new();
        let mut core = true;
        for k in 0..layers {
            let d = radius - (k as f32 + 0.5) * spacing;
            if d < 0.5 * spacing {
                break;
            }
            offsets.push(d);
            if k + 1 == layers {
                core = false;
            }
        }
        for d in offsets {
            if length > 0.0 {
                for i in 0..=rows {
                    let p = start + (i as f32 / rows as f32) * along;
                    out.push(p + d * tangent.perp());
                    out.push(p - d * tangent.perp());
                }
                // Half rings round both ends, without the end points the rows placed.
                let arcs = ((PI * d) / spacing).round().max(1.0) as usize;
                for (centre, from) in [(end, normal_angle - PI), (start, normal_angle)] {
                    for i in 1..arcs {
                        let angle = from + PI * i as f32 / arcs as f32;
                        out.push(centre + d * Vec2::from_angle(angle));
                    }
                }
            } else {
                let ring = ((TAU * d) / spacing).round().max(3.0) as usize;
                for i in 0..ring {
                    out.push(start + d * Vec2::from_angle(TAU * i as f32 / ring as f32));
                }
            }
        }
        if core {
            if length > 0.0 {
                for i in 0..=rows {
                    out.push(start + (i as f32 / rows as f32) * along);
                }
            } else {
                out.push(start);
            }
        }
    }
}

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

    #[test]
    fn obstacles_push_particles_out() {
        let circle = Shape::circle(Vec2::new(1.0, 1.0), 0.2);
        let mut p = Vec2::new(1.05, 1.0);
        let mut v = Vec2::new(-1.0, 0.3);
        circle.push_out(&mut p, &mut v, 0.0);
        assert!((p - Vec2::new(1.2, 1.0)).length() < 1e-6);
        assert!(v.x.abs() < 1e-6 && (v.y - 0.3).abs() < 1e-6);

        let capsule = Shape::segment(Vec2::ZERO, Vec2::new(1.0, 0.0), 0.05);
        let mut p = Vec2::new(0.5, -0.01);
        let mut v = Vec2::new(0.0, 1.0);
        capsule.push_out(&mut p, &mut v, 1.0);
        assert!((p - Vec2::new(0.5, -0.05)).length() < 1e-6);
        assert!((v - Vec2::new(0.0, -1.0)).length() < 1e-6);
        assert!(capsule.distance(Vec2::new(1.2, 0.0)).0 - 0.15 < 1e-6);
    }

    #[test]
    fn obstacle_samples_lie_inside_and_are_spaced() {
        for obstacle in [
            Shape::circle(Vec2::new(0.3, 0.4), 0.25),
            Shape::segment(Vec2::new(0.0, 0.0), Vec2::new(0.6, 0.3), 0.12),
            Shape::segment(Vec2::new(0.0, 0.0), Vec2::new(0.0, 0.5), 0.0),
        ] {
            let mut pts = Vec::new();
            obstacle.sample(0.02, 3, &mut pts);
            assert!(pts.len() > 20, "{obstacle:?}: only {} particles", pts.len());
            for (i, p) in pts.iter().enumerate() {
                assert!(obstacle.distance(*p).0 <= 1e-5, "{obstacle:?}: {p} outside");
                for q in &pts[i + 1..] {
                    assert!(p.distance(*q) > 0.005, "{obstacle:?}: {p} and {q} overlap");
                }
            }
        }
    }

    #[test]
    fn a_solid_is_counted_before_it_is_sampled_and_a_huge_one_does_not_fit() {
        let shapes = [
            Shape::circle(Vec2::ZERO, 0.1),
            Shape::circle(Vec2::ZERO, 0.012),
            Shape::segment(Vec2::ZERO, Vec2::new(0.3, 0.1), 0.05),
            Shape::segment(Vec2::ZERO, Vec2::new(0.2, 0.0), 0.004),
        ];
        for shape in shapes {
            let mut points = Vec::new();
            shape.sample(0.01, 3, &mut points);
            assert_eq!(
                shape.sample_count(0.01, 3),
                points.len() as u64,
                "{shape:?}"
            );
            assert!(shape.fits(0.01, 3));
        }
        // Sampling this would take about 8 GB: it is counted, not sampled.
        let huge = Shape::circle(Vec2::ZERO, 1.0e9);
        assert!(huge.sample_count(0.01, 3) > MAX_BOUNDARY_PARTICLES);
        assert!(!huge.fits(0.01, 3));
    }
}
