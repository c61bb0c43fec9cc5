//! Two liquids or more in one fluid: the [`Liquid`]s of [`SphParams::liquids`] besides the base
//! liquid, and the [`FluidMaterial`] component that says which one a particle is.
//!
//! Each particle keeps its own liquid's rest density: the solver sums the particles' number
//! density (Solenthaler & Pajarola 2008, "Density contrast SPH interfaces"), which is one at
//! rest on both sides of the surface between two liquids, so that surface stays sharp, and a
//! particle's mass is its liquid's. The pressure is continuous across the surface; a heavier
//! liquid's rises faster with depth.

use super::SphParams;
use bevy::prelude::*;

/// The most rest densities a liquid may have against the base liquid's, either way: a liquid
/// from a quarter to four times as dense.
pub const MAX_DENSITY_RATIO: f32 = 4.0;

/// A liquid besides the base one ([`SphParams::rest_density`]).
#[derive(Reflect, Debug, Clone, PartialEq)]
pub struct Liquid {
    /// What the panel and logs call it.
    pub name: String,
    /// Rest density, kg/m³: within [`MAX_DENSITY_RATIO`] of the base liquid's either way.
    pub rest_density: f32,
    /// Kinematic viscosity `ν`, m²/s, as the base liquid's
    /// ([`SphParams::kinematic_viscosity`]): between a particle of this liquid and one of
    /// another the laminar term takes the harmonic mean of their two. Snapshots saved before
    /// liquids had viscosities read as water's.
    #[reflect(default = "water_viscosity")]
    pub kinematic_viscosity: f32,
}

/// [`Liquid::WATER_VISCOSITY`], for the reflection of snapshots that lack a viscosity.
fn water_viscosity() -> f32 {
    Liquid::WATER_VISCOSITY
}

impl Liquid {
    /// Water's kinematic viscosity, m²/s: a new liquid's.
    pub const WATER_VISCOSITY: f32 = 1.0e-6;

    /// A liquid of `rest_density` kg/m³ called `name`, as viscous as water
    /// ([`WATER_VISCOSITY`](Self::WATER_VISCOSITY)).
    pub fn new(name: impl Into<String>, rest_density: f32) -> Self {
        Self {
            name: name.into(),
            rest_density,
            kinematic_viscosity: Self::WATER_VISCOSITY,
        }
    }

    /// This liquid with a kinematic viscosity of `nu` m²/s.
    pub fn with_viscosity(self, nu: f32) -> Self {
        Self {
            kinematic_viscosity: nu,
            ..self
        }
    }

    /// Cooking (sunflower) oil at 20 °C: 920 kg/m³, floats on water; `ν` 5.4 × 10⁻⁵ m²/s,
    /// fifty times water's (0.05 Pa·s).
    pub fn oil() -> Self {
        Self::new("oil", 920.0).with_viscosity(5.4e-5)
    }

    /// Brine (about 26% salt) at 20 °C: 1,200 kg/m³, sinks under water; `ν` 1.6 × 10⁻⁶ m²/s
    /// (1.9 mPa·s).
    pub fn brine() -> Self {
        Self::new("brine", 1200.0).with_viscosity(1.6e-6)
    }
}

/// Which liquid a [`FluidParticle`](super::FluidParticle) is: 0 (or no component) the base
/// liquid, `k` the liquid `SphParams::liquids[k − 1]`. A material past the list's end counts as
/// the base liquid.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[reflect(Component, Default, Debug, PartialEq)]
pub struct FluidMaterial(pub u8);

/// What the step needs of one liquid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LiquidConstants {
    /// Its rest density over the base liquid's.
    pub ratio: f32,
    /// Its kinematic viscosity, m²/s.
    pub viscosity: f32,
}

impl SphParams {
    /// The rest density of `material`'s liquid over the base liquid's (one for the base liquid
    /// and for a material past the list's end).
    pub fn density_ratio(&self, material: FluidMaterial) -> f32 {
        (self.liquid_constants())
            .nth(material.0 as usize)
            .map_or(1.0, |liquid| liquid.ratio)
    }

