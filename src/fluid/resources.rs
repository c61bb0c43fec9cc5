//! The fluid plugin's resources: the solver's state ([`SphSolver`]), the tick's statistics
//! ([`SphStats`]) and whether the last parameters were taken ([`SphParamsStatus`]).

use super::liquids::LiquidConstants;
use super::params::{SphParams, SphParamsError};
use crate::sim::clock::SubstepClock;
use crate::sim::config::{PressureSolver, SphConstants};
use crate::sim::dfsph::DfsphReport;
use crate::sim::profile::StageProfile;
use crate::sim::step::{FluidStep, Particles, SolverIterations};
use bevy::prelude::*;

/// The solver's working state: the core's sub-step state (constants, cell-sorted snapshot,
/// walls, clock and the pressure solver's own state) and the particles gathered from the
/// components. Read it for diagnostics; the fluid's systems own it.
#[derive(Resource, Debug, Clone)]
pub struct SphSolver {
    pub(crate) step: FluidStep,
    /// The components' values by gathered index (see [`FluidIndex`](super::FluidIndex)).
    pub(crate) particles: Particles,
    /// The walls need re-sampling (the tank or the spacing changed).
    pub(crate) walls_dirty: bool,
    /// Counts gatherings; [`FluidIndex`](super::FluidIndex)es carry the one they were given in.
    pub(crate) generation: u32,
    /// Particles the guard removed for a non-finite state, and for leaving the tank.
    pub(crate) removed_non_finite: u64,
    pub(crate) removed_escaped: u64,
    /// The solids' entities, in the order of the step's solids.
    pub(crate) solids: super::solids::SolidIndex,
    /// What the step needs of each [`FluidMaterial`](super::FluidMaterial)'s liquid, by
    /// material (the base liquid first).
    pub(crate) liquids: Vec<LiquidConstants>,
}

impl Default for SphSolver {
    fn default() -> Self {
        Self::new(
            SphParams::default()
                .constants()
                .expect("the default parameters are valid"),
        )
    }
}

impl SphSolver {
    fn new(constants: SphConstants) -> Self {
        Self {
            step: FluidStep::new(constants),
            particles: Particles::default(),
            walls_dirty: true,
            generation: 0,
            removed_non_finite: 0,
            solids: Default::default(),
            removed_escaped: 0,
            liquids: vec![LiquidConstants {
                ratio: 1.0,
                viscosity: constants.kinematic_viscosity,
            }],
        }
    }

    /// The constants in use: those of the last valid [`SphParams`].
    pub fn constants(&self) -> &SphConstants {
        self.step.constants()
    }

    /// Where the last tick left the [`Solid`](super::Solid) of entity `solid`: its pose and
    /// velocities after the sub-steps (a body with [`SolidDynamics`](super::SolidDynamics) has
    /// answered the fluid's force on the way); `None` if the fluid holds no such solid.
    pub fn solid_motion(&self, solid: Entity) -> Option<crate::sim::solid::SolidMotion> {
        let k = self.solids.position(solid)?;
        self.step.solids().get(k).map(|s| s.motion())
    }

    /// The contact angle the fluid takes on the [`Solid`](super::Solid) of entity `solid`,
    /// degrees: its valid [`ContactAngle`](super::ContactAngle), or the tank's
    /// ([`SphParams::contact_angle`](super::SphParams::contact_angle)); `None` if the fluid
    /// holds no such solid.
    pub fn solid_contact_angle(&self, solid: Entity) -> Option<f32> {
        let k = self.solids.position(solid)?;
        let solid = self.step.solids().get(k)?;
        let tank = self.step.constants().wetting.acos().to_degrees();
        Some(solid.contact_angle().unwrap_or(tank))
    }

    /// Switches on the [`StageProfile`] of the sub-steps (each part's wall time from now on),
    /// or off with `None`.
    pub fn set_stage_profile(&mut self, profile: Option<StageProfile>) {
        self.step.shared.profile = profile;
    }

