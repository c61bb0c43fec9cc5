//! The headless integration tests, as one binary: every test module links Bevy once, instead of
//! once per file. `tests/window.rs`, which needs a window and its own `main`, stays apart.

mod common;

mod controls;
#[cfg(feature = "avian")]
mod coupling;
mod determinism;
mod ecs_matches_slices;
mod gravity;
mod headless_cli;
mod liquids;
mod params;
mod physics;
mod save_restore;
mod schedule;
mod soak;
mod solids;
mod sources_and_sensors;
mod surface_tension;
#[path = "../../examples/validation/mod.rs"]
mod validation;
#[cfg(all(feature = "avian", feature = "render"))]
mod with_avian;
