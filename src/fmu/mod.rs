//! The FMUs: the platform's, the slow model's and the inverse's cores, variables and archives.
//!
//! The HaselPlatform FMU: its variable table ([`variables`]), the model core that maps FMI
//! calls onto a simulation ([`hasel_core`]), and the archive with its documentation
//! ([`pack`]). The generic FMI 2.0 shell of [`crate::fmi2`] does every check of the standard
//! around the core. Beside it the HaselPlatformReduced FMU, the same core around the slow model
//! (src/model/reduced.rs), from a build of the library with the feature `reduced-fmu`, and the
//! HaselInverse FMU for feedforward ([`inverse`]), served by the same shell from a build with the
//! feature `inverse-fmu`.

#[cfg(feature = "tools")]
pub mod binary;
pub mod hasel_core;
pub mod inverse;
#[cfg(feature = "tools")]
pub mod pack;
pub mod structure;
pub mod variables;

pub use hasel_core::PlatformCore;

use crate::fmi_common::variables::{DefaultExperiment, ModelInfo};
use crate::model::Reduction;
use crate::simulation::DEFAULT_RTOL;

/// `modelIdentifier` and the shared libraries' name in `binaries/<platform>/`.
pub const MODEL_IDENTIFIER: &str = "HaselPlatform";

/// `modelIdentifier` of the slow model's FMU.
pub const REDUCED_MODEL_IDENTIFIER: &str = "HaselPlatformReduced";

/// Which model an FMU of the platform runs, with its model-level data.
pub trait FmuModel: Clone + std::fmt::Debug + Send + 'static {
    const REDUCTION: Reduction;
    fn model_info() -> ModelInfo;
}

/// The full model: HaselPlatform.
#[derive(Clone, Debug)]
pub struct FullModel;

/// The slow model (src/model/reduced.rs): HaselPlatformReduced.
#[derive(Clone, Debug)]
pub struct SlowModel;

impl FmuModel for FullModel {
    const REDUCTION: Reduction = Reduction::Full;
    fn model_info() -> ModelInfo {
        model_info()
    }
}

impl FmuModel for SlowModel {
    const REDUCTION: Reduction = Reduction::Slow;
    fn model_info() -> ModelInfo {
        model_info_of(
            REDUCED_MODEL_IDENTIFIER,
            "The HaselPlatform FMU's slow model: the charges and the momentum of each HASEL \
             actuator on their quasi-steady values (singular perturbation), one angle per \
             actuator, for Model Exchange with any integrator, fixed-step and real-time targets; \
             the same inputs U1..U3 [V], outputs and parameters",
            DEFAULT_RTOL,
            true,
        )
    }
}

/// The core of HaselPlatform.
pub type HaselCore = PlatformCore<FullModel>;

/// The core of HaselPlatformReduced.
pub type HaselReducedCore = PlatformCore<SlowModel>;

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

/// The C functions of the platform's binary around [`HaselCore`], FMI 2.0's 44 and FMI 3.0's 75
/// in one library (their names differ by the prefix, so one build serves both FMUs); in modules
/// of their own, as the macros import the C types where they are invoked. The features
/// `reduced-fmu` and `inverse-fmu` build the library of another FMU instead.
#[cfg(not(any(feature = "inverse-fmu", feature = "reduced-fmu")))]
mod fmi2_functions {
    crate::export_fmi2!(super::HaselCore);
}

#[cfg(not(any(feature = "inverse-fmu", feature = "reduced-fmu")))]
mod fmi3_functions {
    crate::export_fmi3!(super::HaselCore);
}

/// The FMI 2.0 and 3.0 functions of HaselPlatformReduced (`--features reduced-fmu`).
#[cfg(feature = "reduced-fmu")]
mod reduced_fmi2_functions {
    crate::export_fmi2!(super::HaselReducedCore);
}

#[cfg(feature = "reduced-fmu")]
mod reduced_fmi3_functions {
    crate::export_fmi3!(super::HaselReducedCore);
}
