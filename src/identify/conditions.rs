//! The conditions a record was taken under, estimated beside the model (src/identify/
//! identify.md, "Records that start mid-run" and "Sensor lag"): where the device stood at the
//! first sample (at rest, or mid-run on the slow manifold: one angle per actuator) and how late
//! the sensor shows the outputs. Neither is physics of the device: they are unknowns of the
//! experiment, fitted with the parameters held, so that neither names an effect.

use nalgebra::{DMatrix, DVector};

use super::experiment::{Channel, Conditions, Experiment, Weighting};
use super::fit::{median, noise_level, robust_sigma, span};
use super::{Error, lm, simulate};
use crate::model::{Params, Platform};
use crate::simulation::{SimError, Start};

/// The longest sensor lag taken as the instrument's \[s\]: one to two samples at 0.5–1 ms, half
/// of one at 2 ms. A longer one is a transport delay of the device's own (the `delay` effect,
/// 8 ms and more), which the diagnosis names: the lag, fitted to a model without it, takes up
/// to this much of it.
pub const LAG_MAX: f64 = 1e-3;

/// A record starts mid-run when its first sample stands away from the rest state's outputs
/// by more than this many σ, σ the larger of the noise's and the fit's (the median residual
/// over the record, as a normal σ: a model that lacks an effect is off at the rest state by as
/// much as elsewhere, and a fit bends the parameters that set the rest heights)…
const START_SIGMAS: f64 = 5.0;
/// …and by more than this share of the output's range.
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
    /// Stated: the heights at the first sample \[m\].
    Heights([f64; 3]),
    /// As the record's conditions have it (found before: a first fit keeps its start).
    Kept,
    /// As the record's conditions have it, but a start mid-run estimated again, with the
    /// effects' states among its unknowns where the model has any (a refit: the effect moves
    /// the trajectory the start must meet, and its slow states stood elsewhere than settled
    /// when the device had been driven before the record).
    Refined,
}

/// The sensor's lag, as asked (`--lag`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LagChoice {
    /// Estimated within [0, LAG_MAX].
    Estimate,
    /// Stated \[s\].
    Stated(f64),
    /// As the record's conditions have it.
    Kept,
}

/// What to estimate of each record's conditions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    pub start: StartChoice,
    pub lag: LagChoice,
}

