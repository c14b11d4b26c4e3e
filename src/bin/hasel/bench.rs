//! `hasel bench`: solver speed on the paper's excitation, with the error against the
//! independent reference data printed beside the time.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hasel_fmu::io::csv::Table;
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Sample, Simulator};
use hasel_fmu::solver::Stats;

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
    /// Benchmark the missing-effect diagnosis on hidden mechanisms (the confusion matrix)
    #[arg(long)]
    diagnose: bool,
    /// With --diagnose: seeds per hidden mechanism
    #[arg(long, default_value_t = 2)]
    seeds: u64,
    /// With --diagnose: recorded outputs, h or tip
    #[arg(long, default_value = "h", value_parser = ["h", "tip"])]
    columns: String,
    /// With --diagnose: only this hidden mechanism (an effect, `none` or `vibration`)
    #[arg(long)]
    only: Option<String>,
}

/// The reference trajectories of tests/data/reference/ (see its README), built into the
/// executable so that an installed `hasel bench` needs no source tree.
const EMBEDDED: [(&str, &str); 2] = [
    (
        "sine60_w3pi.csv",
        include_str!("../../../tests/data/reference/sine60_w3pi.csv"),
    ),
    (
        "zoh1ms_sine60_w3pi.csv",
        include_str!("../../../tests/data/reference/zoh1ms_sine60_w3pi.csv"),
    ),
];

/// The reference trajectory `name`: from `dir` when given, else the embedded copy.
pub(crate) fn reference(dir: Option<&Path>, name: &str) -> Result<Table, String> {
    match dir {
        Some(dir) => Table::read(&dir.join(name)).map_err(|e| e.to_string()),
        None => {
            let (_, text) = EMBEDDED
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| format!("no embedded reference trajectory {name}"))?;
            Table::parse(Path::new(name), text).map_err(|e| e.to_string())
        }
    }
}

/// Largest |Δh| and |Δtip| [µm] against a reference trajectory, over the rows both have;
/// `None` when its columns or times do not match the samples.
pub(crate) fn error_against(table: &Table, samples: &[Sample]) -> Option<(f64, f64)> {
    let cols: Vec<usize> = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]
        .iter()
        .map(|c| table.find(c))
        .collect::<Option<_>>()?;
    let (mut dh, mut dtip): (f64, f64) = (0.0, 0.0);
    for (row, s) in table.rows.iter().zip(samples) {
        if (row[0] - s.t).abs() > 1e-9 {
            return None;
        }
        for i in 0..3 {
            dh = dh.max((row[cols[i]] - s.h[i]).abs());
            dtip = dtip.max((row[cols[3 + i]] - s.tip[i]).abs());
        }
    }
    Some((dh * 1e6, dtip * 1e6))
}

pub(crate) fn best<T>(repeat: usize, mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut out = None;
    let mut fastest = Duration::MAX;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        let r = f();
        fastest = fastest.min(start.elapsed());
        out = Some(r);
    }
    (fastest, out.expect("at least one repetition"))
}

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

pub fn run(a: Args) -> Result<(), String> {
    if a.diagnose {
        return crate::bench_diagnose::run(a.seeds, crate::common::columns(&a.columns), a.only);
    }
    if a.identify {
        return crate::bench_identify::run();
    }
    let model = Platform::new(Params::default()).map_err(|e| e.to_string())?;
    let omega = 3.0 * std::f64::consts::PI;
    let input = Input::sine(60.0, omega);
    say!(
        "Radau IIA(5), rtol {DEFAULT_RTOL:e}, 15 states, best of {} runs",
        a.repeat
    );

    let (wall, (stats, samples)) = best(a.repeat, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL).expect("valid model");
        let mut samples = Vec::with_capacity(10_001);
        sim.run(&input, 10.0, 1e-3, |s| samples.push(*s))
            .expect("the default run succeeds");
        (sim.stats(), samples)
    });
    let error = error_against(
        &reference(a.reference.as_deref(), "sine60_w3pi.csv")?,
        &samples,
    );
    #[cfg(feature = "compare")]
    let sine_row = (wall, stats, error);
    report(
        "10 s of 60 V at 3pi rad/s, outputs every 1 ms (dense output)",
        wall,
        stats,
        error,
        5.0,
    );

    let (wall, (stats, samples)) = best(a.repeat, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL).expect("valid model");
        let mut samples = Vec::with_capacity(10_001);
        samples.push(sim.sample());
        for k in 0..10_000 {
            let t = k as f64 * 1e-3;
            sim.step_held(input.value(t), (k + 1) as f64 * 1e-3)
                .expect("the default run succeeds");
            let mut s = sim.sample();
            s.u = input.value(s.t);
            samples.push(s);
        }
        (sim.stats(), samples)
    });
    let error = error_against(
        &reference(a.reference.as_deref(), "zoh1ms_sine60_w3pi.csv")?,
        &samples,
    );
    report(
        "10,000 co-simulation steps of 1 ms, input held and changed at every step",
        wall,
        stats,
        error,
        50.0,
    );
    #[cfg(feature = "compare")]
    {
        use crate::compare::{Case, case_row};
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
        crate::compare::print(&model, DEFAULT_RTOL, a.repeat, a.reference.as_deref(), ours)?;
    }
    Ok(())
}
