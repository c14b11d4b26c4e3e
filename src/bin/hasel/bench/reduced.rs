//! `hasel bench --reduced`: the reduced models (src/model/reduced.rs) against the full one on
//! the paper's excitation, the same as held co-simulation steps of 1 ms, and a step.

use std::time::Duration;

use hasel_fmu::model::{Params, Platform, Reduction};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Sample, SimError, Simulator, largest_difference};

use super::timing::best;
use crate::error::Error;

/// Relative tolerance of every run: tight enough that the differences are the models', not
/// the integrator's.
const RTOL: f64 = 1e-9;

/// Where the comparison after the start-up is taken from \[s\]: past the boundary layer that a
/// jump of the command at t = 0 leaves in the slow model's angle (module doc of
/// src/model/reduced.rs).
const AFTER: f64 = 0.05;

/// One excitation of the comparison.
struct Case {
    name: &'static str,
    t_end: f64,
    /// Held co-simulation steps of 1 ms (the input sampled at each step's start), or the
    /// input followed exactly with outputs every 1 ms.
    held: bool,
    input: Input,
}

fn cases() -> [Case; 3] {
    let sine = || Input::sine(60.0, 3.0 * std::f64::consts::PI);
    [
        Case {
            name: "paper sine 60 V, 3pi rad/s, 10 s",
            t_end: 10.0,
            held: false,
            input: sine(),
        },
        Case {
            name: "the same, 10,000 held steps of 1 ms",
            t_end: 10.0,
            held: true,
            input: sine(),
        },
        Case {
            name: "step to 60 / 40 / 20 V from rest, 1 s",
            t_end: 1.0,
            held: false,
            input: Input::constant([60.0, 40.0, 20.0]),
        },
    ]
}

/// The samples every 1 ms of `model` from rest through `case` at relative tolerance `rtol`.
fn run(model: &Platform, case: &Case, rtol: f64) -> Result<Vec<Sample>, Error> {
    let mut sim = Simulator::new(model.clone(), 0.0, rtol)?;
    let steps = (case.t_end / 1e-3).round() as usize;
    let mut samples = Vec::with_capacity(steps + 1);
    if case.held {
        samples.push(sim.sample());
        for k in 0..steps {
            sim.step_held(case.input.value(k as f64 * 1e-3), (k + 1) as f64 * 1e-3)?;
            samples.push(sim.sample());
        }
    } else {
        sim.run(&case.input, case.t_end, 1e-3, |s| samples.push(*s))?;
    }
    Ok(samples)
}

/// The issue 26 target of one held 1 ms co-simulation step of the slow model \[µs\].
const SLOW_STEP_TARGET_US: f64 = 0.2;

pub fn run_all(repeat: usize) -> Result<(), Error> {
    say!(
        "Reduced models against the full one (rtol {RTOL:e} for all; max over the run, and from {} ms on), best of {repeat} runs",
        AFTER * 1e3
    );
    say!(
        "| case | model | states | max abs dh [um] | max abs dtip [um] | from {} ms: dh / dtip [um] | wall [ms] |",
        AFTER * 1e3
    );
    say!("|---|---|---|---|---|---|---|");
    for case in cases() {
        let full = Platform::new(Params::default())?;
        let (wall, reference) = best(repeat, || run(&full, &case, RTOL));
        let reference = reference?;
        row(&case, &full, wall, (0.0, 0.0), (0.0, 0.0));
        for reduction in [Reduction::QuasiStatic, Reduction::Slow] {
            let model = Platform::reduced(Params::default(), reduction)?;
            let (wall, samples) = best(repeat, || run(&model, &case, RTOL));
            let samples = samples?;
            let all = largest_difference(&reference, &samples, 0.0);
            let after = largest_difference(&reference, &samples, AFTER);
            row(&case, &model, wall, all, after);
        }
    }
    step_costs(repeat)
}

/// The cost of one held 1 ms co-simulation step of each model at the FMUs' default tolerance,
/// over the 10,000 steps of the paper's sine, with what it is made of: the integrator, the
/// right-hand side's evaluations per step and the cost of one (at the run's last state and
/// command); and the same run's distance from the full model's at rtol [`RTOL`].
fn step_costs(repeat: usize) -> Result<(), Error> {
    say!(
        "One held 1 ms co-simulation step, rtol {DEFAULT_RTOL:e} (the FMUs' default), 10,000 steps of the paper's sine (its values computed before the clock starts: an importer's, not the step's), best of {repeat} runs; max |dh| / |dtip| against the full model at rtol {RTOL:e}:"
    );
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let commands: Vec<[f64; 3]> = (0..STEPS).map(|k| input.value(k as f64 * 1e-3)).collect();
    let held = &cases()[1];
    let reference = run(&Platform::new(Params::default())?, held, RTOL)?;
    for reduction in Reduction::ALL {
        let model = Platform::reduced(Params::default(), reduction)?;
        let (wall, sim) = best(repeat, || -> Result<Simulator, Error> {
            let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL)?;
            for (k, &u) in commands.iter().enumerate() {
                sim.step_held(u, (k + 1) as f64 * 1e-3)?;
            }
            Ok(sim)
        });
        let sim = sim?;
        let (x, u) = (sim.state(), input.value(STEPS as f64 * 1e-3));
        let mut dx = vec![0.0; x.len()];
        let (rhs_wall, done) = best(repeat, || -> Result<(), Error> {
            for _ in 0..RHS_CALLS {
                model
                    .rhs(std::hint::black_box(x), u, &mut dx)
                    .map_err(SimError::from)?;
            }
            Ok(())
        });
        done?;
        let us = wall.as_secs_f64() * 1e6 / STEPS as f64;
        let verdict = match reduction {
            Reduction::Slow => format!(
                " (target <= {SLOW_STEP_TARGET_US} us: {})",
                if us <= SLOW_STEP_TARGET_US {
                    "met"
                } else {
                    "MISSED"
                }
            ),
            _ => String::new(),
        };
        let stats = sim.stats();
        let (dh, dtip) = largest_difference(&reference, &run(&model, held, DEFAULT_RTOL)?, 0.0);
        say!(
            "  {:<12} {us:.3} us{verdict}; {}, per step {:.2} right-hand sides of {:.0} ns each, {:.4} Jacobians; {:.4} / {:.4} um",
            reduction.name(),
            sim.method(),
            stats.rhs_evals as f64 / STEPS as f64,
            rhs_wall.as_secs_f64() * 1e9 / RHS_CALLS as f64,
            stats.jac_evals as f64 / STEPS as f64,
            dh * 1e6,
            dtip * 1e6
        );
    }
    Ok(())
}

/// Held steps of the step cost, and evaluations of the right-hand side timed for its cost.
const STEPS: usize = 10_000;
const RHS_CALLS: usize = 100_000;

fn row(case: &Case, model: &Platform, wall: Duration, all: (f64, f64), after: (f64, f64)) {
    let um = 1e6;
    say!(
        "| {} | {} | {} | {:.4} | {:.4} | {:.4} / {:.4} | {:.1} |",
        case.name,
        model.reduction().name(),
        model.n_states(),
        all.0 * um,
        all.1 * um,
        after.0 * um,
        after.1 * um,
        wall.as_secs_f64() * 1e3
    );
}
