//! The constants and settings every pass of a sub-step reads: [`SphConstants`] (derived once
//! from validated parameters), the choice of [`PressureSolver`] and the [`DfsphSettings`]. Their
//! own file, so that the passes and the parameter table both import it and nothing imports back.

use super::boundary::Tank;
use super::kernels::KernelKind;
use bevy::math::Vec2;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Everything the sub-step maths needs, derived once from validated
/// [`SphParams`](crate::fluid::SphParams) by
/// [`SphParams::constants`](crate::fluid::SphParams::constants).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphConstants {
    /// Kernel choice.
    pub kernel: KernelKind,
    /// Initial particle spacing, m.
    pub spacing: f32,
    /// Kernel support radius `H`, m.
    pub support: f32,
    /// `H²`, m².
    pub support_sq: f32,
    /// Smoothing length `h = H/2`, m (the length in the time-step limits and viscosity terms).
    pub smoothing_length: f32,
    /// Mass of every particle, kg per metre of depth.
    pub mass: f32,
    /// Rest density `ρ₀`, kg/m³.
    pub rest_density: f32,
    /// Speed of sound `c₀`, m/s.
    pub speed_of_sound: f32,
    /// Tait exponent `γ`.
    pub eos_exponent: f32,
    /// Tait stiffness `B = ρ₀c₀²/γ`, Pa.
    pub stiffness: f32,
    /// Background pressure added to the equation of state, Pa.
    pub background_pressure: f32,
    /// Monaghan artificial viscosity `α`.
    pub artificial_viscosity: f32,
    /// Kinematic viscosity `ν`, m²/s.
    pub kinematic_viscosity: f32,
    /// Gravity, m/s².
    pub gravity: Vec2,
    /// Courant number of the acoustic time-step limit.
    pub cfl_number: f32,
    /// Speeds are capped here, m/s: beyond `c₀` the weakly compressible model is meaningless.
    pub speed_limit: f32,
    /// Restitution of the collision safety net, 0..1.
    pub wall_restitution: f32,
    /// The tank, if any.
    pub tank: Option<Tank>,
    /// Layers of boundary particles behind each wall.
    pub wall_layers: u32,
    /// Sub-steps allowed per tick.
    pub max_substeps: u32,
    /// Which pressure solver runs.
    pub solver: PressureSolver,
    /// The settings of [`PressureSolver::Dfsph`].
    pub dfsph: DfsphSettings,
    /// Volume of a particle, `m/ρ₀`, m² (per metre of depth).
    pub volume: f32,
    /// Factor on the kernel gradient in the DFSPH solver that makes the discrete gradient
    /// of a linear field exact on the rest lattice (about 1.05 at 2.5 spacings), so hydrostatic
    /// pressure comes out at `ρ₀g` per metre instead of a few percent high.
    pub gradient_scale: f32,
    /// Surface tension `σ`, N/m (0: none; see `sim::tension`).
    pub surface_tension: f32,
    /// `cos θ` of the contact angle on the tank's walls and on solids without one of their own.
    pub wetting: f32,
    /// How a flat surface of the rest lattice reads, for the tension pass.
    pub surface: SurfaceCalibration,
}

impl SphConstants {
    /// These constants with the kinematic viscosity raised to `largest` (m²/s) where that is
    /// larger: what the step limits read when the liquids have viscosities of their own.
    pub fn with_largest_viscosity(mut self, largest: f32) -> Self {
        self.kinematic_viscosity = self.kinematic_viscosity.max(largest);
        self
    }
}

/// How the colour gradient of the rest lattice reads at a flat free surface.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceCalibration {
    /// `|∇c|` of the top row, 1/m.
    pub top_row: f32,
    /// `S = Σₖ V |nₖ| / Δx` over the rows that are on the surface (at least
    /// `SURFACE_FRACTION` of the top row): the share of the surface's delta function that
    /// the particles carry, dimensionless.
    pub integral: f32,
    /// The factor that brings the surface stress's pull between lattice neighbours, held at
    /// close range against pairing, back to the kernel's.
    pub held: f32,
}

/// The pressure solver.
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PressureSolver {
    /// Weakly compressible SPH with the Tait equation of state: explicit, stepped at the acoustic
    /// CFL limit (`C h / c₀`, a tenth of a millisecond at centimetre spacing). The reference, and
    /// the solver for gases (`SphParams::gas`) and anything else that needs an equation of
    /// state.
    Wcsph,
    /// Divergence-free SPH (Bender & Koschier 2015, 2017): an implicit incompressible solver
    /// whose time step follows the flow's CFL (`C Δx / v_max`, milliseconds), not the speed of
    /// sound. The default. See [`DfsphSettings`].
    #[default]
    Dfsph,
}

