//! Why a command failed: the library's errors as they are, and the command line's own. `main`
//! prints it after `hasel: error: `.

use std::path::PathBuf;

use hasel_fmu::io::file::FileError;
use hasel_fmu::model::params::ParamError;
use hasel_fmu::model::statics::StaticsError;
use hasel_fmu::simulation::SimError;
use hasel_fmu::uncertainty::UncertaintyError;
use hasel_fmu::{diagnose, identify};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file read or written, located.
    #[error(transparent)]
    File(#[from] FileError),
    #[error(transparent)]
    Param(#[from] ParamError),
    #[error(transparent)]
    Simulation(#[from] SimError),
    #[error(transparent)]
    Identify(#[from] identify::Error),
    #[error(transparent)]
    Diagnose(#[from] diagnose::Error),
    #[error(transparent)]
    Uncertainty(#[from] UncertaintyError),
    #[error(transparent)]
    Control(#[from] hasel_fmu::control::ControlError),
    #[error(transparent)]
    Statics(#[from] StaticsError),
    /// Points of a tip path that no heights or voltages reach, each with its line, time and
    /// reason (`hasel inverse`; nothing is written).
    #[error("{}", unreachable(path, *total, points))]
    Unreachable {
        path: PathBuf,
        total: usize,
        points: Vec<UnreachablePoint>,
    },
    /// A combination or range of command-line settings that does not work, as a sentence.
    #[error("{0}")]
    Usage(String),
    /// A value given on the command line that is wrong, named with its flag.
    #[error("--{flag} {value}: {problem}")]
    Flag {
        flag: &'static str,
        value: String,
        problem: String,
    },
    /// The FMU library is looked for beside this executable.
    #[error("cannot locate this executable: {0}")]
    CurrentExe(std::io::Error),
    /// A command that `hasel bench` times failed.
    #[error("benchmark: {command}: {problem}")]
    Benchmark { command: String, problem: String },
    #[error("no embedded reference trajectory {0}")]
    NoEmbeddedReference(String),
    /// The library solver of `hasel bench --features compare`, with the method once it runs.
    #[cfg(feature = "compare")]
    #[error("{}{source}", method.map(|m| format!("{m}: ")).unwrap_or_default())]
    Diffsol {
        method: Option<&'static str>,
        source: diffsol::DiffsolError,
    },
    /// A SUNDIALS call of the CVODE comparison failed: the call and CVODE's flag name.
    #[cfg(feature = "compare")]
    #[error("CVODE: {call}: {flag}")]
    Cvode { call: &'static str, flag: String },
}

/// One point of a tip path that cannot be reached.
#[derive(Debug)]
pub struct UnreachablePoint {
    /// 1-based line of the file.
    pub line: usize,
    /// Its time \[s\].
    pub t: f64,
    pub why: String,
}

/// How many points are listed before the rest is counted.
const LISTED: usize = 20;

fn unreachable(path: &std::path::Path, total: usize, points: &[UnreachablePoint]) -> String {
    let mut text = format!(
        "{}: {} of {total} tip points cannot be reached (nothing written):",
        path.display(),
        points.len()
    );
    for p in points.iter().take(LISTED) {
        text.push_str(&format!("\n  line {}, t = {} s: {}", p.line, p.t, p.why));
    }
    if points.len() > LISTED {
        text.push_str(&format!("\n  ... and {} more", points.len() - LISTED));
    }
    text
}

impl Error {
    /// `--flag value: problem`.
    pub fn flag(flag: &'static str, value: impl ToString, problem: impl Into<String>) -> Error {
        Error::Flag {
            flag,
            value: value.to_string(),
            problem: problem.into(),
        }
    }
}
