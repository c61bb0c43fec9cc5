//! Runtime-tunable fluid parameters in SI units, and their validation. See
//! [`SphPlugin`](crate::fluid::SphPlugin).

use crate::params::{ParamField, ParamTable, param_field};
use crate::sim::boundary::Tank;
use crate::sim::config::{DfsphSettings, PressureSolver, SphConstants, SurfaceCalibration};
use crate::sim::kernels::{self, KernelKind};
use crate::sim::tension;
use bevy::prelude::*;

/// Standard gravity, m/s².
pub const STANDARD_GRAVITY: f32 = 9.81;

/// The fluid's parameters, in SI units (metres, seconds, kilograms; 2D masses and densities are
/// per metre of depth, so densities keep their 3D values in kg/m³).
///
/// Edit the resource at any time: the solver validates every change with
/// [`validate`](Self::validate) before using it. A change that fails is not applied: the solver
/// keeps the last valid parameters, logs the error, and shows it in
/// [`SphParamsStatus`](crate::fluid::SphParamsStatus).
///
/// The particle spacing and kernel fix each particle's mass, so change them together with a
/// respawn; everything else can change live.
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug, PartialEq)]
pub struct SphParams {
    /// Rest density `ρ₀`, kg/m³ (water: 1000).
    pub rest_density: f32,
    /// Speed of sound `c₀`, m/s. Weakly compressible SPH keeps density errors near
    /// `(v/c₀)²`, so pick about ten times the fastest flow speed (see
    /// [`speed_of_sound_for_height`](Self::speed_of_sound_for_height)); larger values cost smaller
    /// time steps.
    pub speed_of_sound: f32,
    /// Exponent `γ` of the Tait equation of state (7 for water; 1 gives a linear law).
    pub eos_exponent: f32,
    /// Background pressure `p_b`, Pa, added to the equation of state: 0 for a liquid, whose
    /// free surface sits at zero pressure; a positive value pushes particles apart everywhere,
    /// so the fluid expands to fill its container like a gas (`p_b = ρ₀c₀²/γ` with `γ = 1`
    /// gives the isothermal ideal gas `p = c₀²ρ`).
    pub background_pressure: f32,
    /// Kinematic viscosity `ν`, m²/s (water: 1.0e-6; honey about 5e-3).
    pub kinematic_viscosity: f32,
    /// Monaghan's artificial viscosity `α`, dimensionless (0.01–0.1): damps the acoustic noise of
    /// a weakly compressible fluid; keep it small for water.
    pub artificial_viscosity: f32,
    /// Initial particle spacing `Δx`, m. Sets particle mass and the resolution.
    pub particle_spacing: f32,
    /// Kernel support radius over particle spacing, `H/Δx` (1.5–5; 2 gives about 11 neighbours,
    /// 2.6 about 21, 3 about 29). Smaller is faster but less accurate. With WCSPH the discrete
    /// pressure gradient on a square lattice is 6% weak at 2, 4% at 2.6 and under 1% at 3 (its
    /// default), and hydrostatic pressure comes out high by as much; DFSPH corrects its
    /// gradient on the lattice and defaults to 2.
    pub support_ratio: f32,
    /// Which kernels compute density and gradients.
    pub kernel: KernelKind,
    /// Gravity, m/s² (default `(0, −9.81)`); tilt it to slosh the tank.
    pub gravity: Vec2,
    /// The rectangular tank, inner corner at the origin; `None` leaves the fluid unbounded.
    pub tank: Option<Tank>,
    /// Courant number of the acoustic time-step limit, 0–1 (0.4 is standard).
    pub cfl_number: f32,
    /// Most sub-steps in one fixed tick. If stability needs more, the rest of the tick is dropped
    /// (the fluid runs slower than real time) instead of the simulation blowing up.
    pub max_substeps: u32,
    /// Restitution of the geometric wall collision that backs up the boundary particles, 0–1.
    pub wall_restitution: f32,
    /// Which pressure solver keeps the fluid incompressible.
    pub solver: PressureSolver,
    /// Settings of [`PressureSolver::Dfsph`] (ignored by WCSPH).
    pub dfsph: DfsphSettings,
    /// Surface tension `σ`, N/m (water against air: 0.072; 0, the default, switches it off).
    /// Off by default because at the default 2 cm spacing water's capillary length
    /// (`√(σ/ρg)`, 2.7 mm) is under a spacing: the pull would change nothing one could see, at
    /// a cost per sub-step. It matters for drops and films tens of spacings across (see
    /// `docs/physics.md`, "Surface tension"; experimental: a drop holds together and oscillates
    /// at its Rayleigh period, but its Laplace pressure reads about 40% high), and it shortens
    /// the sub-step to the capillary limit `√(ρ₀Δx³/2πσ)`.
    pub surface_tension: f32,
    /// The contact angle of the liquid on the tank's walls and on every solid without one of
    /// its own, degrees through the liquid, 0–180: under 90 the liquid wets (clings, spreads
    /// into a film), over 90 it beads; 90, the default, is neutral. It acts only with
    /// [`surface_tension`](Self::surface_tension): the surface meets a wall at this angle.
    pub contact_angle: f32,
    /// The liquids besides the base one (whose rest density is
    /// [`rest_density`](Self::rest_density)): a particle with
    /// [`FluidMaterial(k)`](crate::fluid::FluidMaterial) is `liquids[k − 1]`. Empty by default.
    pub liquids: Vec<crate::fluid::Liquid>,
}

