//! hasel-fmu: the HASEL-actuated 3PS micro parallel platform as a library, FMUs of FMI 2.0 and
//! 3.0 (Co-Simulation and Model Exchange) and the `hasel` command-line tool.
//!
//! The model is the published one (Feregrino et al., "Design and Modeling of a HASEL
//! Actuator-Based Micro Parallel Robot"): three port-Hamiltonian HASEL actuators, 15 states, and
//! the kinematics from their heights to the tip of an antenna. The book in `book/` (built by
//! `mdbook build book`) documents the equations, the FMUs, identification, the missing-effect
//! diagnosis and control design; this page shows the library's entry points.
//!
//! The rooms, each using only those listed before it (book/src/architecture.md):
//! [`model`] (the physics), [`solver`] (Radau IIA and an explicit pair), [`fmi_common`],
//! [`fmi2`] and [`fmi3`] (the C boundaries), [`simulation`] (model + solver + input), [`io`],
//! [`fmu`] (the FMUs' cores, variable tables and archives), and with the feature `tools`
//! (default): `plot`, `identify`, `control`, `diagnose` and `uncertainty`.
//!
//! # Simulate
//!
//! Two seconds of the paper's excitation, sampled every millisecond:
//!
//! ```
//! use hasel_fmu::model::{params::Params, platform::Platform};
//! use hasel_fmu::simulation::{DEFAULT_RTOL, Simulator, input::Input};
//!
//! let model = Platform::new(Params::default())?;
//! let mut sim = Simulator::new(model, 0.0, DEFAULT_RTOL)?;
//! let mut peak = 0.0_f64;
//! sim.run(&Input::sine(60.0, 3.0 * std::f64::consts::PI), 2.0, 1e-3, |s| {
//!     peak = peak.max(s.h[1]); // s.t, s.u, s.h [m], s.tip [m]
//! })?;
//! assert!(peak > 50e-6 && peak < 150e-6, "h2 peaks at {peak} m");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Step it as a co-simulation master does
//!
//! Each step holds the voltages until its end, as the FMUs' `DoStep` does:
//!
//! ```
//! # use hasel_fmu::model::{params::Params, platform::Platform};
//! # use hasel_fmu::simulation::{DEFAULT_RTOL, Simulator};
//! let mut sim = Simulator::new(Platform::new(Params::default())?, 0.0, DEFAULT_RTOL)?;
//! for k in 1..=100 {
//!     sim.step_held([60.0, 30.0, 0.0], k as f64 * 1e-3)?;
//! }
//! let out = sim.sample();
//! println!("after 0.1 s: h = {:?} m, tip = {:?} m", out.h, out.tip);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Fit the model to measured data
//!
//! An experiment is a CSV file with `t,U1,U2,U3` and any of `h1..h3`, `tip_x`, `tip_y`
//! (book/src/identify.md, "Measured data files"):
//!
//! ```no_run
//! use hasel_fmu::identify::{self, Options, experiment::Experiment};
//! use hasel_fmu::model::params::Params;
//! use std::path::Path;
//!
//! let estimation = [Experiment::read(Path::new("est.csv"))?];
//! let validation = [Experiment::read(Path::new("val.csv"))?];
//! let fit = identify::identify(&Params::default(), &estimation, &validation, &Options::default())?;
//! for e in fit.estimates.iter().filter(|e| e.estimated) {
//!     println!("{} = {} ± {:?}", e.name, e.value, e.std_error);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Find the effect the model misses
//!
//! The first experiment estimates, the others are held out (book/src/diagnose.md, "The
//! workflow"):
//!
//! ```no_run
//! use hasel_fmu::diagnose::{self, Options};
//! use hasel_fmu::identify::experiment::Experiment;
//! use hasel_fmu::model::params::Params;
//! use std::path::Path;
//!
//! let records = ["w3pi.csv", "w11.csv"].map(|f| Experiment::read(Path::new(f)));
//! let records = records.into_iter().collect::<Result<Vec<_>, _>>()?;
//! let found = diagnose::diagnose(&Params::default(), records, &Options::default())?;
//! println!("{}: {:?}", found.verdict.name(), found.effects);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

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
