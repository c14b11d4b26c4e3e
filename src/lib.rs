//! hasel-fmu: the HASEL-actuated 3PS micro parallel platform as a library, FMUs of FMI 2.0 and
//! 3.0 (Co-Simulation and Model Exchange) and the `hasel` command-line tool.

#[cfg(feature = "tools")]
pub mod control;
#[cfg(feature = "tools")]
pub mod diagnose;
pub mod fmi2;
pub mod fmi3;
pub mod fmi_common;
pub mod fmu;
#[cfg(feature = "tools")]
pub mod identify;
pub mod io;
pub mod model;
#[cfg(feature = "tools")]
pub mod plot;
pub mod simulation;
pub mod solver;
#[cfg(feature = "tools")]
pub mod uncertainty;
