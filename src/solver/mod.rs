//! ODE integration over a small trait (f and its Jacobian). Knows no physics and no FMI.
//!
//! The method is the 3-stage Radau IIA collocation method of order 5 (Hairer & Wanner,
//! "Solving Ordinary Differential Equations II", IV.8), chosen with evidence
//! (book/src/solver.md, "Why Radau IIA"): L-stable for the platform's 2.7 ns electrical modes,
//! order 5 at rtol 1e-6, and a one-step method that loses nothing when a co-simulation restarts
//! it every millisecond, where multistep BDF drops back to order 1. A system that is not stiff at
//! the step is integrated more cheaply by the explicit Bogacki–Shampine 3(2) pair (`bs23`), which
//! estimates the stiffness each step meets so that its user can tell when it is not.

pub mod bs23;
pub mod lu;
pub mod radau5;
pub mod sensitivity;

pub use bs23::Bs23;
pub use radau5::Radau5;

use serde::{Deserialize, Serialize};

/// A system ẏ = f(t, y) with an analytic Jacobian.
pub trait OdeSystem {
    fn dim(&self) -> usize;
    /// f(t, y) into `dy`.
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError>;
    /// ∂f/∂y into `jac`, column-major `dim × dim` (entry (r, c) at `c * dim + r`).
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError>;
    /// Sizes of the diagonal blocks when ∂f/∂y is block diagonal (summing to `dim`), so that
    /// the linear algebra works block by block; one block of `dim` by default.
    fn jacobian_blocks(&self) -> Vec<usize> {
        vec![self.dim()]
    }
}

/// Most steps an integration takes between two times it must reach ([`Radau5::advance`]'s
/// default, and a run's budget between its output times in `simulation`): past it the steps
/// have shrunk until the run crawls.
pub const MAX_STEPS: usize = 100_000;

/// The system could not be evaluated (for example outside the domain of its equations).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct RhsError(pub String);

/// Why an integration stopped.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolverError {
    /// The step size fell below the rounding of t: the problem is too stiff, singular or
    /// undefined here.
    #[error("step size {h:e} s too small at t = {t} s ({reason})")]
    StepTooSmall { t: f64, h: f64, reason: String },
    /// More steps than the limit before the next time the caller must reach (the end of one
    /// call, an output time, the end of a budgeted run): the steps shrank until the run crawls.
    #[error("more than {limit} steps without reaching the next time to stop at, at t = {t} s")]
    TooManySteps { t: f64, limit: usize },
    /// f or J failed at the start of the step, so no smaller step can help.
    #[error("at t = {t} s: {message}")]
    Rhs { t: f64, message: String },
}

/// Error control: the local error of state i is kept below `atol[i] + rtol |y_i|`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    pub rtol: f64,
    pub atol: Vec<f64>,
}

impl Tolerances {
    /// Absolute tolerances scaled to each state's size: atol_i = rtol · scale_i.
    pub fn scaled(rtol: f64, scales: &[f64]) -> Tolerances {
        Tolerances {
            rtol,
            atol: scales.iter().map(|s| rtol * s).collect(),
        }
    }
}

/// Work counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub accepted: usize,
    pub rejected: usize,
    pub rhs_evals: usize,
    pub jac_evals: usize,
    pub decompositions: usize,
    pub newton_iterations: usize,
}
