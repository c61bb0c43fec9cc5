//! # bevy_sph2d
//!
//! Bevy plugins for real-time 2D particle physics: an incompressible SPH fluid in SI units
//! (divergence-free SPH by default, weakly compressible SPH on request), stepped in a fixed-step
//! schedule (`FixedUpdate` unless you choose another) over a cell-sorted snapshot with an O(n) cell-list neighbour search, its passes
//! over neighbours in parallel on one pool (as many threads as Bevy's `ComputeTaskPool`); and
//! Barnes-Hut gravity for anything with a mass.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_sph2d::prelude::*;
//!
//! fn main() {
//!     App::new()
//!         .add_plugins((MinimalPlugins, ParticlePlugins::default()))
//!         .add_systems(Startup, |mut commands: Commands| {
//!             // A 0.5 m × 1 m column of water against the left wall of the default tank.
//!             commands.queue(FluidBlock::dam_break(0.5, 1.0));
//!         })
//!         .run();
//! }
//! ```
//!
//! - [`SphPlugin`](fluid::SphPlugin): the fluid; [`SphParams`](fluid::SphParams) tunes it.
//! - [`GravityPlugin`](gravity::GravityPlugin): Barnes-Hut gravity between every entity with a
//!   [`Mass`](gravity::Mass), fluid particles included; [`GravityParams`](gravity::GravityParams)
//!   tunes it.
//! - [`ParticlePlugins`]: the simulation plugins, as a group (headless-safe), in one schedule
//!   under crate-wide sets ([`ParticleSystems`], [`SphSubstepSystems`]) that every plugin
//!   nests under.
//! - [`gameplay`]: emitters, drains, sensors and the point probe ([`gameplay::FluidEmitter`],
//!   [`gameplay::FluidDrain`], [`gameplay::FluidSensor`], [`gameplay::FluidQuery`]), spawners,
//!   scenarios, save and restore ([`gameplay::save_fluid`], [`gameplay::load_fluid`]).
//! - `ParticleUiPlugins` (features `render`, `egui`, on by default): a liquid view or sprites
//!   tinted through a colour map (`render::ParticleRenderPlugin`), mouse and keyboard tools
//!   (`interact::ParticleInteractPlugin`) and the egui tweak panel (`panel::ParticlePanelPlugin`);
//!   the examples' demo apps (`examples/demo/`) are built on these, as a game would be.
//! - [`SimulationControl`] and [`ResetSimulation`]: pause, single-step and reset for every
//!   simulation plugin.
//! - [`ParamsError`], [`ParamsStatus`] and [`ParamTable`]: the one parameters pattern of
//!   [`SphParams`](fluid::SphParams) and [`GravityParams`](gravity::GravityParams).
//!
//! # Cargo features
//!
//! | feature | default | what it brings |
//! | --- | --- | --- |
//! | `render` | yes | the liquid view, sprites, mouse and keyboard tools; a window through winit with X11 |
//! | `egui` | yes | the tweak panel (implies `render`) |
//! | `parallel` | yes | threads: Bevy's multi-threaded task pools and the crate's rayon pool for the passes over particles |
//! | `wayland` | no | Wayland windows beside X11 (Bevy's `wayland`, implies `render`; building it needs `pkg-config` and `libwayland-dev`) |
//!
//! With `--no-default-features` only the simulation is compiled: no window, renderer or egui,
//! and no threads. Without `parallel` every pass runs on the calling thread and nothing is
//! spawned (rayon's parallel iterators run in order on it), for targets without threads such as
//! the web; the results are the threaded build's bit for bit (CI compares them). A build
//! without a file system gives the save slot a storage of its own
//! ([`gameplay::SnapshotStorage`]).
//!
//! Every algorithm lives in a pure simulation core (private module `sim`: no ECS, nothing from
//! the rest of the crate, checked by CI) that writes the order of a fluid sub-step once; the
//! plugins are thin drivers of it. Its parts can be used on their own: the smoothing kernels
//! ([`fluid::kernels`]), the cell-list neighbour search ([`slices::NeighborGrid`]), the whole
//! fluid on plain vectors ([`slices::SliceFluid`], the core's second driver, with the core's
//! own types in [`slices`]) and the quadtree
//! ([`gravity::QuadTree`]). The Martin & Moyce data and the resting-layer checks run on it
//! live beside the examples (`examples/validation/`), which share them with the tests.

#![warn(missing_docs)]
// Unsafe code only in the SIMD sums of the core (each block with its SAFETY note), which allow it.
#![deny(unsafe_code)]

mod compute;
mod control;
#[cfg(feature = "avian")]
pub mod coupling;
pub mod fluid;
pub mod gameplay;
pub mod gravity;
#[cfg(feature = "render")]
pub mod interact;
#[cfg(feature = "egui")]
pub mod panel;
mod params;
pub mod particle;
#[cfg(feature = "render")]
pub mod render;
mod schedule;
mod sim;
pub mod slices;

pub use control::{
    ResetSimulation, SimulationControl, SimulationControlPlugin, SimulationControlSystems,
    simulation_running,
};
pub use params::{ParamField, ParamTable, ParamsError, ParamsStatus};
pub use schedule::{
    BodyForceSystems, ParticleSchedule, ParticleSchedulePlugin, ParticleSystems, SphSubstep,
    SphSubstepSystems,
};
pub use sim::simd::simd_path;

use bevy::app::{
    PluginGroup, PluginGroupBuilder, TaskPoolOptions, TaskPoolPlugin,
    TaskPoolThreadAssignmentPolicy,
};
use bevy::ecs::schedule::{LogLevel, ScheduleLabel};
use bevy::prelude::default;

