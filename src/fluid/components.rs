//! Components of a fluid particle. See [`SphPlugin`](crate::fluid::SphPlugin); solids in the
//! fluid, still or moving, are [`Solid`](crate::fluid::Solid)s.
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
///     commands.spawn((FluidParticle, particle::Position(Vec2::new(0.5, 1.0))));
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
    FluidIndex
)]
pub struct FluidParticle;

pub use crate::particle::{Position, Velocity};

/// Acceleration of the last sub-step, m/s²: what
/// [`SphSubstepSystems::Forces`](crate::fluid::SphSubstepSystems::Forces) computes (WCSPH:
/// pressure, viscosity and gravity; DFSPH: viscosity and gravity, the pressure following in the
/// density solve), plus what systems in `FieldForces`, `PointerForces` and `ExternalForces` add
/// with `+=` before [`SphSubstepSystems::Integrate`](crate::fluid::SphSubstepSystems::Integrate)
/// consumes it.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Acceleration(pub Vec2);

/// SPH density (summation over neighbours, the particle itself included), kg/m³.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Density(pub f32);

/// Gauge pressure, Pa (zero at the free surface, never negative): under DFSPH `ρ₀κ`, the density
/// solve's; under WCSPH the equation of state's.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct Pressure(pub f32);

/// The divergence-free solver's stiffness `[κ, κᵛ]` of the particle's last sub-step (the
/// density and divergence solves' pressures per rest density, m²/s²), kept to warm-start the
/// next one. Solver state; games can ignore it.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub(crate) struct Stiffness(pub Vec2);

/// Where the particle sits in the solver's gathered particles, and in which gathering: written
/// by [`SphSubstepSystems::Neighbors`](crate::fluid::SphSubstepSystems::Neighbors) when a game's
/// systems run between the stages, so an index is only trusted in the generation it was given
/// in (a particle spawned since has none). Games can ignore it.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq, Eq)]
#[reflect(Component, Default, Debug, PartialEq)]
pub(crate) struct FluidIndex {
    /// Index in the gathered particles.
    pub index: u32,
    /// The gathering the index belongs to (0: none yet).
    pub generation: u32,
}

impl Default for FluidIndex {
    fn default() -> Self {
        Self {
            index: u32::MAX,
            generation: 0,
        }
    }
}