impl Default for SphParams {
    fn default() -> Self {
        Self::water()
    }
}

/// Why a [`SphParams`] value was refused (the crate's one [`ParamsError`](crate::params::ParamsError)).
pub type SphParamsError = crate::params::ParamsError;

/// The panel's row for one side of the tank (see [`SphParams::TANK_WIDTH`]).
macro_rules! tank_field {
    ($side:ident, $label:expr) => {
        ParamField {
            field: concat!("tank.", stringify!($side)),
            label: $label,
            unit: "m",
            valid: (0.0, 1.0e4),
            positive: true,
            slider: (0.1, 10.0),
            logarithmic: true,
            integer: false,
            scale: None,
            get: |p| p.tank.map_or(0.0, |tank| tank.$side),
            set: |p, v| {
                if let Some(tank) = &mut p.tank {
                    tank.$side = v;
                }
            },
        }
    };
}

/// The rows of [`SphParams`]'s table, by name: the panel draws each by reference.
#[rustfmt::skip]
impl SphParams {
    // path, label, unit, accepted range, zero excluded, slider range, logarithmic
    /// [`rest_density`](Self::rest_density).
    pub const REST_DENSITY: ParamField<Self> = param_field!(rest_density, "rest density ρ₀", "kg/m³", (0.0, 1.0e5), true, (0.5, 5000.0), true);
    /// [`speed_of_sound`](Self::speed_of_sound).
    pub const SPEED_OF_SOUND: ParamField<Self> = param_field!(speed_of_sound, "speed of sound c₀", "m/s", (0.0, 1.0e4), true, (1.0, 300.0), true);
    /// [`eos_exponent`](Self::eos_exponent).
    pub const EOS_EXPONENT: ParamField<Self> = param_field!(eos_exponent, "EOS exponent γ", "", (1.0, 10.0), false, (1.0, 10.0), false);
    /// [`background_pressure`](Self::background_pressure), in units of the Tait stiffness.
    pub const BACKGROUND_PRESSURE: ParamField<Self> = param_field!(background_pressure, "background pressure", "Pa", (0.0, 10.0), false, (0.0, 10.0), false, scale: |p| p.tait_stiffness());
    /// [`kinematic_viscosity`](Self::kinematic_viscosity).
    pub const KINEMATIC_VISCOSITY: ParamField<Self> = param_field!(kinematic_viscosity, "kinematic viscosity ν", "m²/s", (0.0, 100.0), false, (0.0, 1.0e-2), true);
    /// [`artificial_viscosity`](Self::artificial_viscosity).
    pub const ARTIFICIAL_VISCOSITY: ParamField<Self> = param_field!(artificial_viscosity, "artificial viscosity α", "", (0.0, 10.0), false, (0.0, 1.0), false);
    /// [`surface_tension`](Self::surface_tension).
    pub const SURFACE_TENSION: ParamField<Self> = param_field!(surface_tension, "surface tension σ", "N/m", (0.0, 100.0), false, (0.0, 0.5), false);
    /// [`contact_angle`](Self::contact_angle).
    pub const CONTACT_ANGLE: ParamField<Self> = param_field!(contact_angle, "contact angle θ", "°", (0.0, 180.0), false, (0.0, 180.0), false);
    /// [`support_ratio`](Self::support_ratio).
    pub const SUPPORT_RATIO: ParamField<Self> = param_field!(support_ratio, "support H/Δx", "spacings", (1.5, 5.0), false, (1.5, 5.0), false);
    /// The x part of [`gravity`](Self::gravity), for the panel: not in the table's
    /// [`FIELDS`](ParamTable::FIELDS), because [`validate`](Self::validate) checks the vector
    /// whole (finite, at most 1e4 m/s² long, which keeps each part in this row's range).
    pub const GRAVITY_X: ParamField<Self> = param_field!(gravity.x, "gravity x", "m/s²", (-1.0e4, 1.0e4), false, (-30.0, 30.0), false);
    /// The y part of [`gravity`](Self::gravity), for the panel, as [`GRAVITY_X`](Self::GRAVITY_X).
    pub const GRAVITY_Y: ParamField<Self> = param_field!(gravity.y, "gravity y", "m/s²", (-1.0e4, 1.0e4), false, (-30.0, 30.0), false);
    /// [`cfl_number`](Self::cfl_number).
    pub const CFL_NUMBER: ParamField<Self> = param_field!(cfl_number, "CFL number", "", (0.01, 1.0), false, (0.01, 1.0), false);
    /// [`max_substeps`](Self::max_substeps).
    pub const MAX_SUBSTEPS: ParamField<Self> = param_field!(count: max_substeps, "max sub-steps / tick", (1.0, 1.0e5), (1.0, 2000.0), true);
    /// [`wall_restitution`](Self::wall_restitution).
    pub const WALL_RESTITUTION: ParamField<Self> = param_field!(wall_restitution, "wall restitution", "", (0.0, 1.0), false, (0.0, 1.0), false);
    /// [`DfsphSettings::cfl_number`].
    pub const DFSPH_CFL_NUMBER: ParamField<Self> = param_field!(dfsph.cfl_number, "flow CFL C", "", (0.05, 1.0), false, (0.05, 1.0), false);
    /// [`DfsphSettings::max_time_step`].
    pub const DFSPH_MAX_TIME_STEP: ParamField<Self> = param_field!(dfsph.max_time_step, "longest sub-step", "s", (1.0e-5, 0.1), false, (1.0e-4, 0.02), true);
    /// [`DfsphSettings::density_tolerance`].
    pub const DFSPH_DENSITY_TOLERANCE: ParamField<Self> = param_field!(dfsph.density_tolerance, "density tolerance", "", (1.0e-6, 0.1), false, (1.0e-6, 0.01), true);
    /// [`DfsphSettings::divergence_tolerance`].
    pub const DFSPH_DIVERGENCE_TOLERANCE: ParamField<Self> = param_field!(dfsph.divergence_tolerance, "divergence tolerance", "", (1.0e-6, 1.0), false, (1.0e-5, 0.1), true);
    /// [`DfsphSettings::max_density_iterations`].
    pub const DFSPH_MAX_DENSITY_ITERATIONS: ParamField<Self> = param_field!(count: dfsph.max_density_iterations, "max density iterations", (1.0, 1.0e4), (1.0, 500.0), true);
    /// [`DfsphSettings::max_divergence_iterations`].
    pub const DFSPH_MAX_DIVERGENCE_ITERATIONS: ParamField<Self> = param_field!(count: dfsph.max_divergence_iterations, "max divergence iterations", (0.0, 1.0e4), (0.0, 500.0), false);
    /// The tank's width, for the panel (no tank: reads 0, writes nothing): not in the table,
    /// because [`validate`](Self::validate) checks the tank whole (at least one particle spacing
    /// on a side, at most 1e4 m, and the wall particles it needs).
    pub const TANK_WIDTH: ParamField<Self> = tank_field!(width, "tank width");
    /// The tank's height, for the panel, as [`TANK_WIDTH`](Self::TANK_WIDTH).
    pub const TANK_HEIGHT: ParamField<Self> = tank_field!(height, "tank height");
}

