//! Components of a fluid particle. See [`SphPlugin`](crate::fluid::SphPlugin).
//!
//! Spawning [`FluidParticle`] with a [`Position`] is enough: the marker requires the rest, and the
//! solver fills in density, pressure and acceleration at the next step.

use bevy::prelude::*;

/// Marks an entity as an SPH fluid particle. Its required components carry the state the solver
/// reads and writes; all particles share the mass given by
/// [`SphParams::particle_mass`](crate::fluid::SphParams::particle_mass).
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_sph2d::prelude::*;
/// fn pour(mut commands: Commands) {
///     commands.spawn((FluidParticle, Position(Vec2::new(0.5, 1.0))));
/// }
/// ```
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
#[require(
    Position,
    Velocity,
    Acceleration,
    Density,
    Pressure,
    Stiffness,
    NeighborSlot
)]
pub struct FluidParticle;

pub use crate::body::{Position, Velocity};

/// Acceleration of the last sub-step, m/s²: pressure, viscosity and gravity as computed in
/// [`SphSubstepSystems::Forces`](crate::fluid::SphSubstepSystems::Forces), plus whatever a game's
/// own systems add in that set before [`SphSubstepSystems::Integrate`](crate::fluid::SphSubstepSystems::Integrate) consumes it.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Acceleration(pub Vec2);

/// SPH density (summation over neighbours, the particle itself included), kg/m³.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Density(pub f32);

/// Gauge pressure from the equation of state, Pa (zero at the free surface, never negative).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Pressure(pub f32);

/// The divergence-free solver's stiffness `[κ, κᵛ]` of the particle's last sub-step (the
/// density and divergence solves' pressures per rest density, m²/s²), kept to warm-start the
/// next one. Solver state; games can ignore it.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub(crate) struct Stiffness(pub Vec2);

/// Where the particle sits in the solver's cell-sorted neighbour snapshot, and in which
/// snapshot: written by [`SphSubstepSystems::Neighbors`](crate::fluid::SphSubstepSystems::Neighbors)
/// each sub-step, so a slot is only trusted in the snapshot generation it was given in.
/// Games can ignore it.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq, Eq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub(crate) struct NeighborSlot {
    /// Sorted slot in the snapshot.
    pub slot: u32,
    /// The snapshot generation the slot belongs to (0: none yet).
    pub generation: u32,
}

impl Default for NeighborSlot {
    fn default() -> Self {
        Self {
            slot: u32::MAX,
            generation: 0,
        }
    }
}
