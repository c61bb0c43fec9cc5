//! Rigid solids that move through the fluid (Akinci et al. 2012, "Versatile rigid-fluid
//! coupling for incompressible SPH").
//!
//! A solid's shape lives in its own frame and is sampled once into boundary particles on the
//! fluid's spacing ([`MovingSolid::new`]); each sub-step they are placed at the solid's pose and carry
//! its point velocity `v + ω × r` into the density, the pressure solves and the viscosity (see
//! [`Walls`](super::layout::Walls)). The force on a boundary particle is minus the force it
//! exerts on the fluid: the pressure solvers sum it pair by pair into [`MovingSolid::load`], averaged
//! over the tick, so momentum is exchanged exactly. Nothing here is an analytic buoyancy.

use super::boundary::MAX_BOUNDARY_PARTICLES;
use bevy::math::{Rot2, Vec2};
use bevy::reflect::Reflect;
use core::f32::consts::{PI, TAU};
use core::ops::Range;

/// One convex piece of a solid's shape, in the solid's own frame (m).
#[derive(Reflect, Debug, Clone, PartialEq)]
#[reflect(Debug, PartialEq)]
pub enum Part {
    /// A disc.
    Circle {
        /// Centre, m.
        center: Vec2,
        /// Radius, m.
        radius: f32,
    },
    /// Every point within `radius` of the segment from `start` to `end` (a segment: one row
    /// of boundary particles along it at zero radius).
    Capsule {
        /// One end of the centre line, m.
        start: Vec2,
        /// The other end, m.
        end: Vec2,
        /// Half thickness, m.
        radius: f32,
    },
    /// A convex polygon, corners counter-clockwise (a box is one with four).
    Polygon {
        /// Corners, m, counter-clockwise.
        vertices: Vec<Vec2>,
    },
}