impl ParamTable for SphParams {
    const OWNER: &'static str = "SphParams";

    /// The numeric fields and counts with a range, in the panel's order (gravity as a vector,
    /// the tank and the switches are checked in [`validate`](Self::validate) itself).
    const FIELDS: &'static [ParamField<Self>] = &[
        Self::REST_DENSITY,
        Self::SPEED_OF_SOUND,
        Self::EOS_EXPONENT,
        Self::BACKGROUND_PRESSURE,
        Self::KINEMATIC_VISCOSITY,
        Self::ARTIFICIAL_VISCOSITY,
        Self::SURFACE_TENSION,
        Self::CONTACT_ANGLE,
        Self::SUPPORT_RATIO,
        Self::CFL_NUMBER,
        Self::MAX_SUBSTEPS,
        Self::WALL_RESTITUTION,
        Self::DFSPH_CFL_NUMBER,
        Self::DFSPH_MAX_TIME_STEP,
        Self::DFSPH_DENSITY_TOLERANCE,
        Self::DFSPH_DIVERGENCE_TOLERANCE,
        Self::DFSPH_MAX_DENSITY_ITERATIONS,
        Self::DFSPH_MAX_DIVERGENCE_ITERATIONS,
    ];
}

/// Most wall particles a tank may need before validation refuses it (memory guard).
pub const MAX_WALL_PARTICLES: u64 = crate::sim::boundary::MAX_BOUNDARY_PARTICLES;

