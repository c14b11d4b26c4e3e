//! Which model of the platform runs: the full one or one of its reductions by singular
//! perturbation (src/model/reduced.rs), named as the command line and the tables name them.

use std::str::FromStr;

use super::actuator::{N, P, THETA};

/// Which model of the platform runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reduction {
    /// The paper's model: θ, l_p, p, Q1, Q2 per actuator.
    #[default]
    Full,
    /// The charges on their quasi-static values: θ, l_p, p per actuator.
    QuasiStatic,
    /// The charges and the momentum quasi-static, l_p on its curve: θ per actuator.
    Slow,
}

impl Reduction {
    /// Every model, in the order of its states' number.
    pub const ALL: [Reduction; 3] = [Reduction::Full, Reduction::QuasiStatic, Reduction::Slow];

    /// The name the command line and the tables use.
    pub fn name(self) -> &'static str {
        match self {
            Reduction::Full => "full",
            Reduction::QuasiStatic => "quasi-static",
            Reduction::Slow => "slow",
        }
    }

    /// How many of the paper's five states per actuator it keeps: a prefix of
    /// (θ, l_p, p, Q1, Q2).
    pub fn kept(self) -> usize {
        match self {
            Reduction::Full => N,
            Reduction::QuasiStatic => P + 1,
            Reduction::Slow => THETA + 1,
        }
    }
}

/// A model name that is none of [`Reduction::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown model {0:?}: one of full, quasi-static, slow")]
pub struct UnknownReductionError(pub String);

impl FromStr for Reduction {
    type Err = UnknownReductionError;
    fn from_str(s: &str) -> Result<Reduction, UnknownReductionError> {
        Reduction::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| UnknownReductionError(s.to_string()))
    }
}