impl Part {
    /// A `width` × `height` box (m) centred on `center`, turned by `angle` (rad).
    pub fn rectangle(center: Vec2, width: f32, height: f32, angle: f32) -> Self {
        let (hx, hy) = (0.5 * width, 0.5 * height);
        let rotation = Rot2::radians(angle);
        let corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)];
        Self::polygon(
            corners
                .map(|(x, y)| center + rotation * Vec2::new(x, y))
                .to_vec(),
        )
    }

    /// A convex polygon through `vertices` (either winding; stored counter-clockwise).
    pub fn polygon(mut vertices: Vec<Vec2>) -> Self {
        if shoelace(&vertices) < 0.0 {
            vertices.reverse();
        }
        Self::Polygon { vertices }
    }

    /// Whether every coordinate is finite and the part has an inside (but a segment): a
    /// positive radius for a circle, a radius of zero or more for a capsule (zero only with two
    /// distinct ends), a polygon of at least three corners, convex, with positive area.
    pub fn is_valid(&self) -> bool {
        match self {
            Self::Circle { center, radius } => {
                center.is_finite() && radius.is_finite() && *radius > 0.0
            }
            Self::Capsule { start, end, radius } => {
                let extent = *radius > 0.0 || start != end;
                start.is_finite()
                    && end.is_finite()
                    && radius.is_finite()
                    && *radius >= 0.0
                    && extent
            }
            Self::Polygon { vertices } => {
                let n = vertices.len();
                n >= 3
                    && vertices.iter().all(|v| v.is_finite())
                    && shoelace(vertices) > 0.0
                    && (0..n).all(|i| {
                        let (a, b, c) = (vertices[i], vertices[(i + 1) % n], vertices[(i + 2) % n]);
                        (b - a).perp_dot(c - b) >= 0.0
                    })
            }
        }
    }

    /// Area, m².
    pub fn area(&self) -> f32 {
        match self {
            Self::Circle { radius, .. } => PI * radius * radius,
            Self::Capsule { start, end, radius } => {
                2.0 * radius * start.distance(*end) + PI * radius * radius
            }
            Self::Polygon { vertices } => shoelace(vertices),
        }
    }

    /// Centre of area, m.
    pub fn centroid(&self) -> Vec2 {
        match self {
            Self::Circle { center, .. } => *center,
            Self::Capsule { start, end, .. } => 0.5 * (*start + *end),
            Self::Polygon { vertices } => polygon_centroid(vertices),
        }
    }

    /// Signed distance from `p` to the surface (negative inside) and the outward unit normal
    /// there (for a polygon, of the nearest side's line: exact inside, where it is used).
    pub fn distance(&self, p: Vec2) -> (f32, Vec2) {
        match self {
            Self::Circle { center, radius } => round_distance(*center, *radius, p),
            Self::Capsule { start, end, radius } => {
                let along = *end - *start;
                let len2 = along.length_squared();
                let t = if len2 > 0.0 {
                    ((p - *start).dot(along) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                round_distance(*start + t * along, *radius, p)
            }
            Self::Polygon { vertices } => {
                let n = vertices.len();
                (0..n)
                    .map(|i| {
                        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                        let normal = -(b - a).perp().normalize_or(Vec2::Y);
                        (normal.dot(p - a), normal)
                    })
                    .fold(
                        (f32::NEG_INFINITY, Vec2::Y),
                        |m, e| if e.0 > m.0 { e } else { m },
                    )
            }
        }
    }

    /// The part's area below the level line `y = level` (world, m) when placed at `pose`, m²
    /// (curves as 64-gons).
    pub fn area_below(&self, pose: Pose, level: f32) -> f32 {
        shoelace(&self.below(pose, level)).abs()
    }

    /// The part placed at `pose`, cut by the level line `y = level` (world, m): the convex
    /// polygon of its part below the line, in world coordinates, in order round it (curves as
    /// 64-gons; empty if none of it is below).
    pub fn below(&self, pose: Pose, level: f32) -> Vec<Vec2> {
        let corners = match self {
            Self::Polygon { vertices } => vertices.clone(),
            Self::Circle { radius, .. } => self.outline(TAU * radius / 64.0),
            Self::Capsule { start, end, radius } => {
                self.outline((2.0 * start.distance(*end) + TAU * radius) / 64.0)
            }
        };
        let world: Vec<Vec2> = corners.into_iter().map(|p| pose.apply(p)).collect();
        clip_below(&world, level)
    }

    /// Points round the outline, in order, about `spacing` (m) apart (to draw it; a capsule
    /// thinner than `spacing` gives its segment's ends, a circle that small nothing).
    pub fn outline(&self, spacing: f32) -> Vec<Vec2> {
        let mut points = Vec::new();
        if spacing > 0.0
            && !self.ring(0.0, spacing, &mut points)
            && let Self::Capsule { start, end, .. } = self
        {
            points.extend([*start, *end]);
        }
        points
    }

    /// Points on the outline moved `depth` (m) inwards, in order round it, about `spacing` (m)
    /// apart; `false` (and nothing added) where the part is too thin for it.
    fn ring(&self, depth: f32, spacing: f32, out: &mut Vec<Vec2>) -> bool {
        match self {
            Self::Circle { center, radius } => {
                let d = radius - depth;
                if d < 0.5 * spacing {
                    return false;
                }
                let n = ((TAU * d) / spacing).round().max(3.0) as usize;
                out.extend(
                    (0..n).map(|i| *center + d * Vec2::from_angle(TAU * i as f32 / n as f32)),
                );
                true
            }
            Self::Capsule { start, end, radius } => {
                let d = radius - depth;
                if d < 0.5 * spacing {
                    return false;
                }
                let along = *end - *start;
                let length = along.length();
                let tangent = along.normalize_or(Vec2::X);
                let normal = -tangent.perp();
                let perimeter = 2.0 * length + TAU * d;
                let n = (perimeter / spacing).round().max(3.0) as usize;
                out.extend((0..n).map(|i| {
                    let mut s = perimeter * i as f32 / n as f32;
                    if s < length {
                        return *start + s * tangent + d * normal;
                    }
                    s -= length;
                    if s < PI * d {
                        return *end + d * Vec2::from_angle(normal.to_angle() + s / d);
                    }
                    s -= PI * d;
                    if s < length {
                        return *end - s * tangent - d * normal;
                    }
                    s -= length;
                    *start + d * Vec2::from_angle((-normal).to_angle() + s / d)
                }));
                true
            }
            Self::Polygon { vertices } => match inset(vertices, depth) {
                Some(inner) => {
                    walk_outline(&inner, spacing, out);
                    true
                }
                None => false,
            },
        }
    }

    /// Samples the part: rings `spacing` apart from half a spacing under the surface, at most
    /// `layers` deep; a part thinner than that gets its centre (or centre line) too.
    fn sample(&self, spacing: f32, layers: u32, out: &mut Vec<Vec2>) {
        for k in 0..layers {
            if !self.ring((k as f32 + 0.5) * spacing, spacing, out) {
                match self {
                    Self::Capsule { start, end, .. } => {
                        let rows = (start.distance(*end) / spacing).round().max(1.0) as usize;
                        out.extend((0..=rows).map(|i| start.lerp(*end, i as f32 / rows as f32)));
                    }
                    _ => out.push(self.centroid()),
                }
                return;
            }
        }
    }

    /// Half the part's extent across its thinnest direction is at least this, m (bounds the
    /// sample count).
    fn bounding_radius(&self) -> f32 {
        match self {
            Self::Circle { center, radius } => center.length() + radius,
            Self::Capsule { start, end, radius } => start.length().max(end.length()) + radius,
            Self::Polygon { vertices } => vertices.iter().map(|v| v.length()).fold(0.0, f32::max),
        }
    }
}

/// Signed distance from `p` to the surface of the points within `radius` of `axis_point`
/// (negative inside), and the outward unit normal.
#[inline]
fn round_distance(axis_point: Vec2, radius: f32, p: Vec2) -> (f32, Vec2) {
    let d = p - axis_point;
    let len = d.length();
    let normal = if len > 0.0 { d / len } else { Vec2::Y };
    (len - radius, normal)
}

/// Twice the signed area of a polygon over two, m² (positive counter-clockwise).
/// The part of polygon `vertices` below `y = level` (Sutherland–Hodgman against one line).
fn clip_below(vertices: &[Vec2], level: f32) -> Vec<Vec2> {
    let n = vertices.len();
    let mut out = Vec::with_capacity(n + 2);
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        if a.y <= level {
            out.push(a);
        }
        if (a.y <= level) != (b.y <= level) {
            let t = (level - a.y) / (b.y - a.y);
            out.push(a + t * (b - a));
        }
    }
    out
}

fn shoelace(vertices: &[Vec2]) -> f32 {
    let n = vertices.len();
    0.5 * (0..n)
        .map(|i| vertices[i].perp_dot(vertices[(i + 1) % n]))
        .sum::<f32>()
}

/// Centre of area of a polygon, m.
fn polygon_centroid(vertices: &[Vec2]) -> Vec2 {
    let n = vertices.len();
    let area = shoelace(vertices);
    if area.abs() < f32::MIN_POSITIVE || n == 0 {
        return vertices.iter().copied().sum::<Vec2>() / n.max(1) as f32;
    }
    let sum: Vec2 = (0..n)
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            (a + b) * a.perp_dot(b)
        })
        .sum();
    sum / (6.0 * area)
}