impl SphParams {
    /// Water in a 2 m × 1.2 m tank at 2 cm spacing, incompressible ([`PressureSolver::Dfsph`],
    /// support 2 spacings: about 12 neighbours, as SPlisHSPlasH's default; the lattice gradient
    /// correction keeps its hydrostatic pressure exact). The speed of sound only scales the artificial viscosity here, and is
    /// what [`water_wcsph`](Self::water_wcsph) steps at.
    pub fn water() -> Self {
        Self {
            rest_density: 1000.0,
            speed_of_sound: Self::speed_of_sound_for_height(1.0),
            eos_exponent: 7.0,
            background_pressure: 0.0,
            kinematic_viscosity: 1.0e-6,
            artificial_viscosity: 0.02,
            particle_spacing: 0.02,
            support_ratio: 2.0,
            kernel: KernelKind::WendlandC2,
            gravity: Vec2::new(0.0, -STANDARD_GRAVITY),
            tank: Some(Tank::new(2.0, 1.2)),
            cfl_number: 0.4,
            max_substeps: 400,
            wall_restitution: 0.0,
            solver: PressureSolver::Dfsph,
            dfsph: DfsphSettings::default(),
            surface_tension: 0.0,
            contact_angle: 90.0,
            liquids: Vec::new(),
        }
    }

    /// [`water`](Self::water) with the strict DFSPH solve ([`DfsphSettings::reference`]): each
    /// solve to its tolerance, whatever the iterations. What the default is checked against.
    pub fn reference() -> Self {
        Self {
            dfsph: DfsphSettings::reference(),
            ..Self::water()
        }
    }

