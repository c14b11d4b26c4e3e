//! What lab data add to any hidden case (issue #11, "Robust to lab data"): a sensor lag and a
//! sensor resolution (set on the synthesis, [`Sensor`]), outliers (spikes on single samples) and
//! dropouts (rows missing at random and one longer gap, so the sampling is uneven). None of them
//! is a mechanism of the platform: the diagnosis must not name an effect because of them.

use super::Error;
use crate::identify::Experiment;
use crate::identify::fit::span;
use crate::identify::synth::{Normal, Sensor};

/// The artifacts of one case.
#[derive(Clone, Debug, PartialEq)]
pub struct Artifacts {
    /// Sensor lag and resolution.
    pub sensor: Sensor,
    /// Share of the samples of each output that are spikes.
    pub outlier_rate: f64,
    /// Size of a spike in noise standard deviations, drawn within this range, either sign.
    outlier_sigmas: (f64, f64),
    /// Share of the rows dropped at random.
    dropout_rate: f64,
    /// Length of one gap in the record \[s\].
    pub gap: f64,
    seed: u64,
}

impl Artifacts {
    /// Draws the artifacts of a case with measurement noise `noise` (fraction of each output's
    /// range): a 0.1–0.5 ms sensor lag, a resolution of 0.3–1 noise σ, 0.1–0.4 % of samples
    /// spiking by 10–40 σ, 0.5–3 % of rows dropped and a gap of 20–100 ms.
    pub fn draw(noise: f64, seed: u64) -> Artifacts {
        let mut rng = Normal::new(seed.wrapping_mul(0x9E37_79B9) ^ 0xA271_FAC7);
        let mut between = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        Artifacts {
            sensor: Sensor {
                lag: between(1e-4, 5e-4),
                quantum: between(0.3, 1.0) * noise,
            },
            outlier_rate: between(1e-3, 4e-3),
            outlier_sigmas: (10.0, 40.0),
            dropout_rate: between(5e-3, 3e-2),
            gap: between(0.02, 0.1),
            seed,
        }
    }

    /// In words, for the case's description.
    pub fn describe(&self) -> String {
        format!(
            "sensor lag {:.2} ms, resolution {:.3} % of range, {:.2} % outliers, {:.1} % rows dropped and a {:.0} ms gap",
            1e3 * self.sensor.lag,
            100.0 * self.sensor.quantum,
            100.0 * self.outlier_rate,
            100.0 * self.dropout_rate,
            1e3 * self.gap
        )
    }

    /// `exp` (recorded with noise `noise`) with spikes on its outputs and rows dropped; `k`
    /// tells the experiments of a case apart.
    pub fn apply(&self, exp: &Experiment, noise: f64, k: u64) -> Result<Experiment, Error> {
        let mut rng = Normal::new(self.seed.wrapping_mul(0x2545_F491).wrapping_add(k) ^ 0xD209);
        let mut out = exp.clone();
        let n = exp.t.len();
        for (_, y) in out.channels.iter_mut() {
            let (lo, hi) = span(y.iter().copied());
            let sigma = noise * (hi - lo);
            let (a, b) = self.outlier_sigmas;
            for v in y.iter_mut() {
                if rng.uniform() < self.outlier_rate {
                    let size = a + (b - a) * rng.uniform();
                    *v += size * sigma * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                }
            }
        }
        let duration = exp.t[n - 1] - exp.t[0];
        let gap_start = exp.t[0] + (0.1 + 0.8 * rng.uniform()) * duration;
        let keep: Vec<bool> = exp
            .t
            .iter()
            .map(|&t| {
                let in_gap = (gap_start..gap_start + self.gap).contains(&t);
                rng.uniform() >= self.dropout_rate && !in_gap
            })
            .collect();
        Ok(out.rows(&keep).map_err(crate::identify::Error::from)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::analysis;
    use crate::identify::synth::{self, Columns, Spec};
    use crate::model::Params;

    #[test]
    fn artifacts_spike_and_thin_the_record_as_drawn() {
        let noise = 0.01;
        let art = Artifacts::draw(noise, 3);
        for (k, omega) in [3.0 * std::f64::consts::PI, 11.0].into_iter().enumerate() {
            let mut spec = Spec::paper(&Params::default(), omega, Columns::Heights, noise, 3);
            spec.t_end = 2.0;
            spec.sensor = art.sensor;
            let e = art
                .apply(&synth::experiment(&spec, "e.csv").unwrap(), noise, k as u64)
                .unwrap();
            // rows dropped, and the gap is there
            let kept = e.t.len() as f64 / 2001.0;
            assert!(kept < 1.0 - art.gap / 2.0 && kept > 0.9, "{kept}");
            let widest = e.t.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
            assert!(widest >= art.gap - 2e-3, "{widest} {}", art.gap);
            // the spikes are there, about as many as drawn, and found
            let spikes: usize = e
                .channels
                .iter()
                .map(|(_, y)| analysis::outliers(&e.t, y).len())
                .sum();
            let expected = art.outlier_rate * 3.0 * e.t.len() as f64;
            assert!(
                (spikes as f64) > 0.4 * expected && (spikes as f64) < 2.0 * expected + 3.0,
                "{spikes} spikes, {expected:.1} expected"
            );
        }
    }
}
