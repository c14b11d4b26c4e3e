//! The HaselPlatform FMU: its variable table ([`variables`]), the model core that maps FMI
//! calls onto a simulation ([`hasel_core`]), and the archive with its documentation
//! ([`pack`]). The generic FMI 2.0 shell of [`crate::fmi2`] does every check of the standard
//! around the core.

pub mod hasel_core;
pub mod pack;
pub mod structure;
pub mod variables;

pub use hasel_core::HaselCore;

use crate::fmi_common::variables::{DefaultExperiment, ModelInfo};
use crate::simulation::DEFAULT_RTOL;

/// `modelIdentifier` and the shared library's name in `binaries/linux64/`.
pub const MODEL_IDENTIFIER: &str = "HaselPlatform";

/// The parameter file inside the FMU's `resources/` that `hasel fmu --params` packs; its values
/// are the parameters' start values.
pub const RESOURCE_PARAMS: &str = "parameters.toml";

/// The model-level data of `modelDescription.xml`.
pub fn model_info() -> ModelInfo {
    ModelInfo {
        model_name: MODEL_IDENTIFIER.into(),
        model_identifier: MODEL_IDENTIFIER.into(),
        description: "3-DOF micro parallel platform (3PS) driven by three HASEL actuators, each a \
                      port-Hamiltonian system (Feregrino et al.); inputs U1..U3 [V], outputs \
                      actuator heights and antenna tip [m]"
            .into(),
        author: "hasel-fmu".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        generation_tool: concat!("hasel-fmu ", env!("CARGO_PKG_VERSION")).into(),
        default_experiment: DefaultExperiment {
            start_time: 0.0,
            stop_time: 10.0,
            step_size: 1e-3,
            tolerance: DEFAULT_RTOL,
        },
        log_categories: vec![],
    }
}

/// The 44 C functions of the FMI 2.0 binary, around [`HaselCore`]; in a module of their own,
/// as the macro imports the C types where it is invoked.
#[cfg(not(feature = "fmi3"))]
mod fmi2_functions {
    crate::export_fmi2!(super::HaselCore);
}

/// The C functions of the FMI 3.0 binary (`--features fmi3`), around the same core.
#[cfg(feature = "fmi3")]
mod fmi3_functions {
    crate::export_fmi3!(super::HaselCore);
}