    /// [`water`](Self::water) on the weakly compressible solver ([`PressureSolver::Wcsph`]),
    /// with the support of 3 spacings that its pressure gradient needs to be accurate.
    pub fn water_wcsph() -> Self {
        Self {
            solver: PressureSolver::Wcsph,
            support_ratio: 3.0,
            ..Self::water()
        }
    }

    /// Honey (about 4 Pa·s at room temperature: `ν = 2.8e-3` m²/s, `ρ₀ = 1420` kg/m³) in the
    /// same tank as [`water`](Self::water). The viscous time-step limit `⅛h²/ν` is far below the
    /// acoustic one, so honey costs many more sub-steps per second than water.
    pub fn honey() -> Self {
        Self {
            rest_density: 1420.0,
            kinematic_viscosity: 2.8e-3,
            ..Self::water()
        }
    }

    /// A gas-like fluid: air's density (1.2 kg/m³), an isothermal linear equation of state
    /// (`γ = 1`) with a background pressure equal to its stiffness, so `p = c₀²ρ` and the fluid
    /// spreads to fill the tank. Its speed of sound (8 m/s) is far below air's 343 m/s so that it
    /// stays cheap to step; it behaves like a very soft gas.
    pub fn gas() -> Self {
        let speed_of_sound = 8.0;
        let rest_density = 1.2;
        Self {
            rest_density,
            speed_of_sound,
            eos_exponent: 1.0,
            background_pressure: rest_density * speed_of_sound * speed_of_sound,
            kinematic_viscosity: 1.5e-5,
            artificial_viscosity: 0.05,
            // A gas is its equation of state: weakly compressible.
            ..Self::water_wcsph()
        }
    }

    /// A speed of sound for free-surface flow from a fluid column `height` (m) high:
    /// `20 √(g h)`, ten times the fastest speed a collapsing column reaches (`2√(g h)`).
    pub fn speed_of_sound_for_height(height: f32) -> f32 {
        20.0 * (STANDARD_GRAVITY * height.max(1e-6)).sqrt()
    }

    /// Kernel support radius `H = support_ratio · particle_spacing`, m.
    pub fn support_radius(&self) -> f32 {
        self.support_ratio * self.particle_spacing
    }

    /// Mass of each particle, kg per metre of depth: `ρ₀` divided by the density kernel's sum
    /// over a square lattice of the particle spacing, so an interior particle of a freshly
    /// spawned block has exactly rest density (within 2% of `ρ₀Δx²` for the default kernel).
    pub fn particle_mass(&self) -> f32 {
        let h = self.support_radius();
        let sum = match self.kernel {
            KernelKind::WendlandC2 => {
                kernels::lattice_sum(&kernels::WendlandC2::new(h), self.particle_spacing)
            }
            KernelKind::CubicSpline => {
                kernels::lattice_sum(&kernels::CubicSpline::new(h), self.particle_spacing)
            }
            KernelKind::Muller => {
                kernels::lattice_sum(&kernels::Poly6::new(h), self.particle_spacing)
            }
        };
        (self.rest_density as f64 / sum) as f32
    }

    /// The factor on kernel gradients that makes the discrete gradient of a linear field exact
    /// on the rest lattice: `1 / Σⱼ Vⱼ (xⱼ − xᵢ)ₓ ∂ₓWᵢⱼ` with `V = m/ρ₀` (see
    /// [`lattice_gradient_moment`](kernels::lattice_gradient_moment)). Used by DFSPH.
    pub fn gradient_scale(&self) -> f32 {
        let h = self.support_radius();
        let dx = self.particle_spacing;
        let (sum, moment) = match self.kernel {
            KernelKind::WendlandC2 => {
                let w = kernels::WendlandC2::new(h);
                (
                    kernels::lattice_sum(&w, dx),
                    kernels::lattice_gradient_moment(&w, dx),
                )
            }
            KernelKind::CubicSpline => {
                let w = kernels::CubicSpline::new(h);
                (
                    kernels::lattice_sum(&w, dx),
                    kernels::lattice_gradient_moment(&w, dx),
                )
            }
            KernelKind::Muller => (
                kernels::lattice_sum(&kernels::Poly6::new(h), dx),
                kernels::lattice_gradient_moment(&kernels::Spiky::new(h), dx),
            ),
        };
        (sum / moment) as f32
    }

