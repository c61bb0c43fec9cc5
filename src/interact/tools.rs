//! Pure mouse-tool maths: the smooth force profile, the accelerations of the pull, push and drag
//! tools and gravity tilting (the pour tool drives a
//! [`FluidEmitter`](crate::gameplay::FluidEmitter)). See
//! [`ParticleInteractPlugin`](crate::interact::ParticleInteractPlugin).

use bevy::math::Vec2;
use bevy::reflect::Reflect;

/// Weight of a tool's effect at `distance` (m) from the cursor: `(1 − (d/r)²)²`, 1 at the
/// centre, falling smoothly to 0 with zero slope at `radius` (and 0 beyond it or for a
/// non-positive radius).
pub fn falloff(distance: f32, radius: f32) -> f32 {
    if !(radius > 0.0 && distance < radius) {
        return 0.0;
    }
    let q = distance / radius;
    let s = 1.0 - q * q;
    s * s
}

/// What the pointer does to the fluid this frame.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PointerAction {
    /// Nothing.
    #[default]
    None,
    /// Accelerate fluid towards the cursor.
    Pull,
    /// Accelerate fluid away from the cursor.
    Push,
    /// Relax the fluid's velocity towards the cursor's.
    Drag,
}

/// The force field around the cursor that the fixed step applies.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
pub struct PointerForce {
    /// What the field does.
    pub action: PointerAction,
    /// Cursor position, m.
    pub center: Vec2,
    /// Cursor velocity, m/s (what [`PointerAction::Drag`] moves the fluid with).
    pub velocity: Vec2,
    /// Radius of the field, m.
    pub radius: f32,
    /// Peak acceleration of pull and push, m/s².
    pub strength: f32,
    /// Rate at which pull damps velocity and drag matches the cursor's, 1/s.
    pub rate: f32,
}

impl PointerForce {
    /// The acceleration (m/s²) of a particle at `position` moving at `velocity`: zero outside
    /// the radius, fading smoothly to zero at it.
    ///
    /// - Pull: `w (s n̂ − k v)`, towards the cursor, with damping so the fluid gathers instead
    ///   of oscillating through it.
    /// - Push: `−w s n̂`.
    /// - Drag: `w k (v_cursor − v)`.
    pub fn acceleration(&self, position: Vec2, velocity: Vec2) -> Vec2 {
        if self.action == PointerAction::None {
            return Vec2::ZERO;
        }
        let offset = self.center - position;
        let w = falloff(offset.length(), self.radius);
        if w == 0.0 {
            return Vec2::ZERO;
        }
        let towards = offset.normalize_or_zero();
        let a = match self.action {
            PointerAction::None => Vec2::ZERO,
            PointerAction::Pull => w * (self.strength * towards - self.rate * velocity),
            PointerAction::Push => -w * self.strength * towards,
            PointerAction::Drag => w * self.rate * (self.velocity - velocity),
        };
        if a.is_finite() { a } else { Vec2::ZERO }
    }
}

/// Gravity of the same magnitude as `gravity`, tilted as if the tank were turned by `angle`
/// (radians, positive: turned anticlockwise, so the fluid runs to the left).
pub fn tilted_gravity(gravity: Vec2, angle: f32) -> Vec2 {
    let magnitude = gravity.length();
    Vec2::new(-angle.sin(), -angle.cos()) * magnitude
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falloff_is_smooth_and_bounded() {
        assert_eq!(falloff(0.0, 0.1), 1.0);
        assert_eq!(falloff(0.1, 0.1), 0.0);
        assert_eq!(falloff(0.2, 0.1), 0.0);
        assert_eq!(falloff(0.05, 0.0), 0.0);
        assert_eq!(falloff(f32::NAN, 0.1), 0.0);
        // Decreasing, with zero slope at the rim.
        let w: Vec<f32> = (0..=100).map(|i| falloff(i as f32 * 0.001, 0.1)).collect();
        assert!(w.windows(2).all(|p| p[1] <= p[0]));
        // The steepest slope is 8/(3√3 r) ≈ 15.4 /m at r = 0.1 m; at the rim it vanishes.
        let slope_at_rim = (falloff(0.1 - 1e-4, 0.1) - falloff(0.1, 0.1)) / 1e-4;
        assert!(slope_at_rim.abs() < 0.1, "{slope_at_rim}");
        assert!((falloff(0.05, 0.1) - 0.5625).abs() < 1e-6);
    }

    #[test]
    fn tools_pull_push_and_drag() {
        let force = PointerForce {
            action: PointerAction::Pull,
            center: Vec2::new(1.0, 1.0),
            velocity: Vec2::new(2.0, 0.0),
            radius: 0.2,
            strength: 50.0,
            rate: 10.0,
        };
        let at = Vec2::new(0.9, 1.0);
        let pull = force.acceleration(at, Vec2::ZERO);
        assert!(pull.x > 0.0 && pull.y == 0.0);
        assert!((pull.x - 50.0 * falloff(0.1, 0.2)).abs() < 1e-4);
        let push = PointerForce {
            action: PointerAction::Push,
            ..force
        }
        .acceleration(at, Vec2::ZERO);
        assert_eq!(push, -pull);
        let drag = PointerForce {
            action: PointerAction::Drag,
            ..force
        };
        let a = drag.acceleration(at, Vec2::new(0.5, 0.0));
        assert!((a - Vec2::new(10.0 * 1.5 * falloff(0.1, 0.2), 0.0)).length() < 1e-4);
        // Nothing outside the radius, nothing for no action, nothing non-finite at the centre.
        assert_eq!(
            force.acceleration(Vec2::new(1.3, 1.0), Vec2::ZERO),
            Vec2::ZERO
        );
        let idle = PointerForce {
            action: PointerAction::None,
            ..force
        };
        assert_eq!(idle.acceleration(at, Vec2::ZERO), Vec2::ZERO);
        assert!(force.acceleration(force.center, Vec2::ZERO).is_finite());
    }

    #[test]
    fn tilt() {
        let g = Vec2::new(0.0, -9.81);
        assert!((tilted_gravity(g, 0.0) - g).length() < 1e-6);
        let left = tilted_gravity(g, 0.3);
        assert!(left.x < 0.0 && (left.length() - 9.81).abs() < 1e-4);
    }
}
