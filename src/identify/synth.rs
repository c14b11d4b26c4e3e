//! Synthetic experiments: the model's own outputs for a chosen input and parameter set, with
//! Gaussian measurement noise, written in the measured-data format. Tests and users check the
//! estimator on them.

use crate::model::{Params, Platform};
use crate::simulation::{DEFAULT_RTOL, Input, Simulator};

use super::Error;
use super::experiment::{Channel, Experiment};
use crate::io::csv::Table;

/// Relative tolerance of synthetic data: 1000 times tighter than the default, so that the
/// data's own integration error is far below anything an estimator is asked to resolve.
pub const DATA_RTOL: f64 = DEFAULT_RTOL * 1e-3;

/// Which outputs a synthetic experiment records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Columns {
    /// h1, h2, h3.
    Heights,
    /// tip_x, tip_y: what the paper's laser measures.
    TipXy,
}

impl Columns {
    pub fn channels(self) -> &'static [Channel] {
        match self {
            Columns::Heights => &[Channel::H(0), Channel::H(1), Channel::H(2)],
            Columns::TipXy => &[Channel::Tip(0), Channel::Tip(1)],
        }
    }
}

/// What to simulate and how to measure it.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The command, as written in the file.
    pub input: Input,
    /// What the actuators receive when it is not the command (a hidden mechanism upstream).
    pub drive: Option<Input>,
    /// A disturbance added to every recorded output, unexplained by the model: amplitude as a
    /// fraction of the output's range, frequency \[Hz\], phase \[rad\].
    pub vibration: Option<(f64, f64, f64)>,
    pub params: Params,
    pub t_end: f64,
    pub dt: f64,
    /// Noise standard deviation as a fraction of each output's range (max − min).
    pub noise: f64,
    /// The sensor's own response: its lag and resolution.
    pub sensor: Sensor,
    pub columns: Columns,
    pub seed: u64,
    pub rtol: f64,
    /// When the recording starts \[s\]: the device is driven from rest at 0, the logger starts
    /// here (0: a record from rest), and its time column goes on from there.
    pub record_from: f64,
}

/// What a real displacement sensor adds to the outputs: a first-order lag before the noise and a
/// resolution (quantization) after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    /// Time constant of the sensor's lag \[s\] (0: none).
    pub lag: f64,
    /// Resolution as a fraction of each output's range (0: none).
    pub quantum: f64,
}

impl Sensor {
    /// No lag, no quantization.
    pub const IDEAL: Sensor = Sensor {
        lag: 0.0,
        quantum: 0.0,
    };

    /// Column `col` of `rows` (time in column 0) seen through the lag, discretized exactly for
    /// a signal held over each step: y ← y + (1 − e^(−Δt/τ)) (u − y).
    fn lag(&self, rows: &mut [Vec<f64>], col: usize) {
        if self.lag <= 0.0 {
            return;
        }
        for k in 1..rows.len() {
            let a = 1.0 - (-(rows[k][0] - rows[k - 1][0]) / self.lag).exp();
            rows[k][col] = rows[k - 1][col] + a * (rows[k][col] - rows[k - 1][col]);
        }
    }
}

impl Spec {
    /// An experiment of the paper's protocol: the 60 V sine at `omega`, 10 s sampled every
    /// 1 ms, from rest, simulated at a tight tolerance.
    pub fn paper(params: &Params, omega: f64, columns: Columns, noise: f64, seed: u64) -> Spec {
        Spec {
            input: Input::sine(60.0, omega),
            drive: None,
            vibration: None,
            params: params.clone(),
            t_end: 10.0,
            dt: 1e-3,
            noise,
            sensor: Sensor::IDEAL,
            columns,
            seed,
            rtol: DATA_RTOL,
            record_from: 0.0,
        }
    }
}

/// `params` with each of `names` off by `fraction`, alternately up and down: a start for
/// checking an estimator.
pub fn offset(params: &Params, names: &[String], fraction: f64) -> Result<Params, Error> {
    let mut out = params.clone();
    for (k, name) in names.iter().enumerate() {
        let v = params.get(name)?;
        let factor = if k % 2 == 0 {
            1.0 + fraction
        } else {
            1.0 - fraction
        };
        out.set(name, v * factor)?;
    }
    Ok(out)
}

/// A deterministic normal random source: SplitMix64 (Steele, Lea & Flood 2014) and the
/// Box–Muller transform. Written here so that a seed gives the same data on every platform
/// and with every version of this tool.
pub struct Normal {
    state: u64,
    spare: Option<f64>,
}

impl Normal {
    pub fn new(seed: u64) -> Normal {
        Normal {
            state: seed,
            spare: None,
        }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal sample.
    pub fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// The header and rows of the synthetic experiment `t,U1,U2,U3,<channels>`.
pub fn synthesize(spec: &Spec) -> Result<(Vec<&'static str>, Vec<Vec<f64>>), Error> {
    let model = Platform::new(spec.params.clone())?;
    let mut sim = Simulator::new(model, 0.0, spec.rtol)?;
    let mut rows = Vec::new();
    let channels = spec.columns.channels();
    sim.run(
        spec.drive.as_ref().unwrap_or(&spec.input),
        spec.t_end,
        spec.dt,
        |s| {
            let u = spec.input.value(s.t);
            let mut row = vec![s.t, u[0], u[1], u[2]];
            row.extend(channels.iter().map(|c| c.of(s)));
            rows.push(row);
        },
    )?;
    // the logger starts late: its first row is the first at or after `record_from`
    let first = rows.partition_point(|r| r[0] < spec.record_from * (1.0 - 1e-12));
    rows.drain(..first);
    let mut rng = Normal::new(spec.seed);
    for (j, _) in channels.iter().enumerate() {
        let col = 4 + j;
        let (lo, hi) = super::fit::span(rows.iter().map(|r| r[col]));
        let sigma = spec.noise * (hi - lo);
        let quantum = spec.sensor.quantum * (hi - lo);
        let (a, f, phase) = spec.vibration.unwrap_or((0.0, 0.0, 0.0));
        spec.sensor.lag(&mut rows, col);
        for r in rows.iter_mut() {
            let disturbance = a * (hi - lo) * (2.0 * std::f64::consts::PI * f * r[0] + phase).sin();
            r[col] += disturbance + sigma * rng.sample();
            if quantum > 0.0 {
                r[col] = (r[col] / quantum).round() * quantum;
            }
        }
    }
    let mut header = vec!["t", "U1", "U2", "U3"];
    header.extend(channels.iter().map(|c| c.name()));
    Ok((header, rows))
}

/// A synthetic experiment in memory, named `name`, as if read from a file.
pub fn experiment(spec: &Spec, name: &str) -> Result<Experiment, Error> {
    let (header, rows) = synthesize(spec)?;
    let table = Table {
        path: name.into(),
        header: header.iter().map(|h| h.to_string()).collect(),
        lines: (2..rows.len() + 2).collect(),
        rows,
    };
    Ok(Experiment::from_table(&table)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_samples_have_unit_variance() {
        let mut n = Normal::new(7);
        let xs: Vec<f64> = (0..200_000).map(|_| n.sample()).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.01 && (var - 1.0).abs() < 0.01,
            "{mean} {var}"
        );
        assert_eq!(Normal::new(3).sample(), Normal::new(3).sample());
    }
}
