//! Regions of the plane for drains and sensors: a circle or an axis-aligned box, in world
//! coordinates (m). Pure, no ECS. The gameplay plugin's drains and
//! sensors use them.

use bevy::math::Vec2;
use bevy::reflect::Reflect;

/// A circle or an axis-aligned box, world coordinates, m.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub enum FluidRegion {
    /// The disc of `radius` around `center`.
    Circle {
        /// Centre, m.
        center: Vec2,
        /// Radius, m.
        radius: f32,
    },
    /// The box from `min` to `max`.
    Box {
        /// Lower-left corner, m.
        min: Vec2,
        /// Upper-right corner, m.
        max: Vec2,
    },
}

impl FluidRegion {
    /// The disc of `radius` around `center`.
    pub fn circle(center: Vec2, radius: f32) -> Self {
        Self::Circle { center, radius }
    }

    /// The box of half-extents `half_size` around `center`.
    pub fn rect(center: Vec2, half_size: Vec2) -> Self {
        Self::Box {
            min: center - half_size,
            max: center + half_size,
        }
    }

    /// Whether `p` lies inside (on the edge counts).
    #[inline]
    pub fn contains(&self, p: Vec2) -> bool {
        match *self {
            Self::Circle { center, radius } => p.distance_squared(center) <= radius * radius,
            Self::Box { min, max } => p.cmpge(min).all() && p.cmple(max).all(),
        }
    }

    /// Area, m².
    pub fn area(&self) -> f32 {
        match *self {
            Self::Circle { radius, .. } => core::f32::consts::PI * radius * radius,
            Self::Box { min, max } => (max - min).x * (max - min).y,
        }
    }

    /// Why the region cannot be used (non-finite coordinates, or no area), if it cannot.
    pub fn check(&self) -> Result<(), String> {
        match *self {
            Self::Circle { center, radius } => {
                if !(center.is_finite() && radius.is_finite() && radius > 0.0) {
                    return Err(format!(
                        "circle at {center} of radius {radius} m: the centre must be finite and \
                         the radius positive"
                    ));
                }
            }
            Self::Box { min, max } => {
                if !(min.is_finite() && max.is_finite() && max.cmpgt(min).all()) {
                    return Err(format!(
                        "box from {min} to {max}: the corners must be finite and the box must \
                         have an area"
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contains_area_and_checks() {
        let disc = FluidRegion::circle(Vec2::new(1.0, 1.0), 0.5);
        assert!(disc.contains(Vec2::new(1.4, 1.0)) && !disc.contains(Vec2::new(1.4, 1.4)));
        assert!((disc.area() - core::f32::consts::FRAC_PI_4).abs() < 1e-5);
        let rect = FluidRegion::rect(Vec2::ZERO, Vec2::new(1.0, 0.5));
        assert!(rect.contains(Vec2::new(-1.0, 0.5)) && !rect.contains(Vec2::new(0.0, 0.6)));
        assert_eq!(rect.area(), 2.0);
        assert!(disc.check().is_ok() && rect.check().is_ok());
        assert!(FluidRegion::circle(Vec2::ZERO, 0.0).check().is_err());
        assert!(FluidRegion::circle(Vec2::NAN, 1.0).check().is_err());
        assert!(
            FluidRegion::rect(Vec2::ZERO, Vec2::new(-1.0, 1.0))
                .check()
                .is_err()
        );
    }
}