impl PressureSolver {
    /// Every choice, for menus.
    pub const ALL: [PressureSolver; 2] = [Self::Wcsph, Self::Dfsph];

    /// A short human-readable name.
    pub fn label(self) -> &'static str {
        match self {
            Self::Dfsph => "DFSPH",
            Self::Wcsph => "WCSPH",
        }
    }
}

/// Settings of the divergence-free solver ([`PressureSolver::Dfsph`]).
///
/// Each sub-step makes the velocity field divergence-free (a pressure solve), adds gravity,
/// viscosity and external forces, then solves for the pressure that brings the predicted density
/// back to rest, and moves the particles. The default ([`Default`]) runs a fixed budget of 4
/// density and 1 divergence iterations a sub-step, the density solve started from a pressure on
/// a coarse grid under the particles plus most of the last sub-step's excess over it
/// ([`grid_start`](Self::grid_start)): a cost per sub-step that does not grow with the depth in
/// particles. [`reference`](Self::reference) solves to the tolerances instead, whatever the
/// iterations (26 a sub-step on the demo's 2,500 particles, 60 at 10,000). `docs/physics.md`'s
/// "The incompressible solver" section lists where it differs from the paper.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Default, Debug, PartialEq)]
pub struct DfsphSettings {
    /// Courant number `C` of the flow's time-step limit `dt = C Δx / v_max`, 0.05–1 (the default
    /// 0.7: no particle moves more than 0.7 spacings per step; the dam-break tests pass with it,
    /// and it takes a sixth fewer sub-steps than 0.6).
    pub cfl_number: f32,
    /// Longest sub-step, s (the limit when the fluid is at rest).
    pub max_time_step: f32,
    /// Mean predicted density error `|ρ − ρ₀|/ρ₀` the density solve stops at, as a fraction
    /// (0.0001 = 0.01%).
    pub density_tolerance: f32,
    /// Mean density change over one step `dt (Dρ/Dt)/ρ₀` the divergence solve stops at, as a
    /// fraction (0.01 = 1%).
    pub divergence_tolerance: f32,
    /// Most iterations of the density solve per sub-step.
    pub max_density_iterations: u32,
    /// Most iterations of the divergence solve per sub-step (0 switches it off).
    pub max_divergence_iterations: u32,
    /// Start each solve from the last sub-step's pressures.
    pub warm_start: bool,
    /// Run each solve for exactly its most iterations, without the tolerance stops (a fixed
    /// cost per sub-step, for measuring what the rest of a sub-step costs and for solves whose
    /// start is already close; a solve with nothing left to gain still stops). The density
    /// solve's iterations are then projected gradient steps, one pressure push and one
    /// density-rate pass each, half what a bounded conjugate-gradient iteration that expands
    /// costs (`docs/physics.md`, "Projected gradient steps under a fixed budget").
    pub fixed_budget: bool,
    /// Start the density solve from a pressure solved on a coarse grid under the particles
    /// (a MAC grid of two spacings a cell, a ghost-fluid free surface,
    /// multigrid-preconditioned conjugate gradients) plus nine tenths of what the last
    /// sub-step's pressure had above it (an excess the iterations leave fades): the smooth,
    /// fluid-wide part of the pressure (a column's weight), which local iterations
    /// remove slowest, so that a fixed budget of a few iterations holds deep water up (4 + 1
    /// holds resting layers 25 to 100 particles deep, where without it they boil).
    pub grid_start: bool,
}

impl Default for DfsphSettings {
    /// The grid start under a fixed budget of 4 density and 1 divergence iterations (see the
    /// type's docs).
    fn default() -> Self {
        Self {
            grid_start: true,
            ..Self::reference().with_budget(4, 1)
        }
    }
}

impl DfsphSettings {
    /// The strict solve: each solve runs until its tolerance is met (mean and largest error),
    /// up to 300 density and 100 divergence iterations, from the last sub-step's pressures.
    /// Right at every depth, at a cost that grows with it; the reference the default is checked
    /// against.
    pub fn reference() -> Self {
        Self {
            cfl_number: 0.7,
            max_time_step: 0.005,
            density_tolerance: 0.0001,
            divergence_tolerance: 0.01,
            max_density_iterations: 300,
            max_divergence_iterations: 100,
            warm_start: true,
            fixed_budget: false,
            grid_start: false,
        }
    }

    /// These settings with a fixed budget: exactly `density` and `divergence` iterations of the
    /// two solves each sub-step, without the tolerance stops ([`fixed_budget`](Self::fixed_budget)).
    pub fn with_budget(self, density: u32, divergence: u32) -> Self {
        Self {
            max_density_iterations: density,
            max_divergence_iterations: divergence,
            fixed_budget: true,
            ..self
        }
    }
}