impl Default for Choice {
    fn default() -> Self {
        Choice {
            start: StartChoice::Auto,
            lag: LagChoice::Estimate,
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
    /// The heights at the first sample the start gives \[m\].
    pub heights: [f64; 3],
    /// Standard error of the lag \[s\], where it was estimated.
    pub lag_se: Option<f64>,
}

/// The residuals of a record against the conditions' unknowns: z = (lag / LAG_MAX) and, where
/// the start is estimated, the three angles over the stroke scale and the effects' states over
/// their scales (`slow_scales`, empty where they settle).
struct Unknowns<'a> {
    params: &'a Params,
    exp: &'a Experiment,
    rtol: f64,
    /// The factor on each channel's residuals (`Weighting`).
    factors: Vec<f64>,
    lag: bool,
    start: bool,
    slow_scales: Vec<f64>,
    /// The conditions the unknowns move from (a stated or rest start, a lag of 0).
    at: Conditions,
    len: usize,
}

/// Scale of an angle among the unknowns [rad]: a tenth of the paper's largest stroke.
const THETA_UNIT: f64 = 1e-3;

impl Unknowns<'_> {
    fn conditions(&self, z: &[f64]) -> Conditions {
        let mut c = self.at.clone();
        let mut k = 0;
        if self.lag {
            c.lag = z[0] * LAG_MAX;
            k = 1;
        }
        if self.start {
            c.start = Start::Settled {
                theta: [0, 1, 2].map(|i| z[k + i] * THETA_UNIT),
                slow: z[k + 3..]
                    .iter()
                    .zip(&self.slow_scales)
                    .map(|(z, s)| z * s)
                    .collect(),
            };
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
        let sim = simulate(self.params, &exp, self.rtol)?;
        let mut k = 0;
        for ((c, y), f) in exp.channels.iter().zip(&self.factors) {
            for (s, m) in sim.iter().zip(y) {
                r[k] = f * (c.of(s) - m);
                k += 1;
            }
        }
        Ok(())
    }
}

/// Whether the first sample of `exp` stands away from the rest state's outputs by more than
/// noise and the fit's error elsewhere can. Only the first: at it a record from rest shows the
/// rest state whatever the input does next, where a later sample shows the response, in which a
/// missing effect looks like a start elsewhere. The fit's error is taken about its median: a
/// model that misses a static load is off by about as much at rest as elsewhere, which is no
/// sign of a start mid-run, and its offset must not widen the bound a start mid-run has to pass.
fn starts_mid_run(params: &Params, exp: &Experiment, rtol: f64) -> Result<bool, Error> {
    let mut at_rest = exp.clone();
    at_rest.conditions.start = Start::Rest;
    let sim = simulate(params, &at_rest, rtol)?;
    Ok(exp.channels.iter().any(|(c, y)| {
        let mut off: Vec<f64> = y.iter().zip(&sim).map(|(m, s)| m - c.of(s)).collect();
        let first = off[0];
        let offset = median(&mut off);
        let mut spread: Vec<f64> = off.iter().map(|r| (r - offset).abs()).collect();
        let fit_sigma = robust_sigma(&mut spread);
        let (lo, hi) = span(y.iter().copied());
        let sigma = noise_level(&exp.t, y).max(fit_sigma);
        (first - offset).abs() > (START_SIGMAS * sigma).max(START_SHARE * (hi - lo))
    }))
}

/// Whether conditions `b` differ from `a` by more than the fit can tell: a lag by a
/// microsecond, a start's angle by 1e-7 rad (about a nanometre of height), an effect's state
/// by 1e-4 of its size.
pub fn moved(a: &Conditions, b: &Conditions) -> bool {
    let start_moved = match (&a.start, &b.start) {
        (
            Start::Settled { theta, slow },
            Start::Settled {
                theta: theta_b,
                slow: slow_b,
            },
        ) => {
            (0..3).any(|i| (theta[i] - theta_b[i]).abs() > 1e-7)
                || slow.len() != slow_b.len()
                || slow
                    .iter()
                    .zip(slow_b)
                    .any(|(x, y)| (x - y).abs() > 1e-4 * x.abs().max(y.abs()))
        }
        (Start::Rest, Start::Rest) => false,
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

/// How far an effect's state at a start mid-run may stand, in its scales (a full stroke, 100 V).
const SLOW_RANGE: f64 = 10.0;

/// Where the effects' states of a start at angles `theta` begin their estimate: as the record's
/// conditions give them, else settled at the angles and the first command.
fn slow_at_start(model: &Platform, exp: &Experiment, theta: [f64; 3]) -> Result<Vec<f64>, Error> {
    let extras = model.n_effect_states();
    if let Start::Settled { slow, .. } = &exp.conditions.start
        && slow.len() == extras
    {
        return Ok(slow.clone());
    }
    let x = model
        .settled_state(theta, &[], exp.input.value(exp.t[0]))
        .map_err(SimError::from)?;
    Ok(model.effect_states(&x))
}

/// Estimates the conditions of `exp` under `params` as `choice` asks, from its current ones.
pub fn estimate(
    params: &Params,
    exp: &Experiment,
    choice: Choice,
    (rtol, weighting): (f64, Weighting),
) -> Result<Found, Error> {
    // a record with a lead-in has its conditions set there alone: what follows is judged
    let lead_in;
    let exp = match exp.lead_in {
        0 => exp,
        k => {
            lead_in = exp.samples_in(0..k)?;
            &lead_in
        }
    };
    let model = Platform::new(params.clone())?;
    let mut at = exp.conditions.clone();
    let estimate_lag = lag_choice(choice.lag, &mut at);
    let (estimate_start, start_how) = start_choice(choice.start, &mut at, params, exp, rtol)?;
    let StartingPoint {
        z0,
        lo,
        hi,
        slow_scales,
    } = unknown_start(&model, exp, estimate_lag, estimate_start)?;
    let len = exp.channels.iter().map(|(_, y)| y.len()).sum();
    let problem = Unknowns {
        params,
        exp,
        rtol,
        factors: exp
            .channels
            .iter()
            .map(|(c, _)| exp.residual_factor(*c, weighting))
            .collect(),
        lag: estimate_lag,
        start: estimate_start,
        slow_scales,
        at: at.clone(),
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
            .then(|| lag_standard_error(&problem, (&sol.x, &sol.residuals), lm::share()))
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

/// Sets the lag of `at` as `lag` asks; whether it is to be estimated.
fn lag_choice(lag: LagChoice, at: &mut Conditions) -> bool {
    match lag {
        LagChoice::Estimate => {
            at.lag = 0.0;
            true
        }
        LagChoice::Stated(lag) => {
            at.lag = lag;
            false
        }
        LagChoice::Kept => false,
    }
}

/// Sets the start of `at` as `start` asks (detecting a start mid-run where it is to be
/// detected); whether it is to be estimated, and how it was set, in words.
fn start_choice(
    start: StartChoice,
    at: &mut Conditions,
    params: &Params,
    exp: &Experiment,
    rtol: f64,
) -> Result<(bool, &'static str), Error> {
    let found_before = matches!(exp.conditions.start, Start::Settled { .. });
    Ok(match start {
        StartChoice::Rest => {
            at.start = Start::Rest;
            (false, "rest")
        }
        StartChoice::Heights(h) => {
            at.start = Start::Settled {
                theta: h.map(|h| (2.0 * h / params.lv).clamp(-0.99, 0.99).asin()),
                slow: Vec::new(),
            };
            (false, "stated")
        }
        StartChoice::Estimate => (true, "estimated"),
        StartChoice::Kept => (false, "kept"),
        // the angles were found before under a model without the effect, which moves the
        // trajectory the start must meet: a delay's as much as a lag's states
        StartChoice::Refined if found_before => (true, "detected mid-run, estimated"),
        StartChoice::Refined => (false, "rest"),
        StartChoice::Auto => {
            // once found mid-run, a record stays so: the fit under its start no longer holds
            // the parameters that set the rest heights to the first samples
            if found_before || starts_mid_run(params, exp, rtol)? {
                (true, "detected mid-run, estimated")
            } else {
                at.start = Start::Rest;
                (false, "rest")
            }
        }
    })
}

/// The unknowns of a record's conditions in the optimiser's units: their start, bounds, and
/// the effects' state scales.
struct StartingPoint {
    z0: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    slow_scales: Vec<f64>,
}

/// The unknowns to estimate, their start from `exp`'s current conditions: the lag, and the
/// start's angles and effects' states.
fn unknown_start(
    model: &Platform,
    exp: &Experiment,
    estimate_lag: bool,
    estimate_start: bool,
) -> Result<StartingPoint, Error> {
    let mut z0 = Vec::new();
    let (mut lo, mut hi) = (Vec::new(), Vec::new());
    if estimate_lag {
        z0.push(exp.conditions.lag / LAG_MAX);
        lo.push(0.0);
        hi.push(1.0);
    }
    let mut slow_scales = Vec::new();
    if estimate_start {
        let theta = match exp.conditions.start {
            Start::Settled { theta, .. } => theta,
            Start::Rest => angles_at_first_samples(model, exp)?,
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
        let slow = slow_at_start(model, exp, theta)?;
        // the effects' scales, picked from the state's as the effects' states are
        slow_scales = model.effect_states(&model.state_scales());
        for (v, s) in slow.iter().zip(&slow_scales) {
            z0.push(v / s);
            lo.push(-SLOW_RANGE);
            hi.push(SLOW_RANGE);
        }
    }
    Ok(StartingPoint {
        z0,
        lo,
        hi,
        slow_scales,
    })
}

/// The lag's standard error from the curvature of the cost: σ² (JᵀJ)⁻¹ on the lag's column,
/// σ² the mean square residual.
fn lag_standard_error(
    problem: &Unknowns<'_>,
    (z, r): (&[f64], &DVector<f64>),
    threads: usize,
) -> Result<Option<f64>, Error> {
    let j: DMatrix<f64> = lm::jacobian_central(problem, z, r, 1e-3, threads)?;
    let sigma2 = r.norm_squared() / problem.len as f64;
    Ok((j.transpose() * &j)
        .try_inverse()
        .map(|inv| (sigma2 * inv[(0, 0)]).max(0.0).sqrt() * LAG_MAX))
}
