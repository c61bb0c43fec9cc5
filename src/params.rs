//! What the parameter resources ([`SphParams`](crate::fluid::SphParams),
//! [`GravityParams`](crate::gravity::GravityParams)) share: one error type for a refused value,
//! one status resource, one system that adopts a valid change, and one table of numeric fields
//! that validation and the panel both read.

use core::fmt;

/// Why a parameters value was refused: whose parameters, the field, and what is wrong with it
/// (the value and the accepted range).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamsError {
    /// The parameters' type, e.g. `"SphParams"`.
    pub owner: &'static str,
    /// The offending field.
    pub field: &'static str,
    /// What is wrong, with the value and the accepted range.
    pub message: String,
}

impl fmt::Display for ParamsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid {}.{}: {}", self.owner, self.field, self.message)
    }
}

impl std::error::Error for ParamsError {}

/// Whether the last change to the parameters resource `P` was taken: why it was refused (the
/// solver keeps running on the last valid parameters), or `None` while `P` is in use.
#[derive(bevy::prelude::Resource, Debug, Clone, PartialEq)]
pub struct ParamsStatus<P> {
    /// Why the current parameters were refused, if they were.
    pub error: Option<ParamsError>,
    marker: core::marker::PhantomData<fn() -> P>,
}

impl<P> Default for ParamsStatus<P> {
    fn default() -> Self {
        Self {
            error: None,
            marker: core::marker::PhantomData,
        }
    }
}

/// A parameters resource that its solver adopts only once validated: [`apply_params`] runs the
/// same pattern for every one of them.
pub trait Params: bevy::prelude::Resource + Sized {
    /// The resource that runs on the parameters.
    type Solver: bevy::prelude::Resource
        + bevy::prelude::Component<Mutability = bevy::ecs::component::Mutable>;

    /// What keeps running on the last valid parameters, for the log ("the fluid").
    const WHAT: &'static str;

    /// Checks the parameters and, if they are valid, hands them to `solver`.
    fn adopt(&self, solver: &mut Self::Solver) -> Result<(), ParamsError>;
}

/// Hands a changed `P` to its solver, or keeps the last valid one and reports why: in
/// [`ParamsStatus<P>`] and, once per distinct error, in the log.
pub(crate) fn apply_params<P: Params>(
    params: bevy::prelude::Res<P>,
    mut solver: bevy::prelude::ResMut<P::Solver>,
    mut status: bevy::prelude::ResMut<ParamsStatus<P>>,
) {
    use bevy::prelude::DetectChanges;
    if !params.is_changed() {
        return;
    }
    match params.adopt(&mut *solver) {
        Ok(()) => {
            if status.error.is_some() {
                status.error = None;
            }
        }
        Err(error) => {
            if status.error.as_ref() != Some(&error) {
                bevy::log::error!(
                    "{error}; {} keeps running on the last valid parameters",
                    P::WHAT
                );
                status.error = Some(error);
            }
        }
    }
}

/// One numeric field of a parameters type `P` as validation and the panel see it: its name,
/// label and unit, the values validation accepts, and the range and scale of the panel's
/// slider. A new numeric field is one row of [`ParamTable::FIELDS`]; the panel draws a row by
/// reference (`&SphParams::REST_DENSITY`), so a row it names always exists.
#[derive(Debug)]
pub struct ParamField<P: 'static> {
    /// The field's path, as errors name it.
    pub field: &'static str,
    /// The panel's label.
    pub label: &'static str,
    /// The unit ("" for none).
    pub unit: &'static str,
    /// The accepted values, inclusive (`positive`: above zero up to the maximum).
    pub valid: (f32, f32),
    /// Zero excluded.
    pub positive: bool,
    /// The panel slider's range (within `valid`).
    pub slider: (f32, f32),
    /// A logarithmic slider.
    pub logarithmic: bool,
    /// A count: whole numbers only (read and written through `f32`, exact up to 2²⁴).
    pub integer: bool,
    /// What `valid` and `slider` are in units of, for a field whose range depends on others
    /// (the background pressure in units of the Tait stiffness); `None`: absolute.
    pub scale: Option<fn(&P) -> f32>,
    /// Reads the field.
    pub get: fn(&P) -> f32,
    /// Writes the field.
    pub set: fn(&mut P, f32),
}