/// A convex counter-clockwise polygon with every side moved `depth` inwards; `None` where a
/// side vanishes or turns round (the polygon is thinner than twice `depth`).
fn inset(vertices: &[Vec2], depth: f32) -> Option<Vec<Vec2>> {
    let n = vertices.len();
    let normal = |i: usize| {
        -(vertices[(i + 1) % n] - vertices[i])
            .perp()
            .normalize_or(Vec2::Y)
    };
    let inner: Vec<Vec2> = (0..n)
        .map(|i| {
            let (before, after) = (normal((i + n - 1) % n), normal(i));
            vertices[i] - depth * (before + after) / (1.0 + before.dot(after)).max(1e-3)
        })
        .collect();
    let keeps = (0..n).all(|i| {
        let old = vertices[(i + 1) % n] - vertices[i];
        let new = inner[(i + 1) % n] - inner[i];
        old.dot(new) > 1e-3 * old.length_squared()
    });
    keeps.then_some(inner)
}

/// Points round a closed polygon about `spacing` apart: each side from its first corner, spread
/// evenly along it (so a symmetric polygon is sampled symmetrically, with its corners).
fn walk_outline(vertices: &[Vec2], spacing: f32, out: &mut Vec<Vec2>) {
    let n = vertices.len();
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        let count = (a.distance(b) / spacing).round().max(1.0) as usize;
        out.extend((0..count).map(|k| a.lerp(b, k as f32 / count as f32)));
    }
}

/// A solid's shape in its own frame: one or more convex [`Part`]s (a compound).
#[derive(Reflect, Debug, Clone, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct SolidShape {
    /// The parts, in the solid's frame.
    pub parts: Vec<Part>,
}

impl SolidShape {
    /// A disc of `radius` (m) round the origin.
    pub fn circle(radius: f32) -> Self {
        Self::compound(vec![Part::Circle {
            center: Vec2::ZERO,
            radius,
        }])
    }

    /// A `width` × `height` box (m) centred on the origin.
    pub fn rectangle(width: f32, height: f32) -> Self {
        Self::compound(vec![Part::rectangle(Vec2::ZERO, width, height, 0.0)])
    }

    /// A capsule of half thickness `radius` round the segment `start`–`end` (m).
    pub fn capsule(start: Vec2, end: Vec2, radius: f32) -> Self {
        Self::compound(vec![Part::Capsule { start, end, radius }])
    }

    /// A convex polygon (m, either winding).
    pub fn polygon(vertices: Vec<Vec2>) -> Self {
        Self::compound(vec![Part::polygon(vertices)])
    }

    /// Several convex parts.
    pub fn compound(parts: Vec<Part>) -> Self {
        Self { parts }
    }

    /// Whether it has parts and every part is valid ([`Part::is_valid`]).
    pub fn is_valid(&self) -> bool {
        !self.parts.is_empty() && self.parts.iter().all(Part::is_valid)
    }

    /// Area, m² (overlapping parts count twice).
    pub fn area(&self) -> f32 {
        self.parts.iter().map(Part::area).sum()
    }

    /// Centre of area, m, in the solid's frame.
    pub fn centroid(&self) -> Vec2 {
        let area = self.area();
        if area <= 0.0 {
            // Segments alone: the mean of their midpoints.
            let n = self.parts.len().max(1) as f32;
            return self.parts.iter().map(Part::centroid).sum::<Vec2>() / n;
        }
        self.parts
            .iter()
            .map(|p| p.area() * p.centroid())
            .sum::<Vec2>()
            / area
    }

    /// Signed distance from `p` (solid's frame) to the nearest part's surface, negative inside
    /// one, and that surface's outward normal.
    pub fn distance(&self, p: Vec2) -> (f32, Vec2) {
        self.parts
            .iter()
            .map(|part| part.distance(p))
            .fold(
                (f32::INFINITY, Vec2::Y),
                |m, d| if d.0 < m.0 { d } else { m },
            )
    }

    /// About how many boundary particles sampling makes at `spacing` (m), `layers` deep, from
    /// the bounding radii alone (an upper bound, cheap for a huge shape).
    pub fn sample_bound(&self, spacing: f32, layers: u32) -> u64 {
        let rings = self.parts.iter().map(|part| {
            let r = part.bounding_radius() as f64;
            (core::f64::consts::TAU * r / spacing as f64 + 8.0) * (layers as f64 + 1.0)
        });
        rings.sum::<f64>().min(u64::MAX as f64) as u64
    }

    /// Whether the shape is valid and its sampling needs at most `MAX_BOUNDARY_PARTICLES` (4 million, the tank's own limit).
    pub fn fits(&self, spacing: f32, layers: u32) -> bool {
        self.is_valid() && self.sample_bound(spacing, layers) <= MAX_BOUNDARY_PARTICLES
    }
}

/// Where a solid is: the position of its frame's origin (m) and its rotation (rad).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct Pose {
    /// The frame's origin, m.
    pub position: Vec2,
    /// Rotation, rad, counter-clockwise.
    pub angle: f32,
}

impl Pose {
    /// A point of the solid's frame in the world, m.
    #[inline]
    pub fn apply(&self, local: Vec2) -> Vec2 {
        self.position + Rot2::radians(self.angle) * local
    }

    /// A world point in the solid's frame, m.
    #[inline]
    pub fn to_local(&self, world: Vec2) -> Vec2 {
        Rot2::radians(-self.angle) * (world - self.position)
    }
}

/// A solid's pose and velocities: the velocity of its centre of mass (m/s) and its angular
/// velocity (rad/s, counter-clockwise).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct SolidMotion {
    /// Pose.
    pub pose: Pose,
    /// Velocity of the centre of mass, m/s.
    pub velocity: Vec2,
    /// Angular velocity, rad/s.
    pub angular_velocity: f32,
}

