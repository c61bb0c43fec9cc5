//! The fluid's solver on plain vectors, without an `App`: [`SliceFluid`] and the core's types it
//! takes and gives (the validated constants, the particles' arrays, the solids' boundary
//! particles and motions, the sub-step clock and profile, the neighbour grid). It runs the very
//! sub-step the plugin runs, bit for bit (tested), for benchmarks, validation and servers.
//!
//! These are the simulation core's own types, gathered here so that the game-facing modules
//! (`fluid`, `gameplay`, `gravity`) hold only what a game spawns and reads: they follow the
//! solver as it changes, and carry no promise beyond it.

pub use crate::sim::clock::SubstepClock;
pub use crate::sim::config::SphConstants;
pub use crate::sim::dfsph::DfsphReport;
pub use crate::sim::grid::NeighborGrid;
pub use crate::sim::profile::{StageProfile, SubstepPart};
pub use crate::sim::solid::{ADDED_MASS_RATIO, MovingSolid, SolidLoad, SolidMotion};
pub use crate::sim::step::{Particles, SolverIterations};
pub use crate::sim::world::SliceFluid;
