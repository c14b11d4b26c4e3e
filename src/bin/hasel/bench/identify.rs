//! `hasel bench --identify`: the identification benchmark of the paper's protocol on synthetic
//! data: all three actuators (Kb, b, gamma1, gamma2 each) from two 10 s experiments sampled at
//! 1 ms, every free parameter 20 % off at the start, 1 % noise.

use hasel_fmu::identify::synth::{self, Columns, Spec};
use hasel_fmu::identify::{Experiment, Options, default_free, identify};
use hasel_fmu::model::Params;

use crate::error::Error;

fn experiments(columns: Columns) -> Result<[Experiment; 2], Error> {
    let truth = Params::default();
    Ok([
        synth::experiment(
            &Spec::paper(&truth, 3.0 * std::f64::consts::PI, columns, 0.01, 1),
            "w3pi.csv",
        )?,
        synth::experiment(&Spec::paper(&truth, 11.0, columns, 0.01, 2), "w11.csv")?,
    ])
}

pub fn run() -> Result<(), Error> {
    let start = synth::offset(&Params::default(), &default_free(), 0.2)?;
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