    /// How a flat free surface of the rest lattice reads, for the surface tension
    /// (on the rest lattice's flat surface).
    pub fn surface_calibration(&self) -> SurfaceCalibration {
        let volume = self.particle_mass() / self.rest_density;
        let (h, dx) = (self.support_radius(), self.particle_spacing);
        match self.kernel {
            KernelKind::WendlandC2 => {
                let w = kernels::WendlandC2::new(h);
                tension::calibrate(&w, &w, dx, volume)
            }
            KernelKind::CubicSpline => {
                let w = kernels::CubicSpline::new(h);
                tension::calibrate(&w, &w, dx, volume)
            }
            KernelKind::Muller => {
                let (w, g) = (kernels::Poly6::new(h), kernels::Spiky::new(h));
                tension::calibrate(&w, &g, dx, volume)
            }
        }
    }

    /// Layers of wall particles needed so a particle at a wall has a full neighbourhood.
    pub fn wall_layers(&self) -> u32 {
        (self.support_ratio.ceil() as u32).max(1)
    }

    /// Checks every field; the first problem found is returned with the field's name, its value
    /// and the accepted range.
    pub fn validate(&self) -> Result<(), SphParamsError> {
        let range = |field, value, min, max, unit| {
            crate::params::check_range(Self::OWNER, field, value, (min, max), unit)
        };
        // Checked before the table, whose row gives a plainer message.
        range("support_ratio", self.support_ratio, 1.5, 5.0, "spacings").map_err(|e| {
            SphParamsError {
                owner: "SphParams",
                message: format!(
                    "{}: the kernel support {} m must span 1.5 to 5 particle spacings ({} m), \
                     or particles see too few (or far too many) neighbours",
                    e.message,
                    self.support_ratio * self.particle_spacing,
                    self.particle_spacing
                ),
                ..e
            }
        })?;
        if !self.gravity.is_finite() || self.gravity.length() > 1.0e4 {
            return Err(SphParamsError {
                owner: "SphParams",
                field: "gravity",
                message: format!(
                    "{} m/s² must be finite and at most 1e4 m/s² long",
                    self.gravity
                ),
            });
        }
        for field in Self::FIELDS {
            field.check(self)?;
        }
        range(
            "particle_spacing",
            self.particle_spacing,
            1.0e-5,
            100.0,
            "m",
        )?;
        self.check_tank()?;
        self.check_liquids()?;
        let mass = self.particle_mass();
        if !(mass.is_finite() && mass > 0.0) {
            return Err(SphParamsError {
                owner: "SphParams",
                field: "particle_spacing",
                message: format!("gives a particle mass of {mass} kg/m"),
            });
        }
        Ok(())
    }

    /// The tank's size, and how many wall particles it needs at this spacing.
    fn check_tank(&self) -> Result<(), SphParamsError> {
        if let Some(tank) = &self.tank {
            for (field, value) in [("tank.width", tank.width), ("tank.height", tank.height)] {
                if !(value.is_finite() && value >= self.particle_spacing && value <= 1.0e4) {
                    return Err(SphParamsError {
                        owner: "SphParams",
                        field,
                        message: format!(
                            "{value} m must be finite, at least one particle spacing ({} m) \
                             and at most 1e4 m",
                            self.particle_spacing
                        ),
                    });
                }
            }
            let walls = tank.sample_count(self.particle_spacing, self.wall_layers());
            if walls > MAX_WALL_PARTICLES {
                return Err(SphParamsError {
                    owner: "SphParams",
                    field: "tank",
                    message: format!(
                        "a {} m × {} m tank at {} m spacing needs {walls} wall particles \
                         (limit {MAX_WALL_PARTICLES}); use a coarser spacing or a smaller tank",
                        tank.width, tank.height, self.particle_spacing
                    ),
                });
            }
        }
        Ok(())
    }

