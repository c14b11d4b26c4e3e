//! The model and solver against the independent reference trajectories of
//! `tests/data/reference/` (computed at relative tolerance 1e-10; see its README).

use std::path::PathBuf;

use hasel_fmu::io::csv::Table;
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{Input, Interpolation, Sample, Simulator};

fn reference(name: &str) -> Table {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/reference")
        .join(name);
    Table::read(&path).unwrap()
}

/// Largest deviation of h and of the tip from the reference, over every row.
fn deviation(reference: &Table, samples: &[Sample]) -> (f64, f64) {
    assert_eq!(reference.rows.len(), samples.len());
    let cols = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"].map(|c| reference.find(c).unwrap());
    let (mut dh, mut dtip) = (0.0f64, 0.0f64);
    for (row, s) in reference.rows.iter().zip(samples) {
        assert!((row[0] - s.t).abs() < 1e-12, "time {} vs {}", row[0], s.t);
        for i in 0..3 {
            dh = dh.max((row[cols[i]] - s.h[i]).abs());
            dtip = dtip.max((row[cols[3 + i]] - s.tip[i]).abs());
        }
    }
    (dh, dtip)
}

fn run_sine(omega: f64, rtol: f64) -> Vec<Sample> {
    let mut sim = Simulator::new(Platform::new(Params::default()).unwrap(), 0.0, rtol).unwrap();
    let mut out = Vec::new();
    sim.run(&Input::sine(60.0, omega), 10.0, 1e-3, |s| out.push(*s))
        .unwrap();
    out
}

#[test]
fn sine_at_3pi_matches_the_reference() {
    let (dh, dtip) = deviation(
        &reference("sine60_w3pi.csv"),
        &run_sine(3.0 * std::f64::consts::PI, 1e-9),
    );
    println!(
        "3pi rad/s, rtol 1e-9: max |dh| = {:.2e} um, max |dtip| = {:.2e} um",
        dh * 1e6,
        dtip * 1e6
    );
    assert!(dh <= 0.01e-6 && dtip <= 0.02e-6);
}

#[test]
fn sine_at_11_matches_the_reference() {
    let (dh, dtip) = deviation(&reference("sine60_w11.csv"), &run_sine(11.0, 1e-9));
    println!(
        "11 rad/s, rtol 1e-9: max |dh| = {:.2e} um, max |dtip| = {:.2e} um",
        dh * 1e6,
        dtip * 1e6
    );
    assert!(dh <= 0.01e-6 && dtip <= 0.02e-6);
}

#[test]
fn default_tolerance_keeps_the_accuracy_contract() {
    // book/src/model.md, "Accuracy contract": at rtol 1e-6, within 0.01 µm on h and 0.02 µm on
    // the tip
    let (dh, dtip) = deviation(
        &reference("sine60_w3pi.csv"),
        &run_sine(3.0 * std::f64::consts::PI, 1e-6),
    );
    println!(
        "3pi rad/s, rtol 1e-6: max |dh| = {:.2e} um, max |dtip| = {:.2e} um",
        dh * 1e6,
        dtip * 1e6
    );
    assert!(dh <= 0.01e-6 && dtip <= 0.02e-6);
}

#[test]
fn zero_order_hold_steps_match_the_reference() {
    let table = reference("zoh1ms_sine60_w3pi.csv");
    let t = table.column("t").unwrap();
    let u: Vec<[f64; 3]> = table.rows.iter().map(|r| [r[1], r[2], r[3]]).collect();
    let input = Input::sampled(t, u, Interpolation::ZeroOrderHold).unwrap();
    let mut sim = Simulator::new(Platform::new(Params::default()).unwrap(), 0.0, 1e-6).unwrap();
    let mut out = Vec::new();
    sim.run(&input, 2.0, 1e-3, |s| out.push(*s)).unwrap();
    let (dh, dtip) = deviation(&table, &out);
    println!(
        "ZOH 1 ms, rtol 1e-6: max |dh| = {:.2e} um, max |dtip| = {:.2e} um",
        dh * 1e6,
        dtip * 1e6
    );
    assert!(dh <= 0.01e-6 && dtip <= 0.02e-6);
}
