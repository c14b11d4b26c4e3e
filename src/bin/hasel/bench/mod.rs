//! `hasel bench`: the solver (`solver.rs`, with the library solvers of `compare/` beside it
//! under the `compare` feature), the command's whole process with and without its CSV
//! (`process.rs`), the identification (`identify.rs`) and the missing-effect
//! diagnosis (`diagnose.rs`), the reduced models against the full one (`reduced.rs`). The reference trajectories (`reference.rs`) and the timing
//! (`timing.rs`) are leaves that the benchmarks use; nothing uses this module's command back.

use std::path::PathBuf;

use crate::error::Error;

#[cfg(feature = "compare")]
mod compare;
mod diagnose;
mod identify;
mod process;
mod reduced;
mod reference;
mod solver;
mod timing;

#[derive(clap::Args)]
pub struct Args {
    /// Folder of other reference trajectories (sine60_w3pi.csv, zoh1ms_sine60_w3pi.csv);
    /// default: the repository's tests/data/reference/, built into this executable
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Repetitions; the best wall time is reported
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Benchmark the identification instead of the solver
    #[arg(long)]
    identify: bool,
    /// Measure the reduced models (quasi-static, slow) against the full one instead
    #[arg(long)]
    reduced: bool,
    /// Benchmark the missing-effect diagnosis on hidden mechanisms (the confusion matrix)
    #[arg(long)]
    diagnose: bool,
    /// With --diagnose: seeds per hidden mechanism
    #[arg(long, default_value_t = 2)]
    seeds: u64,
    /// With --diagnose: the first seed, so that seeds a rule was not tuned on can be run alone
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// With --diagnose: recorded outputs, h or tip
    #[arg(long, default_value = "h", value_parser = ["h", "tip"])]
    columns: String,
    /// With --diagnose: only this hidden mechanism (an effect, a case such as `coupling_tilt`
    /// or `coupling_tilt+creep`, `none`, `vibration`, or `two` for every two-effect case)
    #[arg(long)]
    only: Option<String>,
    /// With --diagnose: record every case as lab data (sensor lag, resolution, outliers, dropouts)
    #[arg(long)]
    artifacts: bool,
    /// With --diagnose: record every case with a lab protocol drawn at random (staircase,
    /// chirp, two voltage levels or the sines; 0.5, 1 or 2 ms; 1-4 records of 3-20 s, a quarter
    /// of them of the tip; about half from 1.3 s into the drive) and print the score per protocol
    #[arg(long)]
    protocols: bool,
    /// With --diagnose: write each case's diagnosis (report.md, diagnosis.json, figures) into
    /// DIR/CASE-SEED
    #[arg(long, value_name = "DIR")]
    reports: Option<std::path::PathBuf>,
    /// With --diagnose: the simulations' relative tolerance in place of the diagnosis's (the
    /// first line printed gives the one used), to measure what a looser one saves and what it
    /// changes in the answers
    #[arg(long)]
    rtol: Option<f64>,
}

pub fn run(a: Args) -> Result<(), Error> {
    if a.diagnose {
        return diagnose::run(
            a.first_seed..=a.first_seed.saturating_add(a.seeds).saturating_sub(1),
            crate::common::columns(&a.columns),
            a.only,
            a.artifacts,
            a.protocols,
            a.reports,
            crate::common::diagnose_options(a.rtol)?,
        );
    }
    if a.identify {
        return identify::run();
    }
    if a.reduced {
        return reduced::run_all(a.repeat);
    }
    solver::run(a.repeat, a.reference.as_deref())?;
    process::run(a.repeat)
}
