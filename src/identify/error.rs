//! Why an identification, or a synthetic experiment, could not be made.

use crate::io::file::FileError;
use crate::model::params::ParamError;
use crate::simulation::SimError;

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// An experiment's data, located in its file.
    #[error(transparent)]
    File(#[from] FileError),
    /// A parameter value that breaks its rule, or a name that does not exist.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A simulation that could not start or go on.
    #[error(transparent)]
    Simulation(#[from] SimError),
    /// The simulation of one experiment failed.
    #[error("{experiment}: {source}")]
    Experiment {
        experiment: String,
        source: SimError,
    },
    #[error("no estimation experiment")]
    NoEstimationExperiment,
    /// A name in the list of parameters to estimate that is not a parameter.
    #[error("unknown parameter '{0}' in the free list")]
    UnknownFree(String),
    #[error(
        "bounds of {name}: [{lo}, {hi}] must be increasing and contain the start value {start}"
    )]
    Bounds {
        name: String,
        lo: f64,
        hi: f64,
        start: f64,
    },
    #[error("non-finite residual")]
    NonFiniteResidual,
    #[error("the Jacobian of the residuals is not finite")]
    NonFiniteJacobian,
    /// The time given to the fit ran out (`lm::Options::deadline`).
    #[error("the time budget of the fit was exhausted")]
    TimeBudget,
    /// The residuals cannot be evaluated where the optimiser starts.
    #[error("at the starting point: {0}")]
    AtStart(Box<Error>),
}
