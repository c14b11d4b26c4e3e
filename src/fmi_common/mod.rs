//! What the FMI 2.0 and 3.0 shells share with each other and with the model behind them.
//!
//! What an FMI shell and the model behind it share, whatever the FMI version: the model's
//! side of the interface ([`model_api::FmuCore`]), its variable table with the rules on
//! causality, variability, initial and start ([`variables`]), the unit table
//! ([`units`]); and the generic shell both versions are made of: the instance with its state
//! handling, argument checks, values and FMU states ([`instance`], over a version's
//! [`instance::Version`]) and the Model Exchange calls both versions word alike
//! (`model_exchange`), the statuses and the logger ([`logging`]), the bodies of the C
//! functions both define alike ([`calls`]) and the macros that declare those of them both
//! versions declare alike (`functions`), what both write alike in `modelDescription.xml`
//! and its document order ([`xml`], over a version's [`xml::Dialect`]), the state machines'
//! mask mechanism and set rule ([`state_machine`]), value access by value reference
//! ([`values`]), FMU states and their serialized frame ([`fmu_state`]) and the version-free
//! helpers ([`shell`]). The FMI 2.0 shell is [`crate::fmi2`], the FMI 3.0 shell
//! [`crate::fmi3`]: their C signatures and types, state tables, XML dialects, FMU-state
//! records and wording.

pub mod calls;
pub mod fmu_state;
mod functions;
pub mod instance;
pub mod logging;
pub mod model_api;
mod model_exchange;
pub mod shell;
pub mod state_machine;
pub mod units;
pub mod values;
pub mod variables;
pub mod xml;