/// What the fluid does to a solid, over the last tick.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct SolidLoad {
    /// The fluid's force (pressure and viscosity), N per metre of depth, averaged over the
    /// tick's sub-steps.
    pub force: Vec2,
    /// Its torque about the centre of mass, N·m per metre, counter-clockwise.
    pub torque: f32,
    /// Area under water, m² (a volume per metre of depth).
    pub submerged_area: f32,
    /// Fraction of the area under water, 0 to 1.
    pub submerged_fraction: f32,
}

/// How a solid that a rigid-body step moves (a dynamic body) answers the fluid within a tick:
/// after each sub-step its velocities take the sub-step's fluid force and torque as the body's
/// step will, `(m + mₐ) a = F + m g` ([`coupled_acceleration`]), plus the acceleration its
/// contacts gave it over the last tick, so that the fluid sees the body it pushes slow down
/// (without it, a body is carried at its velocity through the whole tick, and the film it
/// squeezes against a wall pushes back with the force that would stop it in one sub-step).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct SolidResponse {
    /// Mass, kg/m.
    pub mass: f32,
    /// Moment of inertia about the centre of mass, kg·m.
    pub inertia: f32,
    /// Added mass, kg/m, and added moment of inertia, kg·m ([`MovingSolid::added_mass`]).
    pub added: (f32, f32),
    /// Gravity, m/s², stepped with the added mass as the fluid's force is.
    pub gravity: Vec2,
    /// The acceleration (m/s²) and angular acceleration (rad/s²) of everything but the fluid
    /// and gravity (contacts, the game's forces), taken as they are.
    pub held: (Vec2, f32),
}

impl SolidResponse {
    /// The change of velocity and angular velocity over `dt` under `force` and `torque`.
    fn change(&self, force: Vec2, torque: f32, dt: f32) -> (Vec2, f32) {
        let a = coupled_acceleration(self.mass, self.added.0, force + self.mass * self.gravity);
        let alpha = coupled_acceleration(self.inertia, self.added.1, torque);
        ((a + self.held.0) * dt, (alpha + self.held.1) * dt)
    }
}

/// A rigid solid in the fluid: its shape sampled in its own frame, where it is, and what the
/// fluid did to it (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct MovingSolid {
    shape: SolidShape,
    center_of_mass: Vec2,
    motion: SolidMotion,
    /// Boundary particles in the solid's frame.
    local: Vec<Vec2>,
    /// Each part's outer ring in `local`, in order round it (the wetted outline).
    rings: Vec<Range<usize>>,
    impulse: Vec2,
    angular_impulse: f32,
    elapsed: f32,
    /// Force and torque of the current sub-step found before its length is known.
    pending: (Vec2, f32),
    load: SolidLoad,
    /// Fraction of the outline the fluid reaches at all (any fluid particle within the
    /// support) at the end of the last tick.
    contact: f32,
    /// The sampling's spacing, m.
    spacing: f32,
    /// How it answers the fluid within a tick (`None`: it keeps its velocities).
    response: Option<SolidResponse>,
    /// The waterline of the last tick's end, m (`-∞`: dry).
    waterline: f32,
    /// Its contact angle, degrees (`None`: the tank's).
    contact_angle: Option<f32>,
}

impl MovingSolid {
    /// Samples `shape` at `spacing` (m), `layers` deep, with its centre of mass at
    /// `center_of_mass` (solid's frame, m); `None` if the shape is invalid or too big
    /// ([`SolidShape::fits`]).
    pub fn new(shape: SolidShape, center_of_mass: Vec2, spacing: f32, layers: u32) -> Option<Self> {
        if !spacing.is_finite()
            || spacing <= 0.0
            || !center_of_mass.is_finite()
            || !shape.fits(spacing, layers)
        {
            return None;
        }
        let mut local = Vec::new();
        let mut rings = Vec::new();
        for part in &shape.parts {
            let start = local.len();
            part.ring(0.5 * spacing, spacing, &mut local);
            rings.push(start..local.len());
            local.truncate(start);
            part.sample(spacing, layers, &mut local);
        }
        Some(Self {
            shape,
            center_of_mass,
            motion: SolidMotion::default(),
            local,
            rings,
            impulse: Vec2::ZERO,
            angular_impulse: 0.0,
            elapsed: 0.0,
            pending: (Vec2::ZERO, 0.0),
            load: SolidLoad::default(),
            contact: 0.0,
            spacing,
            response: None,
            waterline: f32::NEG_INFINITY,
            contact_angle: None,
        })
    }

    /// The liquid's contact angle on it, degrees through the liquid (`None`: the tank's,
    /// `SphParams::contact_angle`).
    pub fn contact_angle(&self) -> Option<f32> {
        self.contact_angle
    }

    /// Sets the liquid's contact angle on it, degrees (0–180; `None`: the tank's); `false`,
    /// changing nothing, if it is out of range. The fluid takes it when it next places its
    /// solids (set it through [`SliceFluid::solids_mut`](super::world::SliceFluid::solids_mut)).
    pub fn set_contact_angle(&mut self, degrees: Option<f32>) -> bool {
        if degrees.is_some_and(|a| !(0.0..=180.0).contains(&a)) {
            return false;
        }
        self.contact_angle = degrees;
        true
    }

    /// The shape, in the solid's frame.
    pub fn shape(&self) -> &SolidShape {
        &self.shape
    }

    /// Centre of mass in the solid's frame, m.
    pub fn center_of_mass(&self) -> Vec2 {
        self.center_of_mass
    }

    /// Pose and velocities (advanced through the sub-steps of the current tick).
    pub fn motion(&self) -> SolidMotion {
        self.motion
    }

