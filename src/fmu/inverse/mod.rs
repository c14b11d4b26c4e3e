//! The HaselInverse FMU: a small stateless FMU beside the platform's, for feedforward. Inputs
//! tip_x, tip_y and the mean height; outputs the heights h1..h3 that put the tip there and the
//! voltages U1..U3 that hold them at equilibrium (book/src/model.md, "Inverse kinematics" and
//! "Statics"). The same generic FMI 2.0 shell serves it; the library exports its FMI functions
//! when built with the cargo feature `inverse-fmu` (a cdylib exports `fmi2*` once).

pub mod core;
pub mod variables;

pub use self::core::InverseCore;

use crate::fmi_common::variables::ModelInfo;
use crate::simulation::DEFAULT_RTOL;

use super::model_info_of;

/// `modelIdentifier` and the shared libraries' name in `binaries/<platform>/`.
pub const MODEL_IDENTIFIER: &str = "HaselInverse";

/// The model-level data of `modelDescription.xml` (no solver: the tolerance is the platform's
/// default, which an importer may pass on).
pub fn model_info() -> ModelInfo {
    model_info_of(
        MODEL_IDENTIFIER,
        "Inverse of the HASEL platform for feedforward: from the antenna tip's x, y and the mean \
         height [m] to the actuator heights h1..h3 [m] and the constant voltages U1..U3 [V] that \
         hold them at equilibrium",
        DEFAULT_RTOL,
        // a static map: Co-Simulation only, no directional derivatives
        false,
    )
}

/// The 44 C functions of the inverse FMU's binary, around [`InverseCore`] (the library built
/// with `--features inverse-fmu`).
#[cfg(feature = "inverse-fmu")]
mod fmi2_functions {
    crate::export_fmi2!(super::InverseCore);
}