impl<P> Clone for ParamField<P> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<P> Copy for ParamField<P> {}

/// A parameters type whose numeric fields with a plain range are listed in one table.
pub trait ParamTable: Sized + 'static {
    /// The type's name, as errors give it (`"SphParams"`).
    const OWNER: &'static str;
    /// The numeric fields and counts with a plain range, in the panel's order (fields whose
    /// range depends on others, vectors and switches are checked by the type's `validate`
    /// itself).
    const FIELDS: &'static [ParamField<Self>];

    /// Checks every row of the table; the first problem is returned.
    fn check_fields(&self) -> Result<(), ParamsError> {
        Self::FIELDS.iter().try_for_each(|row| row.check(self))
    }
}

impl<P: ParamTable> ParamField<P> {
    /// The accepted values for `params`, inclusive.
    pub fn valid_range(&self, params: &P) -> (f32, f32) {
        self.scaled(self.valid, params)
    }

    /// The panel slider's range for `params`.
    pub fn slider_range(&self, params: &P) -> (f32, f32) {
        self.scaled(self.slider, params)
    }

    fn scaled(&self, (min, max): (f32, f32), params: &P) -> (f32, f32) {
        match self.scale {
            Some(scale) => {
                let unit = scale(params);
                (min * unit, max * unit)
            }
            None => (min, max),
        }
    }

    /// Whether `params` has an accepted value here; the error names the value and the range.
    pub fn check(&self, params: &P) -> Result<(), ParamsError> {
        let value = (self.get)(params);
        let (min, max) = self.valid_range(params);
        let ok = value.is_finite()
            && value <= max
            && if self.positive {
                value > 0.0
            } else {
                value >= min
            };
        if ok {
            return Ok(());
        }
        let unit = spaced(self.unit);
        Err(ParamsError {
            owner: P::OWNER,
            field: self.field,
            message: if self.positive {
                format!("{value}{unit} must be positive and at most {max}{unit}")
            } else {
                format!("{value}{unit} is outside {min}..={max}{unit}")
            },
        })
    }
}

/// Checks `min ≤ value ≤ max` (finite) for a field whose range a table row cannot hold (it
/// depends on other fields); the error reads as a row's does.
pub(crate) fn check_range(
    owner: &'static str,
    field: &'static str,
    value: f32,
    (min, max): (f32, f32),
    unit: &str,
) -> Result<(), ParamsError> {
    if value.is_finite() && value >= min && value <= max {
        return Ok(());
    }
    let unit = spaced(unit);
    Err(ParamsError {
        owner,
        field,
        message: format!("{value}{unit} is outside {min}..={max}{unit}"),
    })
}

/// `" m/s"` after a number, nothing for a pure number.
fn spaced(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

/// A [`ParamField`] row for the field at `$path` (`rest_density`, `dfsph.cfl_number`): its
/// name, getter and setter come from the path; `scale: f` after the rest makes the ranges
/// relative to `f(params)`. `count: path, label, valid, slider, logarithmic` is the row of a
/// `u32` count.
macro_rules! param_field {
    ($($path:ident).+, $label:expr, $unit:expr, $valid:expr, $positive:expr, $slider:expr,
     $log:expr $(, scale: $scale:expr)?) => {
        $crate::params::ParamField {
            field: stringify!($($path).+),
            label: $label,
            unit: $unit,
            valid: $valid,
            positive: $positive,
            slider: $slider,
            logarithmic: $log,
            integer: false,
            scale: $crate::params::param_field!(@scale $($scale)?),
            get: |p| p.$($path).+,
            set: |p, v| p.$($path).+ = v,
        }
    };
    (count: $($path:ident).+, $label:expr, $valid:expr, $slider:expr, $log:expr) => {
        $crate::params::ParamField {
            field: stringify!($($path).+),
            label: $label,
            unit: "",
            valid: $valid,
            positive: false,
            slider: $slider,
            logarithmic: $log,
            integer: true,
            scale: None,
            get: |p| p.$($path).+ as f32,
            set: |p, v| p.$($path).+ = v.round().max(0.0) as u32,
        }
    };
    (@scale) => { None };
    (@scale $scale:expr) => { Some($scale) };
}
pub(crate) use param_field;