    /// Sets the pose and velocities; non-finite values are refused (the last ones are kept).
    pub fn set_motion(&mut self, motion: SolidMotion) -> bool {
        let finite = motion.pose.position.is_finite()
            && motion.pose.angle.is_finite()
            && motion.velocity.is_finite()
            && motion.angular_velocity.is_finite();
        if finite {
            self.motion = motion;
        }
        finite
    }

    /// Sets how it answers the fluid within a tick (`None`: it keeps the velocities of
    /// [`set_motion`](Self::set_motion) through the tick); a response with a value that is not
    /// finite is refused (none is kept).
    pub fn set_response(&mut self, response: Option<SolidResponse>) -> bool {
        let finite = response.is_none_or(|r| {
            [r.mass, r.inertia, r.added.0, r.added.1, r.held.1]
                .iter()
                .all(|v| v.is_finite())
                && r.gravity.is_finite()
                && r.held.0.is_finite()
        });
        self.response = if finite { response } else { None };
        finite
    }

    /// What the fluid did to it over the last tick.
    pub fn load(&self) -> SolidLoad {
        self.load
    }

    /// The added mass (kg/m) and added moment of inertia (kg·m) to step the body with:
    /// [`ADDED_MASS_RATIO`] times the fluid (`rest_density` kg/m³) in its area, times the
    /// larger of its submerged fraction and the fraction of its outline the fluid reaches at all
    /// (so a body that just touches the water has some), and that mass at the shape's radius of
    /// gyration.
    pub fn added_mass(&self, rest_density: f32) -> (f32, f32) {
        let wetted = self.load.submerged_fraction.max(self.contact);
        let mass = ADDED_MASS_RATIO * rest_density * self.shape.area() * wetted;
        let n = self.local.len().max(1) as f32;
        let gyration = self
            .local
            .iter()
            .map(|p| p.distance_squared(self.center_of_mass))
            .sum::<f32>()
            / n;
        (mass, mass * gyration)
    }

    /// Number of boundary particles.
    pub fn len(&self) -> usize {
        self.local.len()
    }

    /// Whether it has no boundary particles.
    pub fn is_empty(&self) -> bool {
        self.local.is_empty()
    }

    /// Boundary particles in the solid's frame, m.
    pub fn local_points(&self) -> &[Vec2] {
        &self.local
    }

    /// Centre of mass in the world, m.
    pub fn world_center(&self) -> Vec2 {
        self.motion.pose.apply(self.center_of_mass)
    }

    /// Velocity of the solid's material at world point `x`, m/s: `v + ω × (x − c)`.
    #[inline]
    pub fn point_velocity(&self, x: Vec2) -> Vec2 {
        let m = &self.motion;
        m.velocity + m.angular_velocity * (x - self.world_center()).perp()
    }

    /// Whether it moves (any velocity is not zero).
    pub fn is_moving(&self) -> bool {
        self.motion.velocity != Vec2::ZERO || self.motion.angular_velocity != 0.0
    }

    /// Moves it rigidly by its velocities over `dt` seconds, turning about the centre of mass.
    pub fn advance(&mut self, dt: f32) {
        let m = &mut self.motion;
        let center = m.pose.apply(self.center_of_mass) + m.velocity * dt;
        m.pose.angle += m.angular_velocity * dt;
        m.pose.position = center - Rot2::radians(m.pose.angle) * self.center_of_mass;
    }

    /// Signed distance from world point `x` to the surface (negative inside) and the outward
    /// normal in the world.
    pub fn distance(&self, x: Vec2) -> (f32, Vec2) {
        let pose = self.motion.pose;
        let (d, normal) = self.shape.distance(pose.to_local(x));
        (d, Rot2::radians(pose.angle) * normal)
    }

    /// Moves a particle that has entered the solid back onto its surface and reflects the
    /// inward part of its velocity relative to the solid with `restitution`.
    #[inline]
    pub fn push_out(&self, position: &mut Vec2, velocity: &mut Vec2, restitution: f32) {
        let (d, normal) = self.distance(*position);
        if d < 0.0 {
            *position -= d * normal;
            let relative = (*velocity - self.point_velocity(*position)).dot(normal);
            if relative < 0.0 {
                *velocity -= (1.0 + restitution) * relative * normal;
            }
        }
    }

    /// Starts a tick: no impulse yet.
    pub(crate) fn begin_tick(&mut self) {
        self.impulse = Vec2::ZERO;
        self.angular_impulse = 0.0;
        self.elapsed = 0.0;
        self.pending = (Vec2::ZERO, 0.0);
    }

    /// Adds a force (N/m) and torque (N) found before the sub-step's length is known.
    pub(crate) fn add_pending(&mut self, force: Vec2, torque: f32) {
        self.pending.0 += force;
        self.pending.1 += torque;
    }

    /// Ends a sub-step of `dt` seconds with the impulse (N·s/m) and angular impulse the fluid
    /// gave besides the pending force; with a [`SolidResponse`], the velocities take them.
    pub(crate) fn end_substep(&mut self, dt: f32, impulse: Vec2, angular_impulse: f32) {
        let (force, torque) = core::mem::take(&mut self.pending);
        let impulse = impulse + force * dt;
        let angular_impulse = angular_impulse + torque * dt;
        self.impulse += impulse;
        self.angular_impulse += angular_impulse;
        self.elapsed += dt;
        if let Some(response) = self.response.filter(|_| dt > 0.0) {
            let (dv, dw) = response.change(impulse / dt, angular_impulse / dt, dt);
            if dv.is_finite() && dw.is_finite() {
                self.motion.velocity += dv;
                self.motion.angular_velocity += dw;
            }
        }
    }

