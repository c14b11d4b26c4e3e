//! `hasel bench`: solver speed on the paper's excitation, with the error against the
//! independent reference data printed beside the time.

use std::path::Path;
use std::time::Duration;

use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Simulator};
use hasel_fmu::solver::Stats;

use super::reference::{error_against, reference};
use super::timing::best;
use crate::error::Error;

/// The issue #14 target of one held 1 ms co-simulation step \[µs\].
const HELD_STEP_TARGET_US: f64 = 2.4;

fn report(name: &str, wall: Duration, stats: Stats, error: Option<(f64, f64)>, target_ms: f64) {
    let ms = wall.as_secs_f64() * 1e3;
    say!("{name}");
    say!(
        "  wall {ms:.2} ms (target <= {target_ms} ms: {}) | steps {} (+{} rejected) | f {} | J {} | LU {} | Newton {}",
        if ms <= target_ms { "met" } else { "MISSED" },
        stats.accepted,
        stats.rejected,
        stats.rhs_evals,
        stats.jac_evals,
        stats.decompositions,
        stats.newton_iterations
    );
    match error {
        Some((dh, dtip)) => {
            say!("  max error vs reference: |dh| {dh:.2e} um, |dtip| {dtip:.2e} um")
        }
        None => say!("  (the reference's columns or times do not match: no error figure)"),
    }
}

/// Both runs (the sine with dense output, the held co-simulation steps), best of `repeat`,
/// against the reference trajectories of `reference_dir` (default: the embedded ones).
pub fn run(repeat: usize, reference_dir: Option<&Path>) -> Result<(), Error> {
    let model = Platform::new(Params::default())?;
    let omega = 3.0 * std::f64::consts::PI;
    let input = Input::sine(60.0, omega);
    say!(
        "Radau IIA(5), rtol {DEFAULT_RTOL:e}, 15 states, best of {} runs",
        repeat
    );

    let (wall, (stats, samples)) = best(repeat, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL).expect("valid model");
        let mut samples = Vec::with_capacity(10_001);
        sim.run(&input, 10.0, 1e-3, |s| samples.push(*s))
            .expect("the default run succeeds");
        (sim.stats(), samples)
    });
    let error = error_against(&reference(reference_dir, "sine60_w3pi.csv")?, &samples);
    #[cfg(feature = "compare")]
    let sine_row = (wall, stats, error);
    report(
        "10 s of 60 V at 3pi rad/s, outputs every 1 ms (dense output)",
        wall,
        stats,
        error,
        5.0,
    );

    let (wall, (stats, samples)) = best(repeat, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL).expect("valid model");
        let mut samples = Vec::with_capacity(10_001);
        samples.push(sim.sample());
        // the input of the next step, computed once: it is also the new sample's
        let mut u = input.value(0.0);
        for k in 0..10_000 {
            sim.step_held(u, (k + 1) as f64 * 1e-3)
                .expect("the default run succeeds");
            let mut s = sim.sample();
            u = input.value(s.t);
            s.u = u;
            samples.push(s);
        }
        (sim.stats(), samples)
    });
    let error = error_against(
        &reference(reference_dir, "zoh1ms_sine60_w3pi.csv")?,
        &samples,
    );
    report(
        "10,000 co-simulation steps of 1 ms, input held and changed at every step",
        wall,
        stats,
        error,
        HELD_STEP_TARGET_US * 10.0,
    );
    let step_us = wall.as_secs_f64() * 1e6 / 10_000.0;
    say!(
        "  one held step: {step_us:.2} us (target <= {HELD_STEP_TARGET_US} us: {})",
        if step_us <= HELD_STEP_TARGET_US {
            "met"
        } else {
            "MISSED"
        }
    );
    #[cfg(feature = "compare")]
    {
        use super::compare::{Case, case_row};
        let ours = vec![
            case_row(
                "Radau IIA(5)",
                Case::Sine,
                sine_row.0,
                sine_row.1,
                sine_row.2.map(|e| e.0),
            ),
            case_row("Radau IIA(5)", Case::Held, wall, stats, error.map(|e| e.0)),
        ];
        super::compare::print(&model, DEFAULT_RTOL, repeat, reference_dir, ours)?;
    }
    Ok(())
}
