//! Runtime-tunable gravity parameters and their validation. See
//! [`GravityPlugin`](crate::gravity::GravityPlugin).

use crate::params::{ParamField, ParamTable, param_field};
use crate::sim::gravity::quadtree::Multipole;
use bevy::prelude::*;

/// Barnes-Hut gravity parameters. Edit them at any time; every change is validated and a bad one
/// is refused (the plugin keeps the last valid values and says why in
/// [`GravityParamsStatus`](crate::gravity::GravityParamsStatus)).
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug, PartialEq)]
pub struct GravityParams {
    /// Gravitational constant `G`, m³/(kg·s²) (nature's is 6.674e-11; games use far larger).
    pub gravitational_constant: f32,
    /// Opening angle θ, 0–2: a tree node of width `w` at distance `d` counts as one mass when
    /// `w/d < θ`. Smaller is more accurate and slower; 0 sums every pair.
    pub theta: f32,
    /// Plummer softening length ε, m: keeps close encounters finite.
    pub softening: f32,
    /// Most bodies in a leaf of the tree (1–64).
    pub leaf_capacity: u32,
    /// Sum every pair exactly (O(n²)) instead of using the tree: for checking.
    pub direct_sum: bool,
    /// How far the tree expands a node's far field: point masses, or with quadrupole moments
    /// (the same accuracy at a larger θ).
    pub multipole: Multipole,
}

impl Default for GravityParams {
    fn default() -> Self {
        Self {
            gravitational_constant: 6.674e-11,
            theta: 0.7,
            softening: 0.01,
            leaf_capacity: 8,
            direct_sum: false,
            multipole: Multipole::Monopole,
        }
    }
}

/// Why a [`GravityParams`] value was refused (the crate's one
/// [`ParamsError`](crate::params::ParamsError)).
pub type GravityParamsError = crate::params::ParamsError;

/// Whether the last change to [`GravityParams`] was taken (the crate's one
/// [`ParamsStatus`](crate::params::ParamsStatus)).
pub type GravityParamsStatus = crate::params::ParamsStatus<GravityParams>;

impl ParamTable for GravityParams {
    const OWNER: &'static str = "GravityParams";

    #[rustfmt::skip]
    const FIELDS: &'static [ParamField<Self>] = &[
        // path, label, unit, accepted range, zero excluded, slider range, logarithmic
        param_field!(gravitational_constant, "G", "m³/(kg·s²)", (0.0, 1.0e12), false, (1.0e-12, 1.0e3), true),
        param_field!(theta, "opening angle θ", "", (0.0, 2.0), false, (0.0, 1.5), false),
        param_field!(softening, "softening ε", "m", (0.0, 1.0e9), false, (0.0, 0.2), false),
        param_field!(count: leaf_capacity, "leaf capacity", (1.0, 64.0), (1.0, 64.0), false),
    ];
}

impl GravityParams {
    /// Checks every field; the first problem is returned with the field, value and range.
    pub fn validate(&self) -> Result<(), GravityParamsError> {
        self.check_fields()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_and_bad_values_name_their_field() {
        assert_eq!(GravityParams::default().validate(), Ok(()));
        let bad = [
            (
                "gravitational_constant",
                GravityParams {
                    gravitational_constant: -1.0,
                    ..default()
                },
            ),
            (
                "theta",
                GravityParams {
                    theta: f32::NAN,
                    ..default()
                },
            ),
            (
                "softening",
                GravityParams {
                    softening: -0.1,
                    ..default()
                },
            ),
            (
                "leaf_capacity",
                GravityParams {
                    leaf_capacity: 0,
                    ..default()
                },
            ),
        ];
        for (field, params) in bad {
            let error = params.validate().unwrap_err();
            assert_eq!(error.field, field);
            assert!(error.to_string().contains(field));
        }
    }

    #[test]
    fn every_slider_lies_inside_what_validation_accepts() {
        for row in GravityParams::FIELDS {
            for value in [row.slider.0, row.slider.1] {
                let mut p = GravityParams::default();
                (row.set)(&mut p, value);
                assert_eq!((row.get)(&p), value, "{}", row.field);
                assert_eq!(p.validate(), Ok(()), "{} = {value}", row.field);
            }
        }
    }
}
