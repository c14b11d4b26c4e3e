//! Why a diagnosis, or data with a hidden mechanism, could not be made.

use crate::identify;
use crate::model::params::ParamError;
use crate::simulation::InputError;

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// An identification, a simulation or a synthetic experiment failed.
    #[error(transparent)]
    Identify(#[from] identify::Error),
    /// A parameter value that breaks its rule, or a name that does not exist.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The tabulated input of a hidden mechanism.
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("no experiment")]
    NoExperiment,
    /// Hidden data asked for a further form of an effect that it lacks.
    #[error("{0} has no further hidden form {1}")]
    NoVariant(crate::model::Effect, usize),
    /// Hidden data asked for a pair of mechanisms that is not in the table.
    #[error("no two-mechanism case {0}")]
    NoPair(usize),
    /// A candidate's refit ended above the model it contains, the effect neutral: a failed
    /// fit, not evidence against the family (book/src/diagnose.md, "Nested refits").
    #[error(
        "failed fit: it ended at a residual sum of squares of {rss:.6e}, above the {nested:.6e} of the model without the effect ({why})"
    )]
    AboveNested { rss: f64, nested: f64, why: String },
    /// The screening's least-squares projection could not be solved.
    #[error("{0}")]
    Projection(&'static str),
}
