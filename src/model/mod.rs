//! The physics of the HASEL platform and nothing else: parameters, the three
//! port-Hamiltonian actuators, the platform's right-hand side and Jacobian, and kinematics.
//! It knows no solver and no FMI.
//!
//! Equations, parameters and defaults: [book/src/model.md](model.md).

pub mod actuator;
pub mod effects;
mod invariant_curve;
pub mod kinematics;
pub mod linalg;
pub mod params;
pub mod platform;
pub mod reduced;
pub mod reduction;
pub mod shell;
pub mod statics;

pub use effects::{Effect, EffectParams};
pub use kinematics::Kinematics;
pub use params::{ParamError, Params};
pub use platform::{ModelError, Platform};
pub use reduction::{Reduction, UnknownReductionError};
