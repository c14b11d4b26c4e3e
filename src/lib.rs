//! hasel-fmu: the HASEL-actuated 3PS micro parallel platform as a library, an FMI 2.0
//! Co-Simulation FMU and the `hasel` command-line tool.

pub mod control;
pub mod diagnose;
pub mod fmi2;
pub mod fmi3;
pub mod fmi_common;
pub mod fmu;
pub mod identify;
pub mod io;
pub mod model;
pub mod plot;
pub mod simulation;
pub mod solver;
pub mod uncertainty;
