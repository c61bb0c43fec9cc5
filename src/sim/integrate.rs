//! The particle integrator and the collision safety net: symplectic Euler, the speed cap, and the
//! projection out of solids and back into the tank. Both drivers move every particle through
//! these two functions.

use super::config::SphConstants;
use super::layout::Walls;
use bevy::math::Vec2;

/// Advances one particle by `dt` (symplectic Euler: velocity first, then position with the new
/// velocity), caps its speed, and keeps it inside the tank and out of the solids. Returns `false`
/// (and leaves the particle where it was, at rest) if the result would not be finite.
#[inline]
pub fn advance_particle(
    c: &SphConstants,
    walls: &Walls,
    position: &mut Vec2,
    velocity: &mut Vec2,
    acceleration: Vec2,
    dt: f32,
) -> bool {
    let v = *velocity + acceleration * dt;
    move_particle(c, walls, position, velocity, v, dt)
}

/// Gives one particle the velocity `v` (capped at the speed limit) and moves it by `v dt`, keeping
/// it inside the tank and out of the solids. Returns `false` (and leaves the particle where it
/// was, at rest) if the result would not be finite.
#[inline]
pub fn move_particle(
    c: &SphConstants,
    walls: &Walls,
    position: &mut Vec2,
    velocity: &mut Vec2,
    mut v: Vec2,
    dt: f32,
) -> bool {
    let speed_sq = v.length_squared();
    if speed_sq > c.speed_limit * c.speed_limit {
        v *= c.speed_limit / speed_sq.sqrt();
    }
    let mut x = *position + v * dt;
    walls.push_out(&mut x, &mut v, c.wall_restitution);
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
