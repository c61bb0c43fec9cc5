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
