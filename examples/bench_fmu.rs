//! Co-simulation throughput of the packed FMU through a Rust importer (the `fmi` crate):
//! 10 s of the paper's excitation at 1 ms communication steps, inputs set before every step and
//! outputs read after it. Prints the best of 5 runs against the 60 ms target. Then Model
//! Exchange at a state in motion: the cost of one fmi2GetDerivatives and of the full Jacobian
//! ∂ẋ/∂x by fmi2GetDirectionalDerivative (one call per column) beside the same Jacobian by
//! central differences of fmi2GetDerivatives.
//!
//! `cargo run --release --example bench_fmu [-- PATH.fmu]` (default fmu/HaselPlatform.fmu).

use std::time::{Duration, Instant};

use fmi::EventFlags;
use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceME, ModelExchange};
use fmi::traits::FmiImport;
use hasel_fmu::simulation::Input;

fn value_refs<const N: usize>(import: &Fmi2Import, names: [&str; N]) -> [u32; N] {
    names.map(|name| {
        import
            .model_description()
            .get_model_variables()
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("{name} is not in modelDescription.xml"))
            .value_reference
    })
}

/// Sets up an instance of either interface at `start` and takes it through initialization.
fn initialize(inst: &mut impl Common, start: f64) {
    Common::setup_experiment(inst, None, start, None).expect("fmi2SetupExperiment");
    Common::enter_initialization_mode(inst).expect("fmi2EnterInitializationMode");
    Common::exit_initialization_mode(inst).expect("fmi2ExitInitializationMode");
}

/// The mean time of `f` over `n` calls, best of 5 rounds.
fn per_call(n: u32, mut f: impl FnMut()) -> Duration {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..n {
                f();
            }
            start.elapsed() / n
        })
        .min()
        .unwrap_or_default()
}

/// A Model Exchange instance in Continuous-Time Mode at a state in motion (50 ms after the
/// commands `u` were applied to the rest state, by the Co-Simulation interface), with its
/// states' and derivatives' value references.
fn model_exchange_in_motion(import: &Fmi2Import, u: [f64; 3]) -> (InstanceME, Vec<u32>, Vec<u32>) {
    let md = import.model_description();
    let vars: Vec<_> = md.get_model_variables().collect();
    let (states, derivatives): (Vec<u32>, Vec<u32>) = md
        .model_structure
        .derivatives
        .unknowns
        .iter()
        .map(|unknown| {
            let der = vars[unknown.index as usize - 1];
            let state = &der.name["der(".len()..der.name.len() - 1];
            (value_refs(import, [state])[0], der.value_reference)
        })
        .unzip();
    let u_refs = value_refs(import, ["U1", "U2", "U3"]);
    let mut cs = import
        .instantiate_cs("motion", false, false)
        .expect("fmi2Instantiate");
    initialize(&mut cs, 0.0);
    cs.set_real(&u_refs, &u).expect("fmi2SetReal");
    cs.do_step(0.0, 0.05, true).expect("fmi2DoStep");
    let mut x = vec![0.0; states.len()];
    cs.get_real(&states, &mut x).expect("fmi2GetReal");
    let mut me = import
        .instantiate_me("me", false, false)
        .expect("fmi2Instantiate");
    initialize(&mut me, 0.05);
    me.set_real(&u_refs, &u).expect("fmi2SetReal");
    me.new_discrete_states(&mut EventFlags::default())
        .expect("fmi2NewDiscreteStates");
    me.enter_continuous_time_mode()
        .expect("fmi2EnterContinuousTimeMode");
    me.set_continuous_states(&x)
        .expect("fmi2SetContinuousStates");
    (me, states, derivatives)
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fmu/HaselPlatform.fmu".into());
    let import: Fmi2Import =
        fmi::import::from_path(&path).unwrap_or_else(|e| panic!("cannot import {path}: {e}"));
    let u_refs = value_refs(&import, ["U1", "U2", "U3"]);
    let y_refs = value_refs(&import, ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]);
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let (dt, steps) = (1e-3, 10_000);
    let mut best = Duration::MAX;
    let mut last = [0.0; 6];
    for _ in 0..5 {
        let start = Instant::now();
        let mut inst = import
            .instantiate_cs("bench", false, false)
            .expect("fmi2Instantiate");
        initialize(&mut inst, 0.0);
        for k in 0..steps {
            let t = k as f64 * dt;
            inst.set_real(&u_refs, &input.value(t))
                .expect("fmi2SetReal");
            inst.do_step(t, dt, true).expect("fmi2DoStep");
            inst.get_real(&y_refs, &mut last).expect("fmi2GetReal");
        }
        Common::terminate(&mut inst).expect("fmi2Terminate");
        best = best.min(start.elapsed());
    }
    let ms = best.as_secs_f64() * 1e3;
    println!(
        "{path}: 10 s at 1 ms steps ({steps} x SetReal/DoStep/GetReal) through the fmi crate: {ms:.1} ms, best of 5 (target <= 60 ms: {})",
        if ms <= 60.0 { "met" } else { "MISSED" }
    );
    println!(
        "  last outputs h = [{:.3}, {:.3}, {:.3}] um",
        last[0] * 1e6,
        last[1] * 1e6,
        last[2] * 1e6
    );
    model_exchange_costs(&import);
}

/// Prints the cost of one fmi2GetDerivatives and of one full Jacobian ∂ẋ/∂x, analytic by
/// fmi2GetDirectionalDerivative and by central differences of fmi2GetDerivatives.
fn model_exchange_costs(import: &Fmi2Import) {
    let (mut me, states, derivatives) = model_exchange_in_motion(import, [60.0, -30.0, 20.0]);
    let n = states.len();
    let mut x = vec![0.0; n];
    me.get_continuous_states(&mut x)
        .expect("fmi2GetContinuousStates");
    let mut dx = vec![0.0; n];
    let derivative = per_call(10_000, || {
        me.get_derivatives(&mut dx).expect("fmi2GetDerivatives");
    });
    // the fmi crate 0.8 asserts as many knowns as unknowns: all states known, unit seeds
    let (mut seed, mut column) = (vec![0.0; n], vec![0.0; n]);
    let analytic = per_call(200, || {
        for c in 0..n {
            seed.fill(0.0);
            seed[c] = 1.0;
            me.get_directional_derivative(&derivatives, &states, &seed, &mut column)
                .expect("fmi2GetDirectionalDerivative");
        }
    });
    let mut nominal = vec![0.0; n];
    me.get_nominals_of_continuous_states(&mut nominal)
        .expect("fmi2GetNominalsOfContinuousStates");
    let mut xh = x.clone();
    let differences = per_call(200, || {
        for c in 0..n {
            for sign in [1.0, -1.0] {
                xh[c] = x[c] + sign * 1e-6 * nominal[c];
                me.set_continuous_states(&xh)
                    .expect("fmi2SetContinuousStates");
                me.get_derivatives(&mut dx).expect("fmi2GetDerivatives");
            }
            xh[c] = x[c];
        }
    });
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    println!("Model Exchange through the fmi crate, {n} states, at a state in motion:");
    println!("  one fmi2GetDerivatives: {:.2} us", us(derivative));
    println!(
        "  the {n} x {n} Jacobian by fmi2GetDirectionalDerivative ({n} calls): {:.1} us; by central differences of fmi2GetDerivatives ({} calls): {:.1} us",
        us(analytic),
        2 * n,
        us(differences)
    );
    Common::terminate(&mut me).expect("fmi2Terminate");
}
