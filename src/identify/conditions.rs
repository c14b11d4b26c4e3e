//! The conditions a record was taken under, estimated beside the model (src/identify/
//! identify.md, "Records that start mid-run" and "Sensor lag"): where the device stood at the
//! first sample (at rest, or mid-run on the slow manifold: one angle per actuator) and how late
//! the sensor shows the outputs. Neither is physics of the device: they are unknowns of the
//! experiment, fitted with the parameters held, so that neither names an effect.

use nalgebra::DMatrix;

use super::experiment::{Channel, Conditions, Experiment};
use super::fit::noise_level;
use super::{Error, lm, simulate};
use crate::model::{Params, Platform};
use crate::simulation::{SimError, Start};

/// The longest sensor lag taken as the instrument's [s]: one to two samples at 0.5–1 ms, half
/// of one at 2 ms. A longer one is a transport delay of the device's own (the `delay` effect,
/// 8 ms and more), which the diagnosis names: the lag, fitted to a model without it, takes up
/// to this much of it.
pub const LAG_MAX: f64 = 1e-3;

/// The first samples a start is judged on: within them a model from rest has not moved by a
/// micrometre, whatever its parameters or what it lacks (a record from rest of a device with a
/// delay waits, the model does not).
const START_SAMPLES: usize = 3;

/// A record starts mid-run when its first samples stand away from the simulation from rest by
/// more than this many standard errors of their mean…
const START_SIGMAS: f64 = 5.0;
/// …and by more than this share of the output's range (the start parameters are a guess: a
/// model 20 % off moves differently, not from elsewhere).
const START_SHARE: f64 = 0.02;

/// Where a record starts, as asked (`--start`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StartChoice {
    /// Detected: estimated where the first samples are not the rest state's.
    Auto,
    /// At rest, whatever the data.
    Rest,
    /// Estimated, whatever the data.
    Estimate,
    /// Stated: the heights at the first sample [m].
    Heights([f64; 3]),
}

/// What to estimate of each record's conditions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    pub start: StartChoice,
    /// The sensor's lag as stated [s], or `None`: estimated within [0, LAG_MAX].
    pub lag: Option<f64>,
}

impl Default for Choice {
    fn default() -> Self {
        Choice {
            start: StartChoice::Rest,
            lag: Some(0.0),
        }
    }
}

/// The conditions found for one record, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub experiment: String,
    pub conditions: Conditions,
    /// How the start was set: "rest", "detected mid-run, estimated", "estimated", "stated".
    pub start_how: &'static str,
    /// The heights at the first sample the start gives [m].
    pub heights: [f64; 3],
    /// Standard error of the lag [s], where it was estimated.
    pub lag_se: Option<f64>,
}

/// The residuals of a record against the conditions' unknowns: z = (lag / LAG_MAX) and, where
/// the start is estimated, the three angles over the stroke scale.
struct Unknowns<'a> {
    params: &'a Params,
    exp: &'a Experiment,
    rtol: f64,
    lag: bool,
    start: bool,
    /// The conditions the unknowns move from (a stated or rest start, a lag of 0).
    at: Conditions,
    len: usize,
}

/// Scale of an angle among the unknowns [rad]: a tenth of the paper's largest stroke.
const THETA_UNIT: f64 = 1e-3;

impl Unknowns<'_> {
    fn conditions(&self, z: &[f64]) -> Conditions {
        let mut c = self.at;
        let mut k = 0;
        if self.lag {
            c.lag = z[0] * LAG_MAX;
            k = 1;
        }
        if self.start {
            c.start = Start::Settled([0, 1, 2].map(|i| z[k + i] * THETA_UNIT));
        }
        c
    }
}

impl lm::Residuals for Unknowns<'_> {
    fn count(&self) -> usize {
        self.len
    }
    fn eval(&self, z: &[f64], r: &mut [f64]) -> Result<(), Error> {
        let mut exp = self.exp.clone();
        exp.conditions = self.conditions(z);
        residuals(self.params, &exp, self.rtol, r)
    }
}

/// Simulated minus measured, channel after channel.
fn residuals(params: &Params, exp: &Experiment, rtol: f64, r: &mut [f64]) -> Result<(), Error> {
    let sim = simulate(params, exp, rtol)?;
    let mut k = 0;
    for (c, y) in &exp.channels {
        for (s, m) in sim.iter().zip(y) {
            r[k] = c.of(s) - m;
            k += 1;
        }
    }
    Ok(())
}

/// Whether the first samples of `exp` stand away from its simulation from rest by more than
/// noise can: the level of the residual over [`START_SAMPLES`]. (Not a longer window, nor the
/// slope: a model without a delay the data hold moves at once where the data wait.)
fn starts_mid_run(params: &Params, exp: &Experiment, rtol: f64) -> Result<bool, Error> {
    let mut at_rest = exp.clone();
    at_rest.conditions.start = Start::Rest;
    let sim = simulate(params, &at_rest, rtol)?;
    let window = START_SAMPLES;
    Ok(exp.channels.iter().any(|(c, y)| {
        let level = sim
            .iter()
            .zip(y)
            .take(window)
            .map(|(s, m)| m - c.of(s))
            .sum::<f64>()
            / window as f64;
        let (lo, hi) = y
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        let se = START_SIGMAS * noise_level(&exp.t, y) / (window as f64).sqrt();
        level.abs() > se.max(START_SHARE * (hi - lo))
    }))
}

