//! The effect library carried through the simulation: the delay's history in co-simulation
//! steps and in whole runs, and every effect running from rest through the paper's input.

use hasel_fmu::model::{Effect, Params, Platform};
use hasel_fmu::simulation::{Input, Interpolation, Simulator};

const RTOL: f64 = 1e-8;

fn heights_at(params: &Params, input: &Input, times: &[f64]) -> Vec<[f64; 3]> {
    let mut sim = Simulator::new(Platform::new(params.clone()).unwrap(), 0.0, RTOL).unwrap();
    let mut out = Vec::new();
    sim.run_at(input, times, |s| out.push(s.h)).unwrap();
    out
}

#[test]
fn a_delayed_run_is_the_run_shifted_in_time() {
    let tau = 0.0123;
    let mut delayed = Params::default();
    delayed.effects.delay.tau_d = tau;
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let times: Vec<f64> = (0..=400).map(|k| tau + k as f64 * 2.5e-3).collect();
    let shifted: Vec<f64> = times.iter().map(|t| t - tau).collect();
    let a = heights_at(&delayed, &input, &times);
    let b = heights_at(&Params::default(), &input, &shifted);
    let worst = a
        .iter()
        .zip(&b)
        .flat_map(|(x, y)| (0..3).map(move |i| (x[i] - y[i]).abs()));
    let worst = worst.fold(0.0, f64::max);
    // both runs at rtol 1e-8: they differ by their own step-size control, far below 0.01 µm
    assert!(worst < 1e-9, "delayed vs shifted: {worst:e} m");
}

#[test]
fn delayed_held_steps_replay_the_commands_late() {
    // co-simulation steps of 1 ms with a delay that is not a multiple of the step: the
    // outputs at t are those of the undelayed zero-order-hold run at t − τ
    let tau = 0.0047;
    let dt = 1e-3;
    let n = 300;
    let command = |k: usize| {
        let t = k as f64 * dt;
        [60.0 * (9.4 * t).sin(), 50.0 * (7.0 * t + 1.0).sin(), 40.0]
    };
    let mut delayed = Params::default();
    delayed.effects.delay.tau_d = tau;
    let mut sim = Simulator::new(Platform::new(delayed).unwrap(), 0.0, RTOL).unwrap();
    let mut stepped = Vec::new();
    for k in 0..n {
        sim.step_held(command(k), (k + 1) as f64 * dt).unwrap();
        stepped.push(sim.sample().h);
    }
    let ts: Vec<f64> = (0..=n).map(|k| k as f64 * dt).collect();
    let us: Vec<[f64; 3]> = (0..=n).map(command).collect();
    let zoh = Input::sampled(ts, us, Interpolation::ZeroOrderHold).unwrap();
    let late: Vec<f64> = (1..=n)
        .map(|k| k as f64 * dt - tau)
        .filter(|t| *t > 0.0)
        .collect();
    let reference = heights_at(&Params::default(), &zoh, &late);
    let offset = n - late.len();
    let worst = reference
        .iter()
        .zip(&stepped[offset..])
        .flat_map(|(x, y)| (0..3).map(move |i| (x[i] - y[i]).abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "held steps vs late reference: {worst:e} m");
}

#[test]
fn every_effect_changes_the_response_and_runs_from_rest() {
    let input = Input::sine(60.0, 11.0);
    let times: Vec<f64> = (0..=300).map(|k| k as f64 * 5e-3).collect();
    let base = heights_at(&Params::default(), &input, &times);
    let settings: [(Effect, &[(&str, f64)]); 9] = [
        (Effect::Coupling, &[("k_c", 300.0)]),
        (Effect::ChargeDrift, &[("R3", 2e4), ("tau3", 0.5)]),
        (Effect::Creep, &[("k_v", 0.1), ("tau_v", 0.3)]),
        (Effect::Hysteresis, &[("k_h", 0.1), ("theta_h", 2e-3)]),
        (Effect::AmplifierLag, &[("tau_a", 0.03)]),
        (Effect::Delay, &[("tau_d", 0.02)]),
        (Effect::Saturation, &[("U_max", 45.0)]),
        (Effect::Stiffening, &[("k3", 50.0)]),
        (
            Effect::Preload,
            &[("tau0_1", 2e-3), ("tau0_2", 2e-3), ("tau0_3", 2e-3)],
        ),
    ];
    for (effect, values) in settings {
        let mut p = Params::default();
        for (name, v) in values {
            p.set(name, *v).unwrap();
        }
        assert_eq!(p.effects.active(), vec![effect]);
        let h = heights_at(&p, &input, &times);
        let change = h
            .iter()
            .zip(&base)
            .flat_map(|(x, y)| (0..3).map(move |i| (x[i] - y[i]).abs()))
            .fold(0.0, f64::max);
        assert!(
            change > 1e-6,
            "{effect}: the response moved only {change:e} m"
        );
    }
}

#[test]
fn a_held_command_arrives_after_the_delay_in_co_simulation() {
    // as a master steps: t accumulated in floating point, the command set before the first step
    let mut p = Params::default();
    p.effects.delay.tau_d = 0.05;
    let mut sim = Simulator::new(Platform::new(p).unwrap(), 0.0, 1e-6).unwrap();
    let (mut t, h) = (0.0, 1e-3);
    let rest = sim.sample().h[0];
    while t < 0.1 {
        sim.step_held([60.0, 0.0, 0.0], t + h)
            .unwrap_or_else(|e| panic!("at t = {t}: {e}"));
        t += h;
        if t < 0.0495 {
            assert_eq!(
                sim.sample().h[0],
                rest,
                "moved before the command arrived, t = {t}"
            );
        }
    }
    assert!(sim.sample().h[0] - rest > 0.5e-6);
}
