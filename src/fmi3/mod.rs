//! The FMI 3.0 C boundary, Co-Simulation and Model Exchange, generic over the model.
//!
//! A generic FMI 3.0 shell, Co-Simulation and Model Exchange, around one model that implements
//! [`FmuCore`](crate::fmi_common::model_api::FmuCore), beside the FMI 2.0 one
//! ([`crate::fmi2`]) and over the same core: [`export_fmi3!`](crate::export_fmi3) generates
//! the C functions of the FMU, [`instance`] checks every call against [`state_machine`] and
//! the arguments, and [`model_description::model_description_xml`] writes the matching FMI
//! 3.0 `modelDescription.xml` from the same variable table.

pub mod exports;
pub mod fmu_state;
pub mod functions;
pub mod instance;
pub mod logging;
pub mod model_description;
pub mod state_machine;
pub mod types;

/// FMI 3.0: the [`Version`](crate::fmi_common::instance::Version) of the generic instance
/// ([`instance`]) and the [`Dialect`](crate::fmi_common::xml::Dialect) of the description
/// ([`model_description`]).
pub struct Fmi3;

#[cfg(test)]
mod tests;