/// Whether conditions `b` differ from `a` by more than the fit can tell: a lag by a
/// microsecond, a start's angle by 1e-7 rad (about a nanometre of height).
pub fn moved(a: &Conditions, b: &Conditions) -> bool {
    let angles = |s: &Start| match *s {
        Start::Rest => None,
        Start::Settled(theta) => Some(theta),
    };
    let start_moved = match (angles(&a.start), angles(&b.start)) {
        (Some(x), Some(y)) => (0..3).any(|i| (x[i] - y[i]).abs() > 1e-7),
        (None, None) => false,
        _ => true,
    };
    start_moved || (a.lag - b.lag).abs() > 1e-6
}

/// The angles whose heights the record shows at its first samples (the mean of the first
/// three), or the rest angles where it measures no height.
fn angles_at_first_samples(model: &Platform, exp: &Experiment) -> Result<[f64; 3], Error> {
    let rest = model.rest_state().map_err(SimError::from)?;
    let mut theta = model.heights(&rest).map(|h| 2.0 * h / model.params().lv);
    for (c, y) in &exp.channels {
        if let Channel::H(i) = *c {
            let h = y.iter().take(3).sum::<f64>() / y.len().min(3) as f64;
            theta[i] = 2.0 * h / model.params().lv;
        }
    }
    Ok(theta.map(|s: f64| s.clamp(-0.99, 0.99).asin()))
}

/// Estimates the conditions of `exp` under `params` as `choice` asks, from its current ones.
pub fn estimate(
    params: &Params,
    exp: &Experiment,
    choice: Choice,
    rtol: f64,
) -> Result<Found, Error> {
    let model = Platform::new(params.clone())?;
    let mut at = Conditions {
        lag: choice.lag.unwrap_or(0.0),
        ..exp.conditions
    };
    let estimate_lag = choice.lag.is_none();
    let (estimate_start, start_how) = match choice.start {
        StartChoice::Rest => {
            at.start = Start::Rest;
            (false, "rest")
        }
        StartChoice::Heights(h) => {
            at.start = Start::Settled(h.map(|h| (2.0 * h / params.lv).clamp(-0.99, 0.99).asin()));
            (false, "stated")
        }
        StartChoice::Estimate => (true, "estimated"),
        StartChoice::Auto => {
            if starts_mid_run(params, exp, rtol)? {
                (true, "detected mid-run, estimated")
            } else {
                at.start = Start::Rest;
                (false, "rest")
            }
        }
    };
    let mut z0 = Vec::new();
    let (mut lo, mut hi) = (Vec::new(), Vec::new());
    if estimate_lag {
        z0.push(exp.conditions.lag / LAG_MAX);
        lo.push(0.0);
        hi.push(1.0);
    }
    if estimate_start {
        let theta = match exp.conditions.start {
            Start::Settled(theta) => theta,
            Start::Rest => angles_at_first_samples(&model, exp)?,
        };
        let theta_max = model
            .actuators
            .iter()
            .map(|a| std::f64::consts::FRAC_PI_2 / a.par.gamma2);
        for (t, m) in theta.iter().zip(theta_max) {
            z0.push(t / THETA_UNIT);
            lo.push(-m / THETA_UNIT);
            hi.push(m / THETA_UNIT);
        }
    }
    let len = exp.channels.iter().map(|(_, y)| y.len()).sum();
    let problem = Unknowns {
        params,
        exp,
        rtol,
        lag: estimate_lag,
        start: estimate_start,
        at,
        len,
    };
    let (conditions, lag_se) = if z0.is_empty() {
        (at, None)
    } else {
        let opts = lm::Options {
            fd_step: 1e-4,
            max_iterations: 30,
            ..lm::Options::default()
        };
        let sol = lm::minimize(&problem, &z0, &lo, &hi, &opts)?;
        let lag_se = estimate_lag
            .then(|| lag_standard_error(&problem, &sol.x, sol.cost, opts.threads))
            .transpose()?
            .flatten();
        (problem.conditions(&sol.x), lag_se)
    };
    let x0 = conditions
        .start
        .state(&model, exp.input.value(exp.t[0]))
        .map_err(SimError::from)?;
    Ok(Found {
        experiment: exp.name.clone(),
        conditions,
        start_how,
        heights: model.heights(&x0),
        lag_se,
    })
}

/// The lag's standard error from the curvature of the cost: σ² (JᵀJ)⁻¹ on the lag's column,
/// σ² the mean square residual.
fn lag_standard_error(
    problem: &Unknowns<'_>,
    z: &[f64],
    cost: f64,
    threads: usize,
) -> Result<Option<f64>, Error> {
    let j: DMatrix<f64> = lm::jacobian_central(problem, z, 1e-3, threads)?;
    let sigma2 = 2.0 * cost / problem.len as f64;
    Ok((j.transpose() * &j)
        .try_inverse()
        .map(|inv| (sigma2 * inv[(0, 0)]).max(0.0).sqrt() * LAG_MAX))
}
