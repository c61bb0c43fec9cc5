//! The pure simulation core: every algorithm of the fluid and of gravity over plain vectors,
//! with no ECS. It imports nothing from Bevy but `bevy::math` (and `Reflect` derives on the
//! types that are parameters) and nothing from the rest of the crate; `.ci/run` checks both.
//! The Bevy plugins ([`fluid`](crate::fluid), [`gravity`](crate::gravity)) are drivers of it,
//! and so is [`world`], the plain-vector fluid the benchmarks and tests run.
//!
//! - [`config`]: the constants and settings the passes read.
//! - [`kernels`], [`grid`], [`layout`]: smoothing kernels, the cell grid, the cell-sorted
//!   snapshot, the walls and the neighbour lists.
//! - [`boundary`], [`solid`], [`region`]: the tank and static shapes, moving solids, and
//!   regions for drains and sensors.
//! - [`density`], [`integrate`]: summation density and the particle integrator.
//! - [`wcsph`], [`dfsph`]: the two pressure solvers; [`viscosity`]: their laminar pair term
//!   between liquids of their own viscosities.
//! - [`step`]: the one order of a sub-step, which both drivers call.
//! - [`clock`], [`parallel`], [`profile`]: the sub-step clock, the slot passes over threads
//!   and where a sub-step's time goes.
//! - [`simd`], [`gravity`]: SIMD dispatch and the Barnes-Hut tree with its sums.

pub mod boundary;
pub mod clock;
pub mod config;
pub mod density;
pub mod dfsph;
pub mod gravity;
pub mod grid;
pub mod grid_pressure;
pub mod integrate;
pub mod kernels;
pub mod layout;
pub mod parallel;
pub mod profile;
pub mod region;
pub mod simd;
pub mod solid;
pub mod step;
pub mod tension;
pub mod viscosity;
pub mod wcsph;
pub mod world;