    /// Ends a tick: the averaged force and torque, and the submerged area from `weight(x)`, the
    /// fluid's `Σ V W` at the outline point `x` (world; wet from `wet`): the area under a level
    /// waterline through the highest wet point of the outline (a body resting on the floor in
    /// deep water is wholly under, though the fluid cannot reach its underside).
    pub(crate) fn end_tick(&mut self, weight: impl Fn(Vec2) -> f32, wet: f32) {
        if self.elapsed > 0.0 {
            self.load.force = self.impulse / self.elapsed;
            self.load.torque = self.angular_impulse / self.elapsed;
        }
        let pose = self.motion.pose;
        let (mut touched, mut outline) = (0usize, 0usize);
        let mut waterline = f32::NEG_INFINITY;
        for ring in &self.rings {
            for &p in &self.local[ring.clone()] {
                let x = pose.apply(p);
                let w = weight(x);
                touched += usize::from(w > 0.0);
                if w >= wet {
                    waterline = waterline.max(x.y);
                }
            }
            outline += ring.len();
        }
        // The highest wet point of the outer ring (half a spacing inside the surface) lies
        // within a spacing under the water's surface: take the middle.
        waterline += 0.5 * self.spacing;
        let area = self.shape.area();
        let under = if waterline.is_finite() {
            self.shape
                .parts
                .iter()
                .map(|part| part.area_below(pose, waterline))
                .sum()
        } else {
            0.0
        };
        self.contact = touched as f32 / outline.max(1) as f32;
        self.waterline = waterline;
        // The parts' areas below the line can overlap or round past the whole: at most it.
        let under = under.min(area);
        self.load.submerged_area = under;
        self.load.submerged_fraction = if area > 0.0 { under / area } else { 0.0 };
    }

    /// Adds to the tick's load (after [`end_tick`](Self::end_tick)) the pressure of the water
    /// that seeps into its contacts: each dry point of the outline (`weight(x)` under `wet`)
    /// under the waterline where `touches(x, n)` finds another wall just outside the surface
    /// (outward normal `n`) takes the pressure of the nearest wet point of its ring
    /// (`pressure(x)`, Pa, carried hydrostatically), carried to its depth with `head` Pa/m
    /// (ρ₀ |g|), over a spacing of outline.
    ///
    /// A gap thinner than a particle holds no fluid particle, so a body resting on the floor
    /// has a dry bottom with no pressure on it: a crate lighter than water that reached the
    /// floor of a pool stayed there. Real contacts are wet: water fills any gap a body leaves,
    /// at the pressure round it (a rock on the bed feels its buoyancy).
    pub(crate) fn seep(
        &mut self,
        weight: impl Fn(Vec2) -> f32,
        wet: f32,
        pressure: impl Fn(Vec2) -> Option<f32>,
        touches: impl Fn(Vec2, Vec2) -> bool,
        head: f32,
    ) {
        if !self.waterline.is_finite() {
            return;
        }
        let (pose, center) = (self.motion.pose, self.world_center());
        let turn = Rot2::radians(pose.angle);
        let (mut force, mut torque) = (Vec2::ZERO, 0.0);
        for ring in &self.rings {
            let points: Vec<Vec2> = self.local[ring.clone()]
                .iter()
                .map(|&p| pose.apply(p))
                .collect();
            let is_wet: Vec<bool> = points.iter().map(|&x| weight(x) >= wet).collect();
            // The dry points under the waterline that touch another wall, with their normals.
            let seeping: Vec<(usize, Vec2)> = (0..points.len())
                .filter(|&i| !is_wet[i] && points[i].y < self.waterline)
                .map(|i| (i, turn * self.shape.distance(self.local[ring.start + i]).1))
                .filter(|&(i, normal)| touches(points[i], normal))
                .collect();
            if seeping.is_empty() {
                continue;
            }
            // Each wet point's pressure, carried to the height 0 (sampled only for a ring
            // with a contact).
            let at_zero: Vec<Option<f32>> = points
                .iter()
                .zip(&is_wet)
                .map(|(&x, &w)| Some(w.then(|| pressure(x)).flatten()? + head * x.y))
                .collect();
            let n = points.len();
            for (i, normal) in seeping {
                let x = points[i];
                // The nearest wet point round the ring, either way.
                let Some(p0) =
                    (1..n).find_map(|k| at_zero[(i + k) % n].or(at_zero[(i + n - k) % n]))
                else {
                    continue;
                };
                let push = -(p0 - head * x.y).max(0.0) * self.spacing * normal;
                force += push;
                torque += (x - center).perp_dot(push);
            }
        }
        self.load.force += force;
        self.load.torque += torque;
    }
}

/// The added mass a body in the fluid is stepped with, as a multiple of the fluid's mass in
/// its wetted area ([`MovingSolid::added_mass`]).
///
/// Exchanging force and motion once a tick (explicitly, as a rigid-body engine does) is
/// unstable for a body lighter than the fluid it must push aside: the incompressible fluid
/// answers a body's step into it with the impulse that moves that fluid along, which overshoots
/// a light body (measured: a box of relative density 0.3 jumped out of the water within half a
/// second). Stepping the body as if it were heavier by the added mass, `(m + mₐ) a = F`
/// ([`coupled_acceleration`]), keeps where it comes to rest (`F = 0` there either way) and
/// slows its bobbing. (Stepping it as `(m + mₐ) a = F + mₐ a_prev` instead, which keeps the
/// acceleration of free motion, lags the restoring force and pumped a floating box's roll up
/// to 0.23 rad.)
pub const ADDED_MASS_RATIO: f32 = 3.0;

