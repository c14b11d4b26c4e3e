//! `hasel bench` with `--features compare`: the same two runs with library stiff solvers,
//! printed beside our Radau IIA(5): diffsol's BDF, ESDIRK34 and TR-BDF2 ([`diffsol`]) and
//! SUNDIALS CVODE called natively ([`cvode`]), all with the model's analytic Jacobian and the
//! project's tolerances: rtol and atol_i = rtol · scale_i.

use std::path::Path;
use std::time::Duration;

use hasel_fmu::io::csv::Table;
use hasel_fmu::model::Platform;
use hasel_fmu::simulation::Sample;
use hasel_fmu::solver::Stats;

use super::reference::{error_against, reference};
use super::timing::best;
use crate::error::Error;

mod cvode;
mod diffsol;

/// A library solver of the table.
#[derive(Clone, Copy)]
enum Library {
    Diffsol(diffsol::Method),
    Cvode(cvode::Linear),
}

impl Library {
    fn all() -> impl Iterator<Item = Library> {
        let diffsol = diffsol::Method::ALL.into_iter().map(Library::Diffsol);
        diffsol.chain(cvode::Linear::ALL.into_iter().map(Library::Cvode))
    }

    fn name(self) -> &'static str {
        match self {
            Library::Diffsol(m) => m.name(),
            Library::Cvode(l) => l.name(),
        }
    }

    /// One run of `case`: the samples every 1 ms and the work done.
    fn run(self, model: &Platform, case: Case, rtol: f64) -> Result<(Vec<Sample>, Work), Error> {
        match self {
            Library::Diffsol(m) => diffsol::run(model, m, case, rtol),
            Library::Cvode(l) => cvode::run(model, l, case, rtol),
        }
    }
}

/// The two runs of `hasel bench`.
#[derive(Clone, Copy, PartialEq)]
pub enum Case {
    /// 10 s of the sine, outputs every 1 ms from the solver's interpolant
    Sine,
    /// 10,000 co-simulation steps of 1 ms, input held over each step
    Held,
}

impl Case {
    fn name(self) -> &'static str {
        match self {
            Case::Sine => "10 s sine",
            Case::Held => "10k x 1 ms held",
        }
    }

    fn reference(self) -> &'static str {
        match self {
            Case::Sine => "sine60_w3pi.csv",
            Case::Held => "zoh1ms_sine60_w3pi.csv",
        }
    }
}

/// Work of one run, in the columns of the table.
#[derive(Clone, Copy, Default)]
pub struct Work {
    pub steps: usize,
    pub rejected: usize,
    pub f: usize,
    pub jac: usize,
    pub lu: usize,
}

impl From<Stats> for Work {
    fn from(s: Stats) -> Work {
        Work {
            steps: s.accepted,
            rejected: s.rejected,
            f: s.rhs_evals,
            jac: s.jac_evals,
            lu: s.decompositions,
        }
    }
}

/// One line of the table.
pub struct Row {
    pub solver: String,
    pub case: Case,
    pub wall: Duration,
    pub work: Work,
    /// max |Δh| [µm] against the reference, if the file was found
    pub dh: Option<f64>,
}

fn dh_against(reference: &Table, samples: &[Sample]) -> Option<f64> {
    error_against(reference, samples).map(|(dh, _)| dh)
}

/// Runs both cases with each diffsol method (best of `repeat`) and prints them under `ours`.
pub fn print(
    model: &Platform,
    rtol: f64,
    repeat: usize,
    reference_dir: Option<&Path>,
    ours: Vec<Row>,
) -> Result<(), Error> {
    let mut rows = ours;
    for case in [Case::Sine, Case::Held] {
        let reference = reference(reference_dir, case.reference())?;
        for solver in Library::all() {
            let mut failed = None;
            let (wall, out) = best(repeat, || match solver.run(model, case, rtol) {
                Ok(r) => Some(r),
                Err(e) => {
                    failed = Some(e);
                    None
                }
            });
            match out {
                Some((samples, work)) => rows.push(Row {
                    solver: solver.name().to_string(),
                    case,
                    wall,
                    work,
                    dh: dh_against(&reference, &samples),
                }),
                None => say!(
                    "{} on {}: failed: {}",
                    solver.name(),
                    case.name(),
                    failed.map(|e| e.to_string()).unwrap_or_default()
                ),
            }
        }
    }
    rows.sort_by_key(|r| r.case != Case::Sine);
    say!();
    say!(
        "Side by side with library solvers (diffsol 0.18 with dense nalgebra LU; SUNDIALS CVODE \
         {}, native), analytic Jacobian, rtol {rtol:e}, atol_i = rtol*scale_i, best of {repeat}",
        cvode::version()
    );
    say!(
        "{:<21} | {:<15} | {:>9} | {:>17} | {:>9} | {:>7} | {:>7} | {:>13}",
        "solver",
        "case",
        "wall ms",
        "steps (+rej)",
        "f evals",
        "J evals",
        "LU",
        "max |dh| um"
    );
    say!("{}", "-".repeat(21 + 15 + 9 + 17 + 9 + 7 + 7 + 13 + 7 * 3));
    for r in &rows {
        say!(
            "{:<21} | {:<15} | {:>9.2} | {:>17} | {:>9} | {:>7} | {:>7} | {:>13}",
            r.solver,
            r.case.name(),
            r.wall.as_secs_f64() * 1e3,
            format!("{} (+{})", r.work.steps, r.work.rejected),
            r.work.f,
            r.work.jac,
            r.work.lu,
            r.dh.map_or("n/a".to_string(), |d| format!("{d:.2e}")),
        );
    }
    say!(
        "  diffsol: Newton-failure cap (default 50 per solve) lifted; rej = error-test + Newton \
         failures; the held case restarts at every step (new dy, diffsol's initial step-size rule)"
    );
    say!(
        "  CVODE: BDF orders 1-5, Newton with its own Jacobian reuse; rej = error-test + Newton \
         convergence failures; the held case calls CVodeReInit at every step (the standard \
         restart at an input jump)"
    );
    Ok(())
}

/// Our solver's line of the table.
pub fn case_row(solver: &str, case: Case, wall: Duration, stats: Stats, dh: Option<f64>) -> Row {
    Row {
        solver: solver.to_string(),
        case,
        wall,
        work: stats.into(),
        dh,
    }
}
