//! What the parameter resources ([`SphParams`](crate::fluid::SphParams),
//! [`GravityParams`](crate::gravity::GravityParams)) share: one error type for a refused value.

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