/// A body's acceleration under `force` (its weight included) stepped with `added` mass (see
/// [`ADDED_MASS_RATIO`]); the same for angular acceleration with torque and added inertia.
pub fn coupled_acceleration<T>(mass: f32, added: f32, force: T) -> T
where
    T: core::ops::Mul<f32, Output = T>,
{
    let total = mass + added;
    force * if total > 0.0 { 1.0 / total } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_sample_inside_spaced_and_in_order_round_the_outline() {
        let shapes = [
            SolidShape::circle(0.1),
            SolidShape::rectangle(0.3, 0.12),
            SolidShape::capsule(Vec2::new(-0.1, 0.0), Vec2::new(0.1, 0.05), 0.04),
            SolidShape::polygon(vec![Vec2::ZERO, Vec2::new(0.2, 0.0), Vec2::new(0.0, 0.15)]),
        ];
        for shape in shapes {
            let solid = MovingSolid::new(shape.clone(), Vec2::ZERO, 0.01, 3).unwrap();
            assert!(solid.len() > 30, "{shape:?}: {}", solid.len());
            assert!(solid.len() as u64 <= shape.sample_bound(0.01, 3));
            for (i, p) in solid.local_points().iter().enumerate() {
                assert!(shape.distance(*p).0 < -0.004, "{shape:?}: {p} not inside");
                for q in &solid.local_points()[i + 1..] {
                    assert!(p.distance(*q) > 0.004, "{shape:?}: {p} and {q} overlap");
                }
            }
            // The outer ring's polygon has nearly the area inside half a spacing.
            let ring = &solid.local[solid.rings[0].clone()];
            assert!(shoelace(ring) > 0.0 && shoelace(ring) < shape.area());
        }
        assert!(!SolidShape::circle(1.0e9).fits(0.01, 3));
        assert!(!SolidShape::polygon(vec![Vec2::ZERO, Vec2::X]).is_valid());
        let concave = [
            Vec2::ZERO,
            Vec2::new(1.0, 0.0),
            Vec2::new(0.2, 0.2),
            Vec2::new(0.0, 1.0),
        ];
        assert!(!SolidShape::polygon(concave.to_vec()).is_valid());
    }

    #[test]
    fn a_still_solid_pushes_particles_out_and_a_segment_is_one_row() {
        let still = |shape: SolidShape, at: Vec2| {
            let mut solid = MovingSolid::new(shape, Vec2::ZERO, 0.01, 3).unwrap();
            solid.set_motion(SolidMotion {
                pose: Pose {
                    position: at,
                    angle: 0.0,
                },
                ..Default::default()
            });
            solid
        };
        let disc = still(SolidShape::circle(0.2), Vec2::new(1.0, 1.0));
        let (mut p, mut v) = (Vec2::new(1.05, 1.0), Vec2::new(-1.0, 0.3));
        disc.push_out(&mut p, &mut v, 0.0);
        assert!((p - Vec2::new(1.2, 1.0)).length() < 1e-6, "{p}");
        assert!(v.x.abs() < 1e-6 && (v.y - 0.3).abs() < 1e-6, "{v}");
        let capsule = still(
            SolidShape::capsule(Vec2::ZERO, Vec2::new(1.0, 0.0), 0.05),
            Vec2::ZERO,
        );
        let (mut p, mut v) = (Vec2::new(0.5, -0.01), Vec2::new(0.0, 1.0));
        capsule.push_out(&mut p, &mut v, 1.0);
        assert!((p - Vec2::new(0.5, -0.05)).length() < 1e-6, "{p}");
        assert!((v - Vec2::new(0.0, -1.0)).length() < 1e-6, "{v}");
        // A segment (radius zero): one row along it, a spacing apart, ends included.
        let segment = SolidShape::capsule(Vec2::ZERO, Vec2::new(0.0, 0.5), 0.0);
        assert!(segment.is_valid());
        let row = MovingSolid::new(segment.clone(), Vec2::ZERO, 0.02, 3).unwrap();
        assert_eq!(row.len(), 26);
        for p in row.local_points() {
            assert!(p.x == 0.0 && (0.0..=0.5).contains(&p.y), "{p}");
        }
        assert_eq!(
            segment.parts[0].outline(0.01),
            vec![Vec2::ZERO, Vec2::new(0.0, 0.5)]
        );
        // A segment's centre of mass is its middle; a point (no length, no radius) is refused.
        let off = SolidShape::capsule(Vec2::X, Vec2::new(2.0, 0.0), 0.0);
        assert_eq!(off.centroid(), Vec2::new(1.5, 0.0));
        assert!(!SolidShape::capsule(Vec2::ONE, Vec2::ONE, 0.0).is_valid());
        // Sampled, this disc would need some 10¹² boundary particles: it does not fit.
        assert!(!SolidShape::circle(1.0e9).fits(0.01, 3));
        assert!(MovingSolid::new(SolidShape::circle(1.0e9), Vec2::ZERO, 0.01, 3).is_none());
    }

    #[test]
    fn water_seeps_into_a_dry_contact_at_the_pressure_round_it() {
        let mut solid =
            MovingSolid::new(SolidShape::rectangle(0.2, 0.1), Vec2::ZERO, 0.01, 2).unwrap();
        let head = 9810.0;
        // Water up to y = 1; the bottom is dry but near its ends, and touches the floor.
        let dry = |x: Vec2| x.y < -0.04 && x.x.abs() < 0.07;
        let weight = |x: Vec2| if dry(x) { 0.0 } else { 1.0 };
        let pressure = |x: Vec2| Some(head * (1.0 - x.y));
        solid.begin_tick();
        solid.end_tick(weight, 0.5);
        let before = solid.load();
        solid.seep(weight, 0.5, pressure, |_, n: Vec2| n.y < -0.5, head);
        let bottom: Vec<Vec2> = solid
            .local_points()
            .iter()
            .copied()
            .filter(|&p| dry(p))
            .collect();
        let expected: f32 = bottom.iter().map(|p| head * (1.0 - p.y) * 0.01).sum();
        let load = solid.load();
        assert!(!bottom.is_empty());
        assert!(((load.force - before.force).y - expected).abs() < 1e-3 * expected);
        assert!((load.force - before.force).x.abs() < 1e-3 && load.torque.abs() < 1e-2);
        // Nothing seeps where nothing touches.
        solid.end_tick(weight, 0.5);
        let before = solid.load();
        solid.seep(weight, 0.5, pressure, |_, _| false, head);
        assert_eq!(solid.load(), before);
    }

    #[test]
    fn a_solid_with_a_response_takes_each_substeps_force() {
        let mut solid =
            MovingSolid::new(SolidShape::rectangle(0.2, 0.1), Vec2::ZERO, 0.01, 2).unwrap();
        let response = SolidResponse {
            mass: 2.0,
            inertia: 0.5,
            added: (2.0, 0.5),
            gravity: Vec2::new(0.0, -10.0),
            held: (Vec2::new(1.0, 0.0), 0.0),
        };
        // Without a response the velocities stay through the tick.
        solid.begin_tick();
        solid.end_substep(0.01, Vec2::new(0.0, 0.4), 0.01);
        assert_eq!(solid.motion().velocity, Vec2::ZERO);
        // With one: (m + mₐ) a = F + m g, plus the held acceleration, over the sub-step.
        assert!(solid.set_response(Some(response)));
        solid.end_substep(0.01, Vec2::new(0.0, 0.4), 0.01);
        let a = (Vec2::new(0.0, 40.0) + 2.0 * Vec2::new(0.0, -10.0)) / 4.0 + Vec2::X;
        assert!((solid.motion().velocity - 0.01 * a).length() < 1e-6);
        assert!((solid.motion().angular_velocity - 0.01 * (1.0 / 1.0)).abs() < 1e-6);
        // The impulse is the fluid's, whatever the response.
        solid.end_tick(|_| 0.0, 1.0);
        assert!((solid.load().force - Vec2::new(0.0, 40.0)).length() < 1e-3);
        // A response that is not finite is refused, and none is kept.
        let bad = SolidResponse {
            mass: f32::NAN,
            ..response
        };
        assert!(!solid.set_response(Some(bad)));
        let before = solid.motion().velocity;
        solid.end_substep(0.01, Vec2::new(0.0, 0.4), 0.0);
        assert_eq!(solid.motion().velocity, before);
    }

    #[test]
    fn a_solid_moves_rigidly_about_its_centre_of_mass() {
        let mut solid = MovingSolid::new(
            SolidShape::rectangle(0.2, 0.1),
            Vec2::new(0.05, 0.0),
            0.01,
            2,
        )
        .unwrap();
        solid.set_motion(SolidMotion {
            pose: Pose {
                position: Vec2::new(1.0, 1.0),
                angle: 0.0,
            },
            velocity: Vec2::new(0.5, 0.0),
            angular_velocity: 1.0,
        });
        let center = solid.world_center();
        solid.advance(0.2);
        assert!((solid.world_center() - center - Vec2::new(0.1, 0.0)).length() < 1e-6);
        assert!((solid.motion().pose.angle - 0.2).abs() < 1e-6);
        // A point on the far side of the centre moves with v + ω × r.
        let x = solid.world_center() + Vec2::new(0.0, 0.1);
        assert!((solid.point_velocity(x) - Vec2::new(0.4, 0.0)).length() < 1e-6);
        // A particle inside is put back on the surface.
        let (mut p, mut v) = (solid.world_center(), Vec2::ZERO);
        solid.push_out(&mut p, &mut v, 0.0);
        assert!(solid.distance(p).0.abs() < 1e-5);
    }

    #[test]
    fn the_wetted_outline_gives_the_submerged_area() {
        let mut solid =
            MovingSolid::new(SolidShape::rectangle(0.4, 0.2), Vec2::ZERO, 0.01, 3).unwrap();
        for (level, expected) in [
            (-1.0, 0.0),
            (-0.05, 0.25),
            (0.0, 0.5),
            (0.05, 0.75),
            (1.0, 1.0),
        ] {
            solid.end_tick(|x| if x.y < level { 1.0 } else { 0.0 }, 0.5);
            let load = solid.load();
            assert!(
                (load.submerged_fraction - expected).abs() < 0.04,
                "water at {level}: {} instead of {expected}",
                load.submerged_fraction
            );
        }
        let mut disc = MovingSolid::new(SolidShape::circle(0.1), Vec2::ZERO, 0.005, 3).unwrap();
        disc.end_tick(|x| if x.y < 0.0 { 1.0 } else { 0.0 }, 0.5);
        assert!((disc.load().submerged_fraction - 0.5).abs() < 0.03);
        // Resting on the floor under deep water: the fluid does not reach its underside.
        solid.end_tick(|x| if x.y > -0.09 { 1.0 } else { 0.0 }, 0.5);
        assert_eq!(solid.load().submerged_fraction, 1.0);
        // Tilted by 45° with the water at its centre: half under.
        solid.set_motion(SolidMotion {
            pose: Pose {
                position: Vec2::ZERO,
                angle: core::f32::consts::FRAC_PI_4,
            },
            ..Default::default()
        });
        solid.end_tick(|x| if x.y < -0.005 { 1.0 } else { 0.0 }, 0.5);
        let fraction = solid.load().submerged_fraction;
        assert!((fraction - 0.5).abs() < 0.05, "tilted: {fraction}");
    }
}
