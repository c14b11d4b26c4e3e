//! A generic FMI 2.0 Co-Simulation shell: a per-model core implements [`core::FmuCore`]
//! (physics only), and [`export_fmi2!`](crate::export_fmi2) generates the C functions of the
//! FMU around it; [`model_description::model_description_xml`] writes the matching
//! `modelDescription.xml`.

pub mod core;
pub mod exports;
pub mod fmu_state;
pub mod instance;
pub mod logging;
pub mod model_description;
pub mod types;
pub mod units;
pub mod uri;
pub mod variables;

#[cfg(test)]
mod tests;
