//! What an FMI shell and the model behind it share, whatever the FMI version: the model's
//! side of the interface ([`model_api::FmuCore`]), its variable table with the rules on
//! causality, variability, initial and start ([`variables`]), and the unit table
//! ([`units`]). The FMI 2.0 shell is [`crate::fmi2`]; an FMI 3.0 shell would sit beside it
//! over the same pieces.

pub mod model_api;
pub mod units;
pub mod variables;
