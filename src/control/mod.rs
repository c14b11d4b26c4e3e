//! Control design from the model: equilibrium, linearization, passivity, reduced models.
//!
//! As book/src/control.md, "Control design: `hasel linearize`", describes: the
//! equilibrium under constant voltages, the linearization with the model's analytic Jacobians, its
//! port-Hamiltonian structure and passivity, frequency and step responses, and a reduced model for
//! controller design.
//!
//! Uses `model` (f, ∂f/∂x, ∂f/∂U, ∂y/∂x, the energy's Hessian and the PH structure),
//! `simulation` (the nonlinear runs the linear model is compared with), `solver` (the Radau
//! integrator for the linear step response), `io` and `plot`; never the FMI layers.
//!
//! - [`equilibrium`](mod@equilibrium): Newton on the reduced equations along the invariant curve through the
//!   rest state, continued in U from 0 V;
//! - [`linearize`]: A, B, C, D at a point, the eigenvalues (scaled), the zero eigenvalue of
//!   each actuator's Casimir and the minimal model without it, effects that are not smooth;
//! - [`port_hamiltonian`]: A = (J − R) Q at an equilibrium, the passive port and its check;
//! - [`frequency`]: G(jω), the small-signal check against the nonlinear model, step responses;
//! - [`reduce`]: balanced singular-perturbation reduction with its Hankel-singular-value bound;
//! - [`report`]: `linearization.json`, `reduced.json`, the CSV matrices and the figures.

pub mod equilibrium;
pub mod frequency;
pub mod linalg;
pub mod linearize;
pub mod port_hamiltonian;
pub mod reduce;
pub mod report;

use crate::io::file::FileError;
use crate::model::shell::DomainError;
use crate::model::{ModelError, ParamError};
use crate::simulation::SimError;

pub use equilibrium::{Equilibrium, equilibrium};
pub use linearize::{Linearization, StateSpace, linearize_at, linearize_equilibrium};

/// Why an equilibrium could not be continued to the requested voltages.
#[derive(Clone, Debug, PartialEq)]
pub enum NoEquilibrium {
    /// The stiffness along the invariant curve vanishes: the branch through the rest state
    /// folds (pull-in) and ends before the requested voltage.
    PullIn {
        /// Smallest eigenvalue of the reduced stiffness −∂ṗ/∂θ at the last point found [N m/rad].
        stiffness: f64,
    },
    /// The branch leaves the domain of the shell geometry (the asin of model.md).
    Domain(DomainError),
    /// Newton did not converge even with the smallest continuation step.
    NotConverged,
}

/// Errors of the control-design computations.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ControlError {
    /// A requested voltage is not a finite number.
    #[error("U{} = {value}: must be a finite number", .input + 1)]
    BadVoltage { input: usize, value: f64 },
    /// No equilibrium on the branch through the rest state at the requested voltages.
    #[error("{}", no_equilibrium(*.actuator, .requested, .reached, .cause))]
    NoEquilibrium {
        /// 1-based actuator that limits the branch.
        actuator: usize,
        /// The requested voltages \[V\].
        requested: [f64; 3],
        /// The voltages at which the branch was last found \[V\].
        reached: [f64; 3],
        cause: NoEquilibrium,
    },
    /// A setting is out of range (the name and the value).
    #[error("{name} = {value}: out of range")]
    Setting { name: &'static str, value: f64 },
    #[error(transparent)]
    Param(#[from] ParamError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("simulation: {0}")]
    Simulation(#[from] SimError),
    /// A dense computation failed (what, and why).
    #[error("{what}: {why}")]
    Numerics {
        what: &'static str,
        why: &'static str,
    },
    /// The decomposition is implemented for the paper's model; these effects are active.
    #[error(
        "{what} is implemented for the paper's model; active effects: {}",
        .effects.join(", ")
    )]
    Unsupported {
        what: &'static str,
        effects: Vec<String>,
    },
    /// The linearization has eigenvalues on or right of the imaginary axis (after removing
    /// the Casimir directions), so the Gramians of a balanced reduction do not exist.
    #[error(
        "the linearization is not asymptotically stable (eigenvalue {:.4e} {:+.4e}i)",
        .eigenvalue.0,
        .eigenvalue.1
    )]
    NotStable { eigenvalue: (f64, f64) },
    /// The linearization does not move the outputs at all (every U0 = 0: the electrostatic
    /// force goes with U², so its first-order gain is zero), so there is nothing to reduce.
    #[error(
        "the linearization has no gain from the voltages to the outputs (at U = 0 the \
         electrostatic force goes with U², so its first-order response is zero): no \
         reduced model"
    )]
    NoGain,
    #[error(transparent)]
    File(#[from] FileError),
}

/// The message of [`ControlError::NoEquilibrium`]: how far the branch went, and why it ended.
fn no_equilibrium(
    actuator: usize,
    requested: &[f64; 3],
    reached: &[f64; 3],
    cause: &NoEquilibrium,
) -> String {
    let i = actuator - 1;
    let why = match cause {
        NoEquilibrium::PullIn { stiffness } => format!(
            "where the stiffness along the invariant curve falls to {stiffness:.3e} \
             N m/rad (pull-in: the branch folds)"
        ),
        NoEquilibrium::Domain(e) => format!("where it leaves the model's domain ({e})"),
        NoEquilibrium::NotConverged => {
            "where Newton stops converging (no equilibrium nearby)".to_string()
        }
    };
    format!(
        "no equilibrium at U{actuator} = {} V on the branch through the rest state: \
         continued from 0 V up to U{actuator} = {} V, {why}",
        requested[i], reached[i]
    )
}
