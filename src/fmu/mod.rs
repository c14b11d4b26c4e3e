//! The HaselPlatform FMU: its variable table ([`variables`]), the model core that maps FMI
//! calls onto a simulation ([`hasel_core`]), and the archive with its documentation
//! ([`pack`]). The generic FMI 2.0 shell of [`crate::fmi2`] does every check of the standard
//! around the core. Beside it the HaselInverse FMU for feedforward ([`inverse`]), served by the
//! same shell from a build of the library with the feature `inverse-fmu`.

#[cfg(feature = "tools")]
pub mod binary;
pub mod hasel_core;
pub mod inverse;
#[cfg(feature = "tools")]
pub mod pack;
pub mod structure;
pub mod variables;

pub use hasel_core::HaselCore;

use crate::fmi_common::variables::{DefaultExperiment, ModelInfo};
use crate::simulation::DEFAULT_RTOL;

/// `modelIdentifier` and the shared libraries' name in `binaries/<platform>/`.
pub const MODEL_IDENTIFIER: &str = "HaselPlatform";

/// The parameter file inside the FMU's `resources/` that `hasel fmu --params` packs; its values
/// are the parameters' start values.
pub const RESOURCE_PARAMS: &str = "parameters.toml";

/// The model-level data of `modelDescription.xml`.
pub fn model_info() -> ModelInfo {
    model_info_of(
        MODEL_IDENTIFIER,
        "3-DOF micro parallel platform (3PS) driven by three HASEL actuators, each a \
         port-Hamiltonian system (Feregrino et al.); inputs U1..U3 [V], outputs actuator heights \
         and antenna tip [m]",
        DEFAULT_RTOL,
        true,
    )
}

/// The model-level data of an FMU of this crate: its identifier (also its model name), its
/// description, the default experiment's tolerance (0 to 10 s in steps of 1 ms), and whether it
/// has the dynamics that Model Exchange and directional derivatives need.
pub fn model_info_of(
    identifier: &str,
    description: &str,
    tolerance: f64,
    dynamic: bool,
) -> ModelInfo {
    ModelInfo {
        model_name: identifier.into(),
        model_identifier: identifier.into(),
        description: description.into(),
        author: "hasel-fmu".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        generation_tool: concat!("hasel-fmu ", env!("CARGO_PKG_VERSION")).into(),
        default_experiment: DefaultExperiment {
            start_time: 0.0,
            stop_time: 10.0,
            step_size: 1e-3,
            tolerance,
        },
        log_categories: vec![],
        model_exchange: dynamic,
        directional_derivatives: dynamic,
    }
}

/// The 44 C functions of the platform's FMI 2.0 binary, around [`HaselCore`]; in a module of
/// their own, as the macro imports the C types where it is invoked. The features `fmi3` and
/// `inverse-fmu` build the library of another FMU instead (a cdylib exports one set).
#[cfg(not(any(feature = "fmi3", feature = "inverse-fmu")))]
mod fmi2_functions {
    crate::export_fmi2!(super::HaselCore);
}

/// The C functions of the FMI 3.0 binary (`--features fmi3`), around the same core.
#[cfg(feature = "fmi3")]
mod fmi3_functions {
    crate::export_fmi3!(super::HaselCore);
}
