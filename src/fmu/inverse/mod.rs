//! The HaselInverse FMU: a small stateless FMU beside the platform's, for feedforward. Inputs
//! tip_x, tip_y and the mean height; outputs the heights h1..h3 that put the tip there and the
//! voltages U1..U3 that hold them at equilibrium (src/model/model.md, "Inverse kinematics" and
//! "Statics"). The same generic FMI 2.0 shell serves it; the library exports its FMI functions
//! when built with the cargo feature `inverse-fmu` (a cdylib exports `fmi2*` once).

pub mod core;
pub mod variables;

pub use self::core::InverseCore;

use crate::fmi_common::variables::ModelInfo;
use crate::model::Params;
use crate::simulation::DEFAULT_RTOL;

use super::model_info_of;
use super::pack::Spec;
use crate::fmi_common::model_api::FmuCore;

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

/// What `hasel fmu --model inverse` packs.
pub fn spec(params: &Params) -> Spec {
    Spec {
        info: model_info(),
        variables: variables::variables(params),
        structure: InverseCore::model_structure(),
        about: "The inverse of the HaselPlatform FMU, for feedforward: each communication step \
                maps the inputs held over it (the antenna tip's x and y and the platform's mean \
                height, which x and y leave open) to the actuator heights by the inverse \
                kinematics from X and Y (Newton on the forward kinematics), and to the constant \
                voltages that hold those heights at equilibrium (closed form: the height's angle, \
                the film on its invariant curve, the torque balance with the charges of the DC \
                circuit). The outputs at the end of a step are those of the inputs held over it; \
                a tip it cannot reach (below the rest height, beyond the height where the input \
                gain vanishes) makes the step return fmi2Discard with the reason logged. Its \
                parameters are the platform's.",
    }
}

/// The 44 C functions of the inverse FMU's binary, around [`InverseCore`] (the library built
/// with `--features inverse-fmu`).
#[cfg(feature = "inverse-fmu")]
mod fmi2_functions {
    crate::export_fmi2!(super::InverseCore);
}