/// A [`TaskPoolPlugin`] whose compute pool, which runs `par_iter_mut`, has exactly
/// `compute_threads` threads (at least one), with one thread each for I/O and async compute.
///
/// Bevy's default gives compute only what the other pools leave, which on a two-core machine is
/// a single thread; put this in `DefaultPlugins.set(...)` or `MinimalPlugins.set(...)` to use
/// every core for the fluid.
pub fn task_pool_plugin(compute_threads: usize) -> TaskPoolPlugin {
    let threads = compute_threads.max(1);
    let one = TaskPoolThreadAssignmentPolicy {
        min_threads: 1,
        max_threads: 1,
        percent: 0.0,
        on_thread_spawn: None,
        on_thread_destroy: None,
    };
    TaskPoolPlugin {
        task_pool_options: TaskPoolOptions {
            min_total_threads: threads + 2,
            max_total_threads: threads + 2,
            io: one.clone(),
            async_compute: one.clone(),
            compute: TaskPoolThreadAssignmentPolicy {
                min_threads: threads,
                max_threads: threads,
                percent: 1.0,
                ..one
            },
        },
    }
}

/// The simulation plugins of the crate, all stepping in one schedule ([`FixedUpdate`] by
/// default, or the one given to [`new`](Self::new)) under the crate-wide
/// [`ParticleSystems`]: they run headless (with `MinimalPlugins`) as
/// well as in a game. Configure one with `.set(SphPlugin::default().with_params(params))` (it
/// still steps in the group's schedule: the first [`ParticleSchedulePlugin`] added owns the
/// schedule for every plugin) or leave one out with `.disable::<SphPlugin>()`. The fixed step's
/// rate is the app's `Time<Fixed>`, which the crate never sets. For sprites, mouse tools and the panel add `ParticleUiPlugins`
/// after this group: they step in its schedule too.
///
/// [`FixedUpdate`]: bevy::prelude::FixedUpdate
#[derive(Debug, Clone, Default)]
pub struct ParticlePlugins {
    /// The schedule owner the group adds first: the schedule and its ambiguity detection.
    pub schedule: ParticleSchedulePlugin,
}

impl ParticlePlugins {
    /// The crate's plugins, stepping in `schedule`. The renderer moves sprites between steps by
    /// `Time<Fixed>::overstep_fraction`, so in a schedule that is not fixed-step its motion is
    /// only as smooth as the steps.
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: ParticleSchedulePlugin::new(schedule),
        }
    }

    /// Reports ambiguous system orders at `level` (`Error` fails the first tick).
    pub fn with_ambiguity_detection(mut self, level: LogLevel) -> Self {
        self.schedule.ambiguity_detection = level;
        self
    }
}

impl PluginGroup for ParticlePlugins {
    fn build(self) -> PluginGroupBuilder {
        let schedule = self.schedule.schedule;
        PluginGroupBuilder::start::<Self>()
            .add(self.schedule)
            .add(fluid::SphPlugin {
                schedule,
                ..default()
            })
            .add(gravity::GravityPlugin {
                schedule,
                ..default()
            })
    }
}

/// The plugins that need a window (features `render` and `egui`): sprites
/// ([`render::ParticleRenderPlugin`]), mouse and keyboard tools ([`interact::ParticleInteractPlugin`])
/// and the tweak panel ([`panel::ParticlePanelPlugin`], feature `egui`). Add them after
/// `DefaultPlugins` and [`ParticlePlugins`], and spawn a [`render::ParticleCamera`].
#[cfg(feature = "render")]
#[derive(Debug, Clone, Copy, Default)]
pub struct ParticleUiPlugins;

#[cfg(feature = "render")]
impl PluginGroup for ParticleUiPlugins {
    fn build(self) -> PluginGroupBuilder {
        let group = PluginGroupBuilder::start::<Self>()
            .add(render::ParticleRenderPlugin)
            .add(interact::ParticleInteractPlugin);
        #[cfg(feature = "egui")]
        let group = group.add(panel::ParticlePanelPlugin);
        group
    }
}

/// The types a game needs.
pub mod prelude {
    pub use crate::ParticlePlugins;
    #[cfg(feature = "render")]
    pub use crate::ParticleUiPlugins;
    pub use crate::control::{ResetSimulation, SimulationControl};
    #[cfg(feature = "avian")]
    pub use crate::coupling::{FluidCoupled, FluidCouplingPlugin};
    pub use crate::fluid::{
        Acceleration, ContactAngle, Density, FluidForce, FluidMaterial, FluidParticle, KernelKind,
        Liquid, Pressure, Solid, SolidEntered, SolidLeft, SolidShape, SolidVelocity, SphParams,
        SphParamsStatus, SphPlugin, SphStats, SphSystems, Submerged, Tank,
    };
    pub use crate::gameplay::{
        EmitterRate, FluidBlock, FluidDrain, FluidEmitter, FluidEntered, FluidLeft, FluidQuery,
        FluidRegion, FluidSensor, ScenarioKind, SphScenario,
    };
    pub use crate::gravity::{
        FluidPlanets, GalaxyDisc, GravityAcceleration, GravityParams, GravityPlugin, GravityStats,
        GravitySystems, Multipole,
    };
    #[cfg(feature = "render")]
    pub use crate::interact::{ParticleInteractPlugin, PointerSettings, PointerTool};
    #[cfg(feature = "egui")]
    pub use crate::panel::ParticlePanelPlugin;
    pub use crate::params::ParamTable;
    pub use crate::particle;
    #[cfg(feature = "render")]
    pub use crate::render::{
        ColorMap, LiquidStyle, ParticleCamera, ParticleDraw, ParticleRenderPlugin, ParticleView,
        RenderMode,
    };
    pub use crate::schedule::{
        BodyForceSystems, ParticleSchedulePlugin, ParticleSystems, SphSubstep, SphSubstepSystems,
    };
}