    /// Where the sub-steps' time went since [`set_stage_profile`](Self::set_stage_profile).
    pub fn stage_profile(&self) -> Option<&StageProfile> {
        self.step.shared.profile.as_ref()
    }

    /// The sub-step clock.
    pub fn clock(&self) -> &SubstepClock {
        &self.step.shared.clock
    }

    /// Pressure-solve iteration counts.
    pub fn iterations(&self) -> &SolverIterations {
        &self.step.shared.iterations
    }

    /// What the last DFSPH sub-step's solves did (the default report under WCSPH).
    pub fn dfsph_report(&self) -> DfsphReport {
        self.step.dfsph().map(|d| d.report).unwrap_or_default()
    }

    /// Puts the clock where a saved run left it (see [`load_fluid`](crate::gameplay::load_fluid)).
    pub(crate) fn restore_clock(&mut self, clock: SubstepClock) {
        self.step.shared.clock = clock;
    }

    /// Starts simulated time again from zero (after a reset).
    pub fn restart_clock(&mut self) {
        self.step.shared.clock = SubstepClock::default();
        self.step.shared.iterations = SolverIterations::default();
    }
}

/// Whether the last change to [`SphParams`] was accepted (`error`: why not).
pub type SphParamsStatus = crate::params::ParamsStatus<SphParams>;

impl crate::params::Params for SphParams {
    type Solver = SphSolver;
    const WHAT: &'static str = "the fluid";

    /// Derives the constants and re-samples the walls if the geometry changed.
    fn adopt(&self, solver: &mut SphSolver) -> Result<(), SphParamsError> {
        let constants = self.constants()?;
        let old = *solver.constants();
        let geometry_changed = old.tank != constants.tank
            || old.spacing != constants.spacing
            || old.support != constants.support
            || old.wall_layers != constants.wall_layers;
        solver.step.set_constants(constants);
        solver.liquids.clear();
        solver.liquids.extend(self.liquid_constants());
        if geometry_changed {
            solver.walls_dirty = true;
        }
        Ok(())
    }
}

/// Statistics of the last fixed tick, for panels and logs.
#[derive(Resource, Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct SphStats {
    /// Fluid particles.
    pub particles: usize,
    /// Wall particles of the tank and obstacles.
    pub wall_particles: usize,
    /// Sub-steps in the last tick.
    pub substeps: u32,
    /// Sub-steps since start-up (or the last reset).
    pub total_substeps: u64,
    /// Length of the last sub-step, s.
    pub dt: f32,
    /// Simulated time, s.
    pub time: f64,
    /// Simulated time dropped because a tick needed more than `max_substeps`, s.
    pub dropped_time: f64,
    /// Wall-clock time the last tick's sub-steps took, ms.
    pub tick_ms: f32,
    /// Fastest particle, m/s.
    pub max_speed: f32,
    /// Largest compression `(ρ − ρ₀)/ρ₀`, % (free-surface particles read below `ρ₀` by design of
    /// summation density, so only compression counts as error).
    pub max_density_error: f32,
    /// Mean compression over all particles, %.
    pub mean_density_error: f32,
    /// Particle updates that would have produced a non-finite value and were held back (should
    /// stay zero).
    pub non_finite_resets: u64,
    /// Particles the stability guard removed because their state was not finite (since
    /// start-up; should stay zero).
    pub removed_non_finite: u64,
    /// Particles the guard removed because they were outside the tank (since start-up).
    pub removed_escaped: u64,
    /// Whether the last tick needed more sub-steps than `max_substeps` allows, so the fluid ran
    /// in slow motion (see `dropped_time`).
    pub slow_motion: bool,
    /// The pressure solver in use.
    pub solver: PressureSolver,
    /// DFSPH density-solve iterations in the last tick (all its sub-steps; 0 under WCSPH).
    pub density_iterations: u32,
    /// DFSPH divergence-solve iterations in the last tick.
    pub divergence_iterations: u32,
    /// DFSPH iterations of both solves since start-up (or the last reset).
    pub total_iterations: u64,
    /// Mean predicted compression left by the last density solve, % (0 under WCSPH).
    pub solver_density_error: f32,
}