    /// The Tait stiffness `B = ρ₀ c₀² / γ`, Pa: the equation of state's pressure scale (the one
    /// place it is computed).
    pub fn tait_stiffness(&self) -> f32 {
        self.rest_density * self.speed_of_sound * self.speed_of_sound / self.eos_exponent
    }

    /// The derived constants the solver runs on, if the parameters are valid.
    pub fn constants(&self) -> Result<SphConstants, SphParamsError> {
        self.validate()?;
        let support = self.support_radius();
        let stiffness = self.tait_stiffness();
        Ok(SphConstants {
            kernel: self.kernel,
            spacing: self.particle_spacing,
            support,
            support_sq: support * support,
            smoothing_length: 0.5 * support,
            mass: self.particle_mass(),
            rest_density: self.rest_density,
            speed_of_sound: self.speed_of_sound,
            eos_exponent: self.eos_exponent,
            stiffness,
            background_pressure: self.background_pressure,
            artificial_viscosity: self.artificial_viscosity,
            kinematic_viscosity: self.kinematic_viscosity,
            gravity: self.gravity,
            cfl_number: self.cfl_number,
            speed_limit: self.speed_of_sound,
            wall_restitution: self.wall_restitution,
            tank: self.tank,
            wall_layers: self.wall_layers(),
            max_substeps: self.max_substeps,
            solver: self.solver,
            dfsph: self.dfsph,
            volume: self.particle_mass() / self.rest_density,
            gradient_scale: self.gradient_scale(),
            surface_tension: self.surface_tension,
            wetting: self.contact_angle.to_radians().cos(),
            surface: self.surface_calibration(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_slider_lies_inside_what_validation_accepts() {
        let water = SphParams::water();
        for row in SphParams::FIELDS {
            let (low, high) = row.slider;
            for value in [low, high] {
                let mut p = water.clone();
                (row.set)(&mut p, value);
                assert_eq!((row.get)(&p), value, "{}", row.field);
                let ok = row.check(&p);
                // A positive field's slider may start at zero only if zero is accepted.
                assert!(
                    ok.is_ok() || (row.positive && value == 0.0),
                    "{}: {ok:?}",
                    row.field
                );
            }
            // A count cannot hold NaN: one past its range instead.
            let mut bad = water.clone();
            let nonsense = if row.integer {
                row.valid.1 + 1.0
            } else {
                f32::NAN
            };
            (row.set)(&mut bad, nonsense);
            let error = bad.validate().unwrap_err();
            assert_eq!(error.field, row.field);
        }
    }

    #[test]
    fn defaults_are_valid() {
        assert_eq!(SphParams::default().validate(), Ok(()));
        let c = SphParams::default().constants().unwrap();
        assert!(c.mass > 0.0 && c.stiffness > 0.0);
    }

    #[test]
    fn bad_values_are_refused_with_the_field_named() {
        type Breakage = Box<dyn Fn(&mut SphParams)>;
        let cases: Vec<(&str, Breakage)> = vec![
            ("rest_density", Box::new(|p| p.rest_density = -1.0)),
            ("rest_density", Box::new(|p| p.rest_density = 0.0)),
            ("speed_of_sound", Box::new(|p| p.speed_of_sound = f32::NAN)),
            ("eos_exponent", Box::new(|p| p.eos_exponent = 0.0)),
            (
                "background_pressure",
                Box::new(|p| p.background_pressure = -1.0),
            ),
            (
                "kinematic_viscosity",
                Box::new(|p| p.kinematic_viscosity = -1e-6),
            ),
            (
                "artificial_viscosity",
                Box::new(|p| p.artificial_viscosity = f32::INFINITY),
            ),
            ("surface_tension", Box::new(|p| p.surface_tension = -0.07)),
            (
                "surface_tension",
                Box::new(|p| p.surface_tension = f32::NAN),
            ),
            ("contact_angle", Box::new(|p| p.contact_angle = -1.0)),
            ("contact_angle", Box::new(|p| p.contact_angle = 181.0)),
            ("contact_angle", Box::new(|p| p.contact_angle = f32::NAN)),
            ("particle_spacing", Box::new(|p| p.particle_spacing = 0.0)),
            ("support_ratio", Box::new(|p| p.support_ratio = 0.9)),
            ("support_ratio", Box::new(|p| p.support_ratio = 12.0)),
            (
                "gravity",
                Box::new(|p| p.gravity = Vec2::new(0.0, f32::NAN)),
            ),
            ("cfl_number", Box::new(|p| p.cfl_number = 0.0)),
            ("max_substeps", Box::new(|p| p.max_substeps = 0)),
            ("wall_restitution", Box::new(|p| p.wall_restitution = 1.5)),
            ("dfsph.cfl_number", Box::new(|p| p.dfsph.cfl_number = 0.0)),
            (
                "dfsph.max_time_step",
                Box::new(|p| p.dfsph.max_time_step = -1.0),
            ),
            (
                "dfsph.density_tolerance",
                Box::new(|p| p.dfsph.density_tolerance = f32::NAN),
            ),
            (
                "dfsph.divergence_tolerance",
                Box::new(|p| p.dfsph.divergence_tolerance = 2.0),
            ),
            (
                "dfsph.max_density_iterations",
                Box::new(|p| p.dfsph.max_density_iterations = 0),
            ),
            (
                "dfsph.max_divergence_iterations",
                Box::new(|p| p.dfsph.max_divergence_iterations = 20_000),
            ),
            (
                "tank.width",
                Box::new(|p| p.tank = Some(Tank::new(-1.0, 1.0))),
            ),
            (
                "tank.height",
                Box::new(|p| p.tank = Some(Tank::new(1.0, 0.001))),
            ),
            (
                "tank",
                Box::new(|p| {
                    p.tank = Some(Tank::new(5000.0, 5000.0));
                    p.particle_spacing = 0.001;
                }),
            ),
        ];
        for (field, break_it) in cases {
            let mut p = SphParams::default();
            break_it(&mut p);
            let err = p.validate().expect_err(field);
            assert_eq!(err.field, field, "{err}");
            assert!(err.to_string().contains(field));
            assert!(p.constants().is_err());
        }
    }

    #[test]
    fn support_ratio_error_explains_itself() {
        let p = SphParams {
            support_ratio: 1.0,
            ..default()
        };
        let msg = p.validate().unwrap_err().to_string();
        assert!(msg.contains("spacing"), "{msg}");
    }

    #[test]
    fn particle_mass_is_close_to_rest_density_times_cell_area() {
        for kernel in KernelKind::ALL {
            for ratio in [2.0, 2.6, 3.0] {
                let p = SphParams {
                    kernel,
                    support_ratio: ratio,
                    ..default()
                };
                let naive = p.rest_density * p.particle_spacing * p.particle_spacing;
                let m = p.particle_mass();
                assert!(
                    (m / naive - 1.0).abs() < 0.1,
                    "{kernel:?} at ratio {ratio}: mass {m} vs ρ₀Δx² {naive}"
                );
            }
        }
    }

    #[test]
    fn sound_speed_scales_with_height() {
        let c = SphParams::speed_of_sound_for_height(0.3);
        assert!((c - 20.0 * (9.81f32 * 0.3).sqrt()).abs() < 1e-4);
    }
}