    /// The base liquid's constants, then each of [`liquids`](Self::liquids)'.
    pub(super) fn liquid_constants(&self) -> impl Iterator<Item = LiquidConstants> + '_ {
        let base = LiquidConstants {
            ratio: 1.0,
            viscosity: self.kinematic_viscosity,
        };
        let others = self.liquids.iter().map(|liquid| LiquidConstants {
            ratio: liquid.rest_density / self.rest_density,
            viscosity: liquid.kinematic_viscosity,
        });
        std::iter::once(base).chain(others)
    }

    /// Refuses a liquid whose rest density is not finite or not within
    /// [`MAX_DENSITY_RATIO`] of the base liquid's, a viscosity outside the base liquid's range
    /// ([`SphParams::KINEMATIC_VISCOSITY`]), and more liquids than a material can name.
    pub(super) fn check_liquids(&self) -> Result<(), super::SphParamsError> {
        let refuse = |message: String| super::SphParamsError {
            owner: "SphParams",
            field: "liquids",
            message,
        };
        if self.liquids.len() >= u8::MAX as usize {
            return Err(refuse(format!(
                "{} liquids: at most {} besides the base liquid",
                self.liquids.len(),
                u8::MAX - 1
            )));
        }
        let (low, high) = (
            self.rest_density / MAX_DENSITY_RATIO,
            self.rest_density * MAX_DENSITY_RATIO,
        );
        for (k, liquid) in self.liquids.iter().enumerate() {
            let rho = liquid.rest_density;
            if !(rho.is_finite() && (low..=high).contains(&rho)) {
                return Err(refuse(format!(
                    "liquid {} ({}): rest density {rho} kg/m³ must be within {low} to {high} \
                     kg/m³ ({MAX_DENSITY_RATIO} times the base liquid's either way)",
                    k + 1,
                    liquid.name
                )));
            }
            let nu = liquid.kinematic_viscosity;
            let (least, most) = SphParams::KINEMATIC_VISCOSITY.valid;
            if !(nu.is_finite() && (least..=most).contains(&nu)) {
                return Err(refuse(format!(
                    "liquid {} ({}): kinematic viscosity {nu} m²/s must be within {least} to \
                     {most} m²/s",
                    k + 1,
                    liquid.name
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_material_reads_its_liquids_density_over_the_base_liquids() {
        let params = SphParams {
            liquids: vec![Liquid::oil(), Liquid::brine()],
            ..SphParams::water()
        };
        assert_eq!(params.density_ratio(FluidMaterial(0)), 1.0);
        assert!((params.density_ratio(FluidMaterial(1)) - 0.92).abs() < 1e-6);
        assert!((params.density_ratio(FluidMaterial(2)) - 1.2).abs() < 1e-6);
        assert_eq!(params.density_ratio(FluidMaterial(3)), 1.0, "past the end");
        assert!(params.validate().is_ok());
    }

    #[test]
    fn a_liquid_of_negative_or_endless_viscosity_is_refused() {
        for nu in [-1e-6, f32::INFINITY, f32::NAN, 1e3] {
            let params = SphParams {
                liquids: vec![Liquid::oil().with_viscosity(nu)],
                ..SphParams::water()
            };
            let error = params.validate().expect_err("refused");
            assert_eq!(error.field, "liquids");
            assert!(error.message.contains("viscosity"), "{error}");
        }
    }

    #[test]
    fn a_liquid_too_light_too_dense_or_not_finite_is_refused() {
        for rho in [200.0, 5000.0, f32::NAN, -1.0] {
            let params = SphParams {
                liquids: vec![Liquid::new("odd", rho)],
                ..SphParams::water()
            };
            let error = params.validate().expect_err("refused");
            assert_eq!(error.field, "liquids");
            assert!(error.message.contains("odd"), "{error}");
        }
    }
}
