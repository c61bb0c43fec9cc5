//! What every simulated particle has, whichever plugin moves it: fluid particles
//! ([`FluidParticle`](crate::fluid::FluidParticle)) and gravity bodies ([`Mass`]), read by the
//! render and interaction plugins too.
//!
//! The prelude brings this module, not its items: a game names them `particle::Position`,
//! `particle::Velocity` and `particle::Mass`, so that they live beside avian2d's prelude (whose
//! rigid bodies have a `Position` and a `Mass` of their own) and bevy's, all three glob-imported:
//!
//! ```
//! use bevy::prelude::*;
//! use bevy_sph2d::prelude::*;
//!
//! fn pour(mut commands: Commands) {
//!     commands.spawn((
//!         FluidParticle,
//!         particle::Position(Vec2::new(0.2, 0.5)),
//!         particle::Velocity(Vec2::new(0.0, -1.0)),
//!     ));
//! }
//! # bevy::ecs::system::assert_is_system(pour);
//! ```

pub use crate::gravity::Mass;
use bevy::prelude::*;

/// Position of a body's centre in world space, m (y up).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Position(pub Vec2);

/// Velocity, m/s.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Velocity(pub Vec2);
