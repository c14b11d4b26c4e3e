//! The FMI 2.0 C boundary, Co-Simulation and Model Exchange, generic over the model.
//!
//! A generic FMI 2.0 shell, Co-Simulation and Model Exchange, around one model that implements
//! [`FmuCore`](crate::fmi_common::model_api::FmuCore) (physics only):
//! [`export_fmi2!`](crate::export_fmi2) generates the C functions of the FMU,
//! [`instance`] checks every call against [`state_machine`] and the arguments, and
//! [`model_description::model_description_xml`] writes the matching `modelDescription.xml`.

pub mod exports;
pub mod fmu_state;
pub mod functions;
pub mod instance;
pub mod logging;
pub mod model_description;
pub mod state_machine;
pub mod types;
pub mod uri;

/// FMI 2.0: the [`Version`](crate::fmi_common::instance::Version) of the generic instance
/// ([`instance`]) and the [`Dialect`](crate::fmi_common::xml::Dialect) of the description
/// ([`model_description`]).
pub struct Fmi2;

#[cfg(test)]
mod tests;
