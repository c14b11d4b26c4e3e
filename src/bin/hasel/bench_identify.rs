//! `hasel bench --identify`: the identification benchmark of the paper's protocol on synthetic
//! data: all three actuators (Kb, b, gamma1, gamma2 each) from two 10 s experiments sampled at
//! 1 ms, every free parameter 20 % off at the start, 1 % noise.

use hasel_fmu::identify::synth::{self, Columns, Spec};
use hasel_fmu::identify::{Experiment, Options, default_free, identify};
use hasel_fmu::model::Params;
use hasel_fmu::simulation::Input;

fn experiments(columns: Columns) -> Result<[Experiment; 2], String> {
    let truth = Params::default();
    let spec = |omega: f64, seed: u64| Spec {
        input: Input::sine(60.0, omega),
        params: truth.clone(),
        t_end: 10.0,
        dt: 1e-3,
        noise: 0.01,
        columns,
        seed,
        rtol: 1e-9,
    };
    Ok([
        synth::experiment(&spec(3.0 * std::f64::consts::PI, 1), "w3pi.csv")?,
        synth::experiment(&spec(11.0, 2), "w11.csv")?,
    ])
}

pub fn run() -> Result<(), String> {
    let truth = Params::default();
    let mut start = truth.clone();
    for (k, name) in default_free().iter().enumerate() {
        let v = truth.get(name).map_err(|e| e.to_string())?;
        start
            .set(name, v * if k % 2 == 0 { 1.2 } else { 0.8 })
            .map_err(|e| e.to_string())?;
    }
    say!(
        "identification from a 20 % offset on Kb, b, gamma1, gamma2 of each actuator; synthetic 10 s experiments at 1 ms with 1 % noise (target <= 10 s)"
    );
    for columns in [Columns::Heights, Columns::TipXy] {
        let [w3pi, w11] = experiments(columns)?;
        for (label, est, val) in [
            (
                "estimate on 3pi, validate on 11 rad/s",
                vec![w3pi.clone()],
                vec![w11.clone()],
            ),
            (
                "estimate on both experiments",
                vec![w3pi.clone(), w11.clone()],
                vec![],
            ),
        ] {
            let id = identify(&start, &est, &val, &Options::default())?;
            let worst_fit = |fits: &[hasel_fmu::identify::ExperimentFit]| {
                fits.iter()
                    .flat_map(|f| f.fits.iter().map(|(_, v)| *v))
                    .fold(f64::INFINITY, f64::min)
            };
            say!(
                "  {:?}, {label}: {:.2} s ({}), {} iterations, {} simulations; lowest fit {:.1} % (estimation){}; held: {}",
                columns,
                id.seconds,
                if id.seconds <= 10.0 { "met" } else { "MISSED" },
                id.iterations,
                id.simulations,
                worst_fit(&id.estimation),
                if val.is_empty() {
                    String::new()
                } else {
                    format!(", {:.1} % (validation)", worst_fit(&id.validation))
                },
                if id.not_identifiable.is_empty() {
                    "nothing".into()
                } else {
                    id.not_identifiable
                        .iter()
                        .map(|(n, _)| n.clone())
                        .collect::<Vec<_>>()
                        .join("; ")
                }
            );
        }
    }
    Ok(())
}
