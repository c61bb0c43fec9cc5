//! What every simulated body has, whichever plugin moves it: fluid particles
//! ([`FluidParticle`](crate::fluid::FluidParticle)), gravity bodies
//! ([`Mass`](crate::gravity::Mass)), and what the render and interaction plugins read.

use bevy::prelude::*;

/// Position of a body's centre in world space, m (y up).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Position(pub Vec2);

/// Velocity, m/s.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Velocity(pub Vec2);
